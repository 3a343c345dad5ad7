//! Wavefront OBJ through tobj: polygons triangulated (as fans), one mesh per object or group, diffuse
//! colour (`Kd`) from the material library when it can be read.

use std::path::Path;

use glam::{Mat4, Vec3};

use super::{AssetError, AssetFault};
use crate::mesh::Mesh;
use crate::scene::{Material, Scene};

pub(super) fn load(path: &Path) -> Result<Scene, AssetError> {
    let err = |fault| AssetError::new(path, fault);
    let options = tobj::LoadOptions { single_index: true, triangulate: true, ignore_points: true, ignore_lines: true };
    let (models, materials) = tobj::load_obj(path, &options).map_err(|e| {
        err(match e {
            tobj::LoadError::OpenFileFailed => AssetFault::NotFound(path.display().to_string()),
            tobj::LoadError::ReadError => AssetFault::Io("read error".into()),
            tobj::LoadError::FaceVertexOutOfBounds => {
                AssetFault::Malformed("a face uses a vertex index out of range".into())
            }
            other => AssetFault::Malformed(other.to_string()),
        })
    })?;
    // A missing or broken .mtl only loses colours: keep the default material rather than fail the model.
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
    let mut triangles_seen = 0;
    for model in &models {
        let m = &model.mesh;
        if m.indices.is_empty() {
            continue;
        }
        triangles_seen += m.indices.len() / 3;
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
    if triangles_seen == 0 {
        return Err(err(AssetFault::Unsupported(
            "no triangles or polygons (only points or lines, or nothing at all)".into(),
        )));
    }
    Ok(scene)
}
