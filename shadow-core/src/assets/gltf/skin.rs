//! glTF skins and morph targets: a primitive's `JOINTS_0`/`WEIGHTS_0` and targets, the skins of the
//! nodes that draw it (joints and inverse bind matrices), and the nodes' morph weights.

use glam::{Mat4, Vec3};
use gltf::accessor::{DataType, Dimensions};

use super::Loader;
use super::bytes::{read_accessor, read_floats, read_vec3};
use crate::assets::AssetFault as Fault;
use crate::deform::{Deformers, MorphTarget, SkinWeights};
use crate::scene::Skin;

impl Loader<'_> {
    /// What a primitive deforms by, where it has skin weights or morph targets (`what` names it).
    pub(super) fn deformers(&self, prim: &gltf::Primitive, what: &str) -> Result<Option<Deformers>, Fault> {
        use gltf::mesh::Semantic;
        let skin = match (prim.get(&Semantic::Joints(0)), prim.get(&Semantic::Weights(0))) {
            (None, None) => None,
            (Some(j), Some(w)) => {
                let joints = read_joints(&j, &self.buffers)?;
                let weights = read_floats(&w, &self.buffers, "WEIGHTS_0", Dimensions::Vec4, true)?;
                let weights = weights.chunks_exact(4).map(|w| [w[0], w[1], w[2], w[3]]).collect();
                Some(SkinWeights::new(joints, weights).map_err(|why| Fault::Malformed(format!("{what}: {why}")))?)
            }
            (Some(_), None) => return Err(Fault::Malformed(format!("{what} has JOINTS_0 but no WEIGHTS_0"))),
            (None, Some(_)) => return Err(Fault::Malformed(format!("{what} has WEIGHTS_0 but no JOINTS_0"))),
        };
        let mut morph_targets = Vec::new();
        let count = prim.get(&Semantic::Positions).map_or(0, |a| a.count());
        for (t, target) in prim.morph_targets().enumerate() {
            let positions = match target.positions() {
                Some(a) => read_vec3(&a, &self.buffers, &format!("morph target {t} POSITION"))?,
                None => vec![Vec3::ZERO; count],
            };
            let normals = target
                .normals()
                .map(|a| read_vec3(&a, &self.buffers, &format!("morph target {t} NORMAL")))
                .transpose()?;
            morph_targets.push(MorphTarget { positions, normals });
        }
        Ok((skin.is_some() || !morph_targets.is_empty()).then_some(Deformers { skin, morph_targets }))
    }

    /// Binds the skinned nodes of the loaded scene to their skins, and gives every node that draws morph
    /// targets its weights (the node's, else its mesh's, else zeros).
    pub(super) fn skins_and_weights(&mut self) -> Result<(), Fault> {
        let mut skins = vec![None; self.doc.skins().len()];
        for node in self.doc.nodes() {
            let index = node.index();
            if self.node_keys[index].is_none() {
                continue;
            }
            let Some(mesh) = node.mesh() else { continue };
            let prims = self.primitive_nodes[index].clone();
            if let Some(skin) = node.skin() {
                let key = match skins[skin.index()] {
                    Some(key) => key,
                    None => {
                        let key = self.skin(&skin)?;
                        skins[skin.index()] = Some(key);
                        key
                    }
                };
                for p in &prims {
                    self.scene
                        .set_skin(*p, Some(key))
                        .map_err(|e| Fault::Malformed(format!("node {index}, mesh {}: {e}", mesh.index())))?;
                }
            }
            let targets: Vec<usize> = mesh.primitives().map(|p| p.morph_targets().len()).collect();
            let Some(&n) = targets.iter().max().filter(|&&n| n > 0) else { continue };
            if targets.iter().any(|&t| t != n) {
                return Err(Fault::Malformed(format!(
                    "mesh {}: its primitives have {targets:?} morph targets, where glTF asks for as many each",
                    mesh.index()
                )));
            }
            let weights = node.weights().or_else(|| mesh.weights()).map_or_else(|| vec![0.0; n], <[f32]>::to_vec);
            if weights.len() != n {
                return Err(Fault::Malformed(format!(
                    "node {index}: {} morph weights for the {n} targets of mesh {}",
                    weights.len(),
                    mesh.index()
                )));
            }
            for p in &prims {
                self.scene.set_morph_weights(*p, weights.clone()).map_err(|e| Fault::Malformed(e.to_string()))?;
            }
        }
        Ok(())
    }

    /// A skin of the file as the scene's: every joint a node of the loaded scene, one inverse bind matrix
    /// each (the identity without an accessor).
    fn skin(&mut self, skin: &gltf::Skin) -> Result<crate::scene::SkinKey, Fault> {
        let name = skin.name().map_or_else(|| format!("skin {}", skin.index()), |n| format!("skin '{n}'"));
        let mut joints = Vec::new();
        for j in skin.joints() {
            let key = self.node_keys.get(j.index()).copied().flatten();
            joints.push(
                key.ok_or_else(|| Fault::Malformed(format!("{name}: joint node {} is not in the scene", j.index())))?,
            );
        }
        let inverse_bind_matrices = match skin.inverse_bind_matrices() {
            None => vec![Mat4::IDENTITY; joints.len()],
            Some(a) => {
                let m = read_floats(&a, &self.buffers, "inverseBindMatrices", Dimensions::Mat4, false)
                    .map_err(|e| Fault::Malformed(format!("{name}: {e}")))?;
                if m.len() / 16 < joints.len() {
                    return Err(Fault::Malformed(format!(
                        "{name}: {} inverse bind matrices for {} joints",
                        m.len() / 16,
                        joints.len()
                    )));
                }
                m.chunks_exact(16).take(joints.len()).map(Mat4::from_cols_slice).collect()
            }
        };
        self.scene
            .add_skin(Skin { name: name.clone(), joints, inverse_bind_matrices })
            .map_err(|e| Fault::Malformed(e.to_string()))
    }
}

/// `JOINTS_0`: four unsigned bytes or shorts a vertex.
fn read_joints(acc: &gltf::Accessor, buffers: &[Vec<u8>]) -> Result<Vec<[u16; 4]>, Fault> {
    if acc.dimensions() != Dimensions::Vec4
        || !matches!(acc.data_type(), DataType::U8 | DataType::U16)
        || acc.normalized()
    {
        return Err(Fault::WrongAccessor(format!(
            "JOINTS_0 accessor {} is {:?} of {:?}, expected Vec4 of U8 or U16",
            acc.index(),
            acc.dimensions(),
            acc.data_type()
        )));
    }
    let j = read_accessor(acc, buffers, "JOINTS_0")?;
    Ok(j.chunks_exact(4).map(|j| [j[0] as u16, j[1] as u16, j[2] as u16, j[3] as u16]).collect())
}
