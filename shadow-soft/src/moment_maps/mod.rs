//! Filterable shadow maps: `variance-shadow-map` (Donnelly-Lauritzen 2006), `exponential-variance-shadow-map`
//! (Lauritzen-McCool 2008) and `moment-shadow-map` (Peters-Klein 2015, Hamburger 4MSM). Each texel keeps
//! moments of the depth distribution instead of one depth, so the map can be filtered like a colour
//! texture before the comparison, which then bounds (or reconstructs) the fraction of the filter region
//! nearer the light than the receiver.
//!
//! Build: the light's depth map (with `shadow-map`'s bias, for the blocker search), each texel's
//! normalized linear depth `d = (z - near) / (far - near)` turned into its moments
//! ([`MomentKind::encode`]), a separable box blur of radius `blur` texels, then a mip chain of 2x2
//! averages.
//!
//! Query, per receiver at normalized depth `t` (linear depth `z_r`), sized as `pcss` sizes its kernel so
//! the penumbra is as wide as the light's `radius` makes it:
//!
//! 1. **Blocker search**: `pcss`'s own, 16 taps of the depth map over the disc of texels that can hold a
//!    blocker, their mean linear depth `z_b`. None: lit. (The moments could give `z_b` too, from
//!    Chebyshev's share of the search region in front of the receiver, but only by assuming everything
//!    else stands at the receiver's depth; where the region also holds deeper ground or the empty far
//!    plane, the bound overstates the lit share and the estimate runs to the near plane, and the kernel
//!    with it to the whole map.)
//! 2. **Filter.** The penumbra's half-width `r` at the receiver by similar triangles; the moments averaged
//!    over a square of side `sqrt(3) r`, the box whose variance is a disc's of radius `r` (so a straight
//!    edge gets the same 10-90% width as the light's disc gives it).
//! 3. **Visibility** from the filtered moments ([`MomentKind::visibility`]), then the light-bleeding
//!    reduction `linstep(bleed, 1, v)`: the bound's tail below `bleed` is cut to shadow.
//!
//! Averages over a square come from the mip chain: a 4x4 grid of trilinear taps across the square, each
//! from the levels whose texels are a grid cell wide (see [`cpu::average`]); "mipmapped" rather than
//! summed-area, since a summed-area table in f32 loses the moments' low bits to the running sums at
//! 1024^2 and beyond.
//!
//! Spot lights only, as `pcss`: the blocker search needs the light's position, and a point light's six
//! maps would need filtering across cube faces.

pub mod cpu;
pub mod gpu;
mod moments;

pub use moments::{MomentKind, chebyshev, hamburger_shadow, linstep};

use shadow_core::light::LightView;
use shadow_core::technique::maps::{DepthMap, resolution_key};
use shadow_core::technique::registry::converted;
use shadow_core::technique::settings::{SettingKey, TechniqueSettings};
use shadow_core::technique::{LightKinds, TechniqueError};
use shadow_cpu::CpuBackend;
use shadow_wgpu::WgpuBackend;

use crate::Entry;
use crate::pcss::{Pcss, PcssLens};

/// The side of the box whose per-axis variance is a disc's of radius 1 (`r^2 / 4 = s^2 / 12`).
pub const BOX_PER_DISC_RADIUS: f32 = 1.732_050_8;

/// `blur`: the pre-filter.
const BLUR: SettingKey =
    SettingKey::int("blur", "1", 0, 16, "radius in texels of the separable box blur of the moments (0: none)");

/// The depth map's keys: its side, and the bias `shadow-map` renders with, which the blocker search
/// needs as `pcss`'s does: unbiased, a receiver's own texels tie with it and count as blockers half the
/// time, pulling the blockers' mean depth towards the receiver (on `stacked-boxes` at radius 0.2, to
/// penumbrae two thirds as wide as the reference's). The moments are taken of the same biased depths.
/// The bias applied at the receiver instead, in the search alone, would scale with the receiver's
/// slope, which near a curved surface's terminator is steep enough to hide the facets shadowing it
/// (`cylinder` at radius 0.05: RMSE 0.0087 against 0.0050).
const DEPTH: [SettingKey; 5] = DepthMap::keys(resolution_key("1024", "map side in texels (16 to 16384)"));

/// `bleed`: the light-bleeding reduction, with a technique's own default. The reduction halves the
/// bleeding everywhere but darkens every penumbra too; summed over the nine soft-shadow configurations
/// (three scenes, radius 0.05 to 0.2) the RMSE with 0.1 against none was 0.154 / 0.155 for the variance
/// map, 0.147 / 0.138 for the exponential one and 0.147 / 0.137 for the moment map: 0.1 for the variance
/// map, whose bound bleeds most, none for the two built to bleed less.
const fn bleed_key(default: &'static str) -> SettingKey {
    SettingKey::float(
        "bleed",
        default,
        0.0,
        0.99,
        "light-bleeding reduction: visibility below this is cut to shadow, the rest rescaled (0: none)",
    )
}

shadow_core::technique_settings! {
    /// `variance-shadow-map` settings.
    pub struct VarianceShadowMap {
        /// The depth map: side and bias, as `shadow-map` has them.
        pub depth: DepthMap = DEPTH,
        /// Radius in texels of the moments' blur.
        pub blur: u32 = BLUR,
        /// Light-bleeding reduction.
        pub bleed: f32 = bleed_key("0.1"),
    }
    lights = LightKinds::SPOT;
}

shadow_core::technique_settings! {
    /// `exponential-variance-shadow-map` settings.
    pub struct ExponentialVarianceShadowMap {
        /// The depth map: side and bias, as `shadow-map` has them.
        pub depth: DepthMap = DEPTH,
        /// Radius in texels of the moments' blur.
        pub blur: u32 = BLUR,
        /// Light-bleeding reduction.
        pub bleed: f32 = bleed_key("0"),
        /// The positive warp's exponent (its square must stay inside f32: at most 42).
        pub exponent: f32 = SettingKey::float("exponent", "40", 0.5, 42.0, "positive warp exp(c (2d - 1)): c"),
        /// The negative warp's exponent.
        pub negative_exponent: f32 = SettingKey::float("negative_exponent", "5", 0.5, 42.0, "negative warp -exp(-c (2d - 1)): c"),
    }
    lights = LightKinds::SPOT;
}

shadow_core::technique_settings! {
    /// `moment-shadow-map` settings.
    pub struct MomentShadowMap {
        /// The depth map: side and bias, as `shadow-map` has them.
        pub depth: DepthMap = DEPTH,
        /// Radius in texels of the moments' blur.
        pub blur: u32 = BLUR,
        /// Light-bleeding reduction.
        pub bleed: f32 = bleed_key("0"),
        /// The moment bias alpha (the paper's 3e-5).
        pub moment_bias: f32 = SettingKey::float("moment_bias", "0.00003", 0.0, 0.1, "moments mixed by this weight with those of depths 0, 1/2 and 1 weighing 0.315, 0.37 and 0.315"),
    }
    lights = LightKinds::SPOT;
}

/// A moment map as the backends run it: which moments, and how they are filtered.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MomentMap {
    /// Which moments and how visibility comes from them.
    pub kind: MomentKind,
    /// The depth map: side and bias.
    pub depth: DepthMap,
    /// Radius in texels of the moments' blur.
    pub blur: u32,
    /// Light-bleeding reduction.
    pub bleed: f32,
}

impl From<VarianceShadowMap> for MomentMap {
    fn from(s: VarianceShadowMap) -> Self {
        Self { kind: MomentKind::Variance, depth: s.depth, blur: s.blur, bleed: s.bleed }
    }
}

impl From<ExponentialVarianceShadowMap> for MomentMap {
    fn from(s: ExponentialVarianceShadowMap) -> Self {
        let kind = MomentKind::ExponentialVariance { positive: s.exponent, negative: s.negative_exponent };
        Self { kind, depth: s.depth, blur: s.blur, bleed: s.bleed }
    }
}

impl From<MomentShadowMap> for MomentMap {
    fn from(s: MomentShadowMap) -> Self {
        Self { kind: MomentKind::Hamburger { bias: s.moment_bias }, depth: s.depth, blur: s.blur, bleed: s.bleed }
    }
}

impl MomentMap {
    /// The registry name of the map's kind.
    #[must_use]
    pub fn name(&self) -> &'static str {
        match self.kind {
            MomentKind::Variance => "variance-shadow-map",
            MomentKind::ExponentialVariance { .. } => "exponential-variance-shadow-map",
            MomentKind::Hamburger { .. } => "moment-shadow-map",
        }
    }

    /// The lens of a spot light's view: the blocker search and the penumbra, as `pcss` sizes them.
    ///
    /// # Errors
    /// [`TechniqueError::UnsupportedLight`] for point and directional lights.
    pub fn lens(&self, light: &LightView) -> Result<PcssLens, TechniqueError> {
        let p = crate::spot_projection(light, self.name())?;
        Ok(Pcss::lens_of(light, p))
    }

    /// Visibility of a receiver at normalized depth `t` and linear depth `z_r` behind blockers at mean
    /// linear depth `z_b`, whose map point is where `average(side)` finds the moments averaged over a
    /// square of that side (map coordinates).
    pub fn visibility(&self, lens: &PcssLens, t: f32, z_r: f32, z_b: f32, average: impl Fn(f32) -> [f32; 4]) -> f32 {
        let side = BOX_PER_DISC_RADIUS * lens.filter_radius(z_r, z_b);
        linstep(self.bleed, 1.0, self.kind.visibility(average(side), t))
    }

    /// `[k, near, far, bleed]`: the GPU query's `MapParams.extra` (the kind is a pipeline constant).
    #[must_use]
    pub fn uniform(&self, lens: &PcssLens) -> [f32; 4] {
        [lens.k, lens.proj.near, lens.proj.far, self.bleed]
    }
}

/// The entry of the moment map `S`.
fn entry<S>(name: &'static str, description: &'static str, paper: &'static str) -> Entry
where
    S: TechniqueSettings + Into<MomentMap>,
{
    Entry::new::<S>(
        name,
        description,
        paper,
        Some(converted::<CpuBackend, S, MomentMap>),
        Some(converted::<WgpuBackend, S, MomentMap>),
    )
    .wgsl(gpu::shaders)
    .soft()
}

/// The registry entry of the variance shadow map.
#[must_use]
pub fn variance_entry() -> Entry {
    entry::<VarianceShadowMap>(
        "variance-shadow-map",
        "mean and mean square of depth, filtered; Chebyshev's bound, sized to the penumbra",
        "Donnelly-Lauritzen 2006",
    )
}

/// The registry entry of the exponential variance shadow map.
#[must_use]
pub fn exponential_variance_entry() -> Entry {
    entry::<ExponentialVarianceShadowMap>(
        "exponential-variance-shadow-map",
        "variance maps of exp(c d) and -exp(-c d): less light bleeding, sized to the penumbra",
        "Lauritzen-McCool 2008",
    )
}

/// The registry entry of the moment shadow map.
#[must_use]
pub fn moment_entry() -> Entry {
    entry::<MomentShadowMap>(
        "moment-shadow-map",
        "four moments of depth, filtered; the Hamburger bound, sized to the penumbra",
        "Peters-Klein 2015",
    )
}
