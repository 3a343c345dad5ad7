//! Writing a scene as binary glTF (.glb): every drawn mesh (shared meshes written once), its material's
//! base colour and sidedness, the node hierarchy flattened to world matrices, the cameras and the lights
//! (KHR_lights_punctual), so it opens in Blender or any glTF viewer and loads back through [`super::load`].

use std::collections::HashMap;
use std::io::Write;
use std::path::Path;

use glam::{Mat4, Quat, Vec3};
use serde_json::{Value, json};

use crate::mesh::Mesh;
use crate::scene::{Light, LightKind, Material, MeshKey, Scene};
use crate::shading;

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

/// The GLB bytes of a scene.
#[must_use]
pub fn glb_bytes(scene: &Scene) -> Vec<u8> {
    let mut parts = MeshParts::default();
    let mut nodes = vec![];
    let mut mesh_index: HashMap<(MeshKey, String), usize> = HashMap::new();
    for (_, node, mesh_key, material) in scene.drawables() {
        let Some(mesh) = scene.mesh(mesh_key) else { continue };
        let mi = *mesh_index.entry((mesh_key, material.name.clone())).or_insert_with(|| parts.mesh(mesh, material));
        let m: Mat4 = node.world_transform();
        nodes.push(json!({"name": node.name(), "mesh": mi, "matrix": m.to_cols_array()}));
    }
    let mut cameras = vec![];
    for (_, c) in scene.cameras() {
        cameras.push(json!({"type": "perspective", "perspective": {"yfov": c.fov_y, "znear": c.near}}));
        let mut n = node_trs(c.eye, look_rotation(c.target - c.eye));
        if let Some(o) = n.as_object_mut() {
            o.insert("name".into(), json!("camera"));
            o.insert("camera".into(), json!(cameras.len() - 1));
        }
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
        nodes.push(n);
    }
    let MeshParts { mut bin, views, accessors, meshes, materials } = parts;
    pad4(&mut bin, 0);
    let mut doc = json!({
        "asset": {"version": "2.0", "generator": "shadowlab"},
        "scene": 0,
        "scenes": [{"nodes": (0..nodes.len()).collect::<Vec<_>>()}],
        "nodes": nodes,
        "meshes": meshes,
        "materials": materials,
        "accessors": accessors,
        "bufferViews": views,
        "buffers": [{"byteLength": bin.len()}],
    });
    if let Some(o) = doc.as_object_mut() {
        if !cameras.is_empty() {
            o.insert("cameras".into(), json!(cameras));
        }
        if !lights.is_empty() {
            o.insert("extensionsUsed".into(), json!(["KHR_lights_punctual"]));
            o.insert("extensions".into(), json!({"KHR_lights_punctual": {"lights": lights}}));
        }
    }
    glb_container(doc.to_string().into_bytes(), &bin)
}

/// The binary buffer and the glTF arrays describing the meshes written into it.
#[derive(Default)]
struct MeshParts {
    bin: Vec<u8>,
    views: Vec<Value>,
    accessors: Vec<Value>,
    meshes: Vec<Value>,
    materials: Vec<Value>,
}

impl MeshParts {
    /// Appends `data` as a buffer view (4-byte aligned) for `target`; returns the view's index.
    fn view(&mut self, data: &[u8], target: u32) -> usize {
        pad4(&mut self.bin, 0);
        self.views.push(json!({"buffer": 0, "byteOffset": self.bin.len(), "byteLength": data.len(), "target": target}));
        self.bin.extend_from_slice(data);
        self.views.len() - 1
    }

    /// Writes a mesh with its material (positions, normals, indices, one primitive); returns its index.
    fn mesh(&mut self, mesh: &Mesh, material: &Material) -> usize {
        let b = mesh.bounds();
        let idx: Vec<u32> = mesh.triangles().iter().flatten().copied().collect();
        let pv = self.view(bytemuck::cast_slice(mesh.positions()), 34962);
        let nv = self.view(bytemuck::cast_slice(mesh.normals()), 34962);
        let iv = self.view(bytemuck::cast_slice(&idx), 34963);
        let n = mesh.positions().len();
        self.accessors.push(json!({"bufferView": pv, "componentType": 5126, "count": n, "type": "VEC3", "min": b.min.to_array(), "max": b.max.to_array()}));
        self.accessors.push(json!({"bufferView": nv, "componentType": 5126, "count": n, "type": "VEC3"}));
        self.accessors.push(json!({"bufferView": iv, "componentType": 5125, "count": idx.len(), "type": "SCALAR"}));
        self.materials.push(json!({
            "name": material.name,
            "pbrMetallicRoughness": {"baseColorFactor": [material.base_color.x, material.base_color.y, material.base_color.z, 1.0], "metallicFactor": 0.0},
            "doubleSided": material.two_sided,
        }));
        let a = self.accessors.len();
        self.meshes.push(json!({"primitives": [{"attributes": {"POSITION": a - 3, "NORMAL": a - 2}, "indices": a - 1, "material": self.materials.len() - 1}]}));
        self.meshes.len() - 1
    }
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
    let path = path.as_ref();
    let err = |source| ExportError { path: path.display().to_string(), source };
    let mut f = std::fs::File::create(path).map_err(err)?;
    f.write_all(&glb_bytes(scene)).map_err(err)
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
}
