//! `penumbra-map` (Wyman and Hansen 2003): soft shadow edges from a shadow map and a penumbra map, the
//! comparison the smoothie thesis draws (section 4.5.1).
//!
//! Build: the blockers' depth map, as `shadow-map` renders it; cones at the silhouette vertices and
//! sheets along the silhouette edges ([`geometry`]), rendered from the light's centre into the penumbra
//! map. A fragment of a cone or sheet at linear depth `z_p`, hanging from a silhouette vertex at `z_v`, over
//! a map texel whose surface is at `z_f`, stores how far across the penumbra that surface lies:
//!
//! `(1 - z_v / z_p) / (1 - z_v / z_f)`
//!
//! 0 at the silhouette (`z_p = z_v`), 1 where the cone meets the surface (`z_p = z_f`). The cone's radius
//! grows as `r (z - z_v) / z_v`, so this is the receiver's distance from the hard edge over the
//! penumbra's width there, both in the map; Wyman and Hansen's `(z_p - z_v) / (z_f - z_v)` is its first
//! order (their paper is not among ours: the ratio here is derived from the cones as they describe them).
//! Fragments behind the surface (`z_p >= z_f`) or over a surface not behind the silhouette
//! (`z_f <= z_v`, the blocker itself) are discarded; overlapping ones keep the smallest value (on the GPU
//! written as fragment depth, the depth test the minimum, as smoothies do). Unlike smoothies the map keeps
//! no depth of the cones: every receiver behind them takes their value.
//!
//! Query, at the four nearest texels: behind the depth map 0, else the penumbra map's value (1 where no
//! cone or sheet drew); bilinearly weighted. Like smoothies, the penumbra only grows outward from the hard
//! shadow.

pub mod cpu;
pub mod geometry;
pub mod gpu;

use crate::Entry;
use shadow_core::FrameInputs;
use shadow_core::image::Image;
use shadow_core::light::{LightProjection, LightView};
use shadow_core::technique::LightKinds;
use shadow_core::technique::maps::{DepthMap, resolution_key};
use shadow_core::technique::{DebugView, FrameStats, TechniqueError};

shadow_core::technique_settings! {
    /// `penumbra-map` settings.
    pub struct PenumbraMap {
        /// The depth map: resolution (the penumbra map's too) and bias, as `shadow-map` has them. The
        /// cones' opening is the light's radius.
        pub depth: DepthMap = DepthMap::keys(resolution_key(
            "1024",
            "depth map and penumbra map side in texels (16 to 16384)",
        )),
    }
    lights = LightKinds::SPOT;
}

/// The penumbra map's value for a cone or sheet fragment at linear depth `z_p`, hanging from a silhouette
/// vertex at `z_v`, over a surface at `z_f`; `None` where it is discarded (WGSL twin: `penumbra_value`).
#[must_use]
pub fn penumbra_value(z_p: f32, z_v: f32, z_f: f32) -> Option<f32> {
    (z_p < z_f && z_v < z_f).then(|| ((1.0 - z_v / z_p) / (1.0 - z_v / z_f)).clamp(0.0, 1.0))
}

impl PenumbraMap {
    /// The technique's name.
    pub const NAME: &'static str = "penumbra-map";

    /// The cones and sheets of a frame's casters for a spot light, in its one projection; their counters
    /// recorded in `stats` (both backends alike).
    ///
    /// # Errors
    /// [`TechniqueError::UnsupportedLight`] for point and directional lights.
    pub fn construct<'a>(
        frame: &FrameInputs,
        light: &'a LightView,
        stats: &mut FrameStats,
    ) -> Result<(&'a LightProjection, geometry::ConesAndSheets), TechniqueError> {
        let proj = crate::spot_projection(light, Self::NAME)?;
        let position = light.light.position().unwrap_or_default();
        let casters = frame.caster_silhouettes(light);
        let built = geometry::build(frame, &casters, position, light.light.radius, proj);
        let c = &mut stats.counters;
        c.silhouette_edges = Some(built.edges as u64);
        c.extra.insert("penumbra_triangles".into(), built.triangles.len() as f64);
        c.extra.insert("whole_cones".into(), built.whole_cones as f64);
        Ok((proj, built))
    }
}

/// The debug view of a penumbra map, the same on both backends: its values in grey.
#[must_use]
pub fn debug_views(values: &Image<f32>) -> Vec<DebugView> {
    let grey = Image::from_fn(values.width(), values.height(), |x, y| [(values.get(x, y) * 255.0).round() as u8; 3]);
    vec![DebugView { name: "penumbra-map".into(), image: grey }]
}

/// The registry entry.
#[must_use]
pub fn entry() -> Entry {
    Entry::on_both::<PenumbraMap>(
        PenumbraMap::NAME,
        "fake soft shadows: a shadow map plus cones and sheets at the silhouettes drawn into a penumbra map",
        "Wyman-Hansen 2003 (compared in Chan 2004, thesis 4.5.1)",
    )
    .wgsl(gpu::shaders)
    .soft()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn values_run_from_the_silhouette_to_the_cone_surface() {
        assert_eq!(penumbra_value(2.0, 2.0, 4.0), Some(0.0));
        assert_eq!(penumbra_value(4.0, 2.0, 4.0), None, "the cone meets the surface: discarded, 1 stays");
        // Halfway across in the map: 1 - 2/z_p is half of 1 - 2/4.
        let v = penumbra_value(8.0 / 3.0, 2.0, 4.0).expect("in front of the surface");
        assert!((v - 0.5).abs() < 1e-6, "{v}");
        assert_eq!(penumbra_value(3.0, 2.0, 1.5), None, "over the blocker itself");
    }
}
