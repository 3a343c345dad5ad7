//! The settings every technique built on a light depth map shares: the map's side and its bias (DESIGN 4
//! and 6). `shadow-map` adds a lookup filter; the silhouette map, the reconstruction, the hybrid and the
//! soft techniques add their own keys after these. Declared once here so their defaults and help read the
//! same everywhere.

use super::settings::{
    BiasMode, DepthBias, Filter, MAX_MAP_RESOLUTION, SettingField, SettingKey, SettingsError, Values,
};
use crate::frame::{Coverage, FrameInputs, Instance};
use crate::light::LightView;

/// `bias`: how the map's depth is offset.
pub const BIAS: SettingKey = SettingKey::choice(
    "bias",
    "slope",
    BiasMode::NAMES,
    "none, constant or slope (Vulkan depth bias when the map is rendered), or world (bias_world)",
);

/// `bias_constant`: Vulkan's constant depth-bias factor.
pub const BIAS_CONSTANT: SettingKey = SettingKey::float(
    "bias_constant",
    "16",
    0.0,
    1e9,
    "constant bias factor, in units of the f32 depth resolution at the primitive",
);

/// `bias_slope`: Vulkan's slope depth-bias factor.
pub const BIAS_SLOPE: SettingKey = SettingKey::float(
    "bias_slope",
    "2",
    0.0,
    1e4,
    "slope bias factor, times the primitive's largest depth change per texel",
);

/// `bias_world`: the receiver offset of `bias=world`.
pub const BIAS_WORLD: SettingKey = SettingKey::float(
    "bias_world",
    "0.05",
    0.0,
    1e6,
    "for bias=world: receiver offset towards the light, in scene units",
);

/// `filter`: the lookup filter of a map.
pub const FILTER: SettingKey =
    SettingKey::choice("filter", "none", Filter::NAMES, "none, bilinear, pcf3x3, pcf4x4-jitter or poisson16");

/// `filter_radius`: the kernel radius of the jittered and Poisson filters.
pub const FILTER_RADIUS: SettingKey =
    SettingKey::float("filter_radius", "1.5", 0.0, 64.0, "kernel radius in texels for pcf4x4-jitter and poisson16");

/// The name of the map-side key every technique built on a depth map has.
pub const RESOLUTION: &str = "res";

/// A `res` key: the map side, with the technique's own default and help.
#[must_use]
pub const fn resolution_key(default: &'static str, help: &'static str) -> SettingKey {
    SettingKey::int(RESOLUTION, default, 16, MAX_MAP_RESOLUTION, help)
}

/// A light depth map: its side and how its depth is biased.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DepthMap {
    /// Map side in texels.
    pub resolution: u32,
    /// Bias mode.
    pub bias: BiasMode,
    /// Vulkan constant depth-bias factor. The default, 16 (sixteen f32 steps of the primitive's depth),
    /// settles the ties on surfaces squarely facing the light, which have no depth slope for the slope
    /// term to cover: there the stored and the looked-up depths are equal up to rounding, and the GPU's
    /// looked-up depth comes from a world position interpolated across the receiving triangle, a few
    /// steps off along its diagonal. At 8 a card facing an axis-aligned sun still showed a line of false
    /// shadow along its wall's diagonal on lavapipe, at 4 lines across 0.8% of it (the CPU was exact at
    /// 4). Sixteen steps of a depth in [0.5, 1] are 1e-6 of the light's depth range, far below a texel's
    /// slope bias.
    pub bias_constant: f32,
    /// Vulkan slope depth-bias factor.
    pub bias_slope: f32,
    /// Receiver offset towards the light, in scene units, for `bias=world`.
    pub bias_world: f32,
}

impl DepthMap {
    /// The keys a depth map reads, in order, for a map whose `res` key is `res`.
    #[must_use]
    pub const fn keys(res: SettingKey) -> [SettingKey; 5] {
        [res, BIAS, BIAS_CONSTANT, BIAS_SLOPE, BIAS_WORLD]
    }

    /// The keys of a map rendered through a perspective warp (light-space or post-perspective), whose
    /// slope factor defaults to 4: the warp makes a surface's depth change per texel vary across the map,
    /// and at 2 the near receivers of the outdoor street kept a third of their error as acne.
    #[must_use]
    pub const fn warped_keys(res: SettingKey) -> [SettingKey; 5] {
        [res, BIAS, BIAS_CONSTANT, BIAS_SLOPE.with_default("4"), BIAS_WORLD]
    }

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
}

/// A depth map reads its five keys ([`DepthMap::keys`]) together.
impl SettingField for DepthMap {
    fn read(v: &Values<'_>, keys: &[SettingKey]) -> Result<Self, SettingsError> {
        Ok(Self {
            resolution: v.read(&keys[0])?,
            bias: v.read(&keys[1])?,
            bias_constant: v.read(&keys[2])?,
            bias_slope: v.read(&keys[3])?,
            bias_world: v.read(&keys[4])?,
        })
    }

    fn write(&self, out: &mut Vec<String>) {
        out.extend([
            self.resolution.to_string(),
            self.bias.to_string(),
            self.bias_constant.to_string(),
            self.bias_slope.to_string(),
            self.bias_world.to_string(),
        ]);
    }
}

/// Which texels of light space a technique's maps hold in one frame: the projections it renders (with how
/// a receiver picks among them) and the maps' side.
#[derive(Clone, Debug, PartialEq)]
pub struct MapSampling {
    /// The projections the maps are rendered from.
    pub view: LightView,
    /// Map side in texels.
    pub resolution: u32,
}

/// A technique built on depth maps, as far as where its maps' texels fall: each backend's build renders
/// the projections this gives, and `compare` measures texel density and draws which map each pixel
/// reads from it, without running the technique.
pub trait MapLayout {
    /// The maps for `light` (its fitted view) in `frame`, seen by a view `aspect` wide per unit of height.
    fn sampling(&self, frame: &FrameInputs, light: &LightView, aspect: f32) -> MapSampling;
}

/// The map the techniques built on silhouettes (shadow volumes, the hybrid, penumbra wedges) take the
/// shadows of casters their texture cuts out from ([`crate::frame::Coverage::Cutout`]): a card's outline
/// is not its shadow's edge, so those casters get no volume or wedge; their depths, cut out as every
/// light pass cuts them ([`Casters::CutOut`]), are looked up at each receiver, and a receiver is lit only
/// where both the technique and this map say so (a soft technique's visibility is multiplied by the
/// map's). A frame without such casters renders no map. The bias is `shadow-map`'s default one. Read
/// from [`CutoutMap::KEYS`] by the hard techniques, from [`CutoutMap::SOFT_KEYS`] by the soft ones.
///
/// The defaults, measured with `shadow-volume-zfail` at 512x512: the error falls by half with each
/// doubling of the side (`foliage` under its spot light: 0.413%, 0.215%, 0.108% mismatch at 2048, 4096,
/// 8192), and under the low sun of `fence` one map over the light's view leaves 6.59% (2048) or 5.98%
/// (4096) where four cascades of 2048 leave 0.963% (of 4096, 0.482%). Four cascades of 2048 take the
/// memory of `cascaded-shadow-map`'s defaults and match the best map on each scene (`shadow-map`'s
/// 0.414% on foliage, `cascaded-shadow-map`'s 0.963% on fence). A soft technique filters the map: with
/// `penumbra-wedges` on foliage the RMSE against the area light is 0.0924 unfiltered, 0.0704 through
/// `pcf3x3`, 0.0702 through `poisson16` (on tree, without cut-out casters, 0.0696).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CutoutMap {
    /// Map side in texels.
    pub resolution: u32,
    /// Lookup filter.
    pub filter: Filter,
    /// Under a directional light, how many cascades over the camera's view the map is split into (each
    /// `resolution` wide, fitted as `cascaded-shadow-map`'s); 0, one map over the light's view. Other
    /// lights always take one map per projection.
    pub cascades: u32,
}

/// `cutout_res`: the side of the cut-out casters' map.
const CUTOUT_RES: SettingKey = SettingKey::int(
    "cutout_res",
    "2048",
    16,
    MAX_MAP_RESOLUTION,
    "side in texels of the depth map of the casters their texture cuts out (16 to 16384)",
);

/// `cutout_filter`: its lookup filter.
const CUTOUT_FILTER: SettingKey = SettingKey::choice(
    "cutout_filter",
    "none",
    Filter::NAMES,
    "lookup filter of the cut-out casters' map: none, bilinear, pcf3x3, pcf4x4-jitter or poisson16",
);

/// `cutout_cascades`: its cascades under a directional light.
const CUTOUT_CASCADES: SettingKey = SettingKey::int(
    "cutout_cascades",
    "4",
    0,
    4,
    "directional lights: the cut-out casters' map in this many cascades over the view (1 to 4), or 0: one map over the light's view",
);

/// A cut-out casters' map reads its three keys together.
impl SettingField for CutoutMap {
    fn read(v: &Values<'_>, keys: &[SettingKey]) -> Result<Self, SettingsError> {
        Ok(Self { resolution: v.read(&keys[0])?, filter: v.read(&keys[1])?, cascades: v.read(&keys[2])? })
    }

    fn write(&self, out: &mut Vec<String>) {
        out.extend([self.resolution.to_string(), self.filter.to_string(), self.cascades.to_string()]);
    }
}

impl CutoutMap {
    /// The keys of a hard technique's map, unfiltered by default.
    pub const KEYS: [SettingKey; 3] = [CUTOUT_RES, CUTOUT_FILTER, CUTOUT_CASCADES];

    /// The keys of a soft technique's map, filtered by `pcf3x3` by default.
    pub const SOFT_KEYS: [SettingKey; 3] = [CUTOUT_RES, CUTOUT_FILTER.with_default("pcf3x3"), CUTOUT_CASCADES];

    /// The map: its side, with `shadow-map`'s default bias.
    #[must_use]
    pub fn map(&self) -> DepthMap {
        let default = |key: &SettingKey| key.default.parse().unwrap_or(0.0);
        DepthMap {
            resolution: self.resolution,
            bias: BiasMode::Slope,
            bias_constant: default(&BIAS_CONSTANT),
            bias_slope: default(&BIAS_SLOPE),
            bias_world: default(&BIAS_WORLD),
        }
    }

    /// Whether a build of `frame` reads the camera for this map: the frame has cut-out casters and the
    /// map is in cascades over the view (under a directional light; other lights ignore the cascades, so
    /// for them this only says a build may not be kept when it could be).
    #[must_use]
    pub fn follows_the_camera(&self, frame: &FrameInputs) -> bool {
        self.cascades > 0 && frame.has_cutout_casters()
    }

    /// The kernel radius of the jittered and Poisson filters: `shadow-map`'s default.
    #[must_use]
    pub fn filter_radius(&self) -> f32 {
        FILTER_RADIUS.default.parse().unwrap_or(1.0)
    }
}

/// Which shadow casters a light pass draws ([`Casters::takes`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Casters {
    /// Every one, those their texture cuts out through their alpha test.
    All,
    /// Only those that block light over their whole surface ([`crate::frame::Instance::casts_solid_shadow`]):
    /// the casters shadow volumes are extruded from (`hybrid`'s classifying map).
    Solid,
    /// Only those their texture cuts out ([`crate::frame::Coverage::Cutout`]), through their alpha test:
    /// the map of [`CutoutMap`].
    CutOut,
}

impl Casters {
    /// Whether a light pass of these casters draws `instance` (a caster of the kind named; a masked one
    /// with nothing there is drawn by none).
    #[must_use]
    pub fn takes(self, instance: &Instance) -> bool {
        let coverage = instance.coverage();
        instance.casts_shadow
            && match self {
                Self::All => coverage != Coverage::Absent,
                Self::Solid => coverage == Coverage::Solid,
                Self::CutOut => coverage == Coverage::Cutout,
            }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// On `cutout` the card (cut out) is drawn by the passes of every caster and of the cut-out ones, the
    /// ground by those of every caster and of the solid ones.
    #[test]
    fn each_light_pass_takes_its_casters() {
        let scene = crate::scenes::build("cutout", &crate::scenes::SceneParams::default()).expect("cutout");
        let frame = FrameInputs::from_first_camera(&scene).expect("frame");
        let takers = |i: &Instance| [Casters::All, Casters::Solid, Casters::CutOut].map(|c| c.takes(i));
        let card = frame.instances.iter().find(|i| i.coverage() == Coverage::Cutout).expect("the card");
        assert_eq!(takers(card), [true, false, true]);
        let solid = frame.instances.iter().find(|i| i.casts_shadow && i.coverage() == Coverage::Solid);
        assert_eq!(takers(solid.expect("a solid caster")), [true, true, false]);
    }

    /// The cut-out casters' map is biased as `shadow-map`'s default one (the keys' defaults parse).
    #[test]
    fn the_cutout_map_takes_the_default_bias() {
        let m = CutoutMap { resolution: 512, filter: Filter::None, cascades: 0 };
        let map = m.map();
        assert_eq!((map.resolution, map.bias), (512, BiasMode::Slope));
        assert_eq!((map.bias_constant, map.bias_slope, map.bias_world), (16.0, 2.0, 0.05));
        assert_eq!(m.filter_radius(), 1.5);
    }
}
