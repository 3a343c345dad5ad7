//! The scene graph: slotmap storage with typed keys, a node hierarchy with cached world transforms,
//! materials, lights and cameras.
//!
//! Every mutation goes through a method that keeps the caches right: moving a node recomputes the world
//! transforms of its subtree (and nothing else); replacing a mesh drops its cached adjacency and bumps its
//! version so GPU uploads keyed by [`MeshKey`] know to refresh. Lights and cameras live in world space,
//! or in a node's space, following the node as it and its parents move (as a file's lamps do).

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, OnceLock};

use glam::Mat4;
use slotmap::{SecondaryMap, SlotMap};

use crate::bounds::Aabb;
use crate::geometry::adjacency::Adjacency;
use crate::material::Texture;
use crate::mesh::Mesh;

mod animation;
mod camera;
mod light;
mod placed;
mod skin;

pub use crate::material::Material;
pub use animation::{Animation, AnimationKey, Channel, Interpolation, Keyframes, Trs};
pub use camera::Camera;
pub use light::{Light, LightKind, LightShadow, ShadowUpdate};
use placed::Placed;
pub use skin::{Deformed, Pose, Skin, SkinKey};

slotmap::new_key_type! {
    /// A node of the hierarchy.
    pub struct NodeKey;
    /// A mesh, shared by any number of nodes.
    pub struct MeshKey;
    /// A material.
    pub struct MaterialKey;
    /// A decoded texture, shared by any number of materials.
    pub struct TextureKey;
    /// A light.
    pub struct LightKey;
    /// A camera.
    pub struct CameraKey;
}

/// Why a scene edit was refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SceneError {
    /// The key does not (or no longer) exist.
    #[error("unknown {0} key")]
    UnknownKey(&'static str),
    /// A transform with NaN or infinite entries.
    #[error("transform of node '{node}' is not finite")]
    NonFiniteTransform {
        /// The node's name.
        node: String,
    },
    /// Reparenting would make a node its own ancestor.
    #[error("making '{parent}' the parent of '{child}' would create a cycle")]
    Cycle {
        /// The would-be child.
        child: String,
        /// The would-be parent.
        parent: String,
    },
    /// A light or camera with unusable parameters.
    #[error("{0}")]
    Invalid(String),
    /// Animation data that cannot be played.
    #[error("animation '{animation}', {channel}: {why}")]
    Animation {
        /// The animation's name.
        animation: String,
        /// Which channel, and the property it moves.
        channel: String,
        /// What is wrong.
        why: String,
    },
}

/// A node: a local transform, optionally a mesh with a material, and shadow flags.
#[derive(Clone, Debug)]
pub struct Node {
    name: String,
    parent: Option<NodeKey>,
    children: Vec<NodeKey>,
    local: Mat4,
    world: Mat4,
    mesh: Option<(MeshKey, MaterialKey)>,
    casts_shadow: bool,
    receives_shadow: bool,
}

impl Node {
    /// Name, for reports.
    #[must_use]
    pub fn name(&self) -> &str {
        &self.name
    }
    /// Parent node.
    #[must_use]
    pub fn parent(&self) -> Option<NodeKey> {
        self.parent
    }
    /// Child nodes.
    #[must_use]
    pub fn children(&self) -> &[NodeKey] {
        &self.children
    }
    /// Transform relative to the parent.
    #[must_use]
    pub fn local_transform(&self) -> Mat4 {
        self.local
    }
    /// Cached world transform (always current).
    #[must_use]
    pub fn world_transform(&self) -> Mat4 {
        self.world
    }
    /// The mesh this node draws and its material.
    #[must_use]
    pub fn mesh(&self) -> Option<(MeshKey, MaterialKey)> {
        self.mesh
    }
    /// Whether this node blocks light (combined with its material's flag).
    #[must_use]
    pub fn casts_shadow(&self) -> bool {
        self.casts_shadow
    }
    /// Whether this node shows shadows (combined with its material's flag).
    #[must_use]
    pub fn receives_shadow(&self) -> bool {
        self.receives_shadow
    }
}

struct MeshEntry {
    mesh: Arc<Mesh>,
    adjacency: OnceLock<Arc<Adjacency>>,
    version: u64,
}

/// The scene: nodes, meshes, materials, lights and cameras.
///
/// ```
/// use shadow_core::glam::{Mat4, Vec3};
/// use shadow_core::{Camera, FrameInputs, Light, Material, Scene, procedural};
///
/// let mut scene = Scene::new();
/// let ground = scene.add_mesh(procedural::plane(10.0, 10.0)?);
/// let cube = scene.add_mesh(procedural::cuboid(Vec3::ONE)?);
/// let grey = scene.add_material(Material::colored("grey", Vec3::splat(0.8)));
/// scene.add_instance("ground", ground, grey, Mat4::IDENTITY)?;
/// scene.add_instance("cube", cube, grey, Mat4::from_translation(Vec3::new(0.0, 0.5, 0.0)))?;
/// scene.add_light(Light::spot(Vec3::new(3.0, 6.0, 2.0), Vec3::ZERO, 60.0));
/// scene.add_camera(Camera::look_at(Vec3::new(6.0, 4.0, 6.0), Vec3::ZERO, 45.0));
/// // What a backend renders: the drawn instances in world space, the camera and the lights.
/// let frame = FrameInputs::from_first_camera(&scene)?;
/// assert_eq!((frame.instances.len(), frame.lights.len()), (2, 1));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Default)]
pub struct Scene {
    nodes: SlotMap<NodeKey, Node>,
    roots: Vec<NodeKey>,
    meshes: SlotMap<MeshKey, MeshEntry>,
    /// Shared with the frames that draw them, so a frame carries its instances' materials uncopied.
    materials: SlotMap<MaterialKey, Arc<Material>>,
    textures: SlotMap<TextureKey, Arc<Texture>>,
    warnings: Vec<String>,
    lights: SlotMap<LightKey, Placed<Light>>,
    light_shadows: SecondaryMap<LightKey, LightShadow>,
    cameras: SlotMap<CameraKey, Placed<Camera>>,
    animations: SlotMap<AnimationKey, Animation>,
    /// The rest pose of every node an animation moves.
    rest: SecondaryMap<NodeKey, Trs>,
    skins: SlotMap<SkinKey, Skin>,
    /// The skin each skinned node's mesh is bound to.
    node_skins: SecondaryMap<NodeKey, SkinKey>,
    /// Morph target weights at rest, and as posed.
    rest_weights: SecondaryMap<NodeKey, Vec<f32>>,
    weights: SecondaryMap<NodeKey, Vec<f32>>,
}

/// Mesh versions are unique in the process, not per scene: two scenes hand out the same [`MeshKey`]s,
/// and a backend that caches uploads by key must still tell their meshes apart.
fn next_mesh_version() -> u64 {
    static NEXT: AtomicU64 = AtomicU64::new(1);
    NEXT.fetch_add(1, Ordering::Relaxed)
}

impl Scene {
    /// An empty scene.
    #[must_use]
    pub fn new() -> Self {
        Self::default()
    }

    // ---- meshes ----

    /// Adds a mesh; nodes refer to it by the returned key.
    pub fn add_mesh(&mut self, mesh: Mesh) -> MeshKey {
        self.meshes.insert(MeshEntry { mesh: Arc::new(mesh), adjacency: OnceLock::new(), version: next_mesh_version() })
    }

    /// The mesh behind a key.
    #[must_use]
    pub fn mesh(&self, key: MeshKey) -> Option<&Arc<Mesh>> {
        self.meshes.get(key).map(|e| &e.mesh)
    }

    /// A number that changes whenever the mesh behind `key` is replaced, unique across all scenes.
    #[must_use]
    pub fn mesh_version(&self, key: MeshKey) -> Option<u64> {
        self.meshes.get(key).map(|e| e.version)
    }

    /// Replaces a mesh's geometry for every node that uses it; drops its cached adjacency.
    ///
    /// # Errors
    /// [`SceneError::UnknownKey`] for a removed or foreign key.
    pub fn replace_mesh(&mut self, key: MeshKey, mesh: Mesh) -> Result<(), SceneError> {
        let version = next_mesh_version();
        let entry = self.meshes.get_mut(key).ok_or(SceneError::UnknownKey("mesh"))?;
        *entry = MeshEntry { mesh: Arc::new(mesh), adjacency: OnceLock::new(), version };
        Ok(())
    }

    /// The mesh's edge adjacency, built on first use and cached until the mesh is replaced.
    #[must_use]
    pub fn adjacency(&self, key: MeshKey) -> Option<Arc<Adjacency>> {
        let e = self.meshes.get(key)?;
        Some(e.adjacency.get_or_init(|| Arc::new(Adjacency::build(&e.mesh))).clone())
    }

    /// Builds the adjacency of every mesh that has none cached yet, on all threads, small meshes in
    /// batches ([`Adjacency::build_all`]): a scene of many small meshes built one mesh at a time would
    /// pay a fixed cost per mesh larger than a small mesh's own.
    /// [`FrameInputs::new`](crate::FrameInputs::new) calls it.
    pub fn build_adjacencies(&self) {
        let missing: Vec<&MeshEntry> = self.meshes.values().filter(|e| e.adjacency.get().is_none()).collect();
        let meshes: Vec<&Mesh> = missing.iter().map(|e| e.mesh.as_ref()).collect();
        for (e, adjacency) in missing.iter().zip(Adjacency::build_all(&meshes)) {
            // Set unless a caller on another thread has just set it, to the same adjacency.
            let _ = e.adjacency.set(Arc::new(adjacency));
        }
    }

    /// True when the mesh's adjacency is already cached.
    #[must_use]
    pub fn has_cached_adjacency(&self, key: MeshKey) -> bool {
        self.meshes.get(key).is_some_and(|e| e.adjacency.get().is_some())
    }

    /// Every mesh.
    pub fn meshes(&self) -> impl Iterator<Item = (MeshKey, &Arc<Mesh>)> {
        self.meshes.iter().map(|(k, e)| (k, &e.mesh))
    }

    // ---- materials ----

    /// Adds a material.
    pub fn add_material(&mut self, material: Material) -> MaterialKey {
        self.materials.insert(Arc::new(material))
    }

    /// A material.
    #[must_use]
    pub fn material(&self, key: MaterialKey) -> Option<&Material> {
        self.materials.get(key).map(Arc::as_ref)
    }

    /// Every material.
    pub fn materials(&self) -> impl Iterator<Item = (MaterialKey, &Material)> {
        self.materials.iter().map(|(k, m)| (k, m.as_ref()))
    }

    /// A material, to edit (materials hold no cached state; a frame made before keeps the old one).
    pub fn material_mut(&mut self, key: MaterialKey) -> Option<&mut Material> {
        self.materials.get_mut(key).map(Arc::make_mut)
    }

    // ---- textures ----

    /// Adds a texture; materials name it by the returned key.
    pub fn add_texture(&mut self, texture: Texture) -> TextureKey {
        self.textures.insert(Arc::new(texture))
    }

    /// A texture.
    #[must_use]
    pub fn texture(&self, key: TextureKey) -> Option<&Arc<Texture>> {
        self.textures.get(key)
    }

    /// Every texture.
    pub fn textures(&self) -> impl Iterator<Item = (TextureKey, &Arc<Texture>)> {
        self.textures.iter()
    }

    // ---- warnings ----

    /// Records something the scene's source got wrong that did not stop it loading (an image left out, a
    /// setting ignored), one line each, for the tools to print.
    pub fn add_warning(&mut self, warning: String) {
        self.warnings.push(warning);
    }

    /// Puts `source: ` before every warning recorded so far (the file they came from).
    pub(crate) fn prefix_warnings(&mut self, source: &str) {
        for w in &mut self.warnings {
            *w = format!("{source}: {w}");
        }
    }

    /// The warnings recorded while the scene was built, oldest first.
    #[must_use]
    pub fn warnings(&self) -> &[String] {
        &self.warnings
    }

    // ---- nodes ----

    /// Adds a node under `parent` (or as a root) with a local transform.
    ///
    /// # Errors
    /// An unknown parent, or a non-finite transform.
    pub fn add_node(&mut self, name: &str, parent: Option<NodeKey>, local: Mat4) -> Result<NodeKey, SceneError> {
        if !local.is_finite() {
            return Err(SceneError::NonFiniteTransform { node: name.into() });
        }
        let parent_world = match parent {
            Some(p) => self.nodes.get(p).ok_or(SceneError::UnknownKey("node"))?.world,
            None => Mat4::IDENTITY,
        };
        let key = self.nodes.insert(Node {
            name: name.into(),
            parent,
            children: Vec::new(),
            local,
            world: parent_world * local,
            mesh: None,
            casts_shadow: true,
            receives_shadow: true,
        });
        match parent {
            Some(p) => self.nodes[p].children.push(key),
            None => self.roots.push(key),
        }
        Ok(key)
    }

    /// Adds a root node drawing `mesh` with `material` at `transform`.
    ///
    /// # Errors
    /// Unknown keys or a non-finite transform.
    pub fn add_instance(
        &mut self,
        name: &str,
        mesh: MeshKey,
        material: MaterialKey,
        transform: Mat4,
    ) -> Result<NodeKey, SceneError> {
        let node = self.add_node(name, None, transform)?;
        self.set_mesh(node, Some((mesh, material)))?;
        Ok(node)
    }

    /// A node.
    #[must_use]
    pub fn node(&self, key: NodeKey) -> Option<&Node> {
        self.nodes.get(key)
    }

    /// Root nodes, in insertion order.
    #[must_use]
    pub fn roots(&self) -> &[NodeKey] {
        &self.roots
    }

    /// Number of nodes.
    #[must_use]
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// Sets what a node draws.
    ///
    /// # Errors
    /// Unknown node, mesh or material key.
    pub fn set_mesh(&mut self, node: NodeKey, mesh: Option<(MeshKey, MaterialKey)>) -> Result<(), SceneError> {
        if let Some((m, mat)) = mesh {
            self.meshes.get(m).ok_or(SceneError::UnknownKey("mesh"))?;
            self.materials.get(mat).ok_or(SceneError::UnknownKey("material"))?;
        }
        self.nodes.get_mut(node).ok_or(SceneError::UnknownKey("node"))?.mesh = mesh;
        Ok(())
    }

    /// Gives every node that draws a mesh an earlier node draws too a copy of its own, so no two nodes
    /// share one: the scene as it would stand without instancing, drawing and casting the same. Returns
    /// how many copies it made.
    pub fn unshare_meshes(&mut self) -> usize {
        let mut seen = std::collections::HashSet::new();
        let mut copies = 0;
        for node in self.depth_first() {
            let Some((mesh, material)) = self.nodes[node].mesh else { continue };
            if seen.insert(mesh) {
                continue;
            }
            let copy = Mesh::clone(&self.meshes[mesh].mesh);
            let key = self.add_mesh(copy);
            self.nodes[node].mesh = Some((key, material));
            copies += 1;
        }
        copies
    }

    /// Sets a node's shadow flags.
    ///
    /// # Errors
    /// Unknown node key.
    pub fn set_shadow_flags(&mut self, node: NodeKey, casts: bool, receives: bool) -> Result<(), SceneError> {
        let n = self.nodes.get_mut(node).ok_or(SceneError::UnknownKey("node"))?;
        n.casts_shadow = casts;
        n.receives_shadow = receives;
        Ok(())
    }

    /// Moves a node: sets its local transform and recomputes the world transforms of its subtree. On a node
    /// an animation moves, this is its new rest pose too.
    ///
    /// # Errors
    /// Unknown node, a non-finite transform, or one with shear on an animated node.
    pub fn set_local_transform(&mut self, node: NodeKey, local: Mat4) -> Result<(), SceneError> {
        let n = self.nodes.get_mut(node).ok_or(SceneError::UnknownKey("node"))?;
        if !local.is_finite() {
            return Err(SceneError::NonFiniteTransform { node: n.name.clone() });
        }
        if let Some(rest) = self.rest.get_mut(node) {
            *rest = Trs::from_matrix(local).ok_or_else(|| {
                SceneError::Invalid(format!("node '{}' is animated and cannot take a transform with shear", n.name))
            })?;
        }
        n.local = local;
        self.update_subtree(node);
        Ok(())
    }

    /// Moves a node under a new parent (or to the roots), keeping its local transform.
    ///
    /// # Errors
    /// Unknown keys, or a parent inside the node's own subtree.
    pub fn set_parent(&mut self, node: NodeKey, parent: Option<NodeKey>) -> Result<(), SceneError> {
        self.nodes.get(node).ok_or(SceneError::UnknownKey("node"))?;
        if let Some(p) = parent {
            self.nodes.get(p).ok_or(SceneError::UnknownKey("node"))?;
            let mut a = Some(p);
            while let Some(k) = a {
                if k == node {
                    return Err(SceneError::Cycle {
                        child: self.nodes[node].name.clone(),
                        parent: self.nodes[p].name.clone(),
                    });
                }
                a = self.nodes[k].parent;
            }
        }
        match self.nodes[node].parent {
            Some(old) => self.nodes[old].children.retain(|&c| c != node),
            None => self.roots.retain(|&c| c != node),
        }
        self.nodes[node].parent = parent;
        match parent {
            Some(p) => self.nodes[p].children.push(node),
            None => self.roots.push(node),
        }
        self.update_subtree(node);
        Ok(())
    }

    /// Puts every root node under one new root `name` with transform `local`, and returns it: one pass
    /// over the roots, where moving each with [`Scene::set_parent`] would search the root list each time.
    ///
    /// # Errors
    /// A non-finite transform.
    pub fn group_roots(&mut self, name: &str, local: Mat4) -> Result<NodeKey, SceneError> {
        let roots = std::mem::take(&mut self.roots);
        let group = match self.add_node(name, None, local) {
            Ok(k) => k,
            Err(e) => {
                self.roots = roots;
                return Err(e);
            }
        };
        for &r in &roots {
            self.nodes[r].parent = Some(group);
        }
        self.nodes[group].children = roots;
        self.update_subtree(group);
        Ok(group)
    }

    /// Removes a node and its whole subtree, with the lights and cameras that follow them.
    ///
    /// # Errors
    /// Unknown node key.
    pub fn remove_node(&mut self, node: NodeKey) -> Result<(), SceneError> {
        let parent = self.nodes.get(node).ok_or(SceneError::UnknownKey("node"))?.parent;
        match parent {
            Some(p) => self.nodes[p].children.retain(|&c| c != node),
            None => self.roots.retain(|&c| c != node),
        }
        let mut stack = vec![node];
        while let Some(k) = stack.pop() {
            if let Some(n) = self.nodes.remove(k) {
                stack.extend(n.children);
            }
        }
        // The lights and cameras that followed a removed node go with it.
        let nodes = &self.nodes;
        self.lights.retain(|_, l| l.node.is_none_or(|n| nodes.contains_key(n)));
        let lights = &self.lights;
        self.light_shadows.retain(|k, _| lights.contains_key(k));
        self.cameras.retain(|_, c| c.node.is_none_or(|n| nodes.contains_key(n)));
        self.rest.retain(|n, _| nodes.contains_key(n));
        self.node_skins.retain(|n, _| nodes.contains_key(n));
        self.rest_weights.retain(|n, _| nodes.contains_key(n));
        self.weights.retain(|n, _| nodes.contains_key(n));
        for s in self.skins.values_mut() {
            // A joint that is gone counts as one at the origin: its inverse bind matrix alone moves its vertices.
            for j in &mut s.joints {
                if !nodes.contains_key(*j) {
                    *j = NodeKey::default();
                }
            }
        }
        for a in self.animations.values_mut() {
            a.retain_nodes(nodes);
        }
        Ok(())
    }

    /// Recomputes world transforms below (and including) `node`; nothing else is touched.
    fn update_subtree(&mut self, node: NodeKey) {
        let mut stack = vec![node];
        while let Some(k) = stack.pop() {
            let parent_world = self.nodes[k].parent.map_or(Mat4::IDENTITY, |p| self.nodes[p].world);
            let n = &mut self.nodes[k];
            n.world = parent_world * n.local;
            stack.extend(n.children.iter().copied());
        }
    }

    /// Every node in depth-first order from the roots.
    #[must_use]
    pub fn depth_first(&self) -> Vec<NodeKey> {
        let mut out = Vec::with_capacity(self.nodes.len());
        let mut stack: Vec<NodeKey> = self.roots.iter().rev().copied().collect();
        while let Some(k) = stack.pop() {
            out.push(k);
            stack.extend(self.nodes[k].children.iter().rev().copied());
        }
        out
    }

    /// Nodes that draw a mesh, depth-first, with the mesh and the material.
    pub fn drawables(&self) -> impl Iterator<Item = (NodeKey, &Node, MeshKey, &Arc<Material>)> {
        self.depth_first().into_iter().filter_map(move |k| {
            let n = &self.nodes[k];
            let (m, mat) = n.mesh?;
            Some((k, n, m, self.materials.get(mat)?))
        })
    }

    /// World-space bounds of every drawn mesh, as posed.
    #[must_use]
    pub fn bounds(&self) -> Aabb {
        self.drawables().fold(Aabb::EMPTY, |b, (k, n, m, _)| {
            let placed = match self.deformed(k) {
                Some(Ok(d)) => d.mesh.bounds().transformed(d.world_from_local),
                _ => self.meshes[m].mesh.bounds().transformed(n.world),
            };
            b.union(placed)
        })
    }

    /// Total triangles drawn (instances counted each time).
    #[must_use]
    pub fn triangle_count(&self) -> usize {
        self.drawables().map(|(_, _, m, _)| self.meshes[m].mesh.triangle_count()).sum()
    }
}

#[cfg(test)]
mod tests {
    use std::f32::consts::FRAC_PI_2;

    use super::*;
    use crate::procedural;
    use glam::Vec3;

    #[test]
    fn moving_a_node_updates_its_subtree_only() {
        let mut s = Scene::new();
        let a = s.add_node("a", None, Mat4::from_translation(Vec3::X)).unwrap();
        let b = s.add_node("b", Some(a), Mat4::from_translation(Vec3::Y)).unwrap();
        let c = s.add_node("c", None, Mat4::from_translation(Vec3::Z)).unwrap();
        assert_eq!(s.node(b).unwrap().world_transform().w_axis.truncate(), Vec3::new(1.0, 1.0, 0.0));
        s.set_local_transform(a, Mat4::from_translation(Vec3::splat(2.0))).unwrap();
        assert_eq!(s.node(b).unwrap().world_transform().w_axis.truncate(), Vec3::new(2.0, 3.0, 2.0));
        assert_eq!(s.node(c).unwrap().world_transform().w_axis.truncate(), Vec3::Z);
        s.set_parent(c, Some(b)).unwrap();
        assert_eq!(s.node(c).unwrap().world_transform().w_axis.truncate(), Vec3::new(2.0, 3.0, 3.0));
        assert!(matches!(s.set_parent(a, Some(c)), Err(SceneError::Cycle { .. })));
        assert!(s.set_local_transform(a, Mat4::from_scale(Vec3::splat(f32::NAN))).is_err());
        s.remove_node(a).unwrap();
        assert_eq!(s.node_count(), 0);
    }

    #[test]
    fn grouping_the_roots_moves_every_subtree() {
        let mut s = Scene::new();
        let a = s.add_node("a", None, Mat4::from_translation(Vec3::X)).unwrap();
        let b = s.add_node("b", Some(a), Mat4::from_translation(Vec3::Y)).unwrap();
        let c = s.add_node("c", None, Mat4::from_translation(Vec3::Z)).unwrap();
        let g = s.group_roots("g", Mat4::from_scale(Vec3::splat(2.0))).unwrap();
        assert_eq!(s.roots(), &[g]);
        assert_eq!(s.node(g).unwrap().children(), &[a, c]);
        assert_eq!(s.node(a).unwrap().parent(), Some(g));
        assert_eq!(s.node(b).unwrap().world_transform().w_axis.truncate(), Vec3::new(2.0, 2.0, 0.0));
        assert_eq!(s.node(c).unwrap().world_transform().w_axis.truncate(), Vec3::new(0.0, 0.0, 2.0));
        assert!(s.group_roots("bad", Mat4::from_scale(Vec3::splat(f32::NAN))).is_err());
        assert_eq!(s.roots(), &[g]);
    }

    #[test]
    fn lights_and_cameras_follow_their_nodes() {
        let mut s = Scene::new();
        let arm = s.add_node("arm", None, Mat4::from_translation(Vec3::new(1.0, 0.0, 0.0))).unwrap();
        let hand = s.add_node("hand", Some(arm), Mat4::from_translation(Vec3::new(0.0, 2.0, 0.0))).unwrap();
        let lamp = s.add_light_to(hand, Light::spot(Vec3::ZERO, Vec3::NEG_Y, 40.0)).unwrap();
        let eye = s.add_camera_to(hand, Camera::look_at(Vec3::ZERO, Vec3::NEG_Z, 45.0)).unwrap();
        let fixed = s.add_light(Light::point(Vec3::new(0.0, 5.0, 0.0)));
        // The arm turns a quarter about +z: the hand, 2 up the arm, ends 2 along -x from (1, 0, 0).
        s.set_local_transform(arm, Mat4::from_translation(Vec3::X) * Mat4::from_rotation_z(FRAC_PI_2)).unwrap();
        let lit = s.world_light(lamp).unwrap();
        assert!((lit.position().unwrap() - Vec3::new(-1.0, 0.0, 0.0)).length() < 1e-6);
        let LightKind::Spot { direction, .. } = lit.kind else { panic!("a spot") };
        assert!((direction - Vec3::X).length() < 1e-6, "{direction}");
        assert!((s.world_camera(eye).unwrap().eye - Vec3::new(-1.0, 0.0, 0.0)).length() < 1e-6);
        // As given, the lamp is still at its node's origin; the world light stays put.
        assert_eq!(s.light(lamp).unwrap().position(), Some(Vec3::ZERO));
        assert_eq!(s.world_light(fixed).unwrap().position(), Some(Vec3::new(0.0, 5.0, 0.0)));
        s.remove_node(hand).unwrap();
        assert_eq!(s.lights().map(|(k, _)| k).collect::<Vec<_>>(), vec![fixed]);
        assert!(s.cameras().next().is_none());
        assert!(s.add_light_to(hand, Light::point(Vec3::ZERO)).is_err());
    }

    #[test]
    fn mesh_versions_differ_across_scenes() {
        // Two scenes give out the same first key; a GPU cache keyed by (key, version) must not mix them.
        let (mut a, mut b) = (Scene::new(), Scene::new());
        let ka = a.add_mesh(procedural::cuboid(Vec3::ONE).expect("shape"));
        let kb = b.add_mesh(procedural::plane(1.0, 1.0).expect("shape"));
        assert_eq!(ka, kb);
        assert_ne!(a.mesh_version(ka), b.mesh_version(kb));
    }

    #[test]
    fn replacing_a_mesh_drops_its_adjacency() {
        let mut s = Scene::new();
        let m = s.add_mesh(procedural::cuboid(Vec3::ONE).expect("shape"));
        let v0 = s.mesh_version(m).unwrap();
        assert!(s.adjacency(m).unwrap().closed());
        assert!(s.has_cached_adjacency(m));
        s.replace_mesh(m, procedural::plane(1.0, 1.0).expect("shape")).unwrap();
        assert!(!s.has_cached_adjacency(m));
        assert_ne!(s.mesh_version(m).unwrap(), v0);
        assert!(!s.adjacency(m).unwrap().closed());
    }
}
