//! Settings of the hard-shadow techniques (DESIGN 6).

use super::settings::{
    BiasMode, DepthBias, Filter, MAX_MAP_RESOLUTION, SettingKey, SettingsError, TechniqueSettings, Values,
};

/// `ray-traced`: one shadow ray per G-buffer pixel, the exact reference.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RayTraced {
    /// Shadow-ray origin offset along the geometric normal, as a fraction of the scene's bounding-box
    /// diagonal (so the offset scales with the scene). The default, 5e-7, is a few f32 ulps of the scene's
    /// size: enough to clear the rounding of the surface position, small enough not to shift rays past
    /// sub-centimetre occluders (at 2e-5 the tree's thin branch shadows moved by a pixel in 0.1% of the
    /// image; from 2e-6 down the reference stops changing).
    pub epsilon: f32,
}

impl TechniqueSettings for RayTraced {
    fn keys() -> &'static [SettingKey] {
        &[SettingKey {
            key: "epsilon",
            default: "0.0000005",
            help: "ray origin offset along the normal, as a fraction of the scene diagonal",
        }]
    }
    fn from_values(v: &Values<'_>) -> Result<Self, SettingsError> {
        Ok(Self { epsilon: v.ranged("epsilon", 0.0, 0.1)? })
    }
    fn to_values(&self) -> Vec<String> {
        vec![self.epsilon.to_string()]
    }
}

/// `shadow-map`: Williams' depth map with Vulkan depth bias and percentage-closer filtering.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadowMap {
    /// Map side in texels.
    pub resolution: u32,
    /// Bias mode.
    pub bias: BiasMode,
    /// Vulkan constant depth-bias factor. The default, 4 (four f32 ulps at the primitive's depth), is the
    /// smallest that settles ties on surfaces squarely facing the light: there the stored and the looked-up
    /// depths are equal up to rounding, and at 1 the GPU's interpolated positions lost the tie on a
    /// table top seen through a cube face (0.5% acne on lavapipe, none on the CPU); 4 to 64 changed no
    /// other error.
    pub bias_constant: f32,
    /// Vulkan slope depth-bias factor.
    pub bias_slope: f32,
    /// Lookup filter.
    pub filter: Filter,
    /// Kernel radius in texels for `pcf4x4-jitter` and `poisson16`.
    pub filter_radius: f32,
}

const MAP_KEYS: [SettingKey; 6] = [
    SettingKey { key: "res", default: "2048", help: "map side in texels (16 to 16384)" },
    SettingKey {
        key: "bias",
        default: "slope",
        help: "none, constant or slope (Vulkan depth bias when the map is rendered)",
    },
    SettingKey {
        key: "bias_constant",
        default: "4",
        help: "constant bias factor, in units of the f32 depth resolution at the primitive",
    },
    SettingKey {
        key: "bias_slope",
        default: "2",
        help: "slope bias factor, times the primitive's largest depth change per texel",
    },
    SettingKey { key: "filter", default: "none", help: "none, bilinear, pcf3x3, pcf4x4-jitter or poisson16" },
    SettingKey {
        key: "filter_radius",
        default: "1.5",
        help: "kernel radius in texels for pcf4x4-jitter and poisson16",
    },
];

/// Reads the map resolution key `res`.
///
/// # Errors
/// Out of 16..=[`MAX_MAP_RESOLUTION`].
pub fn read_resolution(v: &Values<'_>) -> Result<u32, SettingsError> {
    v.ranged("res", 16u32, MAX_MAP_RESOLUTION)
}

impl ShadowMap {
    /// The depth bias to render the map with.
    #[must_use]
    pub fn depth_bias(&self) -> DepthBias {
        DepthBias::from_mode(self.bias, self.bias_constant, self.bias_slope)
    }
}

impl TechniqueSettings for ShadowMap {
    fn keys() -> &'static [SettingKey] {
        &MAP_KEYS
    }
    fn from_values(v: &Values<'_>) -> Result<Self, SettingsError> {
        Ok(Self {
            resolution: read_resolution(v)?,
            bias: v.get("bias")?,
            bias_constant: v.ranged("bias_constant", 0.0, 1e9)?,
            bias_slope: v.ranged("bias_slope", 0.0, 1e4)?,
            filter: v.get("filter")?,
            filter_radius: v.ranged("filter_radius", 0.0, 64.0)?,
        })
    }
    fn to_values(&self) -> Vec<String> {
        vec![
            self.resolution.to_string(),
            self.bias.to_string(),
            self.bias_constant.to_string(),
            self.bias_slope.to_string(),
            self.filter.to_string(),
            self.filter_radius.to_string(),
        ]
    }
}

/// How stencil shadow volumes count (the technique name picks it).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VolumeCounting {
    /// Crow / Heidmann: count volume faces in front of the surface; sides only. Wrong where the eye is in
    /// shadow or a volume crosses the near plane.
    ZPass,
    /// Everitt-Kilgard / Carmack: count faces behind the surface; needs both caps; right everywhere with an
    /// infinite far plane.
    ZFail,
}

/// `shadow-volume-zpass` and `shadow-volume-zfail`: stencil shadow volumes from silhouette edges.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadowVolume {
    /// Which counting.
    pub counting: VolumeCounting,
}

impl ShadowVolume {
    /// Z-pass volumes.
    pub const ZPASS: Self = Self { counting: VolumeCounting::ZPass };
    /// Z-fail volumes.
    pub const ZFAIL: Self = Self { counting: VolumeCounting::ZFail };
}

impl TechniqueSettings for ShadowVolume {
    fn keys() -> &'static [SettingKey] {
        &[]
    }
    fn from_values(_: &Values<'_>) -> Result<Self, SettingsError> {
        Ok(Self::ZFAIL)
    }
    fn to_values(&self) -> Vec<String> {
        Vec::new()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_parse_and_print() {
        let s = ShadowMap::defaults();
        assert_eq!(
            s.settings_string(),
            "res=2048,bias=slope,bias_constant=4,bias_slope=2,filter=none,filter_radius=1.5"
        );
        let _ = RayTraced::defaults();
        let _ = ShadowVolume::defaults();
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
        let e = ShadowVolume::parse("shadow-volume-zfail", &given("res", "1")).unwrap_err();
        assert!(e.to_string().contains("settings: none"), "{e}");
    }
}
