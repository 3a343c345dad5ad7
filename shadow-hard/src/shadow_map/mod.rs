//! `shadow-map` (Williams 1978; the survey of Nealen, section 3; Weiskopf-Ertl section 5): depth from the
//! light, rendered with Vulkan's depth bias, compared at each receiver with a percentage-closer filter.
//! Spot and directional lights use one map, point lights six cube faces.
//!
//! The map and its lookup are the backends' shared passes (`passes::maps` on each), which every
//! technique built on a depth map uses too; this technique is the two of them with nothing added.

pub mod cpu;
pub mod gpu;

use crate::Entry;
use shadow_core::technique::maps::{
    BIAS, BIAS_CONSTANT, BIAS_SLOPE, BIAS_WORLD, DepthMap, FILTER, FILTER_RADIUS, resolution_key,
};
use shadow_core::technique::settings::{Filter, SettingKey, SettingsError, TechniqueSettings, Values};

/// `shadow-map`: Williams' depth map with Vulkan depth bias and percentage-closer filtering.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadowMap {
    /// The map: side and bias.
    pub map: DepthMap,
    /// Lookup filter.
    pub filter: Filter,
    /// Kernel radius in texels for `pcf4x4-jitter` and `poisson16`.
    pub filter_radius: f32,
}

impl ShadowMap {
    /// The technique's name.
    pub const NAME: &'static str = "shadow-map";
}

const KEYS: [SettingKey; 7] = [
    resolution_key("2048", "map side in texels (16 to 16384)"),
    BIAS,
    BIAS_CONSTANT,
    BIAS_SLOPE,
    FILTER,
    FILTER_RADIUS,
    BIAS_WORLD,
];

impl TechniqueSettings for ShadowMap {
    fn keys() -> &'static [SettingKey] {
        &KEYS
    }
    fn from_values(v: &Values<'_>) -> Result<Self, SettingsError> {
        Ok(Self {
            map: DepthMap::read(v)?,
            filter: v.get("filter")?,
            filter_radius: v.ranged("filter_radius", 0.0, 64.0)?,
        })
    }
    fn to_values(&self) -> Vec<String> {
        let m = &self.map;
        vec![
            m.resolution.to_string(),
            m.bias.to_string(),
            m.bias_constant.to_string(),
            m.bias_slope.to_string(),
            self.filter.to_string(),
            self.filter_radius.to_string(),
            m.bias_world.to_string(),
        ]
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
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_parse_and_print() {
        assert_eq!(
            ShadowMap::defaults().settings_string(),
            "res=2048,bias=slope,bias_constant=4,bias_slope=2,filter=none,filter_radius=1.5,bias_world=0.05"
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
