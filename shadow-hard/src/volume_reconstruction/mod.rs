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
use shadow_core::technique::maps::{BIAS, BIAS_CONSTANT, BIAS_SLOPE, BIAS_WORLD, DepthMap, resolution_key};
use shadow_core::technique::settings::{OnOff, SettingKey, SettingsError, TechniqueSettings, Values};

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

/// `volume-reconstruction` (McCool 2000): a shadow volume rebuilt from the light's depth map, resolved
/// with a one-bit parity stencil.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VolumeReconstruction {
    /// The depth map: resolution and bias as `shadow-map` has them (the filter is unused). The bias
    /// moves the reconstructed boundary away from the light, as the paper's bias translation of the light
    /// depths does; `bias=world` moves each vertex `bias_world` along its light ray.
    pub depth: DepthMap,
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
    resolution_key("1024", "depth-map side in texels (16 to 16384)"),
    BIAS,
    BIAS_CONSTANT,
    // An eighth of shadow-map's: the mesh is drawn only across discontinuities, where its slopes fall
    // away from the occluder, so the bias is needed only against false-positive cells lying on a surface,
    // and a receiver's bias sinks the slopes' far ends behind it and erodes the shadow (cubes, map 512:
    // slope 2 gives 1.03%, 0.25 gives 0.69%, shadow-map 0.92%; none leaves false-positive rows on strike).
    SettingKey { default: "0.25", ..BIAS_SLOPE },
    BIAS_WORLD,
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
            depth: DepthMap::read(v)?,
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
        let mut v = self.depth.values();
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
}
