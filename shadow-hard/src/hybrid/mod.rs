//! `hybrid` (Chan, thesis chapter 3): shadow maps where they are right, shadow volumes where they are not.
//!
//! Build: the classifying depth maps as `shadow-map` renders them, and the z-fail volumes of every caster
//! (shared geometry, as `shadow-volume-zfail` builds them). Query, the thesis's steps 2 to 4: each receiver
//! is compared with the four texels nearest its map position (`shadow_core::lookup::classify`); where they
//! disagree and the surface faces the light it is a silhouette pixel, otherwise the map's answer is final.
//! The silhouette pixels make a computation mask; the volumes are counted z-fail through it, and a
//! silhouette pixel is shadowed where its count is not 0. [`cpu`] and [`gpu`] say how each backend keeps
//! the mask and what each setting changes there.
//!
//! Ours, on top of the thesis: [`shafts`] (each caster's volume counted only at the silhouette pixels its
//! shadow's bounds hold, `caster_masks`) and [`edge_map`] (receivers near silhouette edges thinner than a
//! texel masked in too, `edge_texels`).
//!
//! Casters their texture cuts out have no silhouette for a volume to extrude, so the classifying map, the
//! mask and the volumes are of the other casters alone (`Casters::Solid`), and the cut-out ones cast
//! through a map of their own, alpha-tested (`passes::maps::CutoutMaps`, the settings `cutout_*`, as the
//! shadow volumes have it): a receiver is lit only where the hybrid's answer and that map both say lit.
//! A frame without such casters renders no such map and runs as before.

pub mod cpu;
pub mod edge_map;
pub mod gpu;
pub mod shafts;

use crate::Entry;
use shadow_core::technique::maps::{CutoutMap, DepthMap, resolution_key};
use shadow_core::technique::settings::{OnOff, SettingKey};

shadow_core::technique_settings! {
    /// `hybrid` (Chan, thesis chapter 3): a shadow map classifies each receiver; where its four nearest
    /// depth tests disagree on a surface facing the light (a silhouette pixel) z-fail shadow volumes decide,
    /// confined to those pixels by a computation mask; everywhere else the map decides.
    pub struct Hybrid {
        /// The classifying map: resolution and bias as `shadow-map` has them (the filter is unused: the
        /// classification reads the four nearest texels). Chan uses a lower resolution than a plain map needs,
        /// the volumes drawing the edges.
        pub depth: DepthMap = DepthMap::keys(resolution_key("512", "classifying map side in texels (16 to 16384)")),
        /// On, each connected component's volume is counted only at the silhouette pixels within the
        /// light-space bounds of its shadow ([`shafts`]; its count is zero everywhere else): on the CPU
        /// by listed draws, on the GPU by compute passes over the pixels the mask pass lists (pieces of more
        /// than a thousand triangles stay rasterized under the mask); off, every volume through the whole
        /// mask. Same picture either way, on the GPU but for the odd pixel where a volume side meets its
        /// receiver to within rounding.
        pub caster_masks: OnOff = SettingKey::choice(
            "caster_masks",
            "on",
            OnOff::NAMES,
            "on, each caster's volume is counted only at the silhouette pixels its shadow's bounds hold (GPU: by compute passes); off, through the whole mask",
        ),
        /// Which receivers facing the light are also silhouette pixels because of the casters' silhouette
        /// edges (drawn into a map of edge depths), so casters and gaps thinner than a texel, which the map
        /// misses (Chan's Fig. 3-8), still get volumes; off: Chan's rule alone. `paired` by default (ours):
        /// it keeps `tree` under 0.1% at 512^2 with a third more silhouette pixels than Chan's rule on tree
        /// and nine tenths more on cubes. Masking every receiver whose texels an edge crosses did as well
        /// for error with twice and ten times as many, so only the pairs are kept.
        pub edge_texels: EdgeTexels = SettingKey::choice(
            "edge_texels",
            "paired",
            EdgeTexels::NAMES,
            "off (Chan's rule) or paired (also mask receivers where two silhouette edges in front enter their footprint, or one ends there)",
        ),
        /// Whether the query also counts the volumes' unmasked fill (what `shadow-volume-zfail` rasterizes),
        /// the counter `unmasked_volume_fragments`, in a pass of its own timed as `count_fragments`; off, the
        /// frame costs what the technique costs.
        pub unmasked_fill: OnOff = SettingKey::choice(
            "unmasked_fill",
            "off",
            OnOff::NAMES,
            "on: also count the volumes' fill without the mask (unmasked_volume_fragments), in an extra pass",
        ),
        /// The map of the casters their texture cuts out.
        pub cutouts: CutoutMap = CutoutMap::KEYS,
        /// What the CPU backend alone reads.
        pub cpu: CpuOptions = CpuOptions::KEYS,
        /// What the GPU backend alone reads.
        pub gpu: GpuOptions = GpuOptions::KEYS,
    }
}

shadow_core::setting_group! {
    /// `hybrid`'s settings for the CPU backend alone.
    pub struct CpuOptions {
        /// Side in pixels of the CPU computation mask's tiles, which the rasterizer skips whole where no pixel
        /// is masked in.
        pub mask_tile: u32 = SettingKey::int(
            "mask_tile",
            "8",
            1,
            64,
            "CPU computation-mask tile side in pixels (1 to 64): tiles with no silhouette pixel are skipped whole",
        ),
    }
}

shadow_core::setting_group! {
    /// `hybrid`'s settings for the GPU backend alone.
    pub struct GpuOptions {
        /// Where the computation mask is kept (the CPU always uses its tiles).
        pub mask: GpuMask = SettingKey::choice(
            "gpu_mask",
            "stencil",
            GpuMask::NAMES,
            "GPU computation mask: stencil (a stencil bit) or depth (a scratch depth of 1 outside the mask)",
        ),
        /// GPU: 0, the volumes are drawn over the whole view and the mask rejects fragments; N, the mask pass
        /// also marks the N x N pixel tiles holding a silhouette pixel, the CPU reads the marks back and the
        /// volumes are drawn only inside scissor rectangles around those tiles, so the rasterizer never makes
        /// the fragments elsewhere (the draws are repeated per rectangle).
        pub scissor_tile: u32 = SettingKey::int(
            "scissor_tile",
            "0",
            8,
            512,
            "GPU: 0, or draw the volumes only in scissor rectangles around the masked NxN tiles (8 to 512)",
        )
        .or("0"),
        /// GPU caster masks: how many pairs of a silhouette pixel and a piece whose shaft holds it the compute
        /// passes have room for; `None`, eight per pixel of the view. A pixel whose pairs do not all fit counts
        /// every one of its pieces by itself, in one invocation (slower, same count), so a small room changes
        /// the time, never the picture.
        pub pair_room: Option<u32> = SettingKey::int(
            "pair_room",
            "auto",
            0,
            MAX_PAIR_ROOM,
            "GPU caster masks: room for pixel-piece pairs, auto (8 per view pixel) or 0 to 268435456; a pixel whose pairs do not fit counts its pieces alone, more slowly",
        )
        .or("auto"),
    }
}

/// The most pairs `hybrid`'s `pair_room` may ask for: 2^28, what a 4 GiB storage binding holds at three
/// words a pair (the device's own limits may allow fewer, and then bound the room).
pub const MAX_PAIR_ROOM: u32 = 1 << 28;

shadow_core::named_enum! {
    /// Which receivers `hybrid` masks in because of the silhouette edges near them (besides Chan's rule).
    pub enum EdgeTexels {
        /// None: Chan's rule alone.
        Off = "off",
        /// Where two edges nearer the light enter the square between the receiver's four texel centres
        /// (its bilinear footprint), or one ends there. One straight edge across the square leaves texel
        /// centres on both of its sides, so Chan's rule already sees it; only a sliver, a gap or a corner
        /// can hide between the centres.
        Paired = "paired",
    }
}

impl EdgeTexels {
    /// Whether the build draws edge maps at all.
    #[must_use]
    pub fn is_on(self) -> bool {
        self != Self::Off
    }
}

shadow_core::named_enum! {
    /// Where `hybrid` keeps its computation mask on the GPU.
    pub enum GpuMask {
        /// A stencil bit, tested by the volume pass (per fragment, in the early stencil test).
        Stencil = "stencil",
        /// The depth of a scratch depth buffer, 1 outside the mask, with the volumes' z-fail test turned
        /// into a passing `GreaterEqual`: hierarchical depth rejects whole tiles outside the mask, as the
        /// depth bounds test does in Chan's implementation (section 3.2), which wgpu does not expose.
        /// Measured on an H100 (Vulkan), it is the slower of the two: the query takes 1.4 to 3.3 times the
        /// stencil mask's, whether the depth outside the mask is written by a shader or rasterized.
        Depth = "depth",
    }
}

impl Hybrid {
    /// The technique's name.
    pub const NAME: &'static str = "hybrid";
}

/// The registry entry.
#[must_use]
pub fn entry() -> Entry {
    Entry::on_both::<Hybrid>(
        Hybrid::NAME,
        "a shadow map, with z-fail shadow volumes at its silhouette pixels only (a computation mask)",
        "Chan 2004 (thesis, chapter 3)",
    )
    .wgsl(gpu::shaders::all)
    .cutouts_by_map()
}
