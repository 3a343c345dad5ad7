// pcss: the query (twin: shadow-soft's pcss/cpu.rs `pcss_lookup`). Follows search.wgsl.

fn pcss_lookup(layer: i32, uv: vec2<f32>, depth: f32, gradient: vec2<f32>, pixel: vec2<u32>) -> f32 {
    if (uv.x < 0.0 || uv.x > 1.0 || uv.y < 0.0 || uv.y > 1.0) {
        return 1.0;
    }
    let z_b = pcss_blockers(layer, uv, depth, gradient, pixel);
    if (z_b < 0.0) {
        return 1.0;
    }
    let k = map.extra.x;
    let z_r = pcss_linear(depth);
    let radius = k * max(z_r - z_b, 0.0) / (z_b * z_r);
    let turn = pixel_turn(pixel);
    var lit = 0.0;
    for (var i = 0; i < 16; i = i + 1) {
        let o = turned_tap(i, turn) * radius;
        lit = lit + compare_bilinear(layer, uv + o, depth + dot(gradient, o));
    }
    return lit / 16.0;
}

@fragment
fn fs_pcss_query(in: FullScreen) -> @location(0) vec4<f32> {
    let px = vec2<i32>(in.pos.xy);
    let g = textureLoad(g_position, px, 0);
    if (g.w == 0.0) {
        return vec4<f32>(1.0);
    }
    let m = map_point(g.xyz);
    let gradient = depth_gradient(m.layer, m.world, textureLoad(g_geometric_normal, px, 0).xyz);
    return vec4<f32>(pcss_lookup(m.layer, m.uv, m.depth, gradient, vec2<u32>(px)));
}
