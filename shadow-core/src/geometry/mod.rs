//! Shadow geometry shared by both backends: pure functions over plain data, written once.
//!
//! - [`adjacency`]: weld coincident positions (`weld`), map edges to faces, classify manifold, boundary and
//!   non-manifold edges, and decide whether a mesh is closed.
//! - [`silhouette`]: the silhouette edges of a mesh for one light, with Bergeron weights for open meshes;
//!   `facing` decides the facing of whole runs of faces at once, so it reads only faces near the
//!   silhouette.
//! - [`volume`]: extrusion of silhouettes to infinity (w = 0) and the front and back caps.

pub mod adjacency;
mod facing;
pub mod silhouette;
pub mod volume;
mod weld;

#[cfg(test)]
mod proptests;

use glam::{Vec3, Vec4};

/// A light as the geometry kernels see it, in the same space as the mesh positions.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LightSource {
    /// A point (or spot) light at this position.
    Point(Vec3),
    /// Parallel light travelling along this direction.
    Directional(Vec3),
}

impl LightSource {
    /// The same light seen from a space whose transform from this one is `m` (affine).
    #[must_use]
    pub fn transformed(&self, m: glam::Mat4) -> Self {
        match *self {
            Self::Point(p) => Self::Point(m.transform_point3(p)),
            Self::Directional(d) => Self::Directional(m.transform_vector3(d)),
        }
    }

    /// The light as a homogeneous point: its position (w = 1), or for parallel light the point at infinity
    /// its rays meet at (w = 0).
    #[must_use]
    pub fn homogeneous(&self) -> Vec4 {
        match *self {
            Self::Point(l) => l.extend(1.0),
            Self::Directional(d) => d.extend(0.0),
        }
    }

    /// Where the ray from the light through `p` ends: the homogeneous point at infinity (w = 0).
    #[must_use]
    pub fn extrude(&self, p: Vec3) -> Vec4 {
        match *self {
            Self::Point(l) => (p - l).extend(0.0),
            Self::Directional(d) => d.extend(0.0),
        }
    }

    /// Signed facing of a plane `(n, d)` (points x with n.x + d = 0) towards the light: positive when the
    /// side the normal points to sees the light.
    #[must_use]
    pub fn facing(&self, plane: Vec4) -> f32 {
        match *self {
            Self::Point(l) => plane.truncate().dot(l) + plane.w,
            Self::Directional(d) => -plane.truncate().dot(d),
        }
    }
}
