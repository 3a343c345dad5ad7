//! hybrid's WGSL, put together per settings: the mask, volume and answer passes after the shadow-map
//! shader, with the pieces each setting swaps in (a `near_edge` per `edge_texels`, tile marks for
//! `scissor_tile`, pixel lists for `caster_masks`), and the caster masks' compute passes.

use shadow_wgpu::shaders::with_shadow_map;

use crate::hybrid::EdgeTexels;

const QUERY: &str = include_str!("../query.wgsl");
const CASTERS: &str = include_str!("../casters.wgsl");
const EDGES_OFF: &str = include_str!("../edges_off.wgsl");
const EDGES_PAIRED: &str = include_str!("../edges_paired.wgsl");
const TILE_MARKS: &str = include_str!("../tile_marks.wgsl");
const TILE_MARKS_OFF: &str = include_str!("../tile_marks_off.wgsl");
const CASTER_LISTS: &str = include_str!("../caster_lists.wgsl");
const LISTED_COUNTS: &str = include_str!("../listed_counts.wgsl");
const LISTED_OFF: &str = include_str!("../listed_off.wgsl");

/// The classification, the mask and the answer, after the shadow-map shader; with `caster_masks`, the
/// mask pass also lists the silhouette pixels and the answer reads their counts.
#[must_use]
pub fn query(edge_texels: EdgeTexels, tile_marks: bool, caster_masks: bool) -> String {
    let edges = match edge_texels {
        EdgeTexels::Off => EDGES_OFF,
        EdgeTexels::Paired => EDGES_PAIRED,
    };
    let tiles = if tile_marks { TILE_MARKS } else { TILE_MARKS_OFF };
    let lists = if caster_masks { format!("{CASTER_LISTS}\n{LISTED_COUNTS}") } else { LISTED_OFF.to_string() };
    with_shadow_map(&format!("{edges}\n{tiles}\n{lists}\n{QUERY}"))
}

/// The caster masks' compute passes that count the small volume pieces at the listed pixels.
#[must_use]
pub fn casters() -> String {
    with_shadow_map(&format!("{CASTER_LISTS}\n{CASTERS}"))
}

/// Every variant, by name, for validation.
#[must_use]
pub fn all() -> Vec<(&'static str, String)> {
    vec![
        ("hybrid", query(EdgeTexels::Off, false, false)),
        ("hybrid tile marks", query(EdgeTexels::Off, true, false)),
        ("hybrid edge_texels=paired, caster masks", query(EdgeTexels::Paired, false, true)),
        ("hybrid caster masks", casters()),
    ]
}
