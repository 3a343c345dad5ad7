//! Light-space perspective shadow maps (Wimmer, Scherzer and Purgathofer 2004) for a directional light:
//! one map, rendered through a perspective whose axis is perpendicular to the light, so that the light
//! stays directional after it and nothing behind the eye is ever inverted (the trouble of perspective
//! shadow maps), while near receivers still get more texels than far ones.
//!
//! The light-space frame looks along the light, its up axis the view direction projected onto the plane
//! perpendicular to the light. A perspective along that up axis, its centre `n` before the near side of
//! the focused body (the view frustum cut by the scene, [`super::focus`]), maps the body into the unit
//! cube. The paper's `n_opt = (z_n + sqrt(z_n z_f)) / sin(gamma)` keeps the worst aliasing error over the
//! view depth range `[z_n, z_f]` smallest (gamma is the angle between view and light directions). As
//! gamma goes to 0 (the duelling frusta and the light from behind the eye) n grows without bound and the
//! perspective becomes the uniform map, focused on the body: the warp cannot help there, and it degrades
//! gracefully instead of failing.

use glam::camera::rh::view::look_to_mat4;
use glam::{Mat4, Vec3, Vec4};

use super::focus::{focused_body, focused_uniform, padded_range as padded, range, transformed, visible_depth_range};
use super::{LightProjection, LightView, safe_up};
use crate::bounds::Aabb;
use crate::scene::{Camera, LightKind};

/// A warp of `n` over `depth` is a uniform map within this fraction (its texel sizes differ by at most
/// `depth / n` across the body), and past it the map is made orthographic: the perspective's divisions
/// would only lose precision.
const UNIFORM_RATIO: f32 = 100.0;

/// The perspective of one frame's light-space warp.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Warp {
    /// Distance from the perspective's centre to the focused body's near side, in scene units.
    pub n: f32,
    /// The body's extent along the perspective's axis.
    pub depth: f32,
    /// Sine of the angle between the view and light directions.
    pub sin_gamma: f32,
}

impl Warp {
    /// The paper's optimal `n` for a view depth range `[z_n, z_f]` at angle `gamma` to the light.
    #[must_use]
    pub fn optimal_n(z_n: f32, z_f: f32, sin_gamma: f32) -> f32 {
        (z_n + (z_n * z_f).sqrt()) / sin_gamma
    }

    /// Whether the warp is strong enough to be a perspective (otherwise the map is uniform).
    #[must_use]
    pub fn is_perspective(&self) -> bool {
        self.n.is_finite() && self.n < UNIFORM_RATIO * self.depth
    }
}

/// The rows of a 4x4 matrix, as a `Mat4`.
fn from_rows(rows: [Vec4; 4]) -> Mat4 {
    Mat4::from_cols(rows[0], rows[1], rows[2], rows[3]).transpose()
}

impl LightView {
    /// The light-space perspective view of a directional light for the view of `camera` (`aspect` wide
    /// per unit of height) into a scene of instances bounded by `boxes`, with the warp it used (`None`
    /// where the map is uniform: nothing is in view, or the warp is too weak to be one). `n` overrides the
    /// paper's optimum when given. Any other light's view is returned unchanged.
    ///
    /// The paper's `z_n` and `z_f` are the near and far planes of a view fitted to the scene; the camera's
    /// own near plane (5 cm at head height) would put every texel into the air in front of the lens, so
    /// the view's depth range is the one its visible instances fill ([`visible_depth_range`]).
    #[must_use]
    pub fn light_space_perspective(
        &self,
        camera: &Camera,
        aspect: f32,
        boxes: &[Aabb],
        n: Option<f32>,
    ) -> (Self, Option<Warp>) {
        let LightKind::Directional { direction } = self.light.kind else { return (self.clone(), None) };
        let l = direction.normalize();
        let v = (camera.target - camera.eye).normalize();
        let bounds = boxes.iter().fold(Aabb::EMPTY, |a, b| a.union(*b));
        let far = bounds.corners().iter().map(|&c| (c - camera.eye).dot(v)).fold(0.0f32, f32::max);
        let Some((z_n, z_f)) = visible_depth_range(camera, aspect, far.max(camera.near * 2.0), boxes) else {
            return (self.clone(), None);
        };
        let body = focused_body(camera, aspect, (z_n, z_f.max(z_n * 1.001)), &bounds);
        if body.is_empty() {
            return (self.clone(), None);
        }
        let cos_gamma = v.dot(l).clamp(-1.0, 1.0);
        let sin_gamma = (1.0 - cos_gamma * cos_gamma).sqrt();
        // Up is the view direction seen from the light; looking along the light, any up does when the two
        // are parallel (the warp is then uniform).
        let up = (v - l * cos_gamma).try_normalize().unwrap_or_else(|| safe_up(l));
        let light_from_world = look_to_mat4(Vec3::ZERO, l, up);
        let points = transformed(&body, light_from_world);
        let scene = bounds.transformed(light_from_world);
        let (y0, y1) = range(points.iter().map(|p| p.y));
        let depth = (y1 - y0).max(1e-6);
        let warp = Warp { n: n.unwrap_or_else(|| Warp::optimal_n(z_n, z_f, sin_gamma)), depth, sin_gamma };
        // The light-side and far-side ends of the scene along the light: casters anywhere above the body.
        let (z_lo, z_hi) = padded((scene.min.z, scene.max.z));
        if !warp.is_perspective() {
            return (Self { projections: vec![focused_uniform(l, &body, &bounds)], ..self.clone() }, None);
        }
        // The perspective's centre: level with the eye across the axis and along the light, `n` before the
        // body along the axis. With q = y - c.y > 0 over the body, the map's axes are u = (x - c.x) / q
        // across and s = -1 / q along (near receivers get the most of s), and depth is t = (c.z - z) / q,
        // which grows away from the light on every light ray (x and y fixed) whatever c.z is. Level with
        // the eye, c.z - z is small at the receivers near it, where q is small: there the division's own
        // change of t across a surface, (c.z - z) dq / q^2, would otherwise swamp the surface's slope and
        // with it the slope-scaled bias (light leaking through thin casters near the viewer).
        let eye = light_from_world.transform_point3(camera.eye);
        let c = Vec3::new(eye.x, y0 - warp.n, eye.z);
        let q = |p: &Vec3| p.y - c.y;
        let (u0, u1) = padded(range(points.iter().map(|p| (p.x - c.x) / q(p))));
        let (s0, s1) = padded(range(points.iter().map(|p| -1.0 / q(p))));
        let (q0, q1) = (y0 - c.y, y1 - c.y);
        let (t0, t1) =
            padded(range([(z_lo, q0), (z_lo, q1), (z_hi, q0), (z_hi, q1)].map(|(z, q)| (c.z - z) / q).into_iter()));
        // Each clip coordinate is affine in the light-space point, with clip w = q: x_ndc = a u + b,
        // y_ndc = e s + f, z_ndc = k t + m.
        let (a, b) = (2.0 / (u1 - u0), -2.0 * u0 / (u1 - u0) - 1.0);
        let (e, f) = (2.0 / (s1 - s0), -2.0 * s0 / (s1 - s0) - 1.0);
        let (k, m) = (1.0 / (t1 - t0), -t0 / (t1 - t0));
        let clip_from_light = from_rows([
            Vec4::new(a, b, 0.0, -a * c.x - b * c.y),
            Vec4::new(0.0, f, 0.0, -e - f * c.y),
            Vec4::new(0.0, m, -k, k * c.z - m * c.y),
            Vec4::new(0.0, 1.0, 0.0, -c.y),
        ]);
        let proj = LightProjection::new(light_from_world, clip_from_light, warp.n, warp.n + depth, false);
        (Self { projections: vec![proj], ..self.clone() }, Some(warp))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Light;

    fn street() -> Aabb {
        Aabb::new(Vec3::new(-100.0, 0.0, -100.0), Vec3::new(100.0, 20.0, 100.0))
    }

    fn warped(sun: Vec3, camera: &Camera) -> (LightView, Option<Warp>) {
        let view = LightView::fit(&Light::directional(sun), &[street()]).unwrap();
        view.light_space_perspective(camera, 16.0 / 9.0, &[street()], None)
    }

    #[test]
    fn the_body_and_the_casters_over_it_land_in_the_map() {
        let camera = Camera::look_at(Vec3::new(3.0, 1.7, 90.0), Vec3::new(-10.0, 1.0, 0.0), 60.0);
        let (view, warp) = warped(Vec3::new(0.8, -0.35, 0.1), &camera);
        let warp = warp.expect("a sun across the view warps");
        assert!(warp.n > 0.0 && warp.n < 100.0 * warp.depth, "{warp:?}");
        let p = &view.projections[0];
        let body = focused_body(&camera, 16.0 / 9.0, (camera.near, 300.0), &street());
        for b in &body {
            // The receiver and a caster above it, towards the light, on the same light ray.
            let caster = *b + Vec3::new(-0.8, 0.35, -0.1).normalize() * 5.0;
            for q in [*b, caster] {
                if q.y > 20.0 {
                    continue;
                }
                let ndc = p.ndc(q);
                assert!(ndc.x.abs() <= 1.0 && ndc.y.abs() <= 1.0 && (0.0..=1.0).contains(&ndc.z), "{q} -> {ndc}");
            }
            // The caster is nearer the light, so its depth is smaller.
            if caster.y <= 20.0 {
                assert!(p.ndc(caster).z < p.ndc(*b).z);
            }
        }
    }

    #[test]
    fn near_receivers_get_more_texels_than_far_ones() {
        let camera = Camera::look_at(Vec3::new(0.0, 1.7, 90.0), Vec3::new(0.0, 1.7, 0.0), 60.0);
        let (view, _) = warped(Vec3::new(1.0, -0.36, 0.0), &camera);
        let p = &view.projections[0];
        // Map distance covered by one metre of ground at 5 m and at 80 m from the eye.
        let span =
            |z: f32| (p.uv_depth(Vec3::new(0.0, 0.0, z)).0 - p.uv_depth(Vec3::new(0.0, 0.0, z - 1.0)).0).length();
        assert!(span(85.0) > 5.0 * span(10.0), "{} vs {}", span(85.0), span(10.0));
    }

    #[test]
    fn light_along_the_view_degrades_to_a_uniform_map() {
        let camera = Camera::look_at(Vec3::new(0.0, 30.0, 90.0), Vec3::new(0.0, 0.0, 0.0), 60.0);
        // The sun straight behind the eye and straight ahead: gamma 0 and 180 degrees.
        let along = (Vec3::new(0.0, 0.0, 0.0) - Vec3::new(0.0, 30.0, 90.0)).normalize();
        for sun in [along, -along] {
            let (view, warp) = warped(sun, &camera);
            assert_eq!(warp, None);
            assert!(view.projections[0].orthographic);
            assert!(view.projections[0].clip_from_world.is_finite());
        }
    }
}
