//! The focused body of a camera's view: the part of the view frustum inside the scene's bounds, as the
//! points whose convex hull it is. A map fitted to these points spends no texels on what the camera cannot
//! see or where nothing is (the sky above a street, the ground beyond the scene's end), the "focusing" that
//! light-space perspective maps start from.

use glam::{Mat4, Vec3};

use crate::bounds::Aabb;
use crate::scene::Camera;

/// The eight corners of the slice `[near, far]` of the view of `camera` (`aspect` wide per unit of
/// height): near face first, each face in the order (-x, -y), (+x, -y), (+x, +y), (-x, +y).
#[must_use]
pub fn frustum_corners(camera: &Camera, aspect: f32, near: f32, far: f32) -> [Vec3; 8] {
    let world_from_camera = camera.view_from_world().inverse();
    let tan_y = (camera.fov_y * 0.5).tan();
    let tan_x = tan_y * aspect;
    let corner = |k: usize| {
        let d = if k < 4 { near } else { far };
        let (sx, sy) = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)][k % 4];
        world_from_camera.transform_point3(Vec3::new(sx * tan_x * d, sy * tan_y * d, -d))
    };
    std::array::from_fn(corner)
}

/// A plane `n . p + d >= 0` bounding a convex body from inside.
#[derive(Clone, Copy, Debug)]
struct HalfSpace {
    n: Vec3,
    d: f32,
}

impl HalfSpace {
    fn distance(&self, p: Vec3) -> f32 {
        self.n.dot(p) + self.d
    }
}

/// The faces of a hexahedron given by eight corners ordered as [`frustum_corners`] (and as a box's
/// corners are taken below), each as four corners.
const FACES: [[usize; 4]; 6] = [[0, 1, 2, 3], [4, 5, 6, 7], [0, 1, 5, 4], [1, 2, 6, 5], [2, 3, 7, 6], [3, 0, 4, 7]];

/// The half-spaces of a convex hexahedron, each face's plane turned towards the centroid.
fn half_spaces(corners: &[Vec3; 8]) -> Vec<HalfSpace> {
    let centre = corners.iter().copied().sum::<Vec3>() / 8.0;
    FACES
        .iter()
        .filter_map(|f| {
            let (a, b, c, d) = (corners[f[0]], corners[f[1]], corners[f[2]], corners[f[3]]);
            // Newell's normal: robust for a quad whose corners are not exactly planar.
            let n = (b - a).cross(c - a) + (c - a).cross(d - a);
            let n = n.try_normalize()?;
            let mid = (a + b + c + d) / 4.0;
            let n = if n.dot(centre - mid) < 0.0 { -n } else { n };
            Some(HalfSpace { n, d: -n.dot(mid) })
        })
        .collect()
}

/// Sutherland-Hodgman: the part of a convex polygon inside every half-space.
fn clip_polygon(mut poly: Vec<Vec3>, planes: &[HalfSpace]) -> Vec<Vec3> {
    for plane in planes {
        if poly.is_empty() {
            break;
        }
        let mut out = Vec::with_capacity(poly.len() + 2);
        for (i, &a) in poly.iter().enumerate() {
            let b = poly[(i + 1) % poly.len()];
            let (da, db) = (plane.distance(a), plane.distance(b));
            if da >= 0.0 {
                out.push(a);
            }
            if (da >= 0.0) != (db >= 0.0) {
                out.push(a + (b - a) * (da / (da - db)));
            }
        }
        poly = out;
    }
    poly
}

/// The corners of a box in the order [`FACES`] takes them.
fn box_corners(b: &Aabb) -> [Vec3; 8] {
    let (lo, hi) = (b.min, b.max);
    [
        Vec3::new(lo.x, lo.y, lo.z),
        Vec3::new(hi.x, lo.y, lo.z),
        Vec3::new(hi.x, hi.y, lo.z),
        Vec3::new(lo.x, hi.y, lo.z),
        Vec3::new(lo.x, lo.y, hi.z),
        Vec3::new(hi.x, lo.y, hi.z),
        Vec3::new(hi.x, hi.y, hi.z),
        Vec3::new(lo.x, hi.y, hi.z),
    ]
}

/// The vertices of the intersection of two convex hexahedra: each one's faces clipped by the other's
/// half-spaces (every vertex of the intersection lies on a face of one of them, inside the other).
#[must_use]
pub fn intersect(a: &[Vec3; 8], b: &[Vec3; 8]) -> Vec<Vec3> {
    let mut points = Vec::new();
    for (body, other) in [(a, b), (b, a)] {
        let planes = half_spaces(other);
        for f in FACES {
            points.extend(clip_polygon(f.iter().map(|&k| body[k]).collect(), &planes));
        }
    }
    points
}

/// The focused body of the view of `camera` into a scene bounded by `bounds`: the vertices of the view
/// frustum from the near plane to `far`, cut by the box. Empty when the camera sees none of the box.
#[must_use]
pub fn focused_body(camera: &Camera, aspect: f32, far: f32, bounds: &Aabb) -> Vec<Vec3> {
    // Slightly larger than the box, so that the ground plane's zero thickness does not cut it away.
    let pad = bounds.size().max_element() * 1e-4 + 1e-5;
    let padded = Aabb::new(bounds.min - Vec3::splat(pad), bounds.max + Vec3::splat(pad));
    intersect(&frustum_corners(camera, aspect, camera.near, far), &box_corners(&padded))
}

/// The points transformed by `m`.
#[must_use]
pub fn transformed(points: &[Vec3], m: Mat4) -> Vec<Vec3> {
    points.iter().map(|&p| m.transform_point3(p)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_view_along_a_street_is_cut_to_the_street() {
        let bounds = Aabb::new(Vec3::new(-100.0, 0.0, -100.0), Vec3::new(100.0, 20.0, 100.0));
        let camera = Camera::look_at(Vec3::new(0.0, 1.7, 90.0), Vec3::new(0.0, 1.7, 0.0), 60.0);
        let body = focused_body(&camera, 16.0 / 9.0, 400.0, &bounds);
        assert!(!body.is_empty());
        let hull = Aabb::from_points(body.iter().copied());
        // Nothing above the scene's top or beyond its end, and the eye's neighbourhood is in.
        assert!(hull.max.y <= 20.05 && hull.min.z >= -100.05, "{hull:?}");
        assert!(hull.max.z > 89.9, "{hull:?}");
        // A camera looking away from the scene sees none of it.
        let away = Camera::look_at(Vec3::new(0.0, 1.7, 300.0), Vec3::new(0.0, 1.7, 400.0), 60.0);
        assert!(focused_body(&away, 1.0, 50.0, &bounds).is_empty());
    }

    #[test]
    fn a_frustum_inside_the_box_is_itself() {
        let bounds = Aabb::new(Vec3::splat(-100.0), Vec3::splat(100.0));
        let camera = Camera::look_at(Vec3::ZERO, Vec3::NEG_Z, 60.0);
        let corners = frustum_corners(&camera, 1.0, camera.near, 10.0);
        let body = focused_body(&camera, 1.0, 10.0, &bounds);
        for c in corners {
            assert!(body.iter().any(|p| (*p - c).length() < 1e-4), "corner {c} missing");
        }
    }
}
