//! Surface acne, told apart from undersampling: a map technique's false shadow counts as acne only where
//! the reference sees the light from every point within one map texel around the pixel (nine shadow rays
//! from points a texel over along the map's axes, slid back onto the surface's tangent plane). The sawtooth of an undersampled map lies within a texel of a true shadow
//! edge, so it is not counted, however wide a texel is on screen; a surface shadowing itself is.

use glam::Vec3;
use shadow_core::light::LightView;
use shadow_core::{FrameInputs, Image};

use crate::bvh::{SceneBvh, Walker};
use crate::gbuffer::GBuffer;

/// World size of one texel of a `res`-texel map of projection `k` around world point `p`, and the map's
/// two axes in world space.
fn texel_axes(light: &LightView, k: usize, p: Vec3, res: u32) -> (Vec3, Vec3) {
    let proj = &light.projections[k];
    let world_from_view = proj.view_from_world.inverse();
    let (right, up) = (world_from_view.x_axis.truncate(), world_from_view.y_axis.truncate());
    let sx = proj.clip_from_view.x_axis.x;
    let sy = proj.clip_from_view.y_axis.y;
    // Clip x spans [-1, 1] over 2 / sx view units (times the depth for a perspective view).
    let depth = if proj.orthographic { 1.0 } else { -(proj.view_from_world.transform_point3(p)).z };
    (right * (2.0 * depth / (sx * res as f32)), up * (2.0 * depth / (sy * res as f32)))
}

/// What the acne count needs from the reference frame.
pub struct AcneProbe<'a> {
    /// The frame.
    pub frame: &'a FrameInputs,
    /// The light's fitted view.
    pub light: &'a LightView,
    /// The reference's G-buffer.
    pub gbuffer: &'a GBuffer,
    /// The casters.
    pub bvh: &'a SceneBvh,
    /// The reference visibility.
    pub reference: &'a Image<f32>,
    /// The measured pixels.
    pub mask: &'a Image<bool>,
}

impl AcneProbe<'_> {
    /// Fraction of measured pixels that are acne in `test` for a map of side `res`: shadowed there, lit
    /// in the reference, and lit in the reference from every point within one texel around them.
    #[must_use]
    pub fn texel_acne(&self, test: &Image<f32>, res: u32) -> f64 {
        let (g, light) = (self.gbuffer, self.light);
        let eps = 5e-7 * self.frame.bounds.size().length();
        let (mut n, mut acne) = (0u64, 0u64);
        // The probes of neighbouring pixels, traced one after another (see [`SceneBvh::occluded_after`]).
        let mut walker = Walker::default();
        for i in 0..self.mask.data().len() {
            if !self.mask.data()[i] {
                continue;
            }
            n += 1;
            if test.data()[i] >= 0.5 || self.reference.data()[i] < 0.5 {
                continue;
            }
            let n = g.geometric_normal.data()[i];
            let p = g.position.data()[i] + n * eps;
            let (du, dv) = texel_axes(light, light.projection_index(p), p, res);
            let l = light.light.to_light(p);
            let all_lit = (-1..=1).all(|a| {
                (-1..=1).all(|b| {
                    // A texel over in the map, slid along the light ray back onto the surface's tangent
                    // plane (measured pixels face the light, so l . n > 0), so no probe starts inside the
                    // surface it sits on.
                    let off = du * a as f32 + dv * b as f32;
                    let slide = (-off.dot(n) / l.dot(n).max(1e-3)).clamp(-4.0 * off.length(), 4.0 * off.length());
                    let q = p + off + l * slide;
                    let (dir, tmax) = match light.light.position() {
                        Some(l) => ((l - q).normalize(), (l - q).length()),
                        None => (light.light.to_light(q), f32::INFINITY),
                    };
                    !self.bvh.occluded_after(&mut walker, q, dir, tmax)
                })
            });
            acne += u64::from(all_lit);
        }
        if n == 0 { 0.0 } else { acne as f64 / n as f64 }
    }
}
