// hybrid (Chan, thesis chapter 3): the map's classification of each receiver, the computation mask it
// makes in the stencil's bit 7, and the passes that answer from the mask (twin: cpu.rs). Follows
// shadow_map.wgsl, whose bindings 0 to 3 it shares, one of the two `near_edge` (edges_paired.wgsl, or
// never), one of the two `mark_tile` and one of the two sets of
// `list_pixel`, `listed_shadowed`, `remember_class` and `remembered_class` (caster masks; shaders.rs).

@group(1) @binding(4) var g_geometric_normal: texture_2d<f32>;

// The map's classes (twin: shadow_core::lookup::MapClass), and no receiver at all.
const MAP_LIT: u32 = 0u;
const MAP_SHADOWED: u32 = 1u;
const SILHOUETTE: u32 = 2u;
const NOT_RECEIVER: u32 = 3u;

// Twin: shadow_core::lookup::classify. The four texels a bilinear lookup reads, compared one by one.
fn classify(layer: i32, uv: vec2<f32>, depth: f32, faces_light: bool) -> u32 {
    if (uv.x < 0.0 || uv.x > 1.0 || uv.y < 0.0 || uv.y > 1.0) {
        return MAP_LIT;
    }
    let st = uv * map.settings.z - vec2<f32>(0.5);
    let x = i32(floor(st.x));
    let y = i32(floor(st.y));
    let lit = compare_texel(layer, x, y, depth) + compare_texel(layer, x + 1, y, depth)
        + compare_texel(layer, x, y + 1, depth) + compare_texel(layer, x + 1, y + 1, depth);
    if (lit == 4.0) {
        return MAP_LIT;
    }
    if (lit == 0.0) {
        return MAP_SHADOWED;
    }
    return select(MAP_SHADOWED, SILHOUETTE, faces_light);
}

// The class of the receiver at `px` (twin: `classify_receivers` in cpu.rs).
fn receiver_class(px: vec2<i32>) -> u32 {
    let g = textureLoad(g_position, px, 0);
    if (g.w == 0.0) {
        return NOT_RECEIVER;
    }
    let faces_light = dot(textureLoad(g_geometric_normal, px, 0).xyz, map_to_light(g.xyz)) > 0.0;
    let m = map_point(g.xyz);
    let c = classify(m.layer, m.uv, m.depth, faces_light);
    if (faces_light && near_edge(m.layer, m.uv, m.depth)) {
        return SILHOUETTE;
    }
    return c;
}

// The computation mask: silhouette pixels pass and the pipeline sets their stencil bit 7; every other
// pixel is discarded.
@fragment
fn fs_hybrid_mask(in: FullScreen) {
    let c = receiver_class(vec2<i32>(in.pos.xy));
    remember_class(vec2<i32>(in.pos.xy), c);
    if (c != SILHOUETTE) {
        discard;
    }
    mark_tile(vec2<i32>(in.pos.xy));
    list_pixel(vec2<i32>(in.pos.xy));
}

// The depth mask's far triangle (gpu_mask=depth): full screen at depth 1, rasterized, no fragment stage.
@vertex
fn vs_hybrid_far(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    // The corners of common.wgsl's vs_full_screen (entry points cannot be called).
    return vec4<f32>(f32(i32(i & 1u) * 4 - 1), f32(i32(i >> 1u) * 4 - 1), 1.0, 1.0);
}

// The map's answer, drawn under the stencil test "outside the mask": the shadowed receivers get 0, the
// lit ones and non-receivers keep what the target holds (1, or the cut-out casters' visibility).
@fragment
fn fs_hybrid_map(in: FullScreen) -> @location(0) vec4<f32> {
    let c = remembered_class(vec2<i32>(in.pos.xy));
    if (c == NOT_RECEIVER || c == MAP_LIT) {
        discard;
    }
    return vec4<f32>(0.0);
}

// Shadowed: drawn under the stencil test "inside the mask and a count that is not 0".
@fragment
fn fs_hybrid_shadowed(in: FullScreen) -> @location(0) vec4<f32> {
    return vec4<f32>(0.0);
}

// With caster masks, drawn under the stencil test "inside the mask and a count of 0": shadowed where the
// pieces counted at the listed pixels gave a count other than 0.
@fragment
fn fs_hybrid_listed(in: FullScreen) -> @location(0) vec4<f32> {
    if (!listed_shadowed(vec2<i32>(in.pos.xy))) {
        discard;
    }
    return vec4<f32>(0.0);
}

// The debug view's codes (shadow_core::lookup::PixelClass discriminants), drawn under the same stencil
// tests as the answer: CODE 0 writes the map's class (outside the mask), any other CODE itself, or
// SHADOWED_CODE where the caster masks' count shadows the pixel.
override CODE: u32 = 0u;
override SHADOWED_CODE: u32 = 0u;

@fragment
fn fs_hybrid_code(in: FullScreen) -> @location(0) u32 {
    if (CODE != 0u) {
        return select(CODE, SHADOWED_CODE, listed_shadowed(vec2<i32>(in.pos.xy)));
    }
    let c = receiver_class(vec2<i32>(in.pos.xy));
    if (c == NOT_RECEIVER) {
        discard;
    }
    // PixelClass::MapLit = 2, PixelClass::MapShadowed = 1.
    return select(1u, 2u, c == MAP_LIT);
}
