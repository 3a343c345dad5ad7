//! `penumbra-wedges`: soft shadow volumes (Akenine-Moeller and Assarsson 2002; the GPU algorithm of
//! Assarsson and Akenine-Moeller 2003), as the survey (Nealen, Fig. 3) and Chan's thesis (2.2) describe
//! them: the hard shadow volume from the light's centre gives the umbra-side count, and a wedge around
//! each silhouette edge bounds the receivers where that edge cuts the light, where the part of the light
//! it covers is computed per pixel and added to a light-visibility buffer.
//!
//! Build (shared, [`geometry`]): the casters' silhouette edges from the light's centre (shadow-core's
//! extraction), each with its hard volume's side quad and its wedge. Query, into per-pixel sums of the
//! occluded share of the light:
//!
//! 1. **Count.** The side quads drawn over the G-buffer, in front of the receiver (the test "less",
//!    with a bias towards the eye: [`geometry::QUAD_DEPTH_BIAS`]); where the eye's ray crosses one, it
//!    adds its weight if the receiver is inside that side and the eye is not, and takes it away the other
//!    way round ([`coverage::count_step`]). Started from the count at the eye, this is the
//!    z-pass count of the hard volume at the receiver: how many silhouette loops hold the light's centre.
//! 2. **Wedges.** The wedges' back faces, drawn against the G-buffer's depth with the test "greater"; a
//!    receiver inside adds the edge's signed share of the light's disc ([`coverage::wedge_area`]),
//!    analytically, for a spherical light seen as the disc it subtends (the paper's lookup tables
//!    tabulate this same area for textured lights).
//! 3. **Visibility** `clamp(1 - occluded - horizon, 0, 1)`, where `horizon` is the part of the disc below
//!    the receiver's own tangent plane ([`coverage::horizon_share`]). Closed meshes' edges and open
//!    meshes' two sides are summed apart ([`geometry::Layer`]): `occluded` is the closed meshes' sum
//!    plus the larger of the open meshes' two.
//!
//! Where the count's decision (inside a side) and the area's sign could disagree, both read the same
//! triple product of the same inputs, so the hard edge and the wedge's half-disc jump cancel exactly.
//! The count is made z-pass, not with
//! the stencil, for the same reason: a depth test would decide "inside" differently from the triple
//! product at receivers on the side planes, and leave a line of wrong pixels along every hard edge.
//! Z-pass needs the count at the eye, which the host finds from the casting faces on the segment from
//! the eye to the light; a volume cut by the camera's near plane is miscounted there, as z-pass volumes
//! are.
//!
//! The approximations the paper makes, and where they show: the silhouette is the one the light's
//! centre sees, so where another point of the light would see a different one (on curved casters, near
//! their terminator) the penumbra is that of the centre's outline; and loops that overlap add, so where
//! two casters (or two parts of one, the teapot's handle and body) cover the same part of the light it
//! counts twice (clamped at full shadow; a receiver in one caster's umbra and another's penumbra is
//! right, one in two penumbrae over-darkens).
//!
//! Spot and point lights, with the light's `radius`; a directional light has no position to find wedges
//! from and is refused by name.
//!
//! Casters their texture cuts out have no silhouette that bounds their shadow, so they get no wedge and
//! no side quad: their shadows come from a depth map of them alone, alpha-tested as every light pass
//! (`passes::maps::CutoutMaps`, the settings `cutout_*`), and the soft visibility is multiplied by that
//! map's. A frame without such casters renders no map and runs as before.

pub mod coverage;
pub mod cpu;
pub mod geometry;
pub mod gpu;

use shadow_core::FrameInputs;
use shadow_core::light::LightView;
use shadow_core::technique::maps::CutoutMap;
use shadow_core::technique::settings::{OnOff, SettingKey};
use shadow_core::technique::{FrameStats, LightKinds, TechniqueError};

use crate::Entry;
use coverage::SphereLight;
use geometry::WedgeGeometry;

shadow_core::technique_settings! {
    /// `penumbra-wedges` settings.
    pub struct PenumbraWedges {
        /// Whether the wedges are drawn; off leaves the count alone: the hard shadow of the light's centre.
        pub wedges: OnOff = SettingKey::choice(
            "wedges",
            "on",
            OnOff::NAMES,
            "on: soft shadows; off: the count alone, the hard shadow of the light's centre",
        ),
        /// The map of the casters their texture cuts out, filtered by default (its cascades are for
        /// directional lights, which wedges do not take).
        pub cutouts: CutoutMap = CutoutMap::SOFT_KEYS,
    }
    lights = LightKinds::POSITIONED;
}

impl PenumbraWedges {
    /// The technique's name.
    pub const NAME: &'static str = "penumbra-wedges";

    /// The light as a sphere.
    ///
    /// # Errors
    /// [`TechniqueError::UnsupportedLight`] for a directional light.
    pub fn sphere(light: &LightView) -> Result<SphereLight, TechniqueError> {
        let centre =
            light.light.position().ok_or_else(|| TechniqueError::unsupported_light(Self::NAME, &light.light))?;
        Ok(SphereLight { centre, radius: light.light.radius })
    }

    /// The quads and wedges of a frame's casters for a light; their counters recorded in `stats` (both
    /// backends alike).
    ///
    /// # Errors
    /// [`TechniqueError::UnsupportedLight`] for a directional light.
    pub fn construct(
        frame: &FrameInputs,
        light: &LightView,
        stats: &mut FrameStats,
    ) -> Result<WedgeGeometry, TechniqueError> {
        let sphere = Self::sphere(light)?;
        let built = WedgeGeometry::build(frame, frame.caster_silhouettes(light), sphere);
        let c = &mut stats.counters;
        c.silhouette_edges = Some(built.edges.len() as u64);
        c.volume_triangles = Some(2 * built.edges.len() as u64);
        c.extra.insert("wedge_triangles".into(), built.hulls.len() as f64);
        c.extra.insert("edges_without_wedge".into(), built.without_wedge as f64);
        Ok(built)
    }
}

/// The registry entry.
#[must_use]
pub fn entry() -> Entry {
    Entry::on_both::<PenumbraWedges>(
        PenumbraWedges::NAME,
        "soft shadow volumes: a wedge per silhouette edge adds the part of the light it covers, per pixel",
        "Akenine-Moeller-Assarsson 2002; Assarsson-Akenine-Moeller 2003",
    )
    .wgsl(gpu::shaders)
    .soft()
    .cutouts_by_map()
}
