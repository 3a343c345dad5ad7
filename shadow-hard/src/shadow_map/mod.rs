//! `shadow-map` (Williams 1978; the survey of Nealen, section 3; Weiskopf-Ertl section 5): depth from the
//! light, rendered with Vulkan's depth bias, compared at each receiver with a percentage-closer filter.
//! Spot and directional lights use one map, point lights six cube faces.
//!
//! The map and its lookup are the backends' shared passes (`passes::maps` on each), which every
//! technique built on a depth map uses too; this technique is the two of them with nothing added.

pub mod cpu;
pub mod gpu;

use crate::Entry;
use shadow_core::FrameInputs;
use shadow_core::light::LightView;
use shadow_core::technique::maps::{
    BIAS, BIAS_CONSTANT, BIAS_SLOPE, BIAS_WORLD, DepthMap, FILTER, FILTER_RADIUS, resolution_key,
};
use shadow_core::technique::maps::{MapLayout, MapSampling};
use shadow_core::technique::settings::{BiasMode, Filter};
#[cfg(test)]
use shadow_core::technique::settings::{SettingsError, TechniqueSettings};

shadow_core::technique_settings! {
    /// `shadow-map`: Williams' depth map with Vulkan depth bias and percentage-closer filtering. The map's
    /// keys come first and the filter's between the bias factors and `bias_world`, so the fields are flat
    /// here; [`ShadowMap::map`] puts the map's together.
    pub struct ShadowMap {
        /// Map side in texels.
        pub resolution: u32 = resolution_key("2048", "map side in texels (16 to 16384)"),
        /// Bias mode.
        pub bias: BiasMode = BIAS,
        /// Vulkan constant depth-bias factor (see [`DepthMap::bias_constant`]).
        pub bias_constant: f32 = BIAS_CONSTANT,
        /// Vulkan slope depth-bias factor.
        pub bias_slope: f32 = BIAS_SLOPE,
        /// Lookup filter.
        pub filter: Filter = FILTER,
        /// Kernel radius in texels for `pcf4x4-jitter` and `poisson16`.
        pub filter_radius: f32 = FILTER_RADIUS,
        /// Receiver offset towards the light, in scene units, for `bias=world`.
        pub bias_world: f32 = BIAS_WORLD,
    }
}

impl ShadowMap {
    /// The technique's name.
    pub const NAME: &'static str = "shadow-map";

    /// The map: side and bias.
    #[must_use]
    pub fn map(&self) -> DepthMap {
        DepthMap {
            resolution: self.resolution,
            bias: self.bias,
            bias_constant: self.bias_constant,
            bias_slope: self.bias_slope,
            bias_world: self.bias_world,
        }
    }
}

/// One map over the light's fitted view, whatever the camera sees: the uniform map.
impl MapLayout for ShadowMap {
    fn sampling(&self, _: &FrameInputs, light: &LightView, _: f32) -> MapSampling {
        MapSampling { view: light.clone(), resolution: self.resolution }
    }
}

/// The registry entry.
#[must_use]
pub fn entry() -> Entry {
    Entry::on_both::<ShadowMap>(
        ShadowMap::NAME,
        "depth map from the light with Vulkan depth bias and percentage-closer filtering",
        "Williams 1978; Reeves et al. 1987 (survey: Nealen 2005)",
    )
    .with_layout::<ShadowMap>()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_parse_and_print() {
        assert_eq!(
            ShadowMap::defaults().settings_string(),
            "res=2048,bias=slope,bias_constant=16,bias_slope=2,filter=none,filter_radius=1.5,bias_world=0.05"
        );
    }

    #[test]
    fn bad_settings_name_key_and_value() {
        let given = |k: &str, v: &str| vec![(k.to_string(), v.to_string())];
        let e = ShadowMap::parse("shadow-map", &given("res", "99999")).unwrap_err();
        assert!(e.to_string().contains("'99999' for 'res'"), "{e}");
        let e = ShadowMap::parse("shadow-map", &given("filter", "gauss")).unwrap_err();
        assert!(e.to_string().contains("pcf3x3"), "{e}");
        let e = ShadowMap::parse("shadow-map", &given("colour", "red")).unwrap_err();
        assert!(matches!(e, SettingsError::UnknownKey { .. }));
    }
}
