// smoothies: the query (twin: shadow-soft's smoothies/cpu.rs `smoothie_lookup` and `FalloffTable`). Follows
// shadow_map.wgsl, whose bindings 0 to 3 it shares.

@group(1) @binding(4) var smoothie_depth: texture_depth_2d;
@group(1) @binding(5) var smoothie_alpha: texture_depth_2d;
@group(1) @binding(6) var<storage, read> falloff: array<f32>;

// The thesis's three cases at one texel, clamped to the map.
fn smoothie_texel(layer: i32, x: i32, y: i32, depth: f32) -> f32 {
    let n = i32(map.settings.z) - 1;
    let t = vec2<i32>(clamp(x, 0, n), clamp(y, 0, n));
    var v = 1.0;
    if (depth > textureLoad(smoothie_depth, t, 0)) {
        v = textureLoad(smoothie_alpha, t, 0);
    }
    if (depth > textureLoad(shadow_maps, t, layer, 0)) {
        v = 0.0;
    }
    return v;
}

// The four nearest texels, bilinearly weighted; 1 outside the map.
fn smoothie_lookup(layer: i32, uv: vec2<f32>, depth: f32) -> f32 {
    if (uv.x < 0.0 || uv.x > 1.0 || uv.y < 0.0 || uv.y > 1.0) {
        return 1.0;
    }
    let st = uv * map.settings.z - vec2<f32>(0.5);
    let i = floor(st);
    let f = st - i;
    let x = i32(i.x);
    let y = i32(i.y);
    let top = smoothie_texel(layer, x, y, depth) * (1.0 - f.x) + smoothie_texel(layer, x + 1, y, depth) * f.x;
    let bottom = smoothie_texel(layer, x, y + 1, depth) * (1.0 - f.x) + smoothie_texel(layer, x + 1, y + 1, depth) * f.x;
    return top * (1.0 - f.y) + bottom * f.y;
}

// The tabulated falloff, linearly interpolated.
fn apply_falloff(v: f32) -> f32 {
    let last = arrayLength(&falloff) - 1u;
    let x = clamp(v, 0.0, 1.0) * f32(last);
    let i = min(u32(x), last - 1u);
    let f = x - f32(i);
    return falloff[i] * (1.0 - f) + falloff[i + 1u] * f;
}

@fragment
fn fs_smoothie_query(in: FullScreen) -> @location(0) vec4<f32> {
    let g = textureLoad(g_position, vec2<i32>(in.pos.xy), 0);
    if (g.w == 0.0) {
        return vec4<f32>(1.0);
    }
    let m = map_point(g.xyz);
    return vec4<f32>(apply_falloff(smoothie_lookup(m.layer, m.uv, m.depth)));
}
