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
    LightTerms::new(light).falloff(p)
}

/// A spot light's cosines of its rim's and its inner cone's half-angles (the falloff runs between them):
/// the inner cone as the light gives it, else the last [`SPOT_SOFT_EDGE`] of the half-angle fades.
/// `None` for other lights. Both backends' shading read the cone from here.
#[must_use]
pub fn cone_cosines(light: &Light) -> Option<(f32, f32)> {
    let LightKind::Spot { cone_angle, .. } = light.kind else { return None };
    let half = cone_angle * 0.5;
    let inner = match light.inner_cone_angle {
        Some(inner) => inner * 0.5,
        None => half * (1.0 - SPOT_SOFT_EDGE),
    };
    Some((half.cos(), inner.cos()))
}

/// How much of a point or spot light with a range reaches `p`: clamp(1 - (d / range)^4, 0, 1), glTF's
/// window, which is 1 near the light and falls to 0 at the range. 1 for lights without one and for
/// directional lights.
#[must_use]
#[inline]
pub fn range_window(light: &Light, p: Vec3) -> f32 {
    match (light.range, light.position()) {
        (Some(range), Some(position)) => {
            let x = (p - position).length() / range;
            (1.0 - x * x * x * x).clamp(0.0, 1.0)
        }
        _ => 1.0,
    }
}

/// Hermite smoothstep of `x` between `e0` and `e1`.
#[must_use]
#[inline]
pub fn smoothstep(e0: f32, e1: f32, x: f32) -> f32 {
    let t = ((x - e0) / (e1 - e0)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// Direct light from one light at a surface point with unit normal `n`, before visibility: colour times
/// intensity times max(n . l, 0) times the cone falloff.
#[must_use]
pub fn direct(light: &Light, p: Vec3, n: Vec3) -> Vec3 {
    LightTerms::new(light).direct(p, n)
}

/// What shading needs of a light that is the same at every point: its colour times intensity, and a spot's
/// cone as a unit axis and the cosines of its rim and of its inner cone. Worked out once a frame instead of
/// once a pixel (the GPU backend hands its shader the same cosines); the same values either way.
#[derive(Clone, Copy, Debug)]
pub struct LightTerms {
    light: Light,
    radiance: Vec3,
    cone: Option<Cone>,
}

#[derive(Clone, Copy, Debug)]
struct Cone {
    apex: Vec3,
    axis: Vec3,
    outer: f32,
    inner: f32,
}

impl Cone {
    /// The falloff along the unit direction `d` from the apex.
    #[inline]
    fn falloff_along(&self, d: Vec3) -> f32 {
        smoothstep(self.outer, self.inner, d.dot(self.axis))
    }
}

impl LightTerms {
    /// The terms of `light`.
    #[must_use]
    pub fn new(light: &Light) -> Self {
        let cone = match light.kind {
            LightKind::Spot { position, direction, .. } => cone_cosines(light).map(|(outer, inner)| Cone {
                apex: position,
                axis: direction.normalize_or_zero(),
                outer,
                inner,
            }),
            _ => None,
        };
        Self { light: *light, radiance: light.color * light.intensity, cone }
    }

    /// [`cone_falloff`] at `p`.
    #[must_use]
    #[inline]
    pub fn falloff(&self, p: Vec3) -> f32 {
        self.cone.map_or(1.0, |c| c.falloff_along((p - c.apex).normalize_or_zero()))
    }

    /// [`direct`] at `p` with unit normal `n`.
    #[must_use]
    #[inline]
    pub fn direct(&self, p: Vec3, n: Vec3) -> Vec3 {
        let l = self.light.to_light(p);
        // A spot's apex is the light's position, so the unit vector from it to `p` is `-l`, to the bit:
        // [`Self::falloff`] without normalizing the same vector again.
        let falloff = self.cone.map_or(1.0, |c| c.falloff_along(-l));
        let term = self.radiance * n.dot(l).max(0.0) * falloff;
        if self.light.range.is_some() { term * range_window(&self.light, p) } else { term }
    }
}

/// Linear radiance of a surface: albedo times (ambient plus the sum of each light's direct term times its
/// visibility).
#[must_use]
#[inline]
pub fn shade<'a>(albedo: Vec3, p: Vec3, n: Vec3, lit: impl IntoIterator<Item = (&'a LightTerms, f32)>) -> Vec3 {
    let direct: Vec3 = lit.into_iter().map(|(l, v)| l.direct(p, n) * v).sum();
    albedo * (Vec3::splat(AMBIENT) + direct)
}

/// Background colour (linear) for pixels that show no surface.
pub const BACKGROUND: Vec3 = Vec3::new(0.02, 0.025, 0.04);

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;

    #[test]
    fn a_range_ends_a_light_by_gltf_s_window() {
        let at = Vec3::new(0.0, 4.0, 0.0);
        let ranged = Light { range: Some(2.0), ..Light::point(at) };
        let below = |d: f32| at - Vec3::Y * d;
        assert_eq!(range_window(&ranged, below(0.0)), 1.0);
        assert!((range_window(&ranged, below(1.0)) - (1.0 - 1.0 / 16.0)).abs() < 1e-6);
        assert_eq!(range_window(&ranged, below(2.0)), 0.0);
        assert_eq!(range_window(&ranged, below(3.0)), 0.0);
        assert_eq!(range_window(&Light::point(at), below(100.0)), 1.0);
        let sun = Light { range: Some(2.0), ..Light::directional(Vec3::NEG_Y) };
        assert_eq!(range_window(&sun, below(100.0)), 1.0);
        // The direct term follows the window: full near the light, none beyond its range.
        let n = Vec3::Y;
        assert_eq!(direct(&ranged, below(3.0), n), Vec3::ZERO);
        let near = direct(&ranged, below(1.0), n);
        assert!((near - direct(&Light::point(at), below(1.0), n) * (15.0 / 16.0)).length() < 1e-6, "{near}");
    }

    #[test]
    fn the_direct_term_falls_off_as_the_cone_does_to_the_bit() {
        let spot = Light::spot(Vec3::new(0.3, 4.0, -0.7), Vec3::new(0.7, 0.0, 0.1), 50.0);
        let terms = LightTerms::new(&spot);
        let n = Vec3::new(0.2, 0.9, 0.1).normalize();
        let apex = spot.position().expect("a spot has a position");
        // A grid through and beyond the cone, its edge included, the apex itself and points next to it.
        let mut points: Vec<Vec3> = (0..41 * 41)
            .map(|k| Vec3::new((k % 41) as f32 * 0.25 - 5.0, 0.01 * (k / 41) as f32, (k / 41) as f32 * 0.25 - 5.0))
            .collect();
        points.extend([apex, apex + Vec3::splat(1e-6), apex - Vec3::X * 1e-30, apex + Vec3::Y * 1e30]);
        let mut inside = 0;
        for p in points {
            let l = spot.to_light(p);
            let expected = spot.color * spot.intensity * n.dot(l).max(0.0) * terms.falloff(p);
            assert_eq!(terms.direct(p, n).to_array().map(f32::to_bits), expected.to_array().map(f32::to_bits), "{p}");
            inside += usize::from(terms.falloff(p) > 0.0 && terms.falloff(p) < 1.0);
        }
        assert!(inside > 0, "some points on the cone's soft edge");
    }
}
