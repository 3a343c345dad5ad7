// pcss: the query (twin: shadow-soft's pcss/cpu.rs `pcss_lookup`). Follows shadow_map.wgsl, whose bindings
// 0 to 3 it shares; map.extra holds the lens: x = k (the light's radius in map coordinates at unit
// distance), y = near, z = far.

@group(1) @binding(4) var g_geometric_normal: texture_2d<f32>;

// Twin: shadow_core::light::LightProjection::linear_depth (perspective).
fn pcss_linear(d: f32) -> f32 {
    let near = map.extra.y;
    let far = map.extra.z;
    return near * far / (far - d * (far - near));
}

// The NDC depth of the texel holding `uv`, clamped to the map's edge.
fn texel_depth(layer: i32, uv: vec2<f32>) -> f32 {
    let n = i32(map.settings.z);
    let t = vec2<i32>(floor(uv * map.settings.z));
    return textureLoad(shadow_maps, clamp(t, vec2<i32>(0), vec2<i32>(n - 1)), layer, 0);
}

fn pcss_lookup(layer: i32, uv: vec2<f32>, depth: f32, gradient: vec2<f32>, pixel: vec2<u32>) -> f32 {
    if (uv.x < 0.0 || uv.x > 1.0 || uv.y < 0.0 || uv.y > 1.0) {
        return 1.0;
    }
    let angle = hash_unit(pixel_hash(pixel.x, pixel.y)) * 6.2831855;
    let s = sin(angle);
    let c = cos(angle);
    let k = map.extra.x;
    let near = map.extra.y;
    let z_r = pcss_linear(depth);
    let search = k * (z_r - near) / (near * z_r);
    var sum = 0.0;
    var blockers = 0u;
    for (var i = 0; i < 16; i = i + 1) {
        let p = POISSON16[i];
        let o = vec2<f32>(c * p.x - s * p.y, s * p.x + c * p.y) * search;
        let d = texel_depth(layer, uv + o);
        if (d < depth + dot(gradient, o)) {
            sum = sum + pcss_linear(d);
            blockers = blockers + 1u;
        }
    }
    if (blockers == 0u) {
        return 1.0;
    }
    let z_b = sum / f32(blockers);
    let radius = k * max(z_r - z_b, 0.0) / (z_b * z_r);
    var lit = 0.0;
    for (var i = 0; i < 16; i = i + 1) {
        let p = POISSON16[i];
        let o = vec2<f32>(c * p.x - s * p.y, s * p.x + c * p.y) * radius;
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
