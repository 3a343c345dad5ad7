//! `cascaded-shadow-map`: the answer of every engine a user would pick (Bevy, Filament, Godot, OGRE,
//! three.js's add-on) to the perspective aliasing of the survey's section 4. A directional sun over a large
//! scene gives a uniform map's texels to the whole scene alike, so receivers at the viewer's feet get a
//! handful each (`d = d_s r_s / r_i` large where `r_i`, the distance to the eye, is small). Cascades cut
//! the camera's view depth into slices by the practical split scheme (Zhang et al. 2006) and give each
//! slice a map of its own, fitted to it: near slices are small, so their texels are small.
//!
//! The fit is in shadow-core (`light::cascades`), stabilised so that the shadows do not shimmer as the
//! camera moves: by default each slice's tight window has its size rounded up on a ladder and is moved in
//! whole texels of a world grid (`stabilize=snapped`); `sphere` bounds each slice by a sphere whose size no
//! turn of the camera changes, as Bevy and Filament do, at the price of texels; `off` fits every frame
//! anew. Each receiver reads the cascade of its view depth and, over the last
//! `blend` of that cascade's range, fades into the next one, so the seam between texel sizes is not a
//! line. The maps, their bias and every lookup filter are `shadow-map`'s (the shared map passes); the
//! slope-scaled bias follows each cascade's texel size by itself, since it is taken in that map's texels.
//!
//! Directional lights only: a spot or point light's view is already a perspective whose texels grow with
//! distance from the light, and cascades over it are a different technique.

pub mod cpu;
pub mod gpu;

use std::borrow::Cow;

use crate::Entry;
use shadow_core::light::{CascadeFit, LightView, Stabilize};
use shadow_core::technique::LightKinds;
use shadow_core::technique::maps::{
    CutoutMap, DepthMap, FILTER, FILTER_RADIUS, MapLayout, MapSampling, resolution_key,
};
use shadow_core::technique::settings::TechniqueSettings;
use shadow_core::technique::settings::{Filter, SettingKey};
use shadow_core::{FrameInputs, LightKind};

shadow_core::technique_settings! {
    /// `cascaded-shadow-map`: a directional light's depth maps, one per slice of the camera's view depth.
    pub struct CascadedShadowMap {
        /// Each cascade's map: side and bias as `shadow-map` has them.
        pub map: DepthMap = DepthMap::keys(resolution_key("2048", "each cascade's map side in texels (16 to 16384)")),
        /// Lookup filter, as `shadow-map`'s.
        pub filter: Filter = FILTER,
        /// Kernel radius in texels of each cascade's map.
        pub filter_radius: f32 = FILTER_RADIUS,
        /// How many cascades.
        pub cascades: u32 = SettingKey::int("cascades", "4", 1, 4, "number of cascades (1 to 4)"),
        /// The practical split scheme's weight of the logarithmic split. Zhang et al. suggest 0.5; on the
        /// outdoor street 0.75 gives the near third of the view 0.98% mismatch against 1.32% (640x360), for
        /// the near field gets more of the texels and the horizon, where shadows are sub-pixel, fewer.
        pub lambda: f32 = SettingKey::float(
            "lambda",
            "0.75",
            0.0,
            1.0,
            "split scheme: 0 uniform, 1 logarithmic, between a blend of the two",
        ),
        /// The fraction of each cascade's depth range over which it fades into the next.
        pub blend: f32 = SettingKey::float(
            "blend",
            "0.1",
            0.0,
            0.5,
            "fraction of each cascade's depth range, at its far end, over which it fades into the next",
        ),
        /// How each cascade's window follows the camera, so that shadows do not shimmer as it moves. The
        /// snapped fit is the default: on the outdoor street at 1920x1080 it keeps the near third of the
        /// view at 0.70% mismatch where the sphere's spare texels leave 0.96% (the tight fit 0.57%), and
        /// on a walk its shadows change at 1/30 of the tight fit's points (the sphere's at 1/330).
        pub stabilize: Stabilize = SettingKey::choice(
            "stabilize",
            "snapped",
            Stabilize::NAMES,
            "sphere: fixed size, whole texels (never shimmers); snapped: tight, size on a ladder, whole texels; \
             off: tight every frame",
        ),
        /// The view depth the last cascade ends at.
        pub distance: f32 = SettingKey::float(
            "distance",
            "0",
            0.0,
            1e7,
            "view depth where the last cascade ends, in scene units; 0 fits it to the scene",
        ),
    }
    lights = LightKinds::DIRECTIONAL;
}

impl CascadedShadowMap {
    /// The technique's name.
    pub const NAME: &'static str = "cascaded-shadow-map";

    /// How the cascades are split and fitted.
    #[must_use]
    pub fn fit(&self) -> CascadeFit {
        CascadeFit {
            count: self.cascades as usize,
            lambda: self.lambda,
            blend: self.blend,
            stabilize: self.stabilize,
            resolution: self.map.resolution,
            distance: self.distance,
        }
    }
}

impl MapLayout for CascadedShadowMap {
    fn sampling(&self, frame: &FrameInputs, light: &LightView, aspect: f32) -> MapSampling {
        MapSampling {
            view: light.cascaded(&frame.camera, aspect, &frame.bounds, &self.fit()),
            resolution: self.map.resolution,
        }
    }
}

/// The view of `light` as `count` cascades over the view of `frame`'s camera (`aspect` wide per unit of
/// height), split and fitted as this technique's defaults do, each map `resolution` texels wide and faded
/// into the next over `blend` of its range: for techniques that put their own maps in cascades. With no
/// cascades, or a light other than directional, the light's own view.
#[must_use]
pub fn cascaded_view<'a>(
    light: &'a LightView,
    frame: &FrameInputs,
    aspect: f32,
    count: u32,
    resolution: u32,
    blend: f32,
) -> Cow<'a, LightView> {
    if count == 0 || !matches!(light.light.kind, LightKind::Directional { .. }) {
        return Cow::Borrowed(light);
    }
    let fit = CascadeFit { count: count as usize, blend, resolution, ..CascadedShadowMap::defaults().fit() };
    Cow::Owned(light.cascaded(&frame.camera, aspect, &frame.bounds, &fit))
}

/// The view the map of the cut-out casters renders (`map`'s `cutout_cascades` over `frame`'s camera, seen
/// `aspect` wide, as [`cascaded_view`] fits them), for a frame with such casters; the light's own
/// otherwise, and for lights other than directional.
#[must_use]
pub fn cutout_view<'a>(map: &CutoutMap, frame: &FrameInputs, light: &'a LightView, aspect: f32) -> Cow<'a, LightView> {
    if !frame.has_cutout_casters() {
        return Cow::Borrowed(light);
    }
    let blend = CascadedShadowMap::defaults().blend;
    cascaded_view(light, frame, aspect, map.cascades, map.resolution, blend)
}

/// The registry entry.
#[must_use]
pub fn entry() -> Entry {
    Entry::on_both::<CascadedShadowMap>(
        CascadedShadowMap::NAME,
        "a directional light's depth maps, one per slice of the view depth, stabilised and blended at the seams",
        "Zhang et al. 2006 (practical split scheme); survey: Nealen 2005, section 4",
    )
    .with_layout::<CascadedShadowMap>()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_parse_and_print() {
        assert_eq!(
            CascadedShadowMap::defaults().settings_string(),
            "res=2048,bias=slope,bias_constant=16,bias_slope=2,bias_world=0.05,filter=none,filter_radius=1.5,\
             cascades=4,lambda=0.75,blend=0.1,stabilize=snapped,distance=0"
        );
    }

    #[test]
    fn bad_settings_name_key_and_value() {
        let given = |k: &str, v: &str| vec![(k.to_string(), v.to_string())];
        let e = CascadedShadowMap::parse("cascaded-shadow-map", &given("cascades", "5")).unwrap_err();
        assert!(e.to_string().contains("'5' for 'cascades'"), "{e}");
        let e = CascadedShadowMap::parse("cascaded-shadow-map", &given("lambda", "2")).unwrap_err();
        assert!(e.to_string().contains("lambda"), "{e}");
    }
}
