//! Mesh statistics of a scene, as `shadowlab inspect` prints them (DESIGN 11).

use crate::bounds::Aabb;
use crate::frame::FrameInputs;
use crate::material::{AlphaMode, Sampler};
use crate::scene::Scene;

/// What `inspect` reports. Counts are after welding coincident positions, summed over drawn instances.
#[derive(Clone, Debug, PartialEq)]
pub struct Inspection {
    /// Triangles drawn.
    pub triangles: usize,
    /// Welded vertices.
    pub vertices: usize,
    /// Every instance's mesh is closed and consistently wound.
    pub closed: bool,
    /// Connected components (faces sharing a welded vertex), each casting a closed volume of its own.
    pub components: usize,
    /// Edges with one face.
    pub boundary_edges: usize,
    /// Edges with three or more faces.
    pub non_manifold_edges: usize,
    /// Edges with two faces that run the same way.
    pub inconsistent_edges: usize,
    /// World bounds.
    pub bounds: Aabb,
    /// Silhouette edges of the casting instances from the scene's first light, `None` without a light.
    pub silhouette_edges: Option<usize>,
    /// The scene's textures: name, level-0 size and bytes with the mip chain, in the order they were added.
    pub textures: Vec<TextureStats>,
    /// The scene's materials, in the order they were added.
    pub materials: Vec<MaterialStats>,
    /// Meshes drawn, each counted once however many instances draw it.
    pub meshes: usize,
    /// Nodes that draw a mesh.
    pub instances: usize,
    /// Bytes the drawn meshes' geometry holds, each mesh once ([`crate::Mesh::geometry_bytes`]).
    pub mesh_bytes: usize,
    /// Bytes it would hold were every instance's mesh a copy of its own: what sharing saves is the
    /// difference.
    pub unshared_mesh_bytes: usize,
    /// Of those, the meshes that carry texture coordinates.
    pub meshes_with_uvs: usize,
    /// The scene's animations, in the order they were added.
    pub animations: Vec<AnimationStats>,
    /// The scene's skins: name and number of joints, in the order they were added.
    pub skins: Vec<(String, usize)>,
    /// Meshes drawn with morph targets, and the most targets one has.
    pub morphed_meshes: (usize, usize),
}

/// One animation as `inspect` reports it.
#[derive(Clone, Debug, PartialEq)]
pub struct AnimationStats {
    /// Its name.
    pub name: String,
    /// The time of its last key, in seconds.
    pub duration: f32,
    /// Its channels.
    pub channels: usize,
    /// The nodes they move.
    pub nodes: usize,
    /// The interpolations its channels use, each named once, in glTF's names.
    pub interpolations: Vec<&'static str>,
}

/// One material as `inspect` reports it.
#[derive(Clone, Debug, PartialEq)]
pub struct MaterialStats {
    /// Its name.
    pub name: String,
    /// How its alpha decides coverage.
    pub alpha_mode: AlphaMode,
    /// Whether both sides are drawn and lit.
    pub double_sided: bool,
    /// Its base-colour texture, as an index into [`Inspection::textures`].
    pub texture: Option<usize>,
    /// How that texture is read.
    pub sampler: Option<Sampler>,
}

/// One texture as `inspect` reports it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct TextureStats {
    /// The image's name (its file, or where in the model it was).
    pub name: String,
    /// Level-0 width.
    pub width: u32,
    /// Level-0 height.
    pub height: u32,
    /// Bytes held, every level.
    pub bytes: usize,
}

impl Inspection {
    /// Inspects a scene (its first camera is not needed; its first light gives the silhouette).
    #[must_use]
    pub fn of(scene: &Scene) -> Self {
        let mut out = Self {
            triangles: 0,
            vertices: 0,
            closed: true,
            components: 0,
            boundary_edges: 0,
            non_manifold_edges: 0,
            inconsistent_edges: 0,
            bounds: scene.bounds(),
            silhouette_edges: None,
            textures: Vec::new(),
            materials: Vec::new(),
            meshes: 0,
            instances: 0,
            mesh_bytes: 0,
            unshared_mesh_bytes: 0,
            meshes_with_uvs: 0,
            animations: Vec::new(),
            skins: scene.skins().map(|(_, s)| (s.name.clone(), s.joints.len())).collect(),
            morphed_meshes: (0, 0),
        };
        for (_, a) in scene.animations() {
            let mut nodes: Vec<_> = a.channels().iter().map(|c| c.node).collect();
            nodes.sort_unstable();
            nodes.dedup();
            let mut interpolations: Vec<&'static str> = Vec::new();
            for c in a.channels() {
                if !interpolations.contains(&c.interpolation.name()) {
                    interpolations.push(c.interpolation.name());
                }
            }
            out.animations.push(AnimationStats {
                name: a.name().to_string(),
                duration: a.duration(),
                channels: a.channels().len(),
                nodes: nodes.len(),
                interpolations,
            });
        }
        let mut texture_index = std::collections::HashMap::new();
        for (key, t) in scene.textures() {
            texture_index.insert(key, out.textures.len());
            out.textures.push(TextureStats {
                name: t.name().to_string(),
                width: t.width(),
                height: t.height(),
                bytes: t.memory_bytes(),
            });
        }
        out.materials = scene
            .materials()
            .map(|(_, m)| MaterialStats {
                name: m.name.clone(),
                alpha_mode: m.alpha_mode,
                double_sided: m.two_sided,
                texture: m.base_color_texture.and_then(|r| texture_index.get(&r.texture).copied()),
                sampler: m.base_color_texture.map(|r| r.sampler),
            })
            .collect();
        let mut seen = std::collections::HashSet::new();
        for (_, _, mesh, _) in scene.drawables() {
            let bytes = scene.mesh(mesh).map_or(0, |m| m.geometry_bytes());
            out.instances += 1;
            out.unshared_mesh_bytes += bytes;
            if seen.insert(mesh) {
                out.meshes += 1;
                out.mesh_bytes += bytes;
                out.meshes_with_uvs += usize::from(scene.mesh(mesh).is_some_and(|m| m.uvs().is_some()));
                let targets = scene.mesh(mesh).and_then(|m| m.deformers()).map_or(0, |d| d.morph_targets.len());
                if targets > 0 {
                    out.morphed_meshes = (out.morphed_meshes.0 + 1, out.morphed_meshes.1.max(targets));
                }
            }
        }
        scene.build_adjacencies();
        for (_, _, mesh, _) in scene.drawables() {
            let (Some(m), Some(adj)) = (scene.mesh(mesh), scene.adjacency(mesh)) else { continue };
            out.triangles += m.triangle_count();
            out.vertices += adj.vertex_count();
            out.closed &= adj.closed();
            out.components += adj.component_bounds().len();
            out.boundary_edges += adj.boundary_edge_count();
            out.non_manifold_edges += adj.non_manifold_edge_count();
            out.inconsistent_edges += adj.inconsistent_edge_count();
        }
        out.silhouette_edges = Self::silhouette_edges_of(scene);
        out
    }

    /// The silhouette edges of `scene`'s casters from its first light ([`Inspection::silhouette_edges`]);
    /// `None` without a light.
    #[must_use]
    pub fn silhouette_edges_of(scene: &Scene) -> Option<usize> {
        let light = scene.lights().next().map(|(_, l)| l)?;
        let camera = crate::scene::Camera::look_at(glam::Vec3::ONE, glam::Vec3::ZERO, 45.0);
        let frame = FrameInputs::new(scene, camera, vec![light]).ok()?;
        let view = frame.light_view(&light).ok()?;
        let volumes = frame.shadow_volumes(&view, crate::geometry::volume::Caps::None);
        Some(volumes.iter().map(|v| v.silhouette_edges).sum())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scenes::{self, SceneParams};

    #[test]
    fn cylinder_scene() {
        let s = scenes::build("cylinder", &SceneParams::default()).unwrap();
        let i = Inspection::of(&s);
        // Ground (2 triangles, 4 boundary edges) plus a closed 64-segment capped cylinder.
        assert_eq!(i.triangles, 2 + 64 * 4);
        assert_eq!(i.boundary_edges, 4);
        assert!(!i.closed);
        assert_eq!(i.components, 2);
        // The cylinder's silhouette from an oblique light: two vertical edges plus parts of both rims,
        // and the ground's four boundary edges.
        let sil = i.silhouette_edges.unwrap();
        assert!(sil > 4 + 2 && sil < 4 + 2 + 2 * 64, "{sil}");
    }
}
