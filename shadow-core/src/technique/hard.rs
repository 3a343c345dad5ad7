//! Settings of the hard-shadow techniques (DESIGN 6).

use crate::silhouette_map::{CornerDepth, Keep};

mod hybrid;
pub use hybrid::{EdgeTexels, GpuMask, Hybrid, MAX_PAIR_ROOM};

use super::settings::{
    BiasMode, DepthBias, Filter, MAX_MAP_RESOLUTION, OnOff, SettingKey, SettingsError, TechniqueSettings, Values,
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
    /// Receiver offset towards the light, in scene units, for `bias=world`.
    pub bias_world: f32,
}

/// The keys of `shadow-map`, in order: `res`, `bias`, `bias_constant`, `bias_slope`, `filter`,
/// `filter_radius`, `bias_world`. Techniques built on a depth map take the ones they use from here, so
/// their defaults and help stay the same.
pub const MAP_KEYS: [SettingKey; 7] = [
    SettingKey { key: "res", default: "2048", help: "map side in texels (16 to 16384)" },
    SettingKey {
        key: "bias",
        default: "slope",
        help: "none, constant or slope (Vulkan depth bias when the map is rendered), or world (bias_world)",
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
    SettingKey {
        key: "bias_world",
        default: "0.05",
        help: "for bias=world: receiver offset towards the light, in scene units",
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

    /// The receiver offset towards the light applied at lookup (non-zero only for `bias=world`).
    #[must_use]
    pub fn receiver_offset(&self) -> f32 {
        if self.bias == BiasMode::World { self.bias_world } else { 0.0 }
    }

    /// Reads the depth-map keys (`res` and the bias keys, as [`MAP_KEYS`] has them), with no filter: for
    /// techniques built on a depth map.
    ///
    /// # Errors
    /// A value that does not parse or is out of range.
    pub fn read_depth(v: &Values<'_>) -> Result<Self, SettingsError> {
        Ok(Self {
            resolution: read_resolution(v)?,
            bias: v.get("bias")?,
            bias_constant: v.ranged("bias_constant", 0.0, 1e9)?,
            bias_slope: v.ranged("bias_slope", 0.0, 1e4)?,
            filter: Filter::None,
            filter_radius: 0.0,
            bias_world: v.ranged("bias_world", 0.0, 1e6)?,
        })
    }

    /// The depth-map keys' values, in [`ShadowMap::read_depth`]'s order: the first values of
    /// `to_values` for techniques built on a depth map.
    #[must_use]
    pub fn depth_values(&self) -> Vec<String> {
        vec![
            self.resolution.to_string(),
            self.bias.to_string(),
            self.bias_constant.to_string(),
            self.bias_slope.to_string(),
            self.bias_world.to_string(),
        ]
    }
}

impl TechniqueSettings for ShadowMap {
    fn keys() -> &'static [SettingKey] {
        &MAP_KEYS
    }
    fn from_values(v: &Values<'_>) -> Result<Self, SettingsError> {
        Ok(Self {
            filter: v.get("filter")?,
            filter_radius: v.ranged("filter_radius", 0.0, 64.0)?,
            ..Self::read_depth(v)?
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
            self.bias_world.to_string(),
        ]
    }
}

/// `silhouette-map` (Sen, Cammarano, Hanrahan 2003): a shadow map plus a map of points on the
/// silhouettes, shifted half a texel; the lookup reconstructs a piecewise-linear shadow edge.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SilhouetteMap {
    /// The depth map: resolution and bias as `shadow-map` has them (its filter is unused: the
    /// reconstruction replaces it).
    pub depth: ShadowMap,
    /// The corner rule's enlargement of the clip square, in texels (section 3.1: "within limits of
    /// precision"). At 0.01 a segment within a hundredth of a texel of a corner is stored in all four texels
    /// around it, far above the rounding of texel coordinates (about 1e-4 at 4096 texels).
    pub corner_margin: f32,
    /// What each corner sample is compared with.
    pub corner_depth: CornerDepth,
    /// Which point a texel crossed by several silhouettes keeps.
    pub keep: Keep,
}

const SILHOUETTE_KEYS: [SettingKey; 8] = [
    SettingKey {
        key: "res",
        default: "1024",
        help: "depth-map side in texels (16 to 16384); the silhouette map has one texel fewer",
    },
    MAP_KEYS[1],
    MAP_KEYS[2],
    MAP_KEYS[3],
    MAP_KEYS[6],
    SettingKey {
        key: "corner_margin",
        default: "0.01",
        help: "corner rule: how far outside a texel, in texels, a segment still counts as crossing it",
    },
    SettingKey {
        key: "corner_depth",
        default: "receiver-plane",
        help: "compare corner samples with the receiver plane's depth there, or the fragment's own (the paper)",
    },
    SettingKey {
        key: "keep",
        default: "nearest",
        help: "the point a texel crossed by several silhouettes keeps: nearest the light, or last drawn (the paper)",
    },
];

impl TechniqueSettings for SilhouetteMap {
    fn keys() -> &'static [SettingKey] {
        &SILHOUETTE_KEYS
    }
    fn from_values(v: &Values<'_>) -> Result<Self, SettingsError> {
        Ok(Self {
            depth: ShadowMap::read_depth(v)?,
            corner_margin: v.ranged("corner_margin", 0.0, 0.25)?,
            corner_depth: v.get("corner_depth")?,
            keep: v.get("keep")?,
        })
    }
    fn to_values(&self) -> Vec<String> {
        let mut v = self.depth.depth_values();
        v.extend([self.corner_margin.to_string(), self.corner_depth.to_string(), self.keep.to_string()]);
        v
    }
}

crate::named_enum! {
    /// The edge detector of `volume-reconstruction`.
    pub enum EdgeTest {
        /// First differences over theta_L thinned by the second-derivative test, sure edges over theta_H
        /// (section 3.3).
        SecondDerivative = "second-derivative",
        /// First differences over theta_L alone (section 3.1).
        FirstDifference = "first-difference",
    }
}

crate::named_enum! {
    /// Whether `volume-reconstruction`'s light pass also renders object IDs, whose differences become edge
    /// flags (McCool section 3.2: "as a last resort").
    pub enum ObjectIds {
        /// Depth edges only.
        Off = "off",
        /// A dangling depth edge is followed along an ID boundary first, before the lowered depth test: the
        /// paper's "this need only be done in the vicinity of a dangling edge".
        Dangling = "dangling",
        /// Every ID difference is an edge, ORed with the depth edges (the paper's test for scenes of convex
        /// objects, which then need no depth test at all).
        All = "all",
    }
}

crate::named_enum! {
    /// Where the mesh of `volume-reconstruction` has its vertices.
    pub enum MeshVertices {
        /// At texel centres, edge midpoints and corners, a border sample taking the far side: shadows the
        /// size of the shadow map's (see `reconstruction::texel_square_grid`).
        Texel = "texel",
        /// At the texel centres, as the paper has them: every shadow half a texel larger.
        Centre = "centre",
    }
}

/// `volume-reconstruction` (McCool 2000): a shadow volume rebuilt from the light's depth map, resolved
/// with a one-bit parity stencil.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VolumeReconstruction {
    /// The depth map: resolution and bias as `shadow-map` has them (the filter is unused). The bias
    /// moves the reconstructed boundary away from the light, as the paper's bias translation of the light
    /// depths does; `bias=world` moves each vertex `bias_world` along its light ray.
    pub depth: ShadowMap,
    /// Where the mesh's vertices are.
    pub vertices: MeshVertices,
    /// The detector.
    pub edges: EdgeTest,
    /// theta_L, theta_H, theta_S and the dangling-edge threshold, as fractions of the fitted light depth
    /// range (far minus near), applied to linear depths.
    pub theta_low: f32,
    /// See `theta_low`.
    pub theta_high: f32,
    /// See `theta_low`.
    pub theta_second: f32,
    /// See `theta_low`.
    pub theta_dangling: f32,
    /// How many cells a dangling edge is followed under the lowered thresholds.
    pub dangling_steps: u32,
    /// Object-ID edges from an ID channel of the light pass.
    pub ids: ObjectIds,
    /// The near-plane cap: on, software caps (McCool section 6.2); off, none, so that where the eye's near
    /// plane cuts the volume parity inverts (Fig. 7).
    pub capping: OnOff,
}

const RECONSTRUCTION_KEYS: [SettingKey; 14] = [
    SettingKey { key: "res", default: "1024", help: "depth-map side in texels (16 to 16384)" },
    MAP_KEYS[1],
    MAP_KEYS[2],
    // An eighth of shadow-map's: the mesh is drawn only across discontinuities, where its slopes fall
    // away from the occluder, so the bias is needed only against false-positive cells lying on a surface,
    // and a receiver's bias sinks the slopes' far ends behind it and erodes the shadow (cubes, map 512:
    // slope 2 gives 1.03%, 0.25 gives 0.69%, shadow-map 0.92%; none leaves false-positive rows on strike).
    SettingKey {
        key: "bias_slope",
        default: "0.25",
        help: "slope bias factor, times the primitive's largest depth change per texel",
    },
    MAP_KEYS[6],
    SettingKey {
        key: "vertices",
        default: "texel",
        help: "texel (centres, midpoints and corners: shadow-map-sized shadows) or centre (the paper's)",
    },
    SettingKey {
        key: "edges",
        default: "second-derivative",
        help: "second-derivative (thinned, section 3.3) or first-difference (section 3.1)",
    },
    SettingKey {
        key: "theta_low",
        default: "0.001",
        help: "candidate edge threshold, fraction of the light depth range",
    },
    SettingKey { key: "theta_high", default: "0.01", help: "sure edge threshold, fraction of the light depth range" },
    SettingKey {
        key: "theta_second",
        default: "0.0005",
        help: "second-derivative zero-crossing strength, fraction of the light depth range",
    },
    SettingKey {
        key: "theta_dangling",
        default: "0.0001",
        help: "lowered threshold along dangling edges, fraction of the light depth range",
    },
    SettingKey { key: "dangling_steps", default: "8", help: "cells a dangling edge is followed (0 to 64)" },
    SettingKey {
        key: "ids",
        default: "off",
        help: "object-ID edges: off, dangling (dangling edges follow ID boundaries) or all (ORed with depth edges)",
    },
    SettingKey { key: "capping", default: "on", help: "near-plane caps: on, or off to see the inversion" },
];

impl TechniqueSettings for VolumeReconstruction {
    fn keys() -> &'static [SettingKey] {
        &RECONSTRUCTION_KEYS
    }
    fn from_values(v: &Values<'_>) -> Result<Self, SettingsError> {
        let r = Self {
            depth: ShadowMap::read_depth(v)?,
            vertices: v.get("vertices")?,
            edges: v.get("edges")?,
            theta_low: v.ranged("theta_low", 0.0, 1.0)?,
            theta_high: v.ranged("theta_high", 0.0, 1.0)?,
            theta_second: v.ranged("theta_second", 0.0, 1.0)?,
            theta_dangling: v.ranged("theta_dangling", 0.0, 1.0)?,
            dangling_steps: v.ranged("dangling_steps", 0, 64)?,
            ids: v.get("ids")?,
            capping: v.get("capping")?,
        };
        if r.theta_high < r.theta_low {
            return Err(v.bad("theta_high", &format!("at least theta_low ({})", r.theta_low)));
        }
        Ok(r)
    }
    fn to_values(&self) -> Vec<String> {
        let mut v = self.depth.depth_values();
        v.extend([
            self.vertices.to_string(),
            self.edges.to_string(),
            self.theta_low.to_string(),
            self.theta_high.to_string(),
            self.theta_second.to_string(),
            self.theta_dangling.to_string(),
            self.dangling_steps.to_string(),
            self.ids.to_string(),
            self.capping.to_string(),
        ]);
        v
    }
}

impl VolumeReconstruction {
    /// The detector's thresholds in scene units for a light depth range of `range`.
    #[must_use]
    pub fn edge_settings(&self, range: f32) -> crate::reconstruction::edges::EdgeSettings {
        crate::reconstruction::edges::EdgeSettings {
            low: self.theta_low * range,
            high: self.theta_high * range,
            second: (self.edges == EdgeTest::SecondDerivative).then_some(self.theta_second * range),
            dangling: self.theta_dangling * range,
            dangling_steps: self.dangling_steps,
        }
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
            "res=2048,bias=slope,bias_constant=4,bias_slope=2,filter=none,filter_radius=1.5,bias_world=0.05"
        );
        let _ = RayTraced::defaults();
        assert_eq!(
            SilhouetteMap::defaults().settings_string(),
            "res=1024,bias=slope,bias_constant=4,bias_slope=2,bias_world=0.05,corner_margin=0.01,\
             corner_depth=receiver-plane,keep=nearest"
        );
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

/// Which depth-layer map (Weiskopf-Ertl 2003): the name picks it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LayerKind {
    /// Woo: the midpoint of the two nearest layers, (z1 + z2) / 2.
    Midpoint,
    /// Wang-Molnar: the second-nearest layer, z2.
    SecondDepth,
    /// Weiskopf-Ertl: z1 + min((z2 - z1) / 2, z_offset).
    Dual,
}

impl LayerKind {
    /// The registry name.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Self::Midpoint => "midpoint-shadow-map",
            Self::SecondDepth => "second-depth-shadow-map",
            Self::Dual => "dual-shadow-map",
        }
    }
}

crate::named_enum! {
    /// Face culling in the light passes.
    pub enum LayerCulling {
        /// Back faces culled for closed meshes, none for open ones (the paper's mix in one scene).
        Auto = "auto",
        /// No culling.
        None = "none",
    }
}

/// The two nearest depth layers from the light, combined into one map: `midpoint-shadow-map`,
/// `second-depth-shadow-map` and `dual-shadow-map`. Only the build differs from `shadow-map`; the lookup
/// and every filter are the same.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DepthLayers {
    /// Which combination.
    pub kind: LayerKind,
    /// Map side in texels.
    pub resolution: u32,
    /// Lookup filter.
    pub filter: Filter,
    /// Kernel radius in texels.
    pub filter_radius: f32,
    /// The dual map's largest bias, in scene units along the light's view axis.
    pub z_offset: f32,
    /// The second pass drops fragments within this NDC depth of the first layer.
    pub peel_epsilon: f32,
    /// Culling in both light passes.
    pub culling: LayerCulling,
}

impl DepthLayers {
    /// The combined depth, in linear depth along the light's axis, of the two nearest layers `l1 <= l2`
    /// (the far plane standing in for a missing layer). Computed on linear depths so `z_offset` is a scene
    /// distance; with an orthographic light (the paper's figures) this is the paper's formula exactly.
    /// WGSL twin: `combine_layers` in depth_layers.wgsl.
    #[must_use]
    pub fn combine(&self, l1: f32, l2: f32) -> f32 {
        match self.kind {
            LayerKind::Midpoint => 0.5 * (l1 + l2),
            LayerKind::SecondDepth => l2,
            LayerKind::Dual => l1 + (0.5 * (l2 - l1)).min(self.z_offset),
        }
    }

    fn keys_with(culling: &'static str) -> [SettingKey; 6] {
        [
            SettingKey { key: "res", default: "1024", help: "map side in texels (16 to 16384)" },
            SettingKey { key: "filter", default: "none", help: "none, bilinear, pcf3x3, pcf4x4-jitter or poisson16" },
            SettingKey {
                key: "filter_radius",
                default: "1.5",
                help: "kernel radius in texels for pcf4x4-jitter and poisson16",
            },
            SettingKey {
                key: "z_offset",
                default: "0.1",
                help: "dual map: largest bias, in scene units along the light axis",
            },
            SettingKey {
                key: "peel_epsilon",
                default: "0.0000001",
                help: "second layer: NDC depth within which a fragment counts as the first layer",
            },
            SettingKey { key: "culling", default: culling, help: "auto (back faces of closed meshes culled) or none" },
        ]
    }

    fn read(kind: LayerKind, v: &Values<'_>) -> Result<Self, SettingsError> {
        Ok(Self {
            kind,
            resolution: read_resolution(v)?,
            filter: v.get("filter")?,
            filter_radius: v.ranged("filter_radius", 0.0, 64.0)?,
            z_offset: v.ranged("z_offset", 0.0, 1e9)?,
            peel_epsilon: v.ranged("peel_epsilon", 0.0, 1.0)?,
            culling: v.get("culling")?,
        })
    }

    fn values(&self) -> Vec<String> {
        vec![
            self.resolution.to_string(),
            self.filter.to_string(),
            self.filter_radius.to_string(),
            self.z_offset.to_string(),
            self.peel_epsilon.to_string(),
            self.culling.to_string(),
        ]
    }
}

/// Declares the settings type of one depth-layer technique: the same keys, with the culling its paper uses
/// as the default (Woo's midpoint and Wang-Molnar without culling, Weiskopf-Ertl's dual with it).
macro_rules! layer_settings {
    ($(#[$m:meta])* $name:ident, $kind:expr, $culling:literal) => {
        $(#[$m])*
        #[derive(Clone, Copy, Debug, PartialEq)]
        pub struct $name(pub DepthLayers);

        impl TechniqueSettings for $name {
            fn keys() -> &'static [SettingKey] {
                static KEYS: std::sync::OnceLock<[SettingKey; 6]> = std::sync::OnceLock::new();
                KEYS.get_or_init(|| DepthLayers::keys_with($culling))
            }
            fn from_values(v: &Values<'_>) -> Result<Self, SettingsError> {
                Ok(Self(DepthLayers::read($kind, v)?))
            }
            fn to_values(&self) -> Vec<String> {
                self.0.values()
            }
        }
    };
}

impl From<MidpointShadowMap> for DepthLayers {
    fn from(s: MidpointShadowMap) -> Self {
        s.0
    }
}
impl From<SecondDepthShadowMap> for DepthLayers {
    fn from(s: SecondDepthShadowMap) -> Self {
        s.0
    }
}
impl From<DualShadowMap> for DepthLayers {
    fn from(s: DualShadowMap) -> Self {
        s.0
    }
}

layer_settings!(
    /// Settings of `midpoint-shadow-map` (Woo).
    MidpointShadowMap, LayerKind::Midpoint, "none"
);
layer_settings!(
    /// Settings of `second-depth-shadow-map` (Wang-Molnar).
    SecondDepthShadowMap, LayerKind::SecondDepth, "none"
);
layer_settings!(
    /// Settings of `dual-shadow-map` (Weiskopf-Ertl).
    DualShadowMap, LayerKind::Dual, "auto"
);

#[cfg(test)]
mod layer_tests {
    use super::*;

    #[test]
    fn combinations_follow_the_paper() {
        let d = DualShadowMap::defaults().0;
        assert_eq!(d.culling, LayerCulling::Auto);
        assert_eq!(MidpointShadowMap::defaults().0.culling, LayerCulling::None);
        // Close layers: the dual map is the midpoint; far layers: capped at z_offset.
        assert_eq!(d.combine(1.0, 1.1), 1.05);
        assert_eq!(d.combine(1.0, 5.0), 1.0 + d.z_offset);
        let m = DepthLayers { kind: LayerKind::Midpoint, ..d };
        assert_eq!(m.combine(1.0, 5.0), 3.0);
        let s = DepthLayers { kind: LayerKind::SecondDepth, ..d };
        assert_eq!(s.combine(1.0, 5.0), 5.0);
    }
}
