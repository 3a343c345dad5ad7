//! What a frame hands to the techniques (DESIGN 5, step 1): world-space instances with their meshes and
//! cached adjacency, the scene bounds, the camera and the lights.
//!
//! Nothing here depends on the light: silhouettes and volumes are found every frame by
//! [`FrameInputs::shadow_volumes`], as the papers require.

use std::sync::Arc;

use glam::{Mat4, Vec3};
use rayon::prelude::*;

use crate::bounds::Aabb;
use crate::geometry::LightSource;
use crate::geometry::adjacency::Adjacency;
use crate::geometry::silhouette::{CastMode, Silhouette, silhouette};
use crate::geometry::volume::{Caps, ShadowVolume, extrude};
use crate::image::Image;
use crate::light::{LightView, LightViewError, Reach};
use crate::material::{AlphaMode, Footprint, Material, Texture};
use crate::mesh::Mesh;
use crate::scene::{Camera, CameraKey, Light, LightShadow, MeshKey, NodeKey, Pose, Scene, SceneError};
use crate::stats::Counters;

/// One drawn mesh in world space.
#[derive(Clone, Debug)]
pub struct Instance {
    /// The node that draws it.
    pub node: NodeKey,
    /// The mesh's key (backends cache uploads by key and version).
    pub mesh_key: MeshKey,
    /// Changes whenever the mesh behind the key is replaced, and for a skinned or morphed mesh whenever
    /// its pose does ([`crate::scene::Deformed::version`]).
    pub mesh_version: u64,
    /// The geometry, in the mesh's own space; a skinned or morphed mesh as posed.
    pub mesh: Arc<Mesh>,
    /// Its adjacency (cached by the scene per mesh; over the posed positions for a posed mesh).
    pub adjacency: Arc<Adjacency>,
    /// What a skinned or morphed mesh was posed from (`None` for a mesh drawn as it is).
    pub pose: Option<Arc<Pose>>,
    /// Mesh space to world space.
    pub world_from_local: Mat4,
    /// World space to mesh space.
    pub local_from_world: Mat4,
    /// The transform mirrors (negative determinant): front faces wind clockwise in world space.
    pub mirrored: bool,
    /// The material it is drawn with (one mesh may be drawn with several).
    pub material: Arc<Material>,
    /// That material's base-colour texture, where it has one the scene holds.
    pub base_color_texture: Option<Arc<Texture>>,
    /// Linear albedo.
    pub base_color: Vec3,
    /// Lit from both sides.
    pub two_sided: bool,
    /// Its back faces are not drawn in the camera's view ([`Material::cull_back_faces`]).
    pub cull_back_faces: bool,
    /// Blocks light (node and material flags combined).
    pub casts_shadow: bool,
    /// Shows shadows (node and material flags combined).
    pub receives_shadow: bool,
    /// World-space bounds.
    pub bounds: Aabb,
}

/// How much of an instance's surface is there to block light or to be seen: its material's alpha test.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Coverage {
    /// All of it: opaque and blended materials (a blended surface blocks as an opaque one for now), and
    /// masked ones whose alpha passes with no texture to read.
    Solid,
    /// Where its texels pass the alpha test: a masked material with a texture, on a mesh with texture
    /// coordinates.
    Cutout,
    /// None: a masked material whose alpha fails with no texture to read.
    Absent,
}

impl Instance {
    /// Whether it blocks light over its whole surface: a caster of [`Coverage::Solid`], the casters whose
    /// silhouettes bound their shadows (what shadow volumes and wedges are extruded from).
    #[must_use]
    pub fn casts_solid_shadow(&self) -> bool {
        self.casts_shadow && self.coverage() == Coverage::Solid
    }

    /// How much of the surface is there ([`Coverage`]).
    #[must_use]
    pub fn coverage(&self) -> Coverage {
        let material = &self.material;
        if !matches!(material.alpha_mode, AlphaMode::Mask { .. }) {
            return Coverage::Solid;
        }
        let textured =
            material.base_color_texture.is_some() && self.base_color_texture.is_some() && self.mesh.uvs().is_some();
        if textured {
            Coverage::Cutout
        } else if material.passes(None, None, Footprint::POINT) {
            Coverage::Solid
        } else {
            Coverage::Absent
        }
    }
}

/// The shadow volume of one casting instance, in that instance's mesh space.
#[derive(Clone, Debug)]
pub struct InstanceVolume {
    /// Index into [`FrameInputs::instances`].
    pub instance: usize,
    /// Sides and caps.
    pub volume: ShadowVolume,
    /// Number of silhouette edges (before weights).
    pub silhouette_edges: usize,
}

impl InstanceVolume {
    /// Sets the counters a volume build reports, `silhouette_edges` and `volume_triangles`, from `volumes`.
    pub fn count(volumes: &[Self], counters: &mut Counters) {
        counters.silhouette_edges = Some(volumes.iter().map(|v| v.silhouette_edges as u64).sum());
        counters.volume_triangles = Some(volumes.iter().map(|v| v.volume.triangle_count() as u64).sum());
    }
}

/// Why a frame could not be assembled.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FrameError {
    /// Bad camera or light, or an unknown key.
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// No light view could be fitted.
    #[error(transparent)]
    LightView(#[from] LightViewError),
    /// The scene draws nothing.
    #[error("the scene has no meshes to draw")]
    Empty,
    /// The scene has no camera to look from.
    #[error("the scene has no camera")]
    NoCamera,
    /// More triangles than a frame can number: both backends give each drawn triangle a 32-bit id.
    #[error("the scene draws {triangles} triangles, over the limit of {} a frame can number", MAX_FRAME_TRIANGLES)]
    TooManyTriangles {
        /// Triangles the frame would draw.
        triangles: u64,
    },
}

/// The most triangles one frame may draw: primitive ids are 32-bit, with `u32::MAX` kept for "none".
pub const MAX_FRAME_TRIANGLES: u64 = u32::MAX as u64;

/// Everything a technique may read about the scene for one frame.
#[derive(Clone, Debug)]
pub struct FrameInputs {
    /// Drawn meshes, depth-first from the scene roots.
    pub instances: Vec<Instance>,
    /// World bounds of every instance.
    pub bounds: Aabb,
    /// The camera of this frame.
    pub camera: Camera,
    /// The lights of this frame.
    pub lights: Vec<Light>,
    /// How each light casts shadows, in the order of `lights`; a light past its end casts with the frame's
    /// technique.
    pub shadows: Vec<LightShadow>,
    /// The work the frame leaves out because no pixel shows it (all of it by default).
    pub savings: Savings,
}

/// The work a frame leaves out because no pixel of its view shows it; each kind can be switched off, to
/// measure what it saves. The pictures are the same either way wherever a light reaches.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub struct Savings {
    /// Each light is queried over the pixels within its reach only ([`crate::light::Reach`]: a ranged
    /// light's ball, cut to its cone for a spot), and a light that reaches no pixel of the view is neither
    /// built nor queried: its visibility is 1 everywhere.
    pub reach: bool,
    /// A light's passes leave out the casters wholly outside each of its projections' frustums, by their
    /// bounds (they would draw nothing there).
    pub culling: bool,
    /// The side in texels of the shadow atlas the maps of spot and point lights share, each light's tiles
    /// sized by the share of the view it reaches ([`crate::light::atlas`]); `None`: each light's maps at
    /// its technique's size.
    pub atlas: Option<u32>,
}

impl Savings {
    /// The side of the shadow atlas [`Savings::ALL`] gives: 16 million texels, 64 MiB of f32 depth.
    pub const ATLAS_SIDE: u32 = 4096;
    /// Every saving.
    pub const ALL: Self = Self { reach: true, culling: true, atlas: Some(Self::ATLAS_SIDE) };
    /// None: every light built from every caster and queried over the whole view, with maps of its
    /// technique's size.
    pub const NONE: Self = Self { reach: false, culling: false, atlas: None };
}

impl Default for Savings {
    /// [`Savings::ALL`].
    fn default() -> Self {
        Self::ALL
    }
}

impl FrameInputs {
    /// Collects the scene's instances (building any missing adjacency) with the given camera and lights.
    ///
    /// # Errors
    /// An invalid camera or light, an empty scene, or one of more than [`MAX_FRAME_TRIANGLES`] triangles.
    pub fn new(scene: &Scene, camera: Camera, lights: Vec<Light>) -> Result<Self, FrameError> {
        camera.validate()?;
        for l in &lights {
            l.validate()?;
        }
        scene.build_adjacencies();
        let instances: Vec<Instance> = scene
            .drawables()
            .filter_map(|(node, n, mesh_key, material)| {
                // A skinned or morphed mesh is drawn as posed; every other as it stands, where its node is.
                let (mesh, adjacency, mesh_version, world, pose) = match scene.deformed(node) {
                    Some(Ok(d)) => (d.mesh, d.adjacency, d.version, d.world_from_local, Some(d.pose)),
                    Some(Err(e)) => return Some(Err(e)),
                    None => (
                        scene.mesh(mesh_key)?.clone(),
                        scene.adjacency(mesh_key)?,
                        scene.mesh_version(mesh_key)?,
                        n.world_transform(),
                        None,
                    ),
                };
                Some(Ok(Instance {
                    node,
                    mesh_key,
                    mesh_version,
                    adjacency,
                    pose,
                    world_from_local: world,
                    local_from_world: crate::affine::inverse(world),
                    mirrored: world.determinant() < 0.0,
                    base_color_texture: material.base_color_texture.and_then(|r| scene.texture(r.texture)).cloned(),
                    base_color: material.base_color,
                    two_sided: material.two_sided,
                    cull_back_faces: material.cull_back_faces,
                    casts_shadow: n.casts_shadow() && material.casts_shadow,
                    receives_shadow: n.receives_shadow() && material.receives_shadow,
                    bounds: mesh.bounds().transformed(world),
                    material: Arc::clone(material),
                    mesh,
                }))
            })
            .collect::<Result<_, SceneError>>()?;
        if instances.is_empty() {
            return Err(FrameError::Empty);
        }
        let bounds = instances.iter().fold(Aabb::EMPTY, |b, i| b.union(i.bounds));
        let shadows = vec![LightShadow::default(); lights.len()];
        let frame = Self { instances, bounds, camera, lights, shadows, savings: Savings::ALL };
        let triangles = frame.triangle_count() as u64;
        if triangles > MAX_FRAME_TRIANGLES {
            return Err(FrameError::TooManyTriangles { triangles });
        }
        Ok(frame)
    }

    /// The frame seen through one of the scene's cameras, with all of the scene's lights.
    ///
    /// # Errors
    /// As [`FrameInputs::new`], or an unknown camera key.
    pub fn from_scene(scene: &Scene, camera: CameraKey) -> Result<Self, FrameError> {
        let cam = scene.world_camera(camera).ok_or(SceneError::UnknownKey("camera"))?;
        let mut frame = Self::new(scene, cam, scene.lights().map(|(_, l)| l).collect())?;
        frame.shadows = scene.lights().map(|(k, _)| scene.light_shadow(k)).collect();
        Ok(frame)
    }

    /// The frame of `scene` seen from its first camera, lit by all its lights.
    ///
    /// # Errors
    /// [`FrameError::NoCamera`], or as [`FrameInputs::from_scene`].
    pub fn from_first_camera(scene: &Scene) -> Result<Self, FrameError> {
        let (camera, _) = scene.cameras().next().ok_or(FrameError::NoCamera)?;
        Self::from_scene(scene, camera)
    }

    /// How light `k` casts shadows.
    #[must_use]
    pub fn shadow(&self, k: usize) -> LightShadow {
        self.shadows.get(k).cloned().unwrap_or_default()
    }

    /// True when some casting instance is alpha-tested ([`Coverage::Cutout`]).
    #[must_use]
    pub fn has_cutout_casters(&self) -> bool {
        self.instances.iter().any(|i| i.casts_shadow && i.coverage() == Coverage::Cutout)
    }

    /// Total triangles drawn.
    #[must_use]
    pub fn triangle_count(&self) -> usize {
        self.instances.iter().map(|i| i.mesh.triangle_count()).sum()
    }

    /// Light `light`'s reach in this frame's view of `width x height` pixels: everywhere when the frame
    /// does not save by reach ([`Savings::reach`]).
    #[must_use]
    pub fn reach(&self, light: &Light, width: u32, height: u32) -> Reach {
        if self.savings.reach {
            Reach::of(light, &self.camera, width, height)
        } else {
            Reach::everywhere(width, height)
        }
    }

    /// The light's projections fitted to this frame's instances.
    ///
    /// # Errors
    /// An invalid light.
    pub fn light_view(&self, light: &Light) -> Result<LightView, LightViewError> {
        let boxes: Vec<Aabb> = self.instances.iter().map(|i| i.bounds).collect();
        LightView::fit(light, &boxes)
    }

    /// The silhouette of every casting instance for the light, found afresh (in parallel over instances),
    /// with the light in the instance's mesh space.
    fn silhouettes(&self, light: &LightView) -> impl IndexedParallelIterator<Item = (usize, LightSource, Silhouette)> {
        let world_light = light.source();
        self.instances.par_iter().enumerate().map(move |(i, inst)| {
            if !inst.casts_shadow || inst.coverage() == Coverage::Absent {
                return (i, world_light, Silhouette::default());
            }
            let local_light = world_light.transformed(inst.local_from_world);
            let adj = &inst.adjacency;
            (i, local_light, silhouette(adj, local_light, CastMode::for_mesh(adj)))
        })
    }

    /// Shadow volumes of every instance casting a solid shadow for the light
    /// ([`Instance::casts_solid_shadow`]), found afresh (in parallel over instances). A caster its texture
    /// cuts out has none: its outline does not bound its shadow, which the techniques built on volumes take
    /// from a map of those casters' depths instead.
    #[must_use]
    pub fn shadow_volumes(&self, light: &LightView, caps: Caps) -> Vec<InstanceVolume> {
        self.silhouettes(light)
            .filter(|(i, ..)| self.instances[*i].casts_solid_shadow())
            .map(|(i, local_light, sil)| self.volume(i, local_light, &sil, caps))
            .collect()
    }

    /// [`Self::shadow_volumes`] and [`Self::silhouette_segments`] from one silhouette pass (`hybrid`'s edge
    /// maps need both), of the same casters as [`Self::shadow_volumes`].
    #[must_use]
    pub fn shadow_volumes_and_segments(&self, light: &LightView, caps: Caps) -> (Vec<InstanceVolume>, Vec<[Vec3; 2]>) {
        let (volumes, segments): (Vec<_>, Vec<_>) = self
            .silhouettes(light)
            .filter(|(i, ..)| self.instances[*i].casts_solid_shadow())
            .map(|(i, local_light, sil)| (self.volume(i, local_light, &sil, caps), self.world_segments(i, &sil)))
            .unzip();
        (volumes, segments.concat())
    }

    fn volume(&self, i: usize, local_light: LightSource, sil: &Silhouette, caps: Caps) -> InstanceVolume {
        InstanceVolume {
            instance: i,
            silhouette_edges: sil.edges.len(),
            volume: extrude(&self.instances[i].adjacency, sil, local_light, caps),
        }
    }

    /// The silhouette of every casting instance for the light, in instance order: its index in
    /// `instances` and its edges in the welded vertices of the instance's adjacency
    /// (`adjacency.positions()`, mesh space), oriented as [`silhouette`] orients them. A caster its texture
    /// cuts out has none, as in [`Self::silhouette_segments`]: the penumbrae built on silhouettes
    /// (smoothies, penumbra maps) would otherwise soften the outline of a card where it casts no shadow.
    #[must_use]
    pub fn caster_silhouettes(&self, light: &LightView) -> Vec<(usize, Silhouette)> {
        self.silhouettes(light)
            .filter(|(i, ..)| self.instances[*i].casts_shadow && self.instances[*i].coverage() != Coverage::Cutout)
            .map(|(i, _, s)| (i, s))
            .collect()
    }

    /// The silhouette edges of every casting instance for the light, in world space, in instance order
    /// (what silhouette maps rasterize; the edges' weights do not matter there). A caster its texture cuts
    /// out has none here: its mesh's outline is not its shadow's edge, which only the map of its depths,
    /// cut out alike, knows.
    #[must_use]
    pub fn silhouette_segments(&self, light: &LightView) -> Vec<[Vec3; 2]> {
        let per_instance: Vec<Vec<[Vec3; 2]>> = self
            .silhouettes(light)
            .filter(|(i, ..)| self.instances[*i].coverage() != Coverage::Cutout)
            .map(|(i, _, sil)| self.world_segments(i, &sil))
            .collect();
        per_instance.concat()
    }

    /// Instance `i`'s silhouette edges in world space.
    fn world_segments(&self, i: usize, sil: &Silhouette) -> Vec<[Vec3; 2]> {
        let inst = &self.instances[i];
        let at = |v: u32| inst.world_from_local.transform_point3(inst.adjacency.positions()[v as usize]);
        sil.edges.iter().map(|e| [at(e.a), at(e.b)]).collect()
    }
}

/// The surface each pixel of a view shows, as one backend's G-buffer saw it: what another backend needs to
/// shade or measure at exactly those points (the reference is traced at each backend's own points, so a
/// sample that lands on the other side of a sub-pixel caster on one backend is not counted as that
/// backend's shadow error).
#[derive(Clone, Debug)]
pub struct Surfaces {
    /// World position of the visible surface.
    pub position: Image<Vec3>,
    /// Unit shading normal.
    pub normal: Image<Vec3>,
    /// Unit face normal, turned towards the viewer.
    pub geometric_normal: Image<Vec3>,
    /// Linear albedo.
    pub albedo: Image<Vec3>,
    /// Pixels that show a surface receiving shadows.
    pub receiver: Image<bool>,
    /// Pixels that show any surface.
    pub covered: Image<bool>,
}

#[cfg(test)]
mod tests {
    use glam::{Mat4, Vec3};

    use super::{FrameError, FrameInputs, MAX_FRAME_TRIANGLES};
    use crate::geometry::volume::Caps;
    use crate::material::AlphaMode;
    use crate::{Camera, Light, Material, Mesh, Scene};

    /// A flat grid of `2 * columns * rows` triangles.
    fn grid(columns: u32, rows: u32) -> Mesh {
        let positions = (0..=rows)
            .flat_map(|y| (0..=columns).map(move |x| Vec3::new(x as f32 / columns as f32, 0.0, y as f32 / rows as f32)))
            .collect();
        let at = |x: u32, y: u32| y * (columns + 1) + x;
        let triangles = (0..rows)
            .flat_map(|y| {
                (0..columns).flat_map(move |x| {
                    [[at(x, y), at(x, y + 1), at(x + 1, y)], [at(x + 1, y), at(x, y + 1), at(x + 1, y + 1)]]
                })
            })
            .collect();
        Mesh::new(positions, triangles).expect("a grid")
    }

    #[test]
    fn a_frame_of_more_triangles_than_32_bit_ids_can_number_is_refused() {
        // One mesh of 2^16 triangles drawn by 2^16 - 1 nodes numbers within u32; one node more does not.
        let mut scene = Scene::new();
        let mesh = scene.add_mesh(grid(256, 128));
        let material = scene.add_material(Material::default());
        let n = 1u64 << 16;
        for k in 0..n - 1 {
            scene.add_instance(&format!("tile {k}"), mesh, material, Mat4::IDENTITY).expect("instance");
        }
        let camera = Camera::look_at(Vec3::new(0.0, 2.0, 2.0), Vec3::ZERO, 45.0);
        let lights = vec![Light::spot(Vec3::new(0.0, 4.0, 0.0), Vec3::ZERO, 60.0)];
        let frame = FrameInputs::new(&scene, camera, lights.clone()).expect("at the limit");
        assert_eq!(frame.triangle_count() as u64, n * (n - 1));
        assert!(n * (n - 1) <= MAX_FRAME_TRIANGLES);
        scene.add_instance("one too many", mesh, material, Mat4::IDENTITY).expect("instance");
        let err = FrameInputs::new(&scene, camera, lights).expect_err("over the limit");
        assert_eq!(err, FrameError::TooManyTriangles { triangles: n * n });
        assert!(err.to_string().contains(&(n * n).to_string()), "{err}");
    }

    #[test]
    fn an_instance_carries_its_material_and_texture_as_the_frame_found_them() {
        use crate::material::{AlphaMode, Texture, TextureRef};
        let mut scene = Scene::new();
        let texture = scene.add_texture(Texture::from_rgba8("clear", 1, 1, vec![[0; 4]]).unwrap());
        let masked = Material {
            alpha_mode: AlphaMode::Mask { cutoff: 0.5 },
            base_color_texture: Some(TextureRef {
                texture,
                sampler: Default::default(),
                transform: Default::default(),
            }),
            ..Material::colored("card", Vec3::ONE)
        };
        let card = scene.add_material(masked);
        let mesh = scene.add_mesh(grid(1, 1));
        scene.add_instance("card", mesh, card, Mat4::IDENTITY).unwrap();
        let camera = Camera::look_at(Vec3::new(0.5, 2.0, 0.5), Vec3::new(0.5, 0.0, 0.5), 45.0);
        let frame = FrameInputs::new(&scene, camera, vec![]).unwrap();
        let instance = &frame.instances[0];
        assert_eq!(instance.material.alpha_mode, AlphaMode::Mask { cutoff: 0.5 });
        let shared = instance.base_color_texture.as_ref().expect("the texture");
        assert!(std::sync::Arc::ptr_eq(shared, scene.texture(texture).unwrap()), "one copy of the texture");
        // Editing the scene's material afterwards leaves the frame's as it was.
        scene.material_mut(card).unwrap().alpha_mode = AlphaMode::Opaque;
        assert_eq!(instance.material.alpha_mode, AlphaMode::Mask { cutoff: 0.5 });
        assert_eq!(scene.material(card).unwrap().alpha_mode, AlphaMode::Opaque);
    }

    /// A caster its texture cuts out gives silhouette maps, the penumbrae built on silhouettes and the
    /// shadow volumes (with the hybrid's edge segments) no edges, though its mesh has an outline; made
    /// opaque, it does.
    #[test]
    fn cut_out_casters_give_silhouette_techniques_no_edges() {
        let mut scene = crate::scenes::build("cutout", &crate::scenes::SceneParams::default()).expect("cutout");
        // The card's edges (it is the one caster a metre over the ground) in the world segments and in
        // the per-caster silhouettes.
        let edges = |scene: &Scene| {
            let frame = FrameInputs::from_first_camera(scene).expect("frame");
            let light = frame.light_view(&frame.lights[0]).expect("light view");
            let segments = frame.silhouette_segments(&light).iter().filter(|[a, b]| a.y > 0.5 && b.y > 0.5).count();
            let card = |i: usize| frame.instances[i].bounds.min.y > 0.5;
            let silhouettes: usize =
                frame.caster_silhouettes(&light).iter().filter(|(i, _)| card(*i)).map(|(_, s)| s.edges.len()).sum();
            let volumes = frame.shadow_volumes(&light, Caps::Both);
            let volume_edges: usize = volumes.iter().filter(|v| card(v.instance)).map(|v| v.silhouette_edges).sum();
            let (volumes, segments_too) = frame.shadow_volumes_and_segments(&light, Caps::Both);
            let card_volumes = volumes.iter().filter(|v| card(v.instance)).count();
            let high = segments_too.iter().filter(|[a, b]| a.y > 0.5 && b.y > 0.5).count();
            assert_eq!(high, segments, "the hybrid's segments are the silhouette maps'");
            (segments, silhouettes, volume_edges, card_volumes)
        };
        assert_eq!(edges(&scene), (0, 0, 0, 0), "the cut-out card");
        let card = scene.materials().find(|(_, m)| m.name == "checkerboard").expect("the card").0;
        scene.material_mut(card).expect("material").alpha_mode = AlphaMode::Opaque;
        assert_eq!(edges(&scene), (4, 4, 4, 1), "the opaque card's outline");
    }
}
