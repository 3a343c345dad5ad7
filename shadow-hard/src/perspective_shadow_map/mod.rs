//! `perspective-shadow-map`: Stamminger and Drettakis's perspective shadow maps (SIGGRAPH 2002), as the
//! survey's section 4 and Fig. 10 describe them (Nealen 2005). The map is rendered in the camera's
//! post-perspective space, where the view is an orthographic look at the unit cube: a receiver's share of
//! the map then follows its share of the screen, and the perspective aliasing of a uniform map (a handful
//! of texels at the viewer's feet) goes.
//!
//! The transform is in shadow-core (`light::psm`), with the paper's special cases: the virtual camera
//! moved back so that casters behind the eye stay in front of it, and the light's kind after the
//! transform (a directional light becomes a point light in front of the camera, an inverted point light
//! behind it, and stays directional across the view). As the survey warns, cases converge to the uniform
//! map: the further back the virtual camera must move, the weaker the warp; and facing the sun (the
//! duelling frusta) the post-perspective light sits at the unit cube's far face and the map falls back to
//! the uniform one, focused on what the camera sees.
//!
//! The bias is `shadow-map`'s: a constant in the map's depth, as the survey describes for PSMs, and the
//! rasterizer's slope-scaled term on top, taken per triangle in the warped map's texels, with a factor of
//! 4 rather than `shadow-map`'s 2 (at 2 the near receivers of the outdoor street kept a third of their
//! error as acne).
//! Directional lights only: the paper's point and spot lights keep their own perspective maps here.

pub mod cpu;
pub mod gpu;

use crate::Entry;
use shadow_core::light::LightView;
use shadow_core::technique::LightKinds;
use shadow_core::technique::maps::{DepthMap, FILTER, FILTER_RADIUS, MapLayout, MapSampling, resolution_key};
use shadow_core::technique::settings::Filter;
#[cfg(test)]
use shadow_core::technique::settings::TechniqueSettings;
use shadow_core::{Aabb, FrameInputs};

shadow_core::technique_settings! {
    /// `perspective-shadow-map`: one depth map in the camera's post-perspective space.
    pub struct PerspectiveShadowMap {
        /// The map: side and bias as `shadow-map` has them, the slope factor 4 for the warp.
        pub map: DepthMap = DepthMap::warped_keys(resolution_key("4096", "map side in texels (16 to 16384)")),
        /// Lookup filter, as `shadow-map`'s.
        pub filter: Filter = FILTER,
        /// Kernel radius in texels.
        pub filter_radius: f32 = FILTER_RADIUS,
    }
    lights = LightKinds::DIRECTIONAL;
}

impl PerspectiveShadowMap {
    /// The technique's name.
    pub const NAME: &'static str = "perspective-shadow-map";
}

impl MapLayout for PerspectiveShadowMap {
    fn sampling(&self, frame: &FrameInputs, light: &LightView, aspect: f32) -> MapSampling {
        let boxes: Vec<Aabb> = frame.instances.iter().map(|i| i.bounds).collect();
        let (view, _) = light.perspective_shadow_map(&frame.camera, aspect, &boxes);
        MapSampling { view, resolution: self.map.resolution }
    }
}

/// The registry entry.
#[must_use]
pub fn entry() -> Entry {
    Entry::on_both::<PerspectiveShadowMap>(
        PerspectiveShadowMap::NAME,
        "one depth map in the camera's post-perspective space: texels where the screen has pixels",
        "Stamminger, Drettakis 2002 (survey: Nealen 2005, section 4)",
    )
    .with_layout::<PerspectiveShadowMap>()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_parse_and_print() {
        assert_eq!(
            PerspectiveShadowMap::defaults().settings_string(),
            "res=4096,bias=slope,bias_constant=16,bias_slope=4,bias_world=0.05,filter=none,filter_radius=1.5"
        );
    }
}
