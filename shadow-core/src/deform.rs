//! Meshes that deform: skin weights (glTF's `JOINTS_0`/`WEIGHTS_0`) and morph targets, and the posed
//! positions and normals they give.
//!
//! A posed vertex is computed in f32 in one fixed order, as glTF orders the two: first the morph targets,
//! the base plus each target's displacement times its weight, target after target; then the skin, the
//! sum over the vertex's four joints (in the order it lists them) of its weight times the joint's matrix
//! (the joint's world transform times its inverse bind matrix), applied to the morphed position. Normals
//! morph the same way and are skinned by that sum's cofactor matrix (its inverse transpose up to scale),
//! then normalized. Every vertex is independent, so the work runs in parallel and gives the same bits on
//! any number of threads.

use glam::{Mat3, Mat4, Vec3};
use rayon::prelude::*;

/// Which joints of a skin move each vertex, and how much: four joints a vertex, the weights summing to one.
#[derive(Clone, Debug, PartialEq)]
pub struct SkinWeights {
    joints: Vec<[u16; 4]>,
    weights: Vec<[f32; 4]>,
}

impl SkinWeights {
    /// Joints and weights of every vertex; the weights are normalized to sum to one (glTF asks files to
    /// store them so, and many store them nearly so), and a joint of weight zero is named 0 (as glTF
    /// asks: it moves nothing).
    ///
    /// # Errors
    /// Counts that differ, or a vertex whose weights are negative, not finite or sum to zero: says which.
    pub fn new(mut joints: Vec<[u16; 4]>, mut weights: Vec<[f32; 4]>) -> Result<Self, String> {
        if joints.len() != weights.len() {
            return Err(format!("{} vertices of joints but {} of weights", joints.len(), weights.len()));
        }
        for (j, w) in joints.iter_mut().zip(&weights) {
            for (j, w) in j.iter_mut().zip(w) {
                if *w == 0.0 {
                    *j = 0;
                }
            }
        }
        for (v, w) in weights.iter_mut().enumerate() {
            if w.iter().any(|x| !(x.is_finite() && *x >= 0.0)) {
                return Err(format!("vertex {v} has weights {w:?}, which must be finite and 0 or more"));
            }
            let sum: f32 = w.iter().sum();
            if sum <= 0.0 {
                return Err(format!("vertex {v}'s weights sum to zero: no joint moves it"));
            }
            *w = w.map(|x| x / sum);
        }
        Ok(Self { joints, weights })
    }

    /// The joints of each vertex, as indices into its skin's joints.
    #[must_use]
    pub fn joints(&self) -> &[[u16; 4]] {
        &self.joints
    }

    /// The weights of each vertex's joints.
    #[must_use]
    pub fn weights(&self) -> &[[f32; 4]] {
        &self.weights
    }

    /// The highest joint index a vertex names with a weight above zero (`None` when none does).
    #[must_use]
    pub fn max_joint(&self) -> Option<u16> {
        let used = self.joints.iter().zip(&self.weights).flat_map(|(j, w)| j.iter().zip(w).filter(|(_, w)| **w > 0.0));
        used.map(|(j, _)| *j).max()
    }

    /// Number of vertices.
    #[must_use]
    pub fn len(&self) -> usize {
        self.joints.len()
    }

    /// True without vertices.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.joints.is_empty()
    }
}

/// A morph target: a displacement of every vertex's position, and of its normal where given.
#[derive(Clone, Debug, PartialEq)]
pub struct MorphTarget {
    /// Position displacements, one a vertex.
    pub positions: Vec<Vec3>,
    /// Normal displacements, one a vertex, where the target has them.
    pub normals: Option<Vec<Vec3>>,
}

/// What a mesh deforms by: its skin weights and its morph targets, either or both.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Deformers {
    /// Joints and weights of each vertex.
    pub skin: Option<SkinWeights>,
    /// The morph targets, in the order weights name them.
    pub morph_targets: Vec<MorphTarget>,
}

/// The posed positions and normals of a mesh's vertices from its rest `positions` and `normals`: morphed
/// by `weights` (one a target; missing weights count as zero), then skinned by `joint_matrices` (each
/// joint's world transform times its inverse bind matrix) where given.
#[must_use]
pub fn pose(
    positions: &[Vec3],
    normals: &[Vec3],
    deformers: &Deformers,
    weights: &[f32],
    joint_matrices: Option<&[Mat4]>,
) -> (Vec<Vec3>, Vec<Vec3>) {
    const RUN: usize = 1024;
    let mut out_p = positions.to_vec();
    let mut out_n = normals.to_vec();
    let targets: Vec<(&MorphTarget, f32)> = deformers
        .morph_targets
        .iter()
        .zip(weights.iter().copied().chain(std::iter::repeat(0.0)))
        .filter(|(_, w)| *w != 0.0)
        .collect();
    let skin = joint_matrices.zip(deformers.skin.as_ref());
    out_p.par_chunks_mut(RUN).zip(out_n.par_chunks_mut(RUN)).enumerate().for_each(|(chunk, (ps, ns))| {
        for (k, (p, n)) in ps.iter_mut().zip(ns.iter_mut()).enumerate() {
            let v = chunk * RUN + k;
            for (target, w) in &targets {
                *p += target.positions[v] * *w;
                if let Some(tn) = &target.normals {
                    *n += tn[v] * *w;
                }
            }
            if let Some((matrices, skin)) = skin {
                let m = skin_matrix(matrices, skin.joints[v], skin.weights[v]);
                *p = m.transform_point3(*p);
                *n = cofactor(Mat3::from_mat4(m)) * *n;
            }
            *n = n.normalize_or_zero();
        }
    });
    (out_p, out_n)
}

/// The weighted sum of a vertex's joint matrices, in the order it names them. A joint index past the
/// matrices (which [`crate::Scene::set_skin`] refuses) counts as the identity.
fn skin_matrix(matrices: &[Mat4], joints: [u16; 4], weights: [f32; 4]) -> Mat4 {
    let mut m = Mat4::ZERO;
    for (j, w) in joints.iter().zip(weights) {
        if w != 0.0 {
            m += *matrices.get(usize::from(*j)).unwrap_or(&Mat4::IDENTITY) * w;
        }
    }
    m
}

/// The cofactor matrix: the inverse transpose times the determinant, which carries normals without a
/// division (its sign turned for a mirroring matrix, so normals keep their side).
fn cofactor(m: Mat3) -> Mat3 {
    let c = Mat3::from_cols(m.y_axis.cross(m.z_axis), m.z_axis.cross(m.x_axis), m.x_axis.cross(m.y_axis));
    if m.determinant() < 0.0 { -c } else { c }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn weights_are_normalized_and_bad_ones_refused() {
        let s = SkinWeights::new(vec![[0, 1, 0, 0]], vec![[1.0, 3.0, 0.0, 0.0]]).unwrap();
        assert_eq!(s.weights()[0], [0.25, 0.75, 0.0, 0.0]);
        assert_eq!(s.max_joint(), Some(1));
        let e = SkinWeights::new(vec![[0; 4], [0; 4]], vec![[1.0, 0.0, 0.0, 0.0], [0.0; 4]]).unwrap_err();
        assert!(e.contains("vertex 1's weights sum to zero"), "{e}");
        assert!(SkinWeights::new(vec![[0; 4]], vec![[-1.0, 2.0, 0.0, 0.0]]).is_err());
        assert!(SkinWeights::new(vec![[0; 4]], vec![]).is_err());
    }

    /// A morph by hand: the base moved by half the first target and twice the second; the skin after it
    /// by one joint that lifts by 1 along y.
    #[test]
    fn morphs_come_before_the_skin() {
        let deformers = Deformers {
            skin: Some(SkinWeights::new(vec![[0; 4]], vec![[1.0, 0.0, 0.0, 0.0]]).unwrap()),
            morph_targets: vec![
                MorphTarget { positions: vec![Vec3::new(2.0, 0.0, 0.0)], normals: None },
                MorphTarget {
                    positions: vec![Vec3::new(0.0, 0.0, 1.0)],
                    normals: Some(vec![Vec3::new(1.0, -1.0, 0.0)]),
                },
            ],
        };
        let lift = [Mat4::from_translation(Vec3::Y)];
        let (p, n) = pose(&[Vec3::ZERO], &[Vec3::Y], &deformers, &[0.5, 2.0], Some(&lift));
        assert_eq!(p[0], Vec3::new(1.0, 1.0, 2.0));
        // (0, 1, 0) + 2 (1, -1, 0) = (2, -1, 0), normalized; a translation leaves normals be.
        assert!((n[0] - Vec3::new(2.0, -1.0, 0.0).normalize()).length() < 1e-6, "{}", n[0]);
    }
}
