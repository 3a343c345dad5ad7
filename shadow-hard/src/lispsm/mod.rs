//! `lispsm`: light-space perspective shadow maps (Wimmer, Scherzer and Purgathofer 2004), the answer of
//! Filament and OGRE to the perspective aliasing of the survey's section 4 (Nealen 2005). One map, like
//! `shadow-map`'s, but rendered through a perspective whose axis is perpendicular to the light and points
//! along the view: receivers near the viewer get more of the map's rows than those on the horizon, and
//! because the warp's axis is perpendicular to the light, the light stays directional after it, and no
//! caster behind the eye is turned inside out (the special cases of perspective shadow maps).
//!
//! The warp is in shadow-core (`light::lispsm`): the map is focused on the part of the view the scene
//! fills, and the perspective's centre lies the paper's `n_opt = (z_n + sqrt(z_n z_f)) / sin(gamma)`
//! before it. When the view looks along the light (the sun behind the camera, or the duelling frusta
//! facing it) `sin(gamma)` vanishes, `n` grows, and the map becomes the uniform one, focused: the
//! graceful degradation the paper promises rather than the inverted or exploding maps of the
//! post-perspective approach.
//!
//! The bias is `shadow-map`'s, applied by the rasterizer in the warped depth: the slope-scaled part is
//! taken per triangle in the warped map's own texels, so it follows the warp without a term of its own;
//! its factor is 4 rather than `shadow-map`'s 2, since the warp makes a surface's depth change per texel
//! vary across the map (at 2 the near receivers of the outdoor street kept a third of their error as acne).
//! Directional lights only: a spot or point light's own view is already a perspective.

pub mod cpu;
pub mod gpu;

use crate::Entry;
use shadow_core::light::LightView;
use shadow_core::technique::LightKinds;
use shadow_core::technique::maps::{DepthMap, FILTER, FILTER_RADIUS, MapLayout, MapSampling, resolution_key};
#[cfg(test)]
use shadow_core::technique::settings::TechniqueSettings;
use shadow_core::technique::settings::{Filter, SettingKey};
use shadow_core::{Aabb, FrameInputs};

shadow_core::technique_settings! {
    /// `lispsm`: one depth map through a perspective perpendicular to a directional light.
    pub struct Lispsm {
        /// The map: side and bias as `shadow-map` has them, the slope factor 4 for the warp.
        pub map: DepthMap = DepthMap::warped_keys(resolution_key("4096", "map side in texels (16 to 16384)")),
        /// Lookup filter, as `shadow-map`'s.
        pub filter: Filter = FILTER,
        /// Kernel radius in texels.
        pub filter_radius: f32 = FILTER_RADIUS,
        /// The perspective's `n`; 0 takes the paper's optimum.
        pub n: f32 = SettingKey::float(
            "n",
            "0",
            0.0,
            1e7,
            "distance of the warp's centre before the view, in scene units (smaller warps more); 0: the paper's n_opt",
        ),
    }
    lights = LightKinds::DIRECTIONAL;
}

impl Lispsm {
    /// The technique's name.
    pub const NAME: &'static str = "lispsm";
}

impl MapLayout for Lispsm {
    fn sampling(&self, frame: &FrameInputs, light: &LightView, aspect: f32) -> MapSampling {
        let n = (self.n > 0.0).then_some(self.n);
        let boxes: Vec<Aabb> = frame.instances.iter().map(|i| i.bounds).collect();
        let (view, _) = light.light_space_perspective(&frame.camera, aspect, &boxes, n);
        MapSampling { view, resolution: self.map.resolution }
    }
}

/// The registry entry.
#[must_use]
pub fn entry() -> Entry {
    Entry::on_both::<Lispsm>(
        Lispsm::NAME,
        "one depth map warped by a perspective perpendicular to a directional light: more texels near the viewer",
        "Wimmer, Scherzer, Purgathofer 2004 (survey: Nealen 2005, section 4)",
    )
    .with_layout::<Lispsm>()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_parse_and_print() {
        assert_eq!(
            Lispsm::defaults().settings_string(),
            "res=4096,bias=slope,bias_constant=16,bias_slope=4,bias_world=0.05,filter=none,filter_radius=1.5,n=0"
        );
    }
}
