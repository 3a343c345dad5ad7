//! `volume-reconstruction` (McCool 2000): a shadow volume rebuilt from the light's depth map, resolved with
//! one stencil bit.
//!
//! Build: depth maps as `shadow-map` renders them (its bias settings, with a smaller default slope; a
//! point light's cube faces widened so their maps meet, see `LightView::with_seamless_faces`), then per
//! map the edge flags and the reconstructed triangles ([`reconstruction`], shared by both backends, with
//! the paper's steps written out there). Query: the near-plane cap for this view, then every triangle
//! drawn with its stencil bit inverted wherever it is in front of the G-buffer (front and back faces
//! alike, one pass), the caps inverted without a depth test, and the bit read: set means shadowed.

pub mod cpu;
pub mod gpu;
pub mod reconstruction;

use crate::Entry;
use shadow_core::technique::maps::{BIAS_SLOPE, DepthMap, resolution_key};
use shadow_core::technique::settings::{OnOff, SettingKey, SettingsError, Values};

shadow_core::named_enum! {
    /// The edge detector of `volume-reconstruction`.
    pub enum EdgeTest {
        /// First differences over theta_L thinned by the second-derivative test, sure edges over theta_H
        /// (section 3.3).
        SecondDerivative = "second-derivative",
        /// First differences over theta_L alone (section 3.1).
        FirstDifference = "first-difference",
    }
}

shadow_core::named_enum! {
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

shadow_core::named_enum! {
    /// Where the mesh of `volume-reconstruction` has its vertices.
    pub enum MeshVertices {
        /// At texel centres, edge midpoints and corners, a border sample taking the far side: shadows the
        /// size of the shadow map's (see `reconstruction::texel_square_grid`).
        Texel = "texel",
        /// At the texel centres, as the paper has them: every shadow half a texel larger.
        Centre = "centre",
    }
}

/// The depth map's keys, with an eighth of shadow-map's slope bias: the mesh is drawn only across
/// discontinuities, where its slopes fall away from the occluder, so the bias is needed only against
/// false-positive cells lying on a surface, and a receiver's bias sinks the slopes' far ends behind it and
/// erodes the shadow (cubes, map 512: slope 2 gives 1.03%, 0.25 gives 0.69%, shadow-map 0.92%; none leaves
/// false-positive rows on strike).
const DEPTH_KEYS: [SettingKey; 5] = {
    let mut keys = DepthMap::keys(resolution_key("1024", "depth-map side in texels (16 to 16384)"));
    keys[3] = BIAS_SLOPE.with_default("0.25");
    keys
};

shadow_core::technique_settings! {
    /// `volume-reconstruction` (McCool 2000): a shadow volume rebuilt from the light's depth map, resolved
    /// with a one-bit parity stencil.
    pub struct VolumeReconstruction {
        /// The depth map: resolution and bias as `shadow-map` has them (the filter is unused). The bias
        /// moves the reconstructed boundary away from the light, as the paper's bias translation of the light
        /// depths does; `bias=world` moves each vertex `bias_world` along its light ray.
        pub depth: DepthMap = DEPTH_KEYS,
        /// Where the mesh's vertices are.
        pub vertices: MeshVertices = SettingKey::choice(
            "vertices",
            "texel",
            MeshVertices::NAMES,
            "texel (centres, midpoints and corners: shadow-map-sized shadows) or centre (the paper's)",
        ),
        /// The detector.
        pub edges: EdgeTest = SettingKey::choice(
            "edges",
            "second-derivative",
            EdgeTest::NAMES,
            "second-derivative (thinned, section 3.3) or first-difference (section 3.1)",
        ),
        /// theta_L, theta_H, theta_S and the dangling-edge threshold, as fractions of the fitted light depth
        /// range (far minus near), applied to linear depths.
        pub theta_low: f32 = SettingKey::float(
            "theta_low",
            "0.001",
            0.0,
            1.0,
            "candidate edge threshold, fraction of the light depth range",
        ),
        /// See `theta_low`.
        pub theta_high: f32 = SettingKey::float(
            "theta_high",
            "0.01",
            0.0,
            1.0,
            "sure edge threshold, fraction of the light depth range",
        ),
        /// See `theta_low`.
        pub theta_second: f32 = SettingKey::float(
            "theta_second",
            "0.0005",
            0.0,
            1.0,
            "second-derivative zero-crossing strength, fraction of the light depth range",
        ),
        /// See `theta_low`.
        pub theta_dangling: f32 = SettingKey::float(
            "theta_dangling",
            "0.0001",
            0.0,
            1.0,
            "lowered threshold along dangling edges, fraction of the light depth range",
        ),
        /// How many cells a dangling edge is followed under the lowered thresholds.
        pub dangling_steps: u32 = SettingKey::int(
            "dangling_steps",
            "8",
            0,
            64,
            "cells a dangling edge is followed (0 to 64)",
        ),
        /// Object-ID edges from an ID channel of the light pass.
        pub ids: ObjectIds = SettingKey::choice(
            "ids",
            "off",
            ObjectIds::NAMES,
            "object-ID edges: off, dangling (dangling edges follow ID boundaries) or all (ORed with depth edges)",
        ),
        /// The near-plane cap: on, software caps (McCool section 6.2); off, none, so that where the eye's near
        /// plane cuts the volume parity inverts (Fig. 7).
        pub capping: OnOff = SettingKey::choice(
            "capping",
            "on",
            OnOff::NAMES,
            "near-plane caps: on, or off to see the inversion",
        ),
    }
    check = VolumeReconstruction::check;
}

impl VolumeReconstruction {
    /// The check across fields: the sure-edge threshold is at least the candidate one.
    fn check(&self, v: &Values<'_>) -> Result<(), SettingsError> {
        if self.theta_high < self.theta_low {
            return Err(v.bad("theta_high", &format!("at least theta_low ({})", self.theta_low)));
        }
        Ok(())
    }

    /// The detector's thresholds in scene units for a light depth range of `range`.
    #[must_use]
    pub fn edge_settings(&self, range: f32) -> reconstruction::edges::EdgeSettings {
        reconstruction::edges::EdgeSettings {
            low: self.theta_low * range,
            high: self.theta_high * range,
            second: (self.edges == EdgeTest::SecondDerivative).then_some(self.theta_second * range),
            dangling: self.theta_dangling * range,
            dangling_steps: self.dangling_steps,
        }
    }
}

impl VolumeReconstruction {
    /// The technique's name.
    pub const NAME: &'static str = "volume-reconstruction";
}

/// The registry entry.
#[must_use]
pub fn entry() -> Entry {
    Entry::on_both::<VolumeReconstruction>(
        VolumeReconstruction::NAME,
        "a shadow volume rebuilt from the light's depth map, resolved with one stencil bit",
        "McCool 2000",
    )
    .wgsl(gpu::shaders)
}
