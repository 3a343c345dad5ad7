//! `midpoint-shadow-map` (Woo), `second-depth-shadow-map` (Wang-Molnar) and `dual-shadow-map`
//! (Weiskopf-Ertl 2003): the two layers nearest the light, found by depth peeling, combined into one map
//! that the ordinary shadow-map lookup then reads (Weiskopf-Ertl section 5: "the rendering of the scene
//! from the eye point in phase two is not modified").
//!
//! Pass 1 renders the nearest depth z1. Pass 2 renders the scene again, discarding every fragment within
//! `peel_epsilon` of z1 at its texel, which leaves the second-nearest depth z2. Where a layer is missing
//! the far plane stands in, as in the paper. Back faces of closed meshes are culled in both passes under
//! `culling=auto`, open meshes are never culled: the paper's mix of solid and thin objects in one scene.
//! The combination is taken on linear depths (see [`DepthLayers::combine`]).

pub mod cpu;
pub mod gpu;

use shadow_core::technique::maps::{FILTER, FILTER_RADIUS, resolution_key};
use shadow_core::technique::registry::converted;
use shadow_core::technique::settings::{Filter, SettingKey, SettingsError, TechniqueSettings, Values};
use shadow_cpu::CpuBackend;
use shadow_wgpu::WgpuBackend;

use std::borrow::Cow;

use crate::Entry;
use crate::cascaded_shadow_map::{CascadedShadowMap, cascaded_view};
use shadow_core::FrameInputs;
use shadow_core::light::LightView;

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

shadow_core::named_enum! {
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
    /// Cascades over the camera's view for a directional light (0: one map over the light's view).
    pub cascades: u32,
}

impl DepthLayers {
    /// The combined depth, in linear depth along the light's axis, of the two nearest layers `l1 <= l2`
    /// (the far plane standing in for a missing layer). Computed on linear depths so `z_offset` is a scene
    /// distance; with an orthographic light (the paper's figures) this is the paper's formula exactly.
    /// WGSL twin: `combine_layers` in layers.wgsl.
    #[must_use]
    pub fn combine(&self, l1: f32, l2: f32) -> f32 {
        match self.kind {
            LayerKind::Midpoint => 0.5 * (l1 + l2),
            LayerKind::SecondDepth => l2,
            LayerKind::Dual => l1 + (0.5 * (l2 - l1)).min(self.z_offset),
        }
    }

    /// The view the layers are peeled from: the light's own, or with `cascades` on a directional light,
    /// cascades over the camera's view fitted as `cascaded-shadow-map`'s defaults (blended as its are).
    #[must_use]
    pub fn view<'a>(&self, frame: &FrameInputs, light: &'a LightView, aspect: f32) -> Cow<'a, LightView> {
        let blend = CascadedShadowMap::defaults().blend;
        cascaded_view(light, frame, aspect, self.cascades, self.resolution, blend)
    }

    const fn keys_with(culling: &'static str) -> [SettingKey; 7] {
        [
            resolution_key("1024", "map side in texels (16 to 16384)"),
            FILTER,
            FILTER_RADIUS,
            SettingKey::float(
                "z_offset",
                "0.1",
                0.0,
                1e9,
                "dual map: largest bias, in scene units along the light axis",
            ),
            SettingKey::float(
                "peel_epsilon",
                "0.0000001",
                0.0,
                1.0,
                "second layer: NDC depth within which a fragment counts as the first layer",
            ),
            SettingKey::choice(
                "culling",
                culling,
                LayerCulling::NAMES,
                "auto (back faces of closed meshes culled) or none",
            ),
            SettingKey::int(
                "cascades",
                "0",
                0,
                4,
                "for a directional light, maps over that many slices of the view as cascaded-shadow-map fits them (0: one)",
            ),
        ]
    }

    fn read(kind: LayerKind, v: &Values<'_>) -> Result<Self, SettingsError> {
        Ok(Self {
            kind,
            resolution: v.get("res")?,
            filter: v.get("filter")?,
            filter_radius: v.get("filter_radius")?,
            z_offset: v.get("z_offset")?,
            peel_epsilon: v.get("peel_epsilon")?,
            culling: v.get("culling")?,
            cascades: v.get("cascades")?,
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
            self.cascades.to_string(),
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
                const KEYS: [SettingKey; 7] = DepthLayers::keys_with($culling);
                &KEYS
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

/// The entry of the layer map `S`.
fn entry<S>(name: &'static str, description: &'static str, paper: &'static str) -> Entry
where
    S: TechniqueSettings + Into<DepthLayers>,
{
    Entry::new::<S>(
        name,
        description,
        paper,
        Some(converted::<CpuBackend, S, DepthLayers>),
        Some(converted::<WgpuBackend, S, DepthLayers>),
    )
    .wgsl(gpu::shaders)
}

/// The registry entry of Woo's midpoint map.
#[must_use]
pub fn midpoint_entry() -> Entry {
    entry::<MidpointShadowMap>(
        LayerKind::Midpoint.name(),
        "a map of the midpoint between the two layers nearest the light (depth peeling)",
        "Woo 1992 (in Weiskopf-Ertl 2003, section 3)",
    )
}

/// The registry entry of Wang and Molnar's second-depth map.
#[must_use]
pub fn second_depth_entry() -> Entry {
    entry::<SecondDepthShadowMap>(
        LayerKind::SecondDepth.name(),
        "a map of the second-nearest layer; meant for closed meshes",
        "Wang-Molnar 1994 (in Weiskopf-Ertl 2003, section 2)",
    )
}

/// The registry entry of Weiskopf and Ertl's dual map.
#[must_use]
pub fn dual_entry() -> Entry {
    entry::<DualShadowMap>(
        LayerKind::Dual.name(),
        "nearest layer plus min(half the gap to the second, z_offset): an adaptive bias",
        "Weiskopf-Ertl 2003",
    )
}

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
