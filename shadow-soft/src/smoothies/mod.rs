//! `smoothies` (Chan and Durand 2003; Chan's thesis, chapter 4): fake soft shadows from a shadow map and
//! a smoothie buffer.
//!
//! Build: the blockers' depth map; their silhouette edges (shadow-core's extraction) each extended
//! outward by `t` in the light's map space into a smoothie edge, with a smoothie corner at every
//! silhouette vertex ([`geometry`]); the smoothies rendered from the light into a buffer of depth and
//! alpha, alpha rising from 0 at the silhouette to 1 at the smoothie's far side, remapped to
//! `a / (1 - b / r)` on linear depths (b the smoothie's, r the map's there: Fig. 4-10, the penumbra widens
//! with the distance behind the blocker) and clamped; pixels behind a blocker (b / r >= 1) discarded;
//! overlapping smoothies keep the minimum. Query, at the four nearest texels: behind the map's depth 0,
//! else behind the smoothie's its alpha, else 1; bilinearly weighted (a 2x2 tent), then the sinusoidal
//! falloff of a spherical light.
//!
//! Like the thesis, smoothies only extend outward: the umbra does not shrink as the light grows.

pub mod cpu;
pub mod geometry;
pub mod gpu;

use crate::Entry;
use shadow_core::glam::Vec3;
use shadow_core::image::false_colour;
use shadow_core::light::{LightProjection, LightView};
use shadow_core::scene::LightKind;
use shadow_core::technique::DebugView;
use shadow_core::technique::FrameStats;
use shadow_core::technique::LightKinds;
use shadow_core::technique::TechniqueError;
use shadow_core::technique::maps::{DepthMap, resolution_key};
use shadow_core::technique::settings::{OnOff, SettingKey, SettingValue};
use shadow_core::{FrameInputs, Image};

shadow_core::technique_settings! {
    /// `smoothies` settings.
    pub struct Smoothies {
        /// The depth map: resolution (the smoothie buffer's too) and bias, as `shadow-map` has them.
        pub depth: DepthMap = DepthMap::keys(resolution_key(
            "1024",
            "depth map and smoothie buffer side in texels (16 to 16384)",
        )),
        /// The smoothie size `t`.
        pub size: SmoothieSize = SettingKey::float(
            "size",
            "auto",
            0.001,
            1.0,
            "smoothie size t in map coordinates (0.001 to 1), or auto: the light's radius seen at the casters",
        )
        .or("auto"),
        /// Whether alpha is remapped by the distances (Eq. 4.1); off shows the fixed-width ramp of Fig. 4-4b.
        pub remap: OnOff = SettingKey::choice(
            "remap",
            "on",
            OnOff::NAMES,
            "on: alpha / (1 - b/r) on linear depths (Eq. 4.1); off: linear ramp",
        ),
        /// The penumbra's profile.
        pub falloff: Falloff = SettingKey::choice("falloff", "sinusoidal", Falloff::NAMES, "sinusoidal or linear"),
    }
    lights = LightKinds::ONE_PROJECTION;
}

/// The smoothie size `t`, in map coordinates (`[0, 1]` across the map).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SmoothieSize {
    /// From the light's radius: the radius as seen from the light at the casters' centre, so the
    /// penumbra outside the hard shadow edge is as wide as a spherical light of that radius makes it
    /// there (`t (r - b) / r` of the map at the receiver against `radius (r - b) / b` in the world).
    Auto,
    /// A fixed size; the thesis uses 0.02 to 0.2 for scenes 10 units across.
    Fixed(f32),
}

/// `auto`, or a fixed size in the key's range.
impl SettingValue for SmoothieSize {
    fn from_setting(text: &str, key: &SettingKey) -> Option<Self> {
        if key.word == Some(text) { Some(Self::Auto) } else { f32::from_setting(text, key).map(Self::Fixed) }
    }
    fn to_setting(&self) -> String {
        match self {
            Self::Auto => "auto".into(),
            Self::Fixed(t) => t.to_string(),
        }
    }
}

shadow_core::named_enum! {
    /// How visibility falls off across a smoothie.
    pub enum Falloff {
        /// `(1 - cos(pi v)) / 2`: the sinusoidal falloff of a diffuse spherical light (Parker et al.,
        /// after Haines), which the thesis precomputes into a 1D texture.
        Sinusoidal = "sinusoidal",
        /// The alpha as it is.
        Linear = "linear",
    }
}

impl Falloff {
    /// The visibility of a filtered alpha `v` (in `[0, 1]`), exactly.
    #[must_use]
    pub fn exact(self, v: f32) -> f32 {
        match self {
            Self::Sinusoidal => 0.5 - 0.5 * (std::f32::consts::PI * v).cos(),
            Self::Linear => v,
        }
    }
}

/// A falloff tabulated as the thesis keeps it, a 1D texture read with linear filtering: `FALLOFF_TEXELS`
/// samples from 0 to 1 (the sinusoid's largest error between them is under 1e-5).
#[derive(Clone, Debug, PartialEq)]
pub struct FalloffTable {
    samples: Vec<f32>,
}

/// Samples in a [`FalloffTable`].
pub const FALLOFF_TEXELS: usize = 256;

impl FalloffTable {
    /// The table of `falloff`.
    #[must_use]
    pub fn new(falloff: Falloff) -> Self {
        let last = (FALLOFF_TEXELS - 1) as f32;
        Self { samples: (0..FALLOFF_TEXELS).map(|i| falloff.exact(i as f32 / last)).collect() }
    }

    /// The samples, for a GPU texture.
    #[must_use]
    pub fn samples(&self) -> &[f32] {
        &self.samples
    }

    /// The falloff at `v`, clamped to `[0, 1]`, linearly interpolated between samples.
    #[must_use]
    pub fn apply(&self, v: f32) -> f32 {
        let x = v.clamp(0.0, 1.0) * (FALLOFF_TEXELS - 1) as f32;
        let i = (x as usize).min(FALLOFF_TEXELS - 2);
        let f = x - i as f32;
        self.samples[i] * (1.0 - f) + self.samples[i + 1] * f
    }
}

impl Smoothies {
    /// The technique's name.
    pub const NAME: &'static str = "smoothies";

    /// The one projection smoothies use: spot and directional lights. Point lights need six buffers the
    /// thesis does not build (section 4.5); they are refused by name.
    ///
    /// # Errors
    /// [`TechniqueError::UnsupportedLight`] for a point light.
    pub fn projection(light: &LightView) -> Result<&LightProjection, TechniqueError> {
        match (light.light.kind, light.projections.as_slice()) {
            (LightKind::Spot { .. } | LightKind::Directional { .. }, [p]) => Ok(p),
            _ => Err(TechniqueError::unsupported_light(Self::NAME, &light.light)),
        }
    }

    /// The smoothies of a frame's casters for `light` in its projection `proj`, with the size `t` they
    /// were built with; their counters recorded in `stats` (both backends alike).
    #[must_use]
    pub fn construct(
        &self,
        frame: &FrameInputs,
        light: &LightView,
        proj: &LightProjection,
        stats: &mut FrameStats,
    ) -> (f32, geometry::Smoothies) {
        let casters = frame.caster_silhouettes(light);
        let centre = geometry::silhouette_centre(frame, &casters).unwrap_or(frame.bounds.center());
        let t = self.size_for(light, proj, centre);
        let smoothies = geometry::build(frame, &casters, proj, t);
        let c = &mut stats.counters;
        c.silhouette_edges = Some(smoothies.edges as u64);
        c.extra.insert("smoothie_triangles".into(), smoothies.triangles.len() as f64);
        c.extra.insert("special_vertices".into(), smoothies.special_vertices as f64);
        c.extra.insert("smoothie_size".into(), f64::from(t));
        (t, smoothies)
    }

    /// `t` for a frame: fixed, or the light's radius as the projection sees it at `centre` (the casters').
    #[must_use]
    pub fn size_for(&self, light: &LightView, proj: &LightProjection, centre: Vec3) -> f32 {
        match self.size {
            SmoothieSize::Fixed(t) => t,
            SmoothieSize::Auto => {
                let across = proj.view_from_world.inverse().transform_vector3(Vec3::X);
                let (a, _) = proj.uv_depth(centre);
                let (b, _) = proj.uv_depth(centre + across.normalize() * light.light.radius);
                (b - a).length().max(1e-4)
            }
        }
    }
}

/// The debug views of a smoothie buffer, the same on both backends: alpha in grey, depth in false colour.
#[must_use]
pub fn debug_views(depth: &Image<f32>, alpha: &Image<f32>) -> Vec<DebugView> {
    let grey = Image::from_fn(alpha.width(), alpha.height(), |x, y| [(alpha.get(x, y) * 255.0).round() as u8; 3]);
    let nearest = depth.data().iter().copied().fold(1.0f32, f32::min);
    vec![
        DebugView { name: "smoothie-alpha".into(), image: grey },
        DebugView { name: "smoothie-depth".into(), image: false_colour(depth, nearest, 1.0) },
    ]
}

/// The registry entry.
#[must_use]
pub fn entry() -> Entry {
    Entry::on_both::<Smoothies>(
        Smoothies::NAME,
        "fake soft shadows: a shadow map plus alpha ramps hung outward from the silhouettes (smoothies)",
        "Chan-Durand 2003; Chan 2004 (thesis, chapter 4)",
    )
    .wgsl(gpu::shaders)
    .soft()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The squared error, along a line across a straight shadow edge of a spherical light, of an outward
    /// ramp `falloff` of width `w` against the truth, in half-widths of the true penumbra: the truth is the
    /// visible fraction of the light's disc, `1 - (acos x - x sqrt(1 - x^2)) / pi` from the umbra (x = -1)
    /// to full light (x = 1), one half at the hard edge (x = 0); the ramp is 0 inside the hard edge and
    /// rises to 1 at `w`; `w = 0` is the hard edge itself.
    fn edge_error(falloff: Falloff, w: f64) -> f64 {
        let truth = |x: f64| {
            let x = x.clamp(-1.0, 1.0);
            1.0 - (x.acos() - x * (1.0 - x * x).sqrt()) / std::f64::consts::PI
        };
        let ramp = |x: f64| match x {
            _ if x < 0.0 => 0.0,
            _ if x >= w => 1.0,
            _ => f64::from(falloff.exact((x / w) as f32)),
        };
        let n = 20_000;
        let (a, b) = (-1.0, 1.0 + w);
        (0..n).map(|i| a + (b - a) * (i as f64 + 0.5) / n as f64).map(|x| (truth(x) - ramp(x)).powi(2)).sum::<f64>()
            * (b - a)
            / n as f64
    }

    #[test]
    fn an_outward_ramp_as_wide_as_the_outer_penumbra_errs_more_than_a_hard_edge() {
        // Why smoothies at the light's size lose to a hard (or bilinearly filtered) edge in RMSE: the
        // truth is already one half at the hard edge, where the ramp starts from 0. Narrower ramps do
        // better, at best by about a sixth, which a bilinear filter's own blur across the edge also gains.
        let hard = edge_error(Falloff::Linear, 0.0);
        let at_width = edge_error(Falloff::Sinusoidal, 1.0);
        assert!(at_width > 1.3 * hard, "sinusoid as wide as the outer penumbra {at_width} against {hard}");
        let best = (1..=20).map(|i| edge_error(Falloff::Sinusoidal, f64::from(i) / 20.0)).fold(f64::MAX, f64::min);
        assert!(best < hard && best > 0.8 * hard, "best narrower sinusoid {best} against {hard}");
    }

    #[test]
    fn the_tabulated_falloff_follows_the_sinusoid() {
        for falloff in [Falloff::Sinusoidal, Falloff::Linear] {
            let table = FalloffTable::new(falloff);
            let worst = (0..=1000)
                .map(|i| i as f32 / 1000.0)
                .map(|v| (table.apply(v) - falloff.exact(v)).abs())
                .fold(0.0, f32::max);
            assert!(worst < 1e-5, "{falloff}: {worst}");
        }
        let table = FalloffTable::new(Falloff::Sinusoidal);
        assert_eq!((table.apply(-1.0), table.apply(0.0), table.apply(1.0), table.apply(2.0)), (0.0, 0.0, 1.0, 1.0));
        assert!((table.apply(0.5) - 0.5).abs() < 1e-6);
    }
}
