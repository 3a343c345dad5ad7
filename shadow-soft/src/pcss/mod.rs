//! `pcss`: percentage-closer soft shadows (Fernando 2005), the comparison the smoothie thesis draws
//! against filtering a single shadow map.
//!
//! Build: the blockers' depth map, as `shadow-map` renders it. Query, per receiver at linear depth `z_r`:
//!
//! 1. **Blocker search.** The map texels whose rays can hold a blocker between the receiver and some point
//!    of the light lie, for blockers no nearer than the map's near plane, within a disc of radius
//!    `k (z_r - near) / (near z_r)` around the receiver's map point (`k` the light's radius in map
//!    coordinates at unit distance). 16 Poisson taps there; those nearer than the receiver are blockers,
//!    their linear depths averaged to `z_b`. None: the receiver is lit.
//! 2. **Penumbra estimate.** Similar triangles: the penumbra's half-width at the receiver is
//!    `radius (z_r - z_b) / z_b`, in map coordinates `k (z_r - z_b) / (z_b z_r)`.
//! 3. **Filtering.** 16 bilinear percentage-closer taps over a disc of that radius.
//!
//! Both discs are `shadow_core::lookup::POISSON16`, turned per pixel by the same hash as the `poisson16`
//! filter (Fernando's fixed pattern bands; a turned one trades the bands for noise). Each tap compares
//! against the receiver's plane at the tap (`LightProjection::depth_gradient`) rather than its depth at
//! the centre: kernels tens of texels wide would otherwise find the receiver itself as a blocker on any
//! surface tilted to the light (receiver-plane depth bias; the map's own bias is `shadow-map`'s).
//!
//! Spot lights only: point lights need the search across cube faces, and a directional light has no
//! position for the similar triangles; both are refused by name.

pub mod cpu;
pub mod gpu;

use crate::Entry;
use shadow_core::light::{LightProjection, LightView};
use shadow_core::technique::LightKinds;
use shadow_core::technique::TechniqueError;
use shadow_core::technique::maps::{DepthMap, resolution_key};

shadow_core::technique_settings! {
    /// `pcss` settings.
    pub struct Pcss {
        /// The depth map: resolution and bias, as `shadow-map` has them. The light's size is its radius.
        pub depth: DepthMap = DepthMap::keys(resolution_key("1024", "depth map side in texels (16 to 16384)")),
    }
    lights = LightKinds::SPOT;
}

/// What the search and filter sizes need of the light and its projection.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PcssLens {
    /// The light's radius in map coordinates at unit distance along the axis.
    pub k: f32,
    /// The projection, for linear depths.
    pub proj: LightProjection,
}

impl PcssLens {
    /// The blocker search radius in map coordinates for a receiver at linear depth `z_r`.
    #[must_use]
    pub fn search_radius(&self, z_r: f32) -> f32 {
        self.k * (z_r - self.proj.near) / (self.proj.near * z_r)
    }

    /// The filter radius in map coordinates: the penumbra's half-width at a receiver at linear depth `z_r`
    /// behind blockers at `z_b`.
    #[must_use]
    pub fn filter_radius(&self, z_r: f32, z_b: f32) -> f32 {
        self.k * (z_r - z_b).max(0.0) / (z_b * z_r)
    }

    /// `[k, near, far, 0]`, the GPU query's `MapParams.extra`.
    #[must_use]
    pub fn uniform(&self) -> [f32; 4] {
        [self.k, self.proj.near, self.proj.far, 0.0]
    }
}

impl Pcss {
    /// The technique's name.
    pub const NAME: &'static str = "pcss";

    /// The lens of a spot light's view.
    ///
    /// # Errors
    /// [`TechniqueError::UnsupportedLight`] for point and directional lights.
    pub fn lens(light: &LightView) -> Result<PcssLens, TechniqueError> {
        Ok(Self::lens_of(light, crate::spot_projection(light, Self::NAME)?))
    }

    /// The lens of `light` through its spot projection `p`.
    #[must_use]
    pub fn lens_of(light: &LightView, p: &LightProjection) -> PcssLens {
        // uv = (x_ndc + 1) / 2 and x_ndc = P00 x / z: a lateral offset x at distance z spans P00 x / (2 z)
        // of the map.
        PcssLens { k: light.light.radius * p.clip_from_view.x_axis.x * 0.5, proj: *p }
    }
}

/// The registry entry.
#[must_use]
pub fn entry() -> Entry {
    Entry::on_both::<Pcss>(
        Pcss::NAME,
        "percentage-closer soft shadows: a blocker search sizes a PCF kernel to the penumbra",
        "Fernando 2005",
    )
    .wgsl(gpu::shaders)
    .soft()
}
