//! WGSL sources. Each is `common.wgsl` followed by its own file (the silhouette-map build pass, which
//! reads no camera state, stands alone); the shadow-map shader also gets the Poisson disk generated from
//! shadow-core's constant, so the two backends share one table.

use std::fmt::Write;

use shadow_core::technique::hard::EdgeTexels;

const COMMON: &str = include_str!("shaders/common.wgsl");

/// `common.wgsl` + `body`.
fn with_common(body: &str) -> String {
    format!("{COMMON}\n{body}")
}

/// The Poisson disk of `shadow_core::lookup::POISSON16` as a WGSL constant.
fn poisson_constant() -> String {
    let mut s = String::from("const POISSON16 = array<vec2<f32>, 16>(");
    for (i, p) in shadow_core::lookup::POISSON16.iter().enumerate() {
        let _ = write!(s, "{}vec2<f32>({:?}, {:?})", if i == 0 { "" } else { ", " }, p.x, p.y);
    }
    s.push_str(");\n");
    s
}

/// G-buffer pass.
#[must_use]
pub fn gbuffer() -> String {
    with_common(include_str!("shaders/gbuffer.wgsl"))
}

/// Shading pass.
#[must_use]
pub fn shade() -> String {
    with_common(include_str!("shaders/shade.wgsl"))
}

/// Shadow-map light pass and query.
#[must_use]
pub fn shadow_map() -> String {
    with_common(&format!("{}{}", poisson_constant(), include_str!("shaders/shadow_map.wgsl")))
}

/// The shadow-map shader followed by `query`: a query written against `MapQuery`'s bindings and the
/// shadow-map shader's functions (the silhouette map's, hybrid's and the soft techniques' in shadow-soft).
#[must_use]
pub fn with_shadow_map(query: &str) -> String {
    format!("{}\n{query}", shadow_map())
}

/// Silhouette-map pass 2 (the points) and the texel count.
#[must_use]
pub fn silhouette_build() -> String {
    include_str!("shaders/silhouette_build.wgsl").to_string()
}

/// Silhouette-map query: the shadow-map shader and the reconstruction.
#[must_use]
pub fn silhouette_query() -> String {
    with_shadow_map(include_str!("shaders/silhouette_query.wgsl"))
}

/// Hybrid maps and volumes: the classification, the mask and the answer, after the shadow-map shader;
/// with `caster_masks`, the mask pass also lists the silhouette pixels and the answer reads their counts.
#[must_use]
pub fn hybrid(edge_texels: EdgeTexels, tile_marks: bool, caster_masks: bool) -> String {
    let edges = match edge_texels {
        EdgeTexels::Off => NEAR_EDGE_OFF,
        EdgeTexels::All => include_str!("shaders/hybrid_edges.wgsl"),
        EdgeTexels::Paired => include_str!("shaders/hybrid_edge_pairs.wgsl"),
    };
    let tiles = if tile_marks { TILE_MARKS } else { TILE_MARKS_OFF };
    let lists = if caster_masks { format!("{CASTER_LISTS}\n{LISTED_COUNTS}") } else { LISTED_OFF.to_string() };
    with_shadow_map(&format!("{edges}\n{tiles}\n{lists}\n{}", include_str!("shaders/hybrid.wgsl")))
}

/// hybrid's caster masks: the compute passes that count the small volume pieces at the listed pixels.
#[must_use]
pub fn hybrid_casters() -> String {
    with_shadow_map(&format!("{CASTER_LISTS}\n{}", include_str!("shaders/hybrid_casters.wgsl")))
}

/// hybrid's caster masks: the silhouette pixels the mask pass lists (`y * width + x`), with the counters
/// the compute pass adds to (the fragments its triangles make at them, its stencil updates, its
/// pixel-triangle tests and the pixels whose pairs did not fit, counted alone).
const CASTER_LISTS: &str = "
struct Listed {
    pixels: atomic<u32>,
    fragments: atomic<u32>,
    updates: atomic<u32>,
    tests: atomic<u32>,
    alone: atomic<u32>,
    at: array<u32>,
};

@group(1) @binding(8) var<storage, read_write> listed: Listed;
";

/// hybrid's fragment passes with caster masks: the mask pass lists its pixels and leaves every pixel's
/// class in `counts`, where the answer reads it outside the mask; a listed pixel the compute passes gave
/// a count other than 0 is shadowed.
const LISTED_COUNTS: &str = "
@group(1) @binding(9) var<storage, read_write> counts: array<i32>;

fn remember_class(px: vec2<i32>, c: u32) {
    counts[u32(px.y) * u32(view.size.x) + u32(px.x)] = i32(c);
}

fn remembered_class(px: vec2<i32>) -> u32 {
    return u32(counts[u32(px.y) * u32(view.size.x) + u32(px.x)]);
}

fn list_pixel(px: vec2<i32>) {
    listed.at[atomicAdd(&listed.pixels, 1u)] = u32(px.y) * u32(view.size.x) + u32(px.x);
}

fn listed_shadowed(px: vec2<i32>) -> bool {
    return counts[u32(px.y) * u32(view.size.x) + u32(px.x)] != 0;
}
";

/// hybrid's `list_pixel`, `listed_shadowed` and the class left for the answer with `caster_masks=off`:
/// nothing, never, and the class found again.
const LISTED_OFF: &str = "
fn list_pixel(px: vec2<i32>) {}
fn listed_shadowed(px: vec2<i32>) -> bool { return false; }
fn remember_class(px: vec2<i32>, c: u32) {}
fn remembered_class(px: vec2<i32>) -> u32 { return receiver_class(px); }
";

/// hybrid's `scissor_tile`: the mask pass marks the tile of each silhouette pixel (map.extra: x the tile
/// side in pixels, y the tiles per row).
const TILE_MARKS: &str = "
@group(1) @binding(7) var<storage, read_write> tile_marks: array<atomic<u32>>;

fn mark_tile(px: vec2<i32>) {
    let t = vec2<u32>(px) / u32(map.extra.x);
    atomicStore(&tile_marks[t.y * u32(map.extra.y) + t.x], 1u);
}
";

/// hybrid's `mark_tile` with `scissor_tile=0`: nothing (and no binding for the marks).
const TILE_MARKS_OFF: &str = "fn mark_tile(px: vec2<i32>) {}";

/// hybrid's `near_edge` with `edge_texels=off`: never (and no binding for the edge maps).
const NEAR_EDGE_OFF: &str = "fn near_edge(layer: i32, uv: vec2<f32>, depth: f32) -> bool { return false; }";

/// hybrid's edge pass: clip-space quads into a depth target (the nearest edge per texel).
pub const HYBRID_EDGE_PASS: &str =
    "@vertex fn vs_edge(@location(0) p: vec4<f32>) -> @builtin(position) vec4<f32> { return p; }";

/// Depth-layer passes (peeling and combination).
#[must_use]
pub fn depth_layers() -> String {
    with_common(include_str!("shaders/depth_layers.wgsl"))
}

/// Shadow-volume pass and resolve.
#[must_use]
pub fn shadow_volume() -> String {
    with_common(include_str!("shaders/shadow_volume.wgsl"))
}

/// Shadow volume reconstruction: the boundary and cap passes, after the shadow-volume shader (its resolve).
#[must_use]
pub fn volume_reconstruction() -> String {
    format!("{}\n{}", shadow_volume(), include_str!("shaders/volume_reconstruction.wgsl"))
}

/// Every shader, by name, for validation.
#[must_use]
pub fn all() -> Vec<(&'static str, String)> {
    vec![
        ("gbuffer", gbuffer()),
        ("shade", shade()),
        ("shadow_map", shadow_map()),
        ("shadow_volume", shadow_volume()),
        ("volume_reconstruction", volume_reconstruction()),
        ("depth_layers", depth_layers()),
        ("silhouette_build", silhouette_build()),
        ("silhouette_query", silhouette_query()),
        ("hybrid", hybrid(EdgeTexels::Off, false, false)),
        ("hybrid edge_texels=all, tile marks", hybrid(EdgeTexels::All, true, false)),
        ("hybrid edge_texels=paired, caster masks", hybrid(EdgeTexels::Paired, false, true)),
        ("hybrid caster masks", hybrid_casters()),
        ("hybrid edge pass", HYBRID_EDGE_PASS.to_string()),
    ]
}

/// A shader module from WGSL text.
#[must_use]
pub fn module(device: &wgpu::Device, label: &str, source: String) -> wgpu::ShaderModule {
    device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(label),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    })
}

#[cfg(test)]
mod tests {
    /// Every WGSL source parses and validates with naga, so a shader error fails `cargo test`, not a user.
    #[test]
    fn every_shader_validates() {
        for (name, src) in super::all() {
            let module =
                naga::front::wgsl::parse_str(&src).unwrap_or_else(|e| panic!("{name}: {}", e.emit_to_string(&src)));
            let mut v =
                naga::valid::Validator::new(naga::valid::ValidationFlags::all(), naga::valid::Capabilities::all());
            if let Err(e) = v.validate(&module) {
                panic!("{name}: {}", e.emit_to_string(&src));
            }
        }
    }
}
