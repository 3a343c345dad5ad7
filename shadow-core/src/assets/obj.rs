//! Wavefront OBJ through tobj: polygons triangulated (as fans), one mesh per object or group, diffuse
//! colour (`Kd`) from the material libraries when they can be read.
//!
//! The text is checked line by line before tobj sees it, so that every refusal names its line: numbers
//! that do not parse, faces with fewer than three corners or indices out of range. Polylines (`l`) and
//! points (`p`) are not surfaces and are left out (tobj would read `l` as a face). Material libraries
//! are resolved under the same [`FileAccess`](super::FileAccess) rule as every file a model names, and
//! only the lines this loader uses (`newmtl`, `Kd`) reach tobj, so a broken library loses colours and
//! nothing else.

use std::io::Cursor;
use std::path::Path;

use glam::{Mat4, Vec3};

use super::{AssetError, AssetFault, LoadOptions, read_model, read_referenced};
use crate::mesh::Mesh;
use crate::scene::{Material, Scene};

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
    let default_material = scene.add_material(Material::default());
    let material_keys: Vec<_> = materials
        .iter()
        .map(|m| {
            let c = m.diffuse.map_or(Vec3::splat(0.8), Vec3::from);
            scene.add_material(Material::colored(&m.name, c))
        })
        .collect();
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
        .map_err(|e| err(AssetFault::Mesh(what, e)))?;
        let mat = m.material_id.and_then(|i| material_keys.get(i).copied()).unwrap_or(default_material);
        let key = scene.add_mesh(mesh);
        scene
            .add_instance(&model.name, key, mat, Mat4::IDENTITY)
            .map_err(|e| err(AssetFault::Malformed(e.to_string())))?;
    }
    Ok(scene)
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
        let keep = match words.next() {
            Some("newmtl") => words.next().is_some(),
            Some("Kd") => {
                let rgb: Vec<Option<f32>> = words.take(3).map(|w| w.parse().ok()).collect();
                rgb.len() == 3 && rgb.iter().all(|c| c.is_some_and(f32::is_finite))
            }
            _ => false,
        };
        if keep {
            kept.push_str(line.trim());
            kept.push('\n');
        }
    }
    tobj::load_mtl_buf(&mut Cursor::new(kept.as_bytes()))
}
