//! Inverses of the affine transforms that place meshes, computed so they hold at every scale the loaders
//! accept.
//!
//! A model in kilometres-as-millimetres (coordinates near [`MAX_COORDINATE`](crate::mesh::MAX_COORDINATE))
//! is staged with a scale near 1e-17; the determinant of that scale is 1e-51, far below f32's smallest
//! normal number, so an f32 inverse divides by a flushed or subnormal determinant and overflows. Such an
//! inverse is taken in f64, where the determinant of any accepted transform is a normal number, and
//! rounded back to f32, where the inverse's entries (near 1e17) fit. Transforms whose determinant is a
//! normal f32 (every transform of ordinary scale) keep f32's own inverse, the one the rest of the frame's
//! f32 arithmetic is consistent with: rounding the f64 inverse instead moves a facing test that lies
//! within an ulp of zero.

use glam::{Mat3, Mat4};

/// The inverse of an affine transform (the world-from-local of an instance gives its local-from-world).
#[must_use]
pub fn inverse(m: Mat4) -> Mat4 {
    if m.determinant().is_normal() {
        let inv = m.inverse();
        if inv.is_finite() {
            return inv;
        }
    }
    m.as_dmat4().inverse().as_mat4()
}

/// The normal matrix of an affine transform: the inverse transpose of its linear part, which keeps
/// normals perpendicular to transformed surfaces. Normalize the normals it gives.
#[must_use]
pub fn normal_matrix(m: Mat4) -> Mat3 {
    let linear = Mat3::from_mat4(m);
    if linear.determinant().is_normal() {
        let inv = linear.inverse();
        if inv.is_finite() {
            return inv.transpose();
        }
    }
    glam::DMat3::from_mat4(m.as_dmat4()).inverse().transpose().as_mat3()
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;

    #[test]
    fn inverses_hold_at_the_extremes_of_accepted_scales() {
        for scale in [1e-17f32, 1e-13, 1.0, 1e13, 1e17] {
            // As staging places a model of size 1 / scale: the offset and the points are at its scale.
            let offset = Vec3::new(3.0, -2.0, 5.0) / scale;
            let m = Mat4::from_scale(Vec3::splat(scale)) * Mat4::from_translation(offset);
            let inv = inverse(m);
            assert!(inv.is_finite(), "scale {scale}");
            let p = Vec3::new(0.25, 0.5, -1.0) / scale;
            let back = inv.transform_point3(m.transform_point3(p));
            assert!(((back - p) * scale).abs().max_element() < 1e-5, "scale {scale}: {p} -> {back}");
            let n = (normal_matrix(m) * Vec3::X).normalize();
            assert!((n - Vec3::X).length() < 1e-6, "scale {scale}: {n}");
        }
        // f32's own inverse fails at the small end: the case this module exists for.
        let tiny = Mat4::from_scale(Vec3::splat(1e-17));
        assert!(!tiny.inverse().is_finite(), "f32's inverse now holds at 1e-17: the f64 detour may go");
    }
}
