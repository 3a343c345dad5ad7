//! Soft shadows, written only against the public APIs of shadow-core, shadow-cpu and shadow-wgpu (DESIGN
//! 2): the proof that a technique can live outside the backends. Where a backend lacked something a
//! technique here needed, it was added to that backend's public API, documented.
//!
//! - [`area_light::AreaLightReference`] (`area-light-reference`): the reference soft techniques are
//!   measured against, Monte Carlo visibility of a spherical light through the CPU backend's BVH.
//! - [`smoothies::Smoothies`] (`smoothies`): Chan and Durand's fake soft shadows.
//! - [`pcss::Pcss`] (`pcss`): Fernando's percentage-closer soft shadows.
//! - [`penumbra_map::PenumbraMap`] (`penumbra-map`): Wyman and Hansen's cones and sheets.
//! - [`moment_maps`] (`variance-shadow-map`, `exponential-variance-shadow-map`, `moment-shadow-map`):
//!   filterable maps of depth moments, sized to the penumbra.
//! - [`penumbra_wedges::PenumbraWedges`] (`penumbra-wedges`): Akenine-Moeller and Assarsson's soft shadow
//!   volumes, a wedge per silhouette edge.

pub mod area_light;
pub mod min_target;
pub mod moment_maps;
pub mod pcss;
pub mod penumbra_map;
pub mod penumbra_wedges;
pub mod smoothies;

/// A registry entry of a technique on the two backends.
pub type Entry = shadow_core::technique::registry::Entry<shadow_cpu::CpuBackend, shadow_wgpu::WgpuBackend>;

pub use area_light::AreaLightReference;
pub use pcss::Pcss;
pub use penumbra_map::PenumbraMap;
pub use penumbra_wedges::PenumbraWedges;
pub use smoothies::Smoothies;

use shadow_core::light::{LightProjection, LightView};
use shadow_core::scene::LightKind;
use shadow_core::technique::TechniqueError;

/// The one projection of a spot light's view, for techniques that need the light's position and a single
/// map. Point lights (six maps) and directional lights (no position) are refused by name.
///
/// # Errors
/// [`TechniqueError::UnsupportedLight`] for point and directional lights.
pub fn spot_projection<'a>(light: &'a LightView, technique: &str) -> Result<&'a LightProjection, TechniqueError> {
    match (light.light.kind, light.projections.as_slice()) {
        (LightKind::Spot { .. }, [p]) => Ok(p),
        _ => Err(TechniqueError::unsupported_light(technique, &light.light)),
    }
}
