//! Perspective shadow maps (Stamminger and Drettakis 2002; survey: Nealen 2005, section 4) for a
//! directional light: the map is rendered and looked up in the camera's post-perspective space, where the
//! view is an orthographic look at a unit cube and near objects are as large as the screen shows them, so
//! the map's texels per screen pixel stay near constant (the survey's `r_s / r_i`).
//!
//! Three things make it work, each handled here:
//! - **The light after the transform.** A directional light is a point at infinity, `(-l, 0)`; the
//!   camera's projection takes it to `M (-l, 0)`, whose `w` is the depth of `-l` along the view. Where
//!   that is 0 (the light across the view) the light stays directional; where it is positive (the sun in
//!   front of the camera) it becomes a point light at the vanishing point of its rays; where negative (the
//!   sun behind the camera) an *inverted* point light, a point the rays run towards, whose depth order
//!   is reversed: the map keeps the farthest from that point.
//! - **Casters behind the eye.** Only points in front of the camera's eye plane keep their order after
//!   the projection, yet a sun behind the camera casts shadows of what is behind it. The projection is
//!   made for a *virtual camera* moved back along the view until every caster that can shadow a visible
//!   receiver (the focused body extruded towards the light to the scene's end) lies in front of its near
//!   plane. The further back, the weaker the warp: the technique converges to the uniform map, as the
//!   survey warns it can.
//! - **A light inside the view.** Facing the sun (the duelling frusta), the point light sits just beyond
//!   the unit cube's far face and would have to see the whole cube from there, over more than a
//!   half-space. Past [`MAX_HALF_ANGLE`] off its axis the map falls back to the uniform map, focused.
//!
//! The map's depth is the post-perspective light's own (perspective, or orthographic for the light that
//! stays directional), biased by the rasterizer as `shadow-map` biases it: a constant offset in that depth,
//! as the survey describes for PSMs, plus the slope-scaled term, which, measured per triangle in the
//! warped map's texels, follows the warp.

use glam::camera::rh::proj::directx;
use glam::camera::rh::view::look_to_mat4;
use glam::{Vec3, Vec4Swizzles};

use super::focus::{focused_body, focused_uniform, padded_range, range, visible_depth_range};
use super::{LightProjection, LightView, safe_up};
use crate::bounds::Aabb;
use crate::scene::{Camera, LightKind};

/// The widest angle off its axis a post-perspective point light's map may see (a 150-degree cone):
/// beyond it the map's outer texels stretch without bound and the uniform map is better.
pub const MAX_HALF_ANGLE: f32 = 75.0;

/// What the light became in post-perspective space.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PostPerspectiveLight {
    /// Across the view: still directional.
    Directional,
    /// In front of the camera: a point light at its rays' vanishing point.
    Point,
    /// Behind the camera: a point its rays converge on, with depth order reversed.
    InvertedPoint,
}

/// How one frame's perspective shadow map was made.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PsmFit {
    /// How far the virtual camera moved back from the eye, in scene units.
    pub shift: f32,
    /// The virtual camera's near and far planes.
    pub near: f32,
    /// Far plane.
    pub far: f32,
    /// The light after the transform.
    pub light: PostPerspectiveLight,
    /// Whether the map is the uniform one instead (the post-perspective light sees the scene over more
    /// than [`MAX_HALF_ANGLE`]).
    pub uniform: bool,
}

/// Where a ray from `p` along `d` leaves the box `b` (the distance along `d`, at least 0).
fn exit_distance(p: Vec3, d: Vec3, b: &Aabb) -> f32 {
    (0..3)
        .filter(|&i| d[i].abs() > 1e-9)
        .map(|i| {
            let bound = if d[i] > 0.0 { b.max[i] } else { b.min[i] };
            ((bound - p[i]) / d[i]).max(0.0)
        })
        .fold(f32::INFINITY, f32::min)
}

impl LightView {
    /// The perspective shadow map of a directional light for the view of `camera` (`aspect` wide per
    /// unit of height) into a scene of instances bounded by `boxes`, with how it was made (`None` when
    /// nothing is in view and the light's own view is returned). Any other light's view is returned
    /// unchanged.
    #[must_use]
    pub fn perspective_shadow_map(&self, camera: &Camera, aspect: f32, boxes: &[Aabb]) -> (Self, Option<PsmFit>) {
        let LightKind::Directional { direction } = self.light.kind else { return (self.clone(), None) };
        let l = direction.normalize();
        let v = (camera.target - camera.eye).normalize();
        let bounds = boxes.iter().fold(Aabb::EMPTY, |a, b| a.union(*b));
        let deepest = bounds.corners().iter().map(|&c| (c - camera.eye).dot(v)).fold(0.0f32, f32::max);
        let Some((z_n, z_f)) = visible_depth_range(camera, aspect, deepest.max(camera.near * 2.0), boxes) else {
            return (self.clone(), None);
        };
        let body = focused_body(camera, aspect, (z_n, z_f.max(z_n * 1.001)), &bounds);
        if body.is_empty() {
            return (self.clone(), None);
        }
        // Every caster of a visible receiver lies between it and where its ray towards the light leaves
        // the scene: the body and its extrusion hold them all.
        let hull: Vec<Vec3> = body.iter().flat_map(|&b| [b, b - l * exit_distance(b, -l, &bounds)]).collect();
        let (nearest, _) = range(hull.iter().map(|&p| (p - camera.eye).dot(v)));
        // The virtual camera: moved back until the nearest caster is as far in front of it as the nearest
        // visible receiver is in front of the eye, so the warp of an unobstructed view is kept whole.
        let shift = (z_n - nearest).max(0.0);
        let eye = camera.eye - v * shift;
        let (_, far) = range(hull.iter().map(|&p| (p - eye).dot(v)));
        let (near, far) = (z_n, far * 1.001);
        let up = if v.cross(camera.up).length_squared() < 1e-8 { Vec3::Z } else { camera.up };
        let pps_from_world = directx::perspective(camera.fov_y, aspect, near, far) * look_to_mat4(eye, v, up);
        let points: Vec<Vec3> = hull.iter().map(|&p| pps_from_world.project_point3(p)).collect();
        let bounds_pps = Aabb::from_points(points.iter().copied());
        let centre = bounds_pps.center();
        let fit = |kind, uniform| PsmFit { shift, near, far, light: kind, uniform };
        let light = pps_from_world * (-l).extend(0.0);
        let kind = if light.w > 0.0 { PostPerspectiveLight::Point } else { PostPerspectiveLight::InvertedPoint };
        match light_in_post_perspective(light, centre, &points) {
            Some((clip_from_pps, spread)) => {
                let kind = if spread < PARALLEL { PostPerspectiveLight::Directional } else { kind };
                let orthographic = kind == PostPerspectiveLight::Directional;
                let projection = LightProjection::new(pps_from_world, clip_from_pps, near, far, orthographic);
                (Self { projections: vec![projection], ..self.clone() }, Some(fit(kind, false)))
            }
            None => {
                let view = Self { projections: vec![focused_uniform(l, &body, &bounds)], ..self.clone() };
                (view, Some(fit(kind, true)))
            }
        }
    }
}

/// Rays within this tangent of each other over the scene are parallel: the light is still directional.
const PARALLEL: f32 = 1e-4;

/// The light's map in post-perspective space, for the light at the homogeneous point `light` (`xyz`
/// towards it, `w` of either sign or 0) and the points `points` around `centre` that it must hold: the
/// clip matrix of post-perspective points, and the largest tangent of a ray's angle off the map's axis.
/// `None` when a point lies behind the light or further off its axis than [`MAX_HALF_ANGLE`].
///
/// One form serves the three kinds of light, without dividing by `w`: with `r(q) = w q - xyz` (the ray
/// from the light to `q`, times `w`), the axis `a` along `r(centre)` and `e1`, `e2` across it, a point's
/// map coordinates are `e_i . (q - centre) / (a . r(q))` (for `w` = 0 the orthographic map along `-xyz`,
/// otherwise the central projection from `xyz / w` scaled by `1 / w`), and its depth is
/// `a . (q - centre) / (a . r(q))`, which grows along every ray away from the light: from a point light
/// away from it, towards an inverted one (the farthest from it is the nearest to the light), and for a
/// directional one along its travel.
fn light_in_post_perspective(light: glam::Vec4, centre: Vec3, points: &[Vec3]) -> Option<(glam::Mat4, f32)> {
    let r = |q: Vec3| q * light.w - light.xyz();
    let a = r(centre).try_normalize()?;
    let e1 = safe_up(a).cross(a).normalize();
    let e2 = a.cross(e1);
    let w_row = (a * light.w).extend(-a.dot(light.xyz()));
    let mut spread = 0.0f32;
    let empty = [f32::INFINITY, f32::NEG_INFINITY];
    let (mut x, mut y, mut z) = (empty, empty, empty);
    for &q in points {
        let along = a.dot(r(q));
        if along <= 0.0 {
            return None;
        }
        let (across1, across2) = (e1.dot(q - centre), e2.dot(q - centre));
        spread = spread.max(light.w.abs() * across1.abs().max(across2.abs()) / along);
        for (range, v) in [(&mut x, across1 / along), (&mut y, across2 / along), (&mut z, a.dot(q - centre) / along)] {
            *range = [range[0].min(v), range[1].max(v)];
        }
    }
    // NaN (a degenerate point) fails too.
    if spread.is_nan() || spread >= MAX_HALF_ANGLE.to_radians().tan() {
        return None;
    }
    // Each NDC coordinate is k v + o over the range of v; its clip row is k (plane) + o w_row.
    let row = |plane: glam::Vec4, [lo, hi]: [f32; 2], (to_lo, to_hi): (f32, f32)| {
        let (lo, hi) = padded_range((lo, hi));
        let k = (to_hi - to_lo) / (hi - lo);
        plane * k + w_row * (to_lo - k * lo)
    };
    let plane = |n: Vec3| n.extend(-n.dot(centre));
    let rows = [row(plane(e1), x, (-1.0, 1.0)), row(plane(e2), y, (-1.0, 1.0)), row(plane(a), z, (0.0, 1.0)), w_row];
    Some((glam::Mat4::from_cols(rows[0], rows[1], rows[2], rows[3]).transpose(), spread))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Light;
    use glam::Mat4;

    /// `m` applied to `p` as a homogeneous point, divided.
    fn apply(m: Mat4, p: Vec3) -> Vec3 {
        m.project_point3(p)
    }

    fn street() -> Vec<Aabb> {
        vec![
            Aabb::new(Vec3::new(-100.0, 0.0, -100.0), Vec3::new(100.0, 0.0, 100.0)),
            Aabb::new(Vec3::new(-30.0, 0.0, -20.0), Vec3::new(-10.0, 20.0, 60.0)),
            Aabb::new(Vec3::new(10.0, 0.0, 40.0), Vec3::new(20.0, 12.0, 120.0).min(Vec3::splat(100.0))),
        ]
    }

    /// Casters above receivers, on the light's ray through them, land on the receiver's texel with a
    /// smaller depth, whatever the light became.
    #[test]
    fn casters_are_nearer_the_light_than_their_receivers() {
        let camera = Camera::look_at(Vec3::new(3.0, 1.7, 90.0), Vec3::new(3.0, 1.7, 0.0), 60.0);
        // Across the view; facing the camera low (inside the view: uniform) and high; behind it.
        let cases = [
            (Vec3::new(0.94, -0.34, 0.0), PostPerspectiveLight::Directional, false),
            (Vec3::new(0.2, -0.34, 0.92), PostPerspectiveLight::Point, true),
            (Vec3::new(0.2, -0.8, 0.56), PostPerspectiveLight::Point, false),
            (Vec3::new(0.2, -0.8, -0.56), PostPerspectiveLight::InvertedPoint, false),
        ];
        for (sun, expected, uniform) in cases {
            let view = LightView::fit(&Light::directional(sun), &street()).unwrap();
            let (psm, fit) = view.perspective_shadow_map(&camera, 16.0 / 9.0, &street());
            let fit = fit.expect("the street is in view");
            assert_eq!((fit.light, fit.uniform), (expected, uniform), "{sun}: {fit:?}");
            let m = psm.projections[0].clip_from_world;
            let l = sun.normalize();
            for (x, z) in [(0.0, 80.0), (-2.0, 60.0), (5.0, 30.0), (-8.0, 10.0), (1.0, 85.0)] {
                let receiver = Vec3::new(x, 0.0, z);
                for up in [0.5f32, 3.0, 9.0] {
                    let caster = receiver - l * (up / -l.y);
                    let (r, c) = (apply(m, receiver), apply(m, caster));
                    assert!(r.x.abs() <= 1.0 && r.y.abs() <= 1.0 && (0.0..=1.0).contains(&r.z), "{sun}: {r}");
                    assert!((r.truncate() - c.truncate()).length() < 1e-3, "{sun}: {r} vs {c}");
                    assert!(c.z < r.z, "{sun}: caster depth {} not before {}", c.z, r.z);
                }
            }
        }
    }

    #[test]
    fn a_sun_behind_the_eye_moves_the_virtual_camera_back() {
        let camera = Camera::look_at(Vec3::new(0.0, 1.7, 90.0), Vec3::new(0.0, 1.7, 0.0), 60.0);
        let view = LightView::fit(&Light::directional(Vec3::new(0.1, -0.34, -0.93)), &street()).unwrap();
        let (_, fit) = view.perspective_shadow_map(&camera, 16.0 / 9.0, &street());
        let fit = fit.unwrap();
        assert!(fit.shift > 1.0, "{fit:?}");
        // Across the view the light needs no shift when nothing stands behind the eye.
        let view = LightView::fit(&Light::directional(Vec3::new(1.0, -0.34, 0.0)), &street()).unwrap();
        let (_, fit) = view.perspective_shadow_map(&camera, 16.0 / 9.0, &street());
        assert!(fit.unwrap().shift < 0.5);
    }
}
