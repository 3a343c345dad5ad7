//! Writing a scene as glTF 2.0, binary (.glb) or JSON (.gltf with its buffer and images beside it):
//! every drawn mesh (shared meshes written once) with its texture coordinates, its material's base colour
//! and alpha, base-colour texture (level 0 as a PNG, with its sampler and `KHR_texture_transform`),
//! alpha mode and cutoff and sidedness, the cameras and the lights (KHR_lights_punctual), so it opens in
//! Blender or any glTF viewer and loads back through [`super::load`] with the same texels. A still scene's
//! node hierarchy is flattened to world matrices (morphed meshes as posed); one with animations or skins
//! keeps its hierarchy, skins, morph targets and animations, and plays again where it loads.
//! Cameras and lights are written where they stand.

use std::collections::HashMap;
use std::io::Write;
use std::path::Path;

use glam::{Mat4, Quat, Vec3};
use serde_json::{Value, json};

use crate::material::{AlphaMode, Filter, Sampler, TextureRef, Wrap};
use crate::mesh::Mesh;
use crate::scene::{Light, LightKind, Material, MeshKey, Scene, TextureKey};
use crate::shading;

mod moving;

/// Why a scene could not be written.
#[derive(Debug, thiserror::Error)]
#[error("cannot write {path}: {source}")]
pub struct ExportError {
    /// The file.
    pub path: String,
    /// What went wrong.
    #[source]
    pub source: std::io::Error,
}

/// A node rotation that makes local -Z look along `dir` with +Y up as far as possible.
fn look_rotation(dir: Vec3) -> Quat {
    let f = dir.normalize_or(Vec3::NEG_Z);
    let up = if f.cross(Vec3::Y).length_squared() < 1e-6 { Vec3::Z } else { Vec3::Y };
    let right = f.cross(up).normalize();
    let up = right.cross(f);
    Quat::from_mat3(&glam::Mat3::from_cols(right, up, -f))
}

fn node_trs(translation: Vec3, rotation: Quat) -> Value {
    json!({"translation": translation.to_array(), "rotation": rotation.to_array()})
}

/// Pads to a multiple of four bytes, as GLB chunks and buffer views require.
fn pad4(v: &mut Vec<u8>, byte: u8) {
    while !v.len().is_multiple_of(4) {
        v.push(byte);
    }
}

/// A scene as glTF, before its buffer and images are placed: the document, the binary buffer, and each
/// image's PNG bytes in the order of the document's `images`.
struct Document {
    doc: Value,
    bin: Vec<u8>,
    pngs: Vec<Vec<u8>>,
}

/// The GLB bytes of a scene: its images in the binary chunk after the meshes.
#[must_use]
pub fn glb_bytes(scene: &Scene) -> Vec<u8> {
    let Document { mut doc, mut bin, pngs } = document(scene);
    for (i, png) in pngs.iter().enumerate() {
        pad4(&mut bin, 0);
        let views = doc["bufferViews"].as_array_mut().expect("the document has buffer views");
        views.push(json!({"buffer": 0, "byteOffset": bin.len(), "byteLength": png.len()}));
        doc["images"][i]["bufferView"] = json!(views.len() - 1);
        doc["images"][i]["mimeType"] = json!("image/png");
        bin.extend_from_slice(png);
    }
    pad4(&mut bin, 0);
    doc["buffers"] = json!([{"byteLength": bin.len()}]);
    glb_container(doc.to_string().into_bytes(), &bin)
}

fn document(scene: &Scene) -> Document {
    let mut parts = MeshParts::default();
    let moves = scene.animations().next().is_some() || scene.skins().next().is_some();
    let (mut nodes, mut roots, skins, animations) = if moves {
        let m = moving::hierarchy(scene, &mut parts);
        (m.nodes, m.roots, m.skins, m.animations)
    } else {
        let nodes = flattened(scene, &mut parts);
        let roots = (0..nodes.len()).collect();
        (nodes, roots, Vec::new(), Vec::new())
    };
    let mut cameras = vec![];
    for (_, c) in scene.cameras() {
        cameras.push(json!({"type": "perspective", "perspective": {"yfov": c.fov_y, "znear": c.near}}));
        let mut n = node_trs(c.eye, look_rotation(c.target - c.eye));
        if let Some(o) = n.as_object_mut() {
            o.insert("name".into(), json!("camera"));
            o.insert("camera".into(), json!(cameras.len() - 1));
        }
        roots.push(nodes.len());
        nodes.push(n);
    }
    let mut lights = vec![];
    for (_, l) in scene.lights() {
        let (light, pos, dir) = light_json(&l);
        lights.push(light);
        let mut n = node_trs(pos, look_rotation(dir));
        if let Some(o) = n.as_object_mut() {
            o.insert("name".into(), json!("light"));
            o.insert("extensions".into(), json!({"KHR_lights_punctual": {"light": lights.len() - 1}}));
        }
        roots.push(nodes.len());
        nodes.push(n);
    }
    let MeshParts { bin, views, accessors, meshes, materials, images, textures, samplers, transformed, pngs, .. } =
        parts;
    let mut doc = json!({
        "asset": {"version": "2.0", "generator": "shadowlab"},
        "scene": 0,
        "scenes": [{"nodes": roots}],
        "nodes": nodes,
        "meshes": meshes,
        "materials": materials,
        "accessors": accessors,
        "bufferViews": views,
    });
    if let Some(o) = doc.as_object_mut() {
        if !cameras.is_empty() {
            o.insert("cameras".into(), json!(cameras));
        }
        if !skins.is_empty() {
            o.insert("skins".into(), json!(skins));
        }
        if !animations.is_empty() {
            o.insert("animations".into(), json!(animations));
        }
        if !images.is_empty() {
            o.insert("images".into(), json!(images));
            o.insert("textures".into(), json!(textures));
            o.insert("samplers".into(), json!(samplers));
        }
        let mut used = vec![];
        if !lights.is_empty() {
            used.push("KHR_lights_punctual");
            o.insert("extensions".into(), json!({"KHR_lights_punctual": {"lights": lights}}));
        }
        if transformed {
            used.push("KHR_texture_transform");
        }
        if !used.is_empty() {
            o.insert("extensionsUsed".into(), json!(used));
        }
    }
    Document { doc, bin, pngs }
}

/// The drawn nodes of a still scene, each with its world matrix (a morphed mesh as posed, a mesh of its
/// own; shared meshes written once).
fn flattened(scene: &Scene, parts: &mut MeshParts) -> Vec<Value> {
    let mut nodes = vec![];
    let mut mesh_index: HashMap<(MeshKey, String), usize> = HashMap::new();
    for (key, node, mesh_key, material) in scene.drawables() {
        let Some(mesh) = scene.mesh(mesh_key) else { continue };
        let (mi, m) = match scene.deformed(key) {
            Some(Ok(posed)) => (parts.mesh(scene, &posed.mesh, material), posed.world_from_local),
            _ => {
                let entry = mesh_index.entry((mesh_key, material.name.clone()));
                (*entry.or_insert_with(|| parts.mesh(scene, mesh, material)), node.world_transform())
            }
        };
        let mut n = json!({"name": node.name(), "mesh": mi});
        // glTF asks that the identity be left out rather than written.
        if m != Mat4::IDENTITY {
            n["matrix"] = json!(m.to_cols_array());
        }
        nodes.push(n);
    }
    nodes
}

/// The binary buffer and the glTF arrays describing the meshes written into it.
#[derive(Default)]
struct MeshParts {
    bin: Vec<u8>,
    views: Vec<Value>,
    accessors: Vec<Value>,
    meshes: Vec<Value>,
    materials: Vec<Value>,
    images: Vec<Value>,
    textures: Vec<Value>,
    samplers: Vec<Value>,
    /// The PNG bytes of each image.
    pngs: Vec<Vec<u8>>,
    /// Image indices of the scene textures written so far.
    image_index: HashMap<TextureKey, usize>,
    /// Texture indices by image and sampler.
    texture_index: HashMap<(usize, Sampler), usize>,
    /// Some texture reference has a coordinate transform.
    transformed: bool,
}

impl MeshParts {
    /// Appends `data` as a buffer view (4-byte aligned) for `target`; returns the view's index.
    fn view(&mut self, data: &[u8], target: u32) -> usize {
        pad4(&mut self.bin, 0);
        self.views.push(json!({"buffer": 0, "byteOffset": self.bin.len(), "byteLength": data.len(), "target": target}));
        self.bin.extend_from_slice(data);
        self.views.len() - 1
    }

    /// Writes a mesh with its material (positions, normals, texture coordinates, indices, one
    /// primitive); returns its index.
    fn mesh(&mut self, scene: &Scene, mesh: &Mesh, material: &Material) -> usize {
        let b = mesh.bounds();
        let idx: Vec<u32> = mesh.triangles().iter().flatten().copied().collect();
        let pv = self.view(bytemuck::cast_slice(mesh.positions()), 34962);
        let nv = self.view(bytemuck::cast_slice(mesh.normals()), 34962);
        let iv = self.view(bytemuck::cast_slice(&idx), 34963);
        let n = mesh.positions().len();
        self.accessors.push(json!({"bufferView": pv, "componentType": 5126, "count": n, "type": "VEC3", "min": b.min.to_array(), "max": b.max.to_array()}));
        self.accessors.push(json!({"bufferView": nv, "componentType": 5126, "count": n, "type": "VEC3"}));
        self.accessors.push(json!({"bufferView": iv, "componentType": 5125, "count": idx.len(), "type": "SCALAR"}));
        let (position, normal, indices) =
            (self.accessors.len() - 3, self.accessors.len() - 2, self.accessors.len() - 1);
        let mut attributes = json!({"POSITION": position, "NORMAL": normal});
        if let Some(uvs) = mesh.uvs() {
            let tv = self.view(bytemuck::cast_slice(uvs), 34962);
            self.accessors.push(json!({"bufferView": tv, "componentType": 5126, "count": n, "type": "VEC2"}));
            attributes["TEXCOORD_0"] = json!(self.accessors.len() - 1);
        }
        let c = material.base_color;
        let mut pbr = json!({"baseColorFactor": [c.x, c.y, c.z, material.alpha], "metallicFactor": 0.0});
        // A texture is written only with the coordinates it reads.
        if let (Some(r), Some(_)) = (&material.base_color_texture, mesh.uvs())
            && let Some(info) = self.texture_info(scene, r)
        {
            pbr["baseColorTexture"] = info;
        }
        let mut m = json!({"name": material.name, "pbrMetallicRoughness": pbr, "doubleSided": material.two_sided});
        match material.alpha_mode {
            AlphaMode::Opaque => {}
            AlphaMode::Mask { cutoff } => {
                m["alphaMode"] = json!("MASK");
                m["alphaCutoff"] = json!(cutoff);
            }
            AlphaMode::Blend => m["alphaMode"] = json!("BLEND"),
        }
        // Meshes that share a material (by everything written of it) share its entry.
        let material = match self.materials.iter().position(|written| *written == m) {
            Some(i) => i,
            None => {
                self.materials.push(m);
                self.materials.len() - 1
            }
        };
        let mut primitive = json!({"attributes": attributes, "indices": indices, "material": material});
        if let Some(d) = mesh.deformers()
            && let Some(targets) = self.deformers(d, &mut primitive["attributes"])
        {
            primitive["targets"] = targets;
        }
        self.meshes.push(json!({"primitives": [primitive]}));
        self.meshes.len() - 1
    }

    /// A material's texture reference as a glTF `textureInfo`, its image (as PNG), sampler and texture
    /// written on first use. `None` for a key the scene does not hold.
    fn texture_info(&mut self, scene: &Scene, r: &TextureRef) -> Option<Value> {
        let image = match self.image_index.get(&r.texture) {
            Some(&i) => i,
            None => {
                let texture = scene.texture(r.texture)?;
                let level = &texture.levels()[0];
                let mut png = Vec::new();
                let raw: &[u8] = bytemuck::cast_slice(level.data());
                image::ImageEncoder::write_image(
                    image::codecs::png::PngEncoder::new(&mut png),
                    raw,
                    level.width(),
                    level.height(),
                    image::ExtendedColorType::Rgba8,
                )
                .ok()?;
                self.pngs.push(png);
                self.images.push(json!({"name": texture.name()}));
                self.image_index.insert(r.texture, self.images.len() - 1);
                self.images.len() - 1
            }
        };
        let texture = *self.texture_index.entry((image, r.sampler)).or_insert_with(|| {
            self.samplers.push(sampler_json(&r.sampler));
            self.textures.push(json!({"source": image, "sampler": self.samplers.len() - 1}));
            self.textures.len() - 1
        });
        let mut info = json!({"index": texture});
        if !r.transform.is_identity() {
            let t = r.transform;
            info["extensions"] = json!({"KHR_texture_transform": {
                "offset": t.offset.to_array(), "rotation": t.rotation, "scale": t.scale.to_array(),
            }});
            self.transformed = true;
        }
        Some(info)
    }
}

/// A sampler as glTF writes it (the filter and wrap enums are OpenGL's).
fn sampler_json(s: &Sampler) -> Value {
    let wrap = |w: Wrap| match w {
        Wrap::Repeat => 10497,
        Wrap::ClampToEdge => 33071,
        Wrap::MirroredRepeat => 33648,
    };
    let mag = match s.mag {
        Filter::Nearest => 9728,
        Filter::Linear => 9729,
    };
    let min = match (s.min, s.mipmap) {
        (Filter::Nearest, None) => 9728,
        (Filter::Linear, None) => 9729,
        (Filter::Nearest, Some(Filter::Nearest)) => 9984,
        (Filter::Linear, Some(Filter::Nearest)) => 9985,
        (Filter::Nearest, Some(Filter::Linear)) => 9986,
        (Filter::Linear, Some(Filter::Linear)) => 9987,
    };
    json!({"magFilter": mag, "minFilter": min, "wrapS": wrap(s.wrap_u), "wrapT": wrap(s.wrap_v)})
}

/// A light as KHR_lights_punctual has it, with the position and direction of its node.
fn light_json(l: &Light) -> (Value, Vec3, Vec3) {
    let color = l.color.to_array();
    let (mut light, pos, dir) = match l.kind {
        LightKind::Spot { position, direction, cone_angle } => (
            json!({"type": "spot", "color": color, "intensity": l.intensity, "spot": {"innerConeAngle": shading::cone_cosines(l).map_or(0.0, |(_, inner)| inner.acos()), "outerConeAngle": cone_angle * 0.5}}),
            position,
            direction,
        ),
        LightKind::Directional { direction } => {
            (json!({"type": "directional", "color": color, "intensity": l.intensity}), Vec3::ZERO, direction)
        }
        LightKind::Point { position } => {
            (json!({"type": "point", "color": color, "intensity": l.intensity}), position, Vec3::NEG_Z)
        }
    };
    if let (Some(range), Some(o)) = (l.range, light.as_object_mut()) {
        o.insert("range".into(), json!(range));
    }
    (light, pos, dir)
}

/// The GLB container: the header, the JSON chunk (padded with spaces) and the binary chunk.
fn glb_container(mut js: Vec<u8>, bin: &[u8]) -> Vec<u8> {
    pad4(&mut js, b' ');
    let total = 12 + 8 + js.len() + 8 + bin.len();
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(js.len() as u32).to_le_bytes());
    out.extend_from_slice(&0x4E4F_534Au32.to_le_bytes());
    out.extend_from_slice(&js);
    out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    out.extend_from_slice(&0x004E_4942u32.to_le_bytes());
    out.extend_from_slice(bin);
    out
}

/// Writes a scene as a .glb file.
///
/// # Errors
/// When the file cannot be written.
pub fn export_glb(scene: &Scene, path: impl AsRef<Path>) -> Result<(), ExportError> {
    write(path.as_ref(), &glb_bytes(scene))
}

/// Writes a scene as a .gltf file with its buffer beside it as `STEM.bin` and each image as
/// `STEM-N.png` (N from 0), `STEM` being the file's name without its extension.
///
/// # Errors
/// When a file cannot be written; the first failure stops the export.
pub fn export_gltf(scene: &Scene, path: impl AsRef<Path>) -> Result<(), ExportError> {
    let path = path.as_ref();
    let stem = path.file_stem().map_or_else(|| "scene".into(), |s| s.to_string_lossy().into_owned());
    let beside = |name: &str| path.with_file_name(name);
    let Document { mut doc, bin, pngs } = document(scene);
    let bin_name = format!("{stem}.bin");
    write(&beside(&bin_name), &bin)?;
    doc["buffers"] = json!([{"byteLength": bin.len(), "uri": uri_of(&bin_name)}]);
    for (i, png) in pngs.iter().enumerate() {
        let name = format!("{stem}-{i}.png");
        write(&beside(&name), png)?;
        doc["images"][i]["uri"] = json!(uri_of(&name));
    }
    let text = serde_json::to_vec_pretty(&doc).expect("a JSON value serializes");
    write(path, &text)
}

/// Writes a scene as glTF, binary for a `.glb` path and JSON ([`export_gltf`]) for any other.
///
/// # Errors
/// When a file cannot be written.
pub fn export(scene: &Scene, path: impl AsRef<Path>) -> Result<(), ExportError> {
    let path = path.as_ref();
    let glb = path.extension().is_some_and(|e| e.eq_ignore_ascii_case("glb"));
    if glb { export_glb(scene, path) } else { export_gltf(scene, path) }
}

fn write(path: &Path, bytes: &[u8]) -> Result<(), ExportError> {
    let err = |source| ExportError { path: path.display().to_string(), source };
    std::fs::File::create(path).and_then(|mut f| f.write_all(bytes)).map_err(err)
}

/// A file name as a relative URI: every byte outside RFC 3986's unreserved characters percent-encoded.
fn uri_of(name: &str) -> String {
    name.bytes()
        .map(|b| {
            if b.is_ascii_alphanumeric() || b"-._~".contains(&b) {
                (b as char).to_string()
            } else {
                format!("%{b:02X}")
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scenes::{self, SceneParams};

    #[test]
    fn round_trip_keeps_triangles_bounds_camera_and_light() {
        let dir = std::env::temp_dir().join(format!("shadowlab-export-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        for name in ["crowd", "room", "l-shape"] {
            let s = scenes::build(name, &SceneParams::default()).unwrap();
            let path = dir.join(format!("{name}.glb"));
            export_glb(&s, &path).unwrap();
            let back = crate::assets::load(&path).unwrap();
            assert_eq!(back.triangle_count(), s.triangle_count(), "{name}");
            let (a, b) = (s.bounds(), back.bounds());
            assert!((a.min - b.min).length() < 1e-4 && (a.max - b.max).length() < 1e-4, "{name}");
            let (c0, c1) = (s.cameras().next().unwrap().1, back.cameras().next().unwrap().1);
            assert!((c0.eye - c1.eye).length() < 1e-5);
            let d0 = (c0.target - c0.eye).normalize();
            let d1 = (c1.target - c1.eye).normalize();
            assert!(d0.dot(d1) > 0.9999, "{name}: camera direction");
            let (l0, l1) = (s.lights().next().unwrap().1, back.lights().next().unwrap().1);
            assert_eq!(l0.type_name(), l1.type_name());
            if let (
                LightKind::Spot { direction: a, cone_angle: ca, .. },
                LightKind::Spot { direction: b, cone_angle: cb, .. },
            ) = (l0.kind, l1.kind)
            {
                assert!(a.dot(b) > 0.9999 && (ca - cb).abs() < 1e-5, "{name}: spot");
            }
        }
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn meshes_sharing_a_material_share_its_entry() {
        let mut s = Scene::new();
        let white = s.add_material(Material::colored("white", Vec3::ONE));
        let red = s.add_material(Material::colored("red", Vec3::X));
        for (i, material) in [white, white, red].into_iter().enumerate() {
            let box_mesh = s.add_mesh(crate::procedural::cuboid(Vec3::ONE * (i + 1) as f32).unwrap());
            s.add_instance("box", box_mesh, material, Mat4::IDENTITY).unwrap();
        }
        let doc = document(&s).doc;
        assert_eq!(doc["meshes"].as_array().unwrap().len(), 3);
        let names: Vec<&str> =
            doc["materials"].as_array().unwrap().iter().map(|m| m["name"].as_str().unwrap()).collect();
        assert_eq!(names, ["white", "red"]);
    }
}
