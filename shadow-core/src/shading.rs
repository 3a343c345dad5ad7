//! Shading shared by both backends (DESIGN 4): Lambert in linear space, material albedo, ambient 0.15, a
//! smooth spot-cone falloff, sRGB8 output. The WGSL twin is `shade_pixel` in shadow-wgpu's common shader.

use glam::Vec3;

use crate::scene::{Light, LightKind};

/// Ambient term, as a fraction of the albedo.
pub const AMBIENT: f32 = 0.15;

/// Fraction of the cone's half-angle over which a spot light fades out at its rim.
pub const SPOT_SOFT_EDGE: f32 = 0.2;

/// Spot-cone falloff at a point (1 inside the inner cone, smoothly 0 at the rim); 1 for other lights.
#[must_use]
pub fn cone_falloff(light: &Light, p: Vec3) -> f32 {
    match light.kind {
        LightKind::Spot { position, direction, cone_angle } => {
            let cos_angle = (p - position).normalize_or_zero().dot(direction.normalize_or_zero());
            let outer = (cone_angle * 0.5).cos();
            let inner = (cone_angle * 0.5 * (1.0 - SPOT_SOFT_EDGE)).cos();
            smoothstep(outer, inner, cos_angle)
        }
        _ => 1.0,
    }
}

/// Hermite smoothstep of `x` between `e0` and `e1`.
#[must_use]
pub fn smoothstep(e0: f32, e1: f32, x: f32) -> f32 {
    let t = ((x - e0) / (e1 - e0)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// Direct light from one light at a surface point with unit normal `n`, before visibility: colour times
/// intensity times max(n . l, 0) times the cone falloff.
#[must_use]
pub fn direct(light: &Light, p: Vec3, n: Vec3) -> Vec3 {
    let l = light.to_light(p);
    light.color * light.intensity * n.dot(l).max(0.0) * cone_falloff(light, p)
}

/// Linear radiance of a surface: albedo times (ambient plus the sum of each light's direct term times its
/// visibility).
#[must_use]
pub fn shade<'a>(albedo: Vec3, p: Vec3, n: Vec3, lit: impl IntoIterator<Item = (&'a Light, f32)>) -> Vec3 {
    let direct: Vec3 = lit.into_iter().map(|(l, v)| direct(l, p, n) * v).sum();
    albedo * (Vec3::splat(AMBIENT) + direct)
}

/// Background colour (linear) for pixels that show no surface.
pub const BACKGROUND: Vec3 = Vec3::new(0.02, 0.025, 0.04);
