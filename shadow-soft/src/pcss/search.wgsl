// pcss: the blocker search (twin: shadow-soft's pcss/cpu.rs `blocker_depth`), which the moment maps
// share. Follows shadow_map.wgsl, whose bindings 0 to 3 it shares, and declares the geometric normals at
// binding 4; map.extra holds the lens: x = k (the light's radius in map coordinates at unit distance),
// y = near, z = far.

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

// The Poisson disc's tap `i`, turned by `turn` (sin, cos).
fn turned_tap(i: i32, turn: vec2<f32>) -> vec2<f32> {
    let p = POISSON16[i];
    return vec2<f32>(turn.y * p.x - turn.x * p.y, turn.x * p.x + turn.y * p.y);
}

// The disc's turn for `pixel`: (sin, cos) of its hashed angle.
fn pixel_turn(pixel: vec2<u32>) -> vec2<f32> {
    let angle = hash_unit(pixel_hash(pixel.x, pixel.y)) * 6.2831855;
    return vec2<f32>(sin(angle), cos(angle));
}

// The blockers' mean linear depth for a receiver at `uv`, NDC depth `depth`, or -1 where there are none.
fn pcss_blockers(layer: i32, uv: vec2<f32>, depth: f32, gradient: vec2<f32>, pixel: vec2<u32>) -> f32 {
    let k = map.extra.x;
    let near = map.extra.y;
    let z_r = pcss_linear(depth);
    let search = k * (z_r - near) / (near * z_r);
    let turn = pixel_turn(pixel);
    var sum = 0.0;
    var blockers = 0u;
    for (var i = 0; i < 16; i = i + 1) {
        let o = turned_tap(i, turn) * search;
        let d = texel_depth(layer, uv + o);
        if (d < depth + dot(gradient, o)) {
            sum = sum + pcss_linear(d);
            blockers = blockers + 1u;
        }
    }
    if (blockers == 0u) {
        return -1.0;
    }
    return sum / f32(blockers);
}
