//! Skins and morph weights in the scene graph, and the posed meshes they give a frame.
//!
//! A skin names its joints (nodes) and their inverse bind matrices; a node that draws a mesh with skin
//! weights is bound to a skin and drawn where its joints put it (its own transform is ignored, as glTF
//! requires). A node that draws a mesh with morph targets has weights, one a target, which animations
//! move. [`Scene::deformed`] poses such a node's mesh from the joints and weights as they stand.

use std::hash::{Hash, Hasher};
use std::sync::Arc;

use glam::Mat4;

use super::{NodeKey, Scene, SceneError};
use crate::deform;
use crate::geometry::adjacency::Adjacency;
use crate::mesh::Mesh;

slotmap::new_key_type! {
    /// A skin.
    pub struct SkinKey;
}

/// The joints that move a skinned mesh and the inverse bind matrix of each (the inverse of the joint's
/// world transform when the mesh was bound to it).
#[derive(Clone, Debug, PartialEq)]
pub struct Skin {
    /// Its name, for reports.
    pub name: String,
    /// The joints, in the order the mesh's joint indices name them.
    pub joints: Vec<NodeKey>,
    /// One a joint.
    pub inverse_bind_matrices: Vec<Mat4>,
}

/// A node's mesh posed for a frame.
#[derive(Clone, Debug)]
pub struct Deformed {
    /// The posed mesh.
    pub mesh: Arc<Mesh>,
    /// Its adjacency: the rest mesh's topology over the posed positions.
    pub adjacency: Arc<Adjacency>,
    /// A number that changes whenever the pose does (the same pose gives the same number), apart from
    /// every mesh version [`Scene::mesh_version`] hands out.
    pub version: u64,
    /// Posed mesh space to world space: the identity for a skinned mesh (its joints place it), the
    /// node's world transform for one that only morphs.
    pub world_from_local: Mat4,
    /// What it was posed from, for a backend that poses meshes on its own.
    pub pose: Arc<Pose>,
}

/// What a posed mesh is posed from: the rest mesh with its deformers and adjacency, and the joint
/// matrices and morph weights of the pose. A backend that poses meshes itself (the GPU's compute pass)
/// uploads the rest mesh once and these numbers every frame, and must give what [`deform::pose`] gives.
#[derive(Clone, Debug)]
pub struct Pose {
    /// The mesh at rest, with its [`deform::Deformers`].
    pub rest: Arc<Mesh>,
    /// The rest mesh's adjacency (its topology is the posed mesh's).
    pub rest_adjacency: Arc<Adjacency>,
    /// The rest mesh's version ([`Scene::mesh_version`]).
    pub rest_version: u64,
    /// Each joint's world transform times its inverse bind matrix, for a skinned mesh.
    pub joint_matrices: Option<Vec<Mat4>>,
    /// The morph targets' weights (missing ones count as zero).
    pub weights: Vec<f32>,
}

impl Scene {
    /// Adds a skin.
    ///
    /// # Errors
    /// A joint that is not a node, no joints, or a count of inverse bind matrices that differs from the
    /// joints' (each names the skin).
    pub fn add_skin(&mut self, skin: Skin) -> Result<SkinKey, SceneError> {
        let refuse = |why: String| SceneError::Invalid(format!("skin '{}': {why}", skin.name));
        if skin.joints.is_empty() {
            return Err(refuse("no joints".into()));
        }
        if let Some(j) = skin.joints.iter().position(|j| !self.nodes.contains_key(*j)) {
            return Err(refuse(format!("joint {j} is not a node of the scene")));
        }
        if skin.inverse_bind_matrices.len() != skin.joints.len() {
            return Err(refuse(format!(
                "{} inverse bind matrices for {} joints",
                skin.inverse_bind_matrices.len(),
                skin.joints.len()
            )));
        }
        if let Some(m) = skin.inverse_bind_matrices.iter().position(|m| !m.is_finite()) {
            return Err(refuse(format!("inverse bind matrix {m} is not finite")));
        }
        Ok(self.skins.insert(skin))
    }

    /// A skin.
    #[must_use]
    pub fn skin(&self, key: SkinKey) -> Option<&Skin> {
        self.skins.get(key)
    }

    /// Every skin.
    pub fn skins(&self) -> impl Iterator<Item = (SkinKey, &Skin)> {
        self.skins.iter()
    }

    /// Binds a node's mesh to a skin (or unbinds it with `None`).
    ///
    /// # Errors
    /// Unknown keys, a node that draws no mesh with skin weights, or weights that name a joint the skin
    /// does not have.
    pub fn set_skin(&mut self, node: NodeKey, skin: Option<SkinKey>) -> Result<(), SceneError> {
        let n = self.nodes.get(node).ok_or(SceneError::UnknownKey("node"))?;
        let Some(key) = skin else {
            self.node_skins.remove(node);
            return Ok(());
        };
        let s = self.skins.get(key).ok_or(SceneError::UnknownKey("skin"))?;
        let weights = n.mesh.and_then(|(m, _)| self.meshes.get(m)).and_then(|e| e.mesh.deformers()?.skin.as_ref());
        let Some(weights) = weights else {
            return Err(SceneError::Invalid(format!("node '{}' draws no mesh with skin weights", n.name)));
        };
        if let Some(j) = weights.max_joint().filter(|&j| usize::from(j) >= s.joints.len()) {
            return Err(SceneError::Invalid(format!(
                "node '{}': its mesh names joint {j}, but skin '{}' has {} joints",
                n.name,
                s.name,
                s.joints.len()
            )));
        }
        self.node_skins.insert(node, key);
        Ok(())
    }

    /// The skin a node's mesh is bound to.
    #[must_use]
    pub fn node_skin(&self, node: NodeKey) -> Option<SkinKey> {
        self.node_skins.get(node).copied()
    }

    /// Sets a node's morph target weights at rest, one a target of its mesh (animations move them from
    /// here).
    ///
    /// # Errors
    /// An unknown node, or weights that are not finite.
    pub fn set_morph_weights(&mut self, node: NodeKey, weights: Vec<f32>) -> Result<(), SceneError> {
        let n = self.nodes.get(node).ok_or(SceneError::UnknownKey("node"))?;
        if weights.iter().any(|w| !w.is_finite()) {
            return Err(SceneError::Invalid(format!("node '{}': morph weights {weights:?} are not finite", n.name)));
        }
        self.weights.insert(node, weights.clone());
        self.rest_weights.insert(node, weights);
        Ok(())
    }

    /// A node's morph target weights at rest (empty where it has none).
    #[must_use]
    pub fn rest_morph_weights(&self, node: NodeKey) -> &[f32] {
        self.rest_weights.get(node).map_or(&[], Vec::as_slice)
    }

    /// A node's morph target weights as posed (empty where it has none: every target at zero).
    #[must_use]
    pub fn morph_weights(&self, node: NodeKey) -> &[f32] {
        self.weights.get(node).map_or(&[], Vec::as_slice)
    }

    /// The mesh `node` draws, posed by its skin and morph weights as they stand; `None` for a node whose
    /// mesh is not deformed (no skin bound, every weight zero), which frames draw as it is.
    ///
    /// # Errors
    /// Posed positions that are not finite (joint matrices that overflow).
    pub fn deformed(&self, node: NodeKey) -> Option<Result<Deformed, SceneError>> {
        let n = self.nodes.get(node)?;
        let (mesh_key, _) = n.mesh?;
        let entry = self.meshes.get(mesh_key)?;
        let deformers = entry.mesh.deformers()?;
        let weights = self.morph_weights(node);
        let skin = self.node_skin(node).and_then(|k| self.skins.get(k)).filter(|_| deformers.skin.is_some());
        let morphs = !deformers.morph_targets.is_empty() && weights.iter().any(|w| *w != 0.0);
        if skin.is_none() && !morphs {
            return None;
        }
        let joints: Option<Vec<Mat4>> = skin.map(|s| {
            let world = |j: &NodeKey| self.nodes.get(*j).map_or(Mat4::IDENTITY, |n| n.world);
            s.joints.iter().zip(&s.inverse_bind_matrices).map(|(j, ib)| world(j) * *ib).collect()
        });
        let mesh = &entry.mesh;
        let (positions, normals) =
            deform::pose(mesh.positions(), mesh.normals(), deformers, weights, joints.as_deref());
        if let Some(v) = positions.iter().position(|p| !p.is_finite()) {
            let why = format!("node '{}': posed vertex {v} is not finite", n.name);
            return Some(Err(SceneError::Invalid(why)));
        }
        let mut h = std::collections::hash_map::DefaultHasher::new();
        entry.version.hash(&mut h);
        for m in joints.iter().flatten() {
            m.to_cols_array().map(f32::to_bits).hash(&mut h);
        }
        weights.iter().map(|w| w.to_bits()).for_each(|w| w.hash(&mut h));
        let posed = mesh.posed(positions, normals);
        let rest_adjacency = self.adjacency(mesh_key)?;
        let adjacency = Arc::new(rest_adjacency.posed(posed.positions()));
        Some(Ok(Deformed {
            mesh: Arc::new(posed),
            adjacency,
            // Counted versions start at 1 and count up; a pose's has its top bit set.
            version: h.finish() | 1 << 63,
            world_from_local: if joints.is_some() { Mat4::IDENTITY } else { n.world },
            pose: Arc::new(Pose {
                rest: Arc::clone(mesh),
                rest_adjacency,
                rest_version: entry.version,
                joint_matrices: joints,
                weights: weights.to_vec(),
            }),
        }))
    }
}
