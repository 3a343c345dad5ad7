// penumbra-map: the query (twin: shadow-soft's penumbra_map/cpu.rs `penumbra_lookup`). Follows
// shadow_map.wgsl, whose bindings 0 to 3 it shares.

@group(1) @binding(4) var penumbra: texture_depth_2d;

// One texel, clamped to the map: behind the blocker 0, else the penumbra map's value.
fn penumbra_texel(layer: i32, x: i32, y: i32, depth: f32) -> f32 {
    let n = i32(map.settings.z) - 1;
    let t = vec2<i32>(clamp(x, 0, n), clamp(y, 0, n));
    if (depth > textureLoad(shadow_maps, t, layer, 0)) {
        return 0.0;
    }
    return textureLoad(penumbra, t, 0);
}

// The four nearest texels, bilinearly weighted; 1 outside the map.
fn penumbra_lookup(layer: i32, uv: vec2<f32>, depth: f32) -> f32 {
    if (uv.x < 0.0 || uv.x > 1.0 || uv.y < 0.0 || uv.y > 1.0) {
        return 1.0;
    }
    let st = uv * map.settings.z - vec2<f32>(0.5);
    let i = floor(st);
    let f = st - i;
    let x = i32(i.x);
    let y = i32(i.y);
    let top = penumbra_texel(layer, x, y, depth) * (1.0 - f.x) + penumbra_texel(layer, x + 1, y, depth) * f.x;
    let bottom = penumbra_texel(layer, x, y + 1, depth) * (1.0 - f.x) + penumbra_texel(layer, x + 1, y + 1, depth) * f.x;
    return top * (1.0 - f.y) + bottom * f.y;
}

@fragment
fn fs_penumbra_query(in: FullScreen) -> @location(0) vec4<f32> {
    let g = textureLoad(g_position, vec2<i32>(in.pos.xy), 0);
    if (g.w == 0.0) {
        return vec4<f32>(1.0);
    }
    let m = map_point(g.xyz);
    return vec4<f32>(penumbra_lookup(m.layer, m.uv, m.depth));
}
