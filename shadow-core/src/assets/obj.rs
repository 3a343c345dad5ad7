//! Wavefront OBJ through tobj: polygons triangulated (as fans), one mesh per object or group, texture
//! coordinates, and from the material libraries when they can be read the diffuse colour (`Kd`) and
//! texture (`map_Kd`), the alpha texture (`map_d`, an alpha mask cut at one half, as renderers read it
//! for foliage) and the dissolve (`d`, or `Tr` as one minus it: blended below one).
//!
//! The text is checked line by line before tobj sees it, so that every refusal names its line: numbers
//! that do not parse, faces with fewer than three corners or indices out of range. Polylines (`l`) and
//! points (`p`) are not surfaces and are left out (tobj would read `l` as a face). Material libraries
//! are resolved under the same [`FileAccess`](super::FileAccess) rule as every file a model names, and
//! only the lines this loader uses (`newmtl`, `Kd`, `d`, `Tr`, `map_Kd`, `map_d`) reach tobj, so a broken
//! library loses colours and nothing else. Images are read under the same rule, relative to the model's
//! folder; one that cannot be read is left out with a warning.

use std::collections::{HashMap, HashSet};
use std::io::Cursor;
use std::path::Path;

use glam::{Mat4, Vec2, Vec3};

use super::images::{self, ImageSource};
use super::{AssetError, AssetFault, LoadOptions, read_model, read_referenced};
use crate::material::{AlphaMode, Sampler, Texture, TextureRef, UvTransform, Wrap};
use crate::mesh::Mesh;
use crate::scene::{Material, Scene, TextureKey};

/// The largest material library read (a library is a few lines per material).
const MAX_MTL_BYTES: u64 = 16 << 20;

pub(super) fn load(path: &Path, options: &LoadOptions) -> Result<Scene, AssetError> {
    let err = |fault| AssetError::new(path, fault);
    let bytes = read_model(path).map_err(err)?;
    let text = String::from_utf8_lossy(&bytes);
    let checked = check(&text).map_err(err)?;
    if checked.faces == 0 {
        return Err(err(AssetFault::Unsupported(if checked.lines_and_points > 0 {
            format!("only lines or points ({} 'l' and 'p' lines), no faces", checked.lines_and_points)
        } else {
            "no faces".into()
        })));
    }

    let tobj_options =
        tobj::LoadOptions { single_index: true, triangulate: true, ignore_points: true, ignore_lines: true };
    let folder = path.parent().unwrap_or(Path::new("."));
    let (models, materials) = tobj::load_obj_buf(&mut Cursor::new(checked.text.as_bytes()), &tobj_options, |library| {
        material_library(folder, library, options)
    })
    .map_err(|e| err(AssetFault::Malformed(e.to_string())))?;
    // A missing or broken library only loses colours: keep the default material rather than fail the model.
    let materials = materials.unwrap_or_default();

    let mut scene = Scene::new();
    // Only the materials some object uses are made, and only their images read.
    let used: Vec<&tobj::Material> = materials
        .iter()
        .enumerate()
        .filter(|(i, _)| models.iter().any(|m| m.mesh.material_id == Some(*i)))
        .map(|(_, m)| m)
        .collect();
    let mut images = Images::read(&used, folder, options).map_err(err)?;
    let mut material_keys = vec![None; materials.len()];
    for (i, m) in materials.iter().enumerate() {
        if models.iter().any(|model| model.mesh.material_id == Some(i)) {
            let material = images.material(m, &mut scene);
            material_keys[i] = Some(scene.add_material(material));
        }
    }
    let mut default_material = None;
    for model in &models {
        let m = &model.mesh;
        if m.indices.is_empty() {
            continue;
        }
        let positions: Vec<Vec3> = m.positions.chunks_exact(3).map(|p| Vec3::new(p[0], p[1], p[2])).collect();
        let triangles: Vec<[u32; 3]> = m.indices.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect();
        let what = format!("object '{}'", model.name);
        let mesh = if m.normals.len() == m.positions.len() {
            let normals = m.normals.chunks_exact(3).map(|n| Vec3::new(n[0], n[1], n[2])).collect();
            Mesh::with_normals(positions, normals, triangles)
        } else {
            Mesh::new(positions, triangles)
        }
        .map_err(|e| err(AssetFault::Mesh(what.clone(), e)))?;
        // OBJ's v runs up the image, glTF's (and so the mesh's) down it from the top.
        let mesh = if m.texcoords.len() / 2 == m.positions.len() / 3 && !m.texcoords.is_empty() {
            let uvs = m.texcoords.chunks_exact(2).map(|t| Vec2::new(t[0], 1.0 - t[1])).collect();
            mesh.with_uvs(uvs).map_err(|e| err(AssetFault::Mesh(what, e)))?
        } else {
            mesh
        };
        let mat = match m.material_id.and_then(|i| material_keys.get(i).copied().flatten()) {
            Some(key) => key,
            None => *default_material.get_or_insert_with(|| scene.add_material(Material::default())),
        };
        let key = scene.add_mesh(mesh);
        scene
            .add_instance(&model.name, key, mat, Mat4::IDENTITY)
            .map_err(|e| err(AssetFault::Malformed(e.to_string())))?;
    }
    Ok(scene)
}

/// The images a model's materials name, each decoded once.
struct Images {
    /// Decoded images by file, or why each could not be used.
    decoded: HashMap<String, Result<Texture, String>>,
    /// Files already warned about.
    warned: HashSet<String>,
    /// Scene textures by the files of their colour and alpha, so materials naming the same stay one.
    keys: HashMap<(Option<String>, Option<String>), TextureKey>,
}

/// A `map_Kd` or `map_d` statement: the file and the options this loader applies.
struct TextureStatement {
    file: String,
    transform: UvTransform,
    clamp: bool,
}

impl Images {
    /// Reads and decodes (in parallel) every image the materials' `map_Kd` and `map_d` name. A file the
    /// model may not read refuses it; any other fault is kept, to be warned about where it is used.
    fn read(materials: &[&tobj::Material], folder: &Path, options: &LoadOptions) -> Result<Self, AssetFault> {
        let mut files: Vec<String> = Vec::new();
        let statements = materials.iter().flat_map(|m| [m.diffuse_texture.as_deref(), m.dissolve_texture.as_deref()]);
        for line in statements.flatten() {
            if let Ok((statement, _)) = texture_statement(line)
                && !files.contains(&statement.file)
            {
                files.push(statement.file);
            }
        }
        let mut sources = Vec::with_capacity(files.len());
        for file in &files {
            let bytes = images::read_image_file(folder, file, "a material library", options)?;
            sources.push(ImageSource { label: file.clone(), name: file.clone(), bytes });
        }
        let decoded = files.into_iter().zip(images::decode_all(sources, &options.textures)).collect();
        Ok(Self { decoded, warned: HashSet::new(), keys: HashMap::new() })
    }

    /// A material from its library entry, with its textures.
    fn material(&mut self, m: &tobj::Material, scene: &mut Scene) -> Material {
        let mut material = Material::colored(&m.name, m.diffuse.map_or(Vec3::splat(0.8), Vec3::from));
        let dissolve = m.dissolve.unwrap_or(1.0).clamp(0.0, 1.0);
        if dissolve < 1.0 {
            material.alpha = dissolve;
            material.alpha_mode = AlphaMode::Blend;
        }
        let what = |key: &str| format!("material '{}' {key}", m.name);
        let (decoded, warned) = (&self.decoded, &mut self.warned);
        let colour = statement(decoded, warned, m.diffuse_texture.as_deref(), &what("map_Kd"), scene);
        let alpha = statement(decoded, warned, m.dissolve_texture.as_deref(), &what("map_d"), scene);
        let first = colour.as_ref().or(alpha.as_ref()).map(|(s, _)| (s.transform, s.clamp));
        let files = (colour.as_ref().map(|(s, _)| s.file.clone()), alpha.as_ref().map(|(s, _)| s.file.clone()));
        if let (Some(&key), Some((transform, clamp))) = (self.keys.get(&files), first) {
            let masked = alpha.is_some() && scene.texture(key).is_some_and(|t| t.has_alpha());
            return textured(material, key, transform, clamp, masked);
        }
        let texture = match (colour, alpha) {
            (Some((_, c)), Some((_, a))) => match with_alpha_of(c, a) {
                Some(t) => Some(t),
                None => {
                    scene.add_warning(format!(
                        "{}: its map_d image is {} x {} and its map_Kd image {} x {}; the map_d is left out",
                        what("map_d"),
                        a.width(),
                        a.height(),
                        c.width(),
                        c.height()
                    ));
                    Some(c.clone())
                }
            },
            (Some((_, c)), None) => Some(c.clone()),
            (None, Some((_, a))) => with_alpha_of(&white_like(a), a),
            (None, None) => None,
        };
        match (texture, first) {
            (Some(texture), Some((transform, clamp))) => {
                let masked = files.1.is_some() && texture.has_alpha();
                let key = scene.add_texture(texture);
                self.keys.insert(files, key);
                textured(material, key, transform, clamp, masked)
            }
            _ => material,
        }
    }
}

/// A `map_Kd` or `map_d` line's options and its decoded image; `None` with a warning (once per file)
/// when the image cannot be used.
fn statement<'a>(
    decoded: &'a HashMap<String, Result<Texture, String>>,
    warned: &mut HashSet<String>,
    line: Option<&str>,
    what: &str,
    scene: &mut Scene,
) -> Option<(TextureStatement, &'a Texture)> {
    let line = line?;
    let statement = match texture_statement(line) {
        Ok((statement, ignored)) => {
            for option in ignored {
                scene.add_warning(format!("{what}: option {option} is not supported and is ignored"));
            }
            statement
        }
        Err(why) => {
            scene.add_warning(format!("{what} '{line}': {why}; the texture is left out"));
            return None;
        }
    };
    match decoded.get(&statement.file)? {
        Ok(texture) => Some((statement, texture)),
        Err(why) => {
            if warned.insert(statement.file.clone()) {
                scene.add_warning(format!("{what} '{}': {why}; the texture is left out", statement.file));
            }
            None
        }
    }
}

/// `material` reading `texture`, cut where its alpha is below one half when `masked` (the material has
/// a `map_d` with some texel that is not opaque).
fn textured(
    mut material: Material,
    texture: TextureKey,
    transform: UvTransform,
    clamp: bool,
    masked: bool,
) -> Material {
    let wrap = if clamp { Wrap::ClampToEdge } else { Wrap::Repeat };
    material.base_color_texture =
        Some(TextureRef { texture, sampler: Sampler { wrap_u: wrap, wrap_v: wrap, ..Sampler::default() }, transform });
    if masked {
        material.alpha_mode = AlphaMode::Mask { cutoff: AlphaMode::DEFAULT_CUTOFF };
    }
    material
}

/// Parses `[options] file` after `map_Kd` or `map_d`: `-o u [v [w]]` and `-s u [v [w]]` become the
/// coordinate transform, `-clamp on` clamps; any other option is skipped with its arguments and
/// returned, to be warned about.
fn texture_statement(line: &str) -> Result<(TextureStatement, Vec<String>), String> {
    let words: Vec<&str> = line.split_whitespace().collect();
    let (mut offset, mut scale, mut clamp, mut ignored) = (Vec2::ZERO, Vec2::ONE, false, Vec::new());
    let mut i = 0;
    while i < words.len() && words[i].starts_with('-') && words[i].len() > 1 {
        let option = words[i];
        i += 1;
        let numbers: Vec<f32> = words[i..].iter().map_while(|w| w.parse::<f32>().ok()).take(3).collect();
        match option {
            "-o" | "-s" if !numbers.is_empty() => {
                let v =
                    Vec2::new(numbers[0], numbers.get(1).copied().unwrap_or(if option == "-s" { 1.0 } else { 0.0 }));
                if option == "-o" {
                    offset = v
                } else {
                    scale = v
                }
                i += numbers.len();
            }
            "-clamp" if i < words.len() => {
                clamp = words[i] == "on";
                i += 1;
            }
            _ => {
                // Options take numbers, or one word (on/off, a channel, a type).
                let skip = if numbers.is_empty() { usize::from(i < words.len() - 1) } else { numbers.len() };
                i += skip;
                ignored.push(option.to_string());
            }
        }
    }
    if i >= words.len() {
        return Err("no image file after the options".into());
    }
    // In OBJ's coordinates (v up) the statement maps uv to uv * s + o; the mesh holds v' = 1 - v, so in
    // its coordinates v' maps to v' * s + (1 - s - o).
    let transform = UvTransform { offset: Vec2::new(offset.x, 1.0 - scale.y - offset.y), rotation: 0.0, scale };
    let transform = if transform.is_identity() { UvTransform::IDENTITY } else { transform };
    Ok((TextureStatement { file: words[i..].join(" "), transform, clamp }, ignored))
}

/// `colour` with the alpha of `alpha` (its alpha channel where it has one, its red otherwise: a grey
/// mask), when the two are the same size.
fn with_alpha_of(colour: &Texture, alpha: &Texture) -> Option<Texture> {
    if (colour.width(), colour.height()) != (alpha.width(), alpha.height()) {
        return None;
    }
    let (c, a) = (&colour.levels()[0], &alpha.levels()[0]);
    let from_alpha = alpha.has_alpha();
    let texels =
        c.data().iter().zip(a.data()).map(|(c, a)| [c[0], c[1], c[2], if from_alpha { a[3] } else { a[0] }]).collect();
    Texture::from_rgba8(colour.name(), colour.width(), colour.height(), texels).ok()
}

/// A white texture the size of `t`.
fn white_like(t: &Texture) -> Texture {
    let texels = vec![[255; 4]; t.width() as usize * t.height() as usize];
    Texture::from_rgba8(t.name(), t.width(), t.height(), texels).expect("the size of a texture that exists")
}

/// The OBJ text as tobj may read it, with what the check counted.
struct Checked {
    text: String,
    faces: usize,
    lines_and_points: usize,
}

/// Checks every line tobj would parse, and leaves out polylines and points.
fn check(text: &str) -> Result<Checked, AssetFault> {
    // Positive indices may name vertices defined further down; negative ones count back from the line.
    let total = |tag: &str| text.lines().filter(|l| l.split_whitespace().next() == Some(tag)).count();
    let totals = [total("v"), total("vt"), total("vn")];
    let mut seen = [0usize; 3];
    let mut out = String::with_capacity(text.len());
    let (mut faces, mut lines_and_points) = (0, 0);
    for (n, line) in text.lines().enumerate() {
        let bad = |why: String| AssetFault::Malformed(format!("line {}: {why}", n + 1));
        let mut words = line.split_whitespace();
        let numbers = |words: std::str::SplitWhitespace, min: usize, max: usize| -> Result<(), AssetFault> {
            let mut count = 0;
            for w in words {
                w.parse::<f32>().map_err(|_| bad(format!("'{w}' is not a number")))?;
                count += 1;
            }
            if count < min || count > max {
                return Err(bad(format!("{count} numbers where {min} to {max} belong")));
            }
            Ok(())
        };
        match words.next() {
            Some("v") => {
                // x y z, x y z w (w divides, so not zero) or x y z r g b, as tobj reads them.
                let values: Vec<&str> = words.clone().collect();
                numbers(words, 3, 6)?;
                match values.len() {
                    4 if values[3].parse::<f32>().is_ok_and(|w| w == 0.0) => {
                        return Err(bad("a vertex with w = 0".into()));
                    }
                    5 => return Err(bad("5 numbers: a vertex is x y z, x y z w or x y z r g b".into())),
                    _ => {}
                }
                seen[0] += 1;
            }
            Some("vt") => {
                numbers(words, 1, 3)?;
                seen[1] += 1;
            }
            Some("vn") => {
                numbers(words, 3, 3)?;
                seen[2] += 1;
            }
            Some("f") => {
                let corners: Vec<&str> = words.collect();
                if corners.len() < 3 {
                    return Err(bad(format!("a face of {} corners", corners.len())));
                }
                for c in &corners {
                    face_corner(c, &seen, &totals).map_err(bad)?;
                }
                faces += 1;
            }
            Some("usemtl") if words.next().is_none() => return Err(bad("'usemtl' without a name".into())),
            Some("l" | "p") => {
                lines_and_points += 1;
                continue;
            }
            _ => {}
        }
        out.push_str(line);
        out.push('\n');
    }
    Ok(Checked { text: out, faces, lines_and_points })
}

/// One `v`, `v/vt`, `v//vn` or `v/vt/vn` corner: whole numbers, not zero, naming vertices that exist.
fn face_corner(corner: &str, seen: &[usize; 3], totals: &[usize; 3]) -> Result<(), String> {
    let parts: Vec<&str> = corner.split('/').collect();
    if parts.len() > 3 || parts[0].is_empty() {
        return Err(format!("'{corner}' is not a face corner (v, v/vt, v//vn or v/vt/vn)"));
    }
    for (k, part) in parts.iter().enumerate() {
        if part.is_empty() {
            continue;
        }
        let what = ["vertex", "texture coordinate", "normal"][k];
        let i: i64 = part.parse().map_err(|_| format!("'{part}' in '{corner}' is not a whole number"))?;
        let ok = match i {
            0 => false,
            i if i > 0 => i as u64 <= totals[k] as u64,
            i => i.unsigned_abs() <= seen[k] as u64,
        };
        if !ok {
            let have = if i < 0 { seen[k] } else { totals[k] };
            return Err(format!("{what} index {i} in '{corner}', but there are {have}"));
        }
    }
    Ok(())
}

/// A material library named by `mtllib`, reduced to the lines this loader uses. Any failure loses the
/// library's colours only.
fn material_library(folder: &Path, library: &Path, options: &LoadOptions) -> tobj::MTLLoadResult {
    let name = library.to_string_lossy();
    let bytes = read_referenced(folder, &name, "material library", Some(MAX_MTL_BYTES), options)
        .map_err(|_| tobj::LoadError::OpenFileFailed)?;
    let mut kept = String::new();
    for line in String::from_utf8_lossy(&bytes).lines() {
        let mut words = line.split_whitespace();
        let number = |w: Option<&str>| w.and_then(|w| w.parse::<f32>().ok()).filter(|v| v.is_finite());
        let keep = match words.next() {
            Some("newmtl") => words.next().is_some(),
            Some("Kd") => {
                let rgb: Vec<Option<f32>> = words.take(3).map(|w| w.parse().ok()).collect();
                rgb.len() == 3 && rgb.iter().all(|c| c.is_some_and(f32::is_finite))
            }
            Some("d") => number(words.next()).is_some(),
            // Transparency, one minus the dissolve, which is what tobj reads.
            Some("Tr") => {
                if let Some(tr) = number(words.next()) {
                    kept.push_str(&format!("d {}\n", 1.0 - tr));
                }
                false
            }
            Some("map_Kd" | "map_d") => words.next().is_some(),
            _ => false,
        };
        if keep {
            kept.push_str(line.trim());
            kept.push('\n');
        }
    }
    tobj::load_mtl_buf(&mut Cursor::new(kept.as_bytes()))
}
