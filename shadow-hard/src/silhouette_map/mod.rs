//! `silhouette-map` (Sen, Cammarano, Hanrahan 2003): a shadow map plus a map of points on the shadow
//! silhouettes, shifted half a texel; the lookup splits each texel the silhouette crosses into four skewed
//! quadrants and so reconstructs a piecewise-linear shadow edge instead of the map's staircase.
//!
//! Pass 1 renders the depth map as `shadow-map` does (same bias); pass 2 stores one silhouette point per
//! texel ([`points`], the reference both backends follow, with the texel space, the corner rule and the
//! reconstruction written out); the query runs the four corner tests and, where they disagree, the
//! reconstruction of Fig. 5. Both defaults of `corner_depth` and `keep` depart from the paper, for reasons
//! measured and given where they are defined; the paper's rules stay one setting away.

pub mod cpu;
pub mod gpu;
pub mod points;

use std::borrow::Cow;

use crate::Entry;
use crate::cascaded_shadow_map::cascaded_view;
use shadow_core::FrameInputs;
use shadow_core::light::LightView;
use shadow_core::technique::maps::{DepthMap, resolution_key};
use shadow_core::technique::maps::{MapLayout, MapSampling};
use shadow_core::technique::settings::SettingKey;
#[cfg(test)]
use shadow_core::technique::settings::TechniqueSettings;

use points::{CornerDepth, Keep};

shadow_core::technique_settings! {
    /// `silhouette-map` (Sen, Cammarano, Hanrahan 2003): a shadow map plus a map of points on the
    /// silhouettes, shifted half a texel; the lookup reconstructs a piecewise-linear shadow edge.
    pub struct SilhouetteMap {
        /// The depth map: resolution and bias as `shadow-map` has them (its filter is unused: the
        /// reconstruction replaces it).
        pub depth: DepthMap = DepthMap::keys(resolution_key(
            "1024",
            "depth-map side in texels (16 to 16384); the silhouette map has one texel fewer",
        )),
        /// The corner rule's enlargement of the clip square, in texels (section 3.1: "within limits of
        /// precision"). At 0.01 a segment within a hundredth of a texel of a corner is stored in all four texels
        /// around it, far above the rounding of texel coordinates (about 1e-4 at 4096 texels).
        pub corner_margin: f32 = SettingKey::float(
            "corner_margin",
            "0.01",
            0.0,
            0.25,
            "corner rule: how far outside a texel, in texels, a segment still counts as crossing it",
        ),
        /// What each corner sample is compared with.
        pub corner_depth: CornerDepth = SettingKey::choice(
            "corner_depth",
            "receiver-plane",
            CornerDepth::NAMES,
            "compare corner samples with the receiver plane's depth there, or the fragment's own (the paper)",
        ),
        /// Which point a texel crossed by several silhouettes keeps.
        pub keep: Keep = SettingKey::choice(
            "keep",
            "nearest",
            Keep::NAMES,
            "the point a texel crossed by several silhouettes keeps: nearest the light, or last drawn (the paper)",
        ),
        /// Cascades over the camera's view for a directional light (0: one map over the light's view).
        pub cascades: u32 = SettingKey::int(
            "cascades",
            "0",
            0,
            4,
            "for a directional light, maps over that many slices of the view as cascaded-shadow-map fits them (0: one)",
        ),
    }
}

impl SilhouetteMap {
    /// The technique's name.
    pub const NAME: &'static str = "silhouette-map";

    /// The view the maps are rendered from: the light's own, or with `cascades` on a directional light,
    /// cascades over the camera's view, split and fitted as `cascaded-shadow-map`'s defaults but without
    /// the blending (two reconstructed edges do not mix into one). The silhouette map answers projection
    /// aliasing, the cascades perspective aliasing: Sen et al. name the combination as future work.
    #[must_use]
    pub fn view<'a>(&self, frame: &FrameInputs, light: &'a LightView, aspect: f32) -> Cow<'a, LightView> {
        cascaded_view(light, frame, aspect, self.cascades, self.depth.resolution, 0.0)
    }
}

impl MapLayout for SilhouetteMap {
    fn sampling(&self, frame: &FrameInputs, light: &LightView, aspect: f32) -> MapSampling {
        MapSampling { view: self.view(frame, light, aspect).into_owned(), resolution: self.depth.resolution }
    }
}

/// The registry entry.
#[must_use]
pub fn entry() -> Entry {
    Entry::on_both::<SilhouetteMap>(
        SilhouetteMap::NAME,
        "a shadow map plus silhouette points half a texel off: piecewise-linear shadow edges",
        "Sen, Cammarano, Hanrahan 2003",
    )
    .wgsl(gpu::shaders)
    .with_layout::<SilhouetteMap>()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_parse_and_print() {
        assert_eq!(
            SilhouetteMap::defaults().settings_string(),
            "res=1024,bias=slope,bias_constant=16,bias_slope=2,bias_world=0.05,corner_margin=0.01,\
             corner_depth=receiver-plane,keep=nearest,cascades=0"
        );
    }
}
