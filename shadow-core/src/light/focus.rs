//! The focused body of a camera's view: the part of the view frustum inside the scene's bounds, as the
//! points whose convex hull it is. A map fitted to these points spends no texels on what the camera cannot
//! see or where nothing is (the sky above a street, the ground beyond the scene's end), the "focusing" that
//! light-space perspective maps start from.

use glam::camera::rh::proj::directx;
use glam::camera::rh::view::look_to_mat4;
use glam::{Mat4, Vec3};

use super::{LightProjection, safe_up};
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

/// The corners of a box in the order [`FACES`] takes them (each face's four in turn around it).
fn box_corners(b: &Aabb) -> [Vec3; 8] {
    let c = b.corners();
    [c[0], c[1], c[3], c[2], c[4], c[5], c[7], c[6]]
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

/// A box grown by a ten-thousandth of its size, so that a ground plane's zero thickness does not cut a
/// body away.
fn padded(b: &Aabb) -> Aabb {
    let pad = b.size().max_element() * 1e-4 + 1e-5;
    Aabb::new(b.min - Vec3::splat(pad), b.max + Vec3::splat(pad))
}

/// The focused body of the view of `camera` into a scene bounded by `bounds`: the vertices of the view
/// frustum's slice `[near, far]`, cut by the box. Empty when the camera sees none of the box.
#[must_use]
pub fn focused_body(camera: &Camera, aspect: f32, (near, far): (f32, f32), bounds: &Aabb) -> Vec<Vec3> {
    intersect(&frustum_corners(camera, aspect, near, far), &box_corners(&padded(bounds)))
}

/// The view depths the scene fills: the nearest and farthest view depth of any of `boxes` (the instances'
/// bounds) inside the view frustum, the camera's near plane to `far`. `None` when none is in view. This
/// is the near plane pushed out to the scene that perspective warps ask for: a camera at head height sees
/// no ground closer than a few metres, and a warp fitted from its 5 cm near plane spends its texels on
/// the air in front of the lens.
#[must_use]
pub fn visible_depth_range(camera: &Camera, aspect: f32, far: f32, boxes: &[Aabb]) -> Option<(f32, f32)> {
    let axis = (camera.target - camera.eye).normalize();
    let frustum = frustum_corners(camera, aspect, camera.near, far);
    let depth = |p: Vec3| (p - camera.eye).dot(axis);
    // Each box's corners bound the depths of its part in view; a box is cut by the frustum only when
    // those bounds could improve on the range found so far, nearest candidates first.
    let mut bounds: Vec<(f32, f32, &Aabb)> = boxes
        .iter()
        .filter(|b| !b.is_empty())
        .map(|b| {
            let d = b.corners().map(depth);
            (d.iter().copied().fold(f32::INFINITY, f32::min), d.iter().copied().fold(f32::NEG_INFINITY, f32::max), b)
        })
        .filter(|&(lo, hi, _)| hi >= camera.near && lo <= far)
        .collect();
    let in_view = |b: &Aabb| intersect(&frustum, &box_corners(&padded(b)));
    bounds.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut near = f32::INFINITY;
    for &(lo, _, b) in &bounds {
        if lo >= near {
            break;
        }
        near = in_view(b).into_iter().map(depth).fold(near, f32::min);
    }
    bounds.sort_by(|a, b| b.1.total_cmp(&a.1));
    let mut deepest = f32::NEG_INFINITY;
    for &(_, hi, b) in &bounds {
        if hi <= deepest {
            break;
        }
        deepest = in_view(b).into_iter().map(depth).fold(deepest, f32::max);
    }
    (near <= deepest).then(|| (near.max(camera.near), deepest.min(far)))
}

/// The smallest and largest of `values`.
#[must_use]
pub fn range(values: impl Iterator<Item = f32>) -> (f32, f32) {
    values.fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), v| (lo.min(v), hi.max(v)))
}

/// A range grown by a thousandth of its length at each end, so that points on its ends stay inside.
#[must_use]
pub fn padded_range((lo, hi): (f32, f32)) -> (f32, f32) {
    let pad = (hi - lo).abs() * 1e-3 + 1e-6;
    (lo - pad, hi + pad)
}

/// The uniform map of a directional light travelling along `direction`, focused: its window fitted to
/// the points of `body` seen along the light, its depth to everything in `bounds` (the casters above the
/// body). What the perspective warps become where they cannot help.
#[must_use]
pub fn focused_uniform(direction: Vec3, body: &[Vec3], bounds: &Aabb) -> LightProjection {
    let light_from_world = look_to_mat4(Vec3::ZERO, direction, safe_up(direction));
    let points = transformed(body, light_from_world);
    let (x0, x1) = padded_range(range(points.iter().map(|p| p.x)));
    let (y0, y1) = padded_range(range(points.iter().map(|p| p.y)));
    let scene = bounds.transformed(light_from_world);
    let (z_lo, z_hi) = padded_range((scene.min.z, scene.max.z));
    let (near, far) = super::orthographic_range(-z_hi, -z_lo);
    let proj = directx::orthographic(x0, x1, y0, y1, near, far);
    LightProjection::new(light_from_world, proj, near, far, true)
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
        let body = focused_body(&camera, 16.0 / 9.0, (camera.near, 400.0), &bounds);
        assert!(!body.is_empty());
        let hull = Aabb::from_points(body.iter().copied());
        // Nothing above the scene's top or beyond its end, and the eye's neighbourhood is in.
        assert!(hull.max.y <= 20.05 && hull.min.z >= -100.05, "{hull:?}");
        assert!(hull.max.z > 89.9, "{hull:?}");
        // A camera looking away from the scene sees none of it.
        let away = Camera::look_at(Vec3::new(0.0, 1.7, 300.0), Vec3::new(0.0, 1.7, 400.0), 60.0);
        assert!(focused_body(&away, 1.0, (away.near, 50.0), &bounds).is_empty());
    }

    #[test]
    fn the_visible_range_starts_where_the_ground_enters_the_view() {
        // Eye at 1.7 over a ground, looking level with a 60-degree field of view: the lowest rays meet
        // the ground 1.7 / tan(30 deg) away, at a view depth of that times cos(0) (the view is level).
        let ground = Aabb::new(Vec3::new(-100.0, 0.0, -100.0), Vec3::new(100.0, 0.0, 100.0));
        let post = Aabb::new(Vec3::new(-0.5, 0.0, 30.0), Vec3::new(0.5, 3.0, 31.0));
        let camera = Camera::look_at(Vec3::new(0.0, 1.7, 90.0), Vec3::new(0.0, 1.7, 0.0), 60.0);
        let (near, far) = visible_depth_range(&camera, 1.0, 1000.0, &[ground, post]).unwrap();
        let expected = 1.7 / 30f32.to_radians().tan();
        assert!((near - expected).abs() < 0.05, "{near} vs {expected}");
        assert!((far - 190.0).abs() < 0.1, "{far}");
        // Behind the camera, nothing.
        let behind = Aabb::new(Vec3::new(-1.0, 0.0, 95.0), Vec3::new(1.0, 2.0, 99.0));
        assert_eq!(visible_depth_range(&camera, 1.0, 1000.0, &[behind]), None);
    }

    #[test]
    fn a_frustum_inside_the_box_is_itself() {
        let bounds = Aabb::new(Vec3::splat(-100.0), Vec3::splat(100.0));
        let camera = Camera::look_at(Vec3::ZERO, Vec3::NEG_Z, 60.0);
        let corners = frustum_corners(&camera, 1.0, camera.near, 10.0);
        let body = focused_body(&camera, 1.0, (camera.near, 10.0), &bounds);
        for c in corners {
            assert!(body.iter().any(|p| (*p - c).length() < 1e-4), "corner {c} missing");
        }
    }
}
