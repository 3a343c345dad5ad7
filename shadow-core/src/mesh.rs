//! Triangle meshes: positions, per-vertex shading normals, optional texture coordinates and
//! counter-clockwise triangles, and for meshes that deform, their skin weights and morph targets.
//!
//! A [`Mesh`] is valid by construction: every index is in range, every position and normal is finite,
//! every coordinate within [`MAX_COORDINATE`], and at least one triangle has an area. Loaders and builders
//! go through [`Mesh::new`] or [`Mesh::with_normals`], so no backend ever sees a mesh that would rasterize
//! garbage.

use std::sync::Arc;

use glam::{Vec2, Vec3};

use crate::bounds::Aabb;
use crate::deform::Deformers;

/// The largest coordinate magnitude a mesh may hold: face normals and areas multiply coordinate
/// differences, so anything near the square root of `f32::MAX` (1.8e19) overflows to infinity and the
/// mesh's silhouettes and volumes come out empty; a margin of a hundred leaves room for sums of them.
pub const MAX_COORDINATE: f32 = 1e17;

/// Why a mesh was refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MeshError {
    /// No triangles at all.
    #[error("mesh has no triangles")]
    Empty,
    /// A triangle names a vertex that does not exist.
    #[error("triangle {triangle} uses vertex index {index}, but the mesh has {vertex_count} vertices")]
    IndexOutOfRange {
        /// Triangle number.
        triangle: usize,
        /// The bad index.
        index: u32,
        /// Number of vertices.
        vertex_count: usize,
    },
    /// A position or normal is NaN or infinite.
    #[error("vertex {vertex} has a non-finite {what} ({value})")]
    NonFinite {
        /// Vertex number.
        vertex: usize,
        /// "position", "normal" or "texture coordinate".
        what: &'static str,
        /// The offending value, printed.
        value: String,
    },
    /// A coordinate beyond [`MAX_COORDINATE`].
    #[error("vertex {vertex} has a position beyond +-{max:e} ({value}), too large for f32 geometry", max = MAX_COORDINATE)]
    TooLarge {
        /// Vertex number.
        vertex: usize,
        /// The position, printed.
        value: String,
    },
    /// Every triangle is degenerate: nothing would be drawn or cast a shadow.
    #[error("every one of its {0} triangles has zero area (in f32)")]
    NoArea(usize),
    /// Normals given, but not one per vertex.
    #[error("{normals} normals for {positions} positions")]
    NormalCount {
        /// Number of normals.
        normals: usize,
        /// Number of positions.
        positions: usize,
    },
    /// Texture coordinates given, but not one per vertex.
    #[error("{uvs} texture coordinates for {positions} positions")]
    UvCount {
        /// Number of texture coordinates.
        uvs: usize,
        /// Number of positions.
        positions: usize,
    },
    /// More vertices than a `u32` index can name.
    #[error("{0} vertices is more than 32-bit indices can address")]
    TooManyVertices(usize),
    /// Skin weights or a morph target not given one per vertex.
    #[error("{what}: {count} for {positions} positions")]
    DeformerCount {
        /// Which: skin weights, a morph target's positions or normals.
        what: String,
        /// How many were given.
        count: usize,
        /// Number of positions.
        positions: usize,
    },
}

/// An indexed triangle mesh with per-vertex normals and, for textured materials, texture coordinates.
/// Front faces wind counter-clockwise.
#[derive(Clone, Debug, PartialEq)]
pub struct Mesh {
    positions: Vec<Vec3>,
    normals: Vec<Vec3>,
    uvs: Option<Vec<Vec2>>,
    triangles: Vec<[u32; 3]>,
    /// The positions' bounds, kept with them: a frame reads them once per instance of the mesh.
    bounds: Aabb,
    /// Skin weights and morph targets, where it deforms.
    deformers: Option<Arc<Deformers>>,
}

impl Mesh {
    /// A mesh with area-weighted vertex normals computed from its triangles.
    ///
    /// # Errors
    /// See [`MeshError`].
    pub fn new(positions: Vec<Vec3>, triangles: Vec<[u32; 3]>) -> Result<Self, MeshError> {
        Self::check(&positions, &triangles)?;
        let normals = vertex_normals(&positions, &triangles);
        let bounds = Aabb::from_points(positions.iter().copied());
        Ok(Self { positions, normals, uvs: None, triangles, bounds, deformers: None })
    }

    /// A mesh with the given shading normals (normalized here; zero normals are replaced by computed ones).
    ///
    /// # Errors
    /// See [`MeshError`].
    pub fn with_normals(positions: Vec<Vec3>, normals: Vec<Vec3>, triangles: Vec<[u32; 3]>) -> Result<Self, MeshError> {
        Self::check(&positions, &triangles)?;
        if normals.len() != positions.len() {
            return Err(MeshError::NormalCount { normals: normals.len(), positions: positions.len() });
        }
        if let Some((vertex, n)) = normals.iter().enumerate().find(|(_, n)| !n.is_finite()) {
            return Err(MeshError::NonFinite { vertex, what: "normal", value: format!("{n}") });
        }
        let computed = vertex_normals(&positions, &triangles);
        let normals = normals.iter().zip(&computed).map(|(n, c)| n.try_normalize().unwrap_or(*c)).collect();
        let bounds = Aabb::from_points(positions.iter().copied());
        Ok(Self { positions, normals, uvs: None, triangles, bounds, deformers: None })
    }

    /// The mesh with texture coordinates, one per vertex (glTF's `TEXCOORD_n`: u to the right, v down
    /// the image from its top).
    ///
    /// # Errors
    /// [`MeshError::UvCount`] when there is not one per vertex, [`MeshError::NonFinite`] for NaN or
    /// infinity.
    pub fn with_uvs(mut self, uvs: Vec<Vec2>) -> Result<Self, MeshError> {
        if uvs.len() != self.positions.len() {
            return Err(MeshError::UvCount { uvs: uvs.len(), positions: self.positions.len() });
        }
        if let Some((vertex, uv)) = uvs.iter().enumerate().find(|(_, uv)| !uv.is_finite()) {
            return Err(MeshError::NonFinite { vertex, what: "texture coordinate", value: format!("{uv}") });
        }
        self.uvs = Some(uvs);
        Ok(self)
    }

    /// The mesh with what it deforms by: skin weights and morph targets, one per vertex each.
    ///
    /// # Errors
    /// [`MeshError::DeformerCount`] for a count that is not the vertex count, [`MeshError::NonFinite`]
    /// for a displacement that is not finite.
    pub fn with_deformers(mut self, deformers: Deformers) -> Result<Self, MeshError> {
        let positions = self.positions.len();
        let count = |what: String, count: usize| {
            if count == positions { Ok(()) } else { Err(MeshError::DeformerCount { what, count, positions }) }
        };
        if let Some(skin) = &deformers.skin {
            count("skin weights".into(), skin.len())?;
        }
        for (t, target) in deformers.morph_targets.iter().enumerate() {
            count(format!("morph target {t}'s positions"), target.positions.len())?;
            let normals = target.normals.iter().flatten();
            if let Some(n) = &target.normals {
                count(format!("morph target {t}'s normals"), n.len())?;
            }
            if let Some((vertex, d)) = target.positions.iter().chain(normals).enumerate().find(|(_, d)| !d.is_finite())
            {
                let what = "morph target displacement";
                return Err(MeshError::NonFinite { vertex: vertex % positions, what, value: format!("{d}") });
            }
        }
        self.deformers = Some(Arc::new(deformers));
        Ok(self)
    }

    /// Its skin weights and morph targets, where it deforms.
    #[must_use]
    pub fn deformers(&self) -> Option<&Deformers> {
        self.deformers.as_deref()
    }

    /// The mesh posed: the same triangles and texture coordinates over posed positions and normals (one
    /// a vertex, finite), with no deformers of its own.
    pub(crate) fn posed(&self, positions: Vec<Vec3>, normals: Vec<Vec3>) -> Self {
        debug_assert_eq!(positions.len(), self.positions.len());
        Self {
            bounds: Aabb::from_points(positions.iter().copied()),
            positions,
            normals,
            uvs: self.uvs.clone(),
            triangles: self.triangles.clone(),
            deformers: None,
        }
    }

    fn check(positions: &[Vec3], triangles: &[[u32; 3]]) -> Result<(), MeshError> {
        if triangles.is_empty() {
            return Err(MeshError::Empty);
        }
        if positions.len() > u32::MAX as usize {
            return Err(MeshError::TooManyVertices(positions.len()));
        }
        if let Some((vertex, p)) = positions.iter().enumerate().find(|(_, p)| !p.is_finite()) {
            return Err(MeshError::NonFinite { vertex, what: "position", value: format!("{p}") });
        }
        if let Some((vertex, p)) = positions.iter().enumerate().find(|(_, p)| p.abs().max_element() > MAX_COORDINATE) {
            return Err(MeshError::TooLarge { vertex, value: format!("{p}") });
        }
        let n = positions.len();
        for (triangle, t) in triangles.iter().enumerate() {
            if let Some(&index) = t.iter().find(|&&i| i as usize >= n) {
                return Err(MeshError::IndexOutOfRange { triangle, index, vertex_count: n });
            }
        }
        if triangles.iter().all(|t| face_normal(t.map(|i| positions[i as usize])) == Vec3::ZERO) {
            return Err(MeshError::NoArea(triangles.len()));
        }
        Ok(())
    }

    /// Vertex positions.
    #[must_use]
    pub fn positions(&self) -> &[Vec3] {
        &self.positions
    }

    /// Unit shading normals, one per vertex.
    #[must_use]
    pub fn normals(&self) -> &[Vec3] {
        &self.normals
    }

    /// Texture coordinates, one per vertex, where the mesh has them.
    #[must_use]
    pub fn uvs(&self) -> Option<&[Vec2]> {
        self.uvs.as_deref()
    }

    /// Triangles as vertex indices, counter-clockwise seen from the front.
    #[must_use]
    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.triangles
    }

    /// Number of triangles.
    #[must_use]
    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }

    /// Bytes its geometry holds: positions, normals, texture coordinates and triangles.
    #[must_use]
    pub fn geometry_bytes(&self) -> usize {
        let vertex = 2 * size_of::<Vec3>() + self.uvs.as_ref().map_or(0, |_| size_of::<Vec2>());
        self.positions.len() * vertex + self.triangles.len() * size_of::<[u32; 3]>()
    }

    /// The three corner positions of triangle `t`.
    #[must_use]
    pub fn triangle_positions(&self, t: usize) -> [Vec3; 3] {
        self.triangles[t].map(|i| self.positions[i as usize])
    }

    /// Bounding box of the positions.
    #[must_use]
    pub fn bounds(&self) -> Aabb {
        self.bounds
    }

    /// A copy with every position and normal moved by an affine transform (normals by its inverse transpose).
    /// A mirroring transform reverses the triangles so they stay counter-clockwise outside. The copy is
    /// static: it keeps no skin weights or morph targets (as an appended mesh keeps none).
    #[must_use]
    pub fn transformed(&self, m: glam::Mat4) -> Self {
        let normal_m = crate::affine::normal_matrix(m);
        let mirror = glam::Mat3::from_mat4(m).determinant() < 0.0;
        let positions: Vec<Vec3> = self.positions.iter().map(|&p| m.transform_point3(p)).collect();
        Self {
            bounds: Aabb::from_points(positions.iter().copied()),
            positions,
            normals: self.normals.iter().map(|&n| (normal_m * n).normalize_or_zero()).collect(),
            uvs: self.uvs.clone(),
            deformers: None,
            triangles: if mirror {
                self.triangles.iter().map(|&[a, b, c]| [a, c, b]).collect()
            } else {
                self.triangles.clone()
            },
        }
    }

    /// Appends another mesh's vertices and triangles. Where only one of the two has texture
    /// coordinates, the other's vertices get (0, 0). The result is static: it keeps no skin weights or
    /// morph targets.
    ///
    /// # Errors
    /// [`MeshError::TooManyVertices`] when the two together have more vertices than 32-bit indices can
    /// address (the mesh is left as it was).
    pub fn append(&mut self, other: &Mesh) -> Result<(), MeshError> {
        let base = appended_base(self.positions.len(), other.positions.len())?;
        self.positions.extend_from_slice(&other.positions);
        self.normals.extend_from_slice(&other.normals);
        if self.uvs.is_some() || other.uvs.is_some() {
            let (have, more) = (self.positions.len() - other.positions.len(), other.positions.len());
            let uvs = self.uvs.get_or_insert_with(|| vec![Vec2::ZERO; have]);
            match &other.uvs {
                Some(o) => uvs.extend_from_slice(o),
                None => uvs.resize(have + more, Vec2::ZERO),
            }
        }
        self.triangles.extend(other.triangles.iter().map(|t| t.map(|i| i + base)));
        self.bounds = self.bounds.union(other.bounds);
        self.deformers = None;
        Ok(())
    }

    /// Several meshes as one.
    ///
    /// # Errors
    /// [`MeshError::Empty`] when `parts` is empty, [`MeshError::TooManyVertices`] past 32-bit indices.
    pub fn merged<'a>(parts: impl IntoIterator<Item = &'a Mesh>) -> Result<Self, MeshError> {
        let mut parts = parts.into_iter();
        let mut out = parts.next().ok_or(MeshError::Empty)?.clone();
        for p in parts {
            out.append(p)?;
        }
        Ok(out)
    }
}

/// The index of the first vertex appended to a mesh of `have` vertices, `more` of them: both together
/// must be addressable by 32-bit indices, as [`Mesh::new`] requires of one mesh.
fn appended_base(have: usize, more: usize) -> Result<u32, MeshError> {
    match have.checked_add(more) {
        Some(total) if total <= u32::MAX as usize => Ok(have as u32),
        total => Err(MeshError::TooManyVertices(total.unwrap_or(usize::MAX))),
    }
}

/// Unnormalized face normal (twice the area, pointing out of the counter-clockwise side).
#[must_use]
pub fn face_normal([a, b, c]: [Vec3; 3]) -> Vec3 {
    (b - a).cross(c - a)
}

/// `n` scaled by the power of two that brings its largest component into [1, 2): the same direction, in a
/// range where products of it with unit-sized vectors, and its length, neither overflow nor underflow.
///
/// A face normal's length is the square of the mesh's size: from coordinates of about 1e10 its squared
/// length passes f32's range (3.4e38), and a normal matrix undoing a small staging scale multiplies it
/// further. Scaling by a power of two is exact and every product and sum made of the result scales by the
/// same power, so a sign read from it, or the unit vector made of it, is bit for bit what the raw normal
/// gives wherever that did not overflow. Normals too small to scale into range unharmed (subnormal
/// components) are left as they are.
#[must_use]
pub fn power_of_two_unit(n: Vec3) -> Vec3 {
    let largest = n.abs().max_element();
    if !(largest.is_normal() && largest.is_finite()) {
        return n;
    }
    // largest = 2^e * m with m in [1, 2); 2^-e is a normal f32 for every e of a normal f32 but the top one.
    let e = ((largest.to_bits() >> 23) & 0xff) as i32 - 127;
    if e >= 127 {
        return n;
    }
    n * f32::from_bits(((127 - e) as u32) << 23)
}

/// Each vertex's normal: the area-weighted mean of its faces' normals.
fn vertex_normals(positions: &[Vec3], triangles: &[[u32; 3]]) -> Vec<Vec3> {
    let mut normals = vec![Vec3::ZERO; positions.len()];
    for t in triangles {
        let n = face_normal(t.map(|i| positions[i as usize]));
        for &i in t {
            normals[i as usize] += n;
        }
    }
    normals.iter().map(|&n| power_of_two_unit(n).normalize_or(Vec3::Y)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn appending_keeps_to_32_bit_indices() {
        let a = Mesh::new(vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![[0, 1, 2]]).expect("a");
        let b = a.transformed(glam::Mat4::from_translation(Vec3::Z));
        let both = Mesh::merged([&a, &b]).expect("two triangles");
        assert_eq!(both.triangles(), &[[0, 1, 2], [3, 4, 5]]);
        assert_eq!(both.bounds(), a.bounds().union(b.bounds()));
        // Past u32 indices (too large to build here): refused with the count, not wrapped.
        let most = u32::MAX as usize;
        assert_eq!(appended_base(most - 1, 1), Ok(most as u32 - 1));
        assert_eq!(appended_base(most, 1), Err(MeshError::TooManyVertices(most + 1)));
        assert_eq!(appended_base(usize::MAX, 1), Err(MeshError::TooManyVertices(usize::MAX)));
    }

    #[test]
    fn vertex_normals_hold_at_the_largest_coordinates() {
        // A face normal's squared length passes f32's range here: the normals must still be the face's.
        for size in [1e14, MAX_COORDINATE] {
            let m = Mesh::new(vec![Vec3::ZERO, Vec3::X * size, Vec3::Y * size], vec![[0, 1, 2]]).expect("triangle");
            assert!(m.normals().iter().all(|&n| n == Vec3::Z), "side {size:e}: {:?}", m.normals());
        }
    }

    #[test]
    fn refuses_bad_meshes() {
        let p = vec![Vec3::ZERO, Vec3::X, Vec3::Y];
        assert_eq!(Mesh::new(p.clone(), vec![]), Err(MeshError::Empty));
        assert!(matches!(Mesh::new(p.clone(), vec![[0, 1, 3]]), Err(MeshError::IndexOutOfRange { index: 3, .. })));
        let mut nan = p.clone();
        nan[1].y = f32::NAN;
        assert!(matches!(Mesh::new(nan, vec![[0, 1, 2]]), Err(MeshError::NonFinite { vertex: 1, .. })));
        // Finite but past f32's square root: its face normal would be infinite.
        let huge = vec![Vec3::ZERO, Vec3::X * 1e38, Vec3::Y * 1e38];
        assert!(!face_normal([huge[0], huge[1], huge[2]]).is_finite());
        assert!(matches!(Mesh::new(huge, vec![[0, 1, 2]]), Err(MeshError::TooLarge { vertex: 1, .. })));
        let big = vec![Vec3::ZERO, Vec3::X * MAX_COORDINATE, Vec3::Y * MAX_COORDINATE];
        assert!(face_normal([big[0], big[1], big[2]]).is_finite());
        assert!(Mesh::new(big, vec![[0, 1, 2]]).is_ok());
        let flat = vec![Vec3::ZERO, Vec3::X, Vec3::X * 2.0];
        assert_eq!(Mesh::new(flat.clone(), vec![[0, 1, 2], [0, 0, 1]]), Err(MeshError::NoArea(2)));
        assert!(Mesh::new([flat, vec![Vec3::Y]].concat(), vec![[0, 1, 2], [0, 1, 3]]).is_ok());
        let m = Mesh::new(p, vec![[0, 1, 2]]).unwrap();
        assert_eq!(m.normals()[0], Vec3::Z);
    }

    #[test]
    fn mirroring_keeps_outside_ccw() {
        let m = Mesh::new(vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![[0, 1, 2]]).unwrap();
        let t = m.transformed(glam::Mat4::from_scale(Vec3::new(-1.0, 1.0, 1.0)));
        assert!(face_normal(t.triangle_positions(0)).z > 0.0);
        assert!(t.normals()[0].z > 0.0);
    }
}
