// A light's shadow maps, looked into in a host's own shader as the technique that made them does: the
// same projection (a cube face for a point light, the cascade for the view depth, with the cascades'
// blend), the same receiver offset and the same filter. The maps and their parameters are
// `FrameRecorder::map(light)` after a recorded frame (`shadow_wgpu::HostMap`): bind its texture as
// `texture_depth_2d_array`, a comparison sampler made from `HostMap::sampler_descriptor()`, and its
// parameters (`HostMap::params_bytes()`) as a `ShadowlabMap` uniform.
//
// Plain WGSL with no bindings of its own: paste it before the host's shader, or compose it with naga_oil
// under the name `shadowlab::maps` (`shadow_wgpu::host_wgsl::MAPS_IMPORT_PATH`).
//
// Twin of shadow-wgpu's shadow_map.wgsl lookup (and so of shadow_core::lookup): the tests hold the two
// to the same visibility.

struct ShadowlabLight {
    // x: kind (0 spot, 1 directional, 2 point)
    kind: vec4<u32>,
    position: vec4<f32>,
    // The unit direction the light travels (a spot's axis).
    direction: vec4<f32>,
    // x: cos of the cone's half-angle, y: cos of its inner cone's, z: range (0: none)
    cone: vec4<f32>,
    // Colour times intensity.
    color: vec4<f32>,
};

struct ShadowlabMap {
    // The clip-from-world transform of each layer: one, a point light's six cube faces (+X, -X, +Y, -Y,
    // +Z, -Z) or the cascades.
    proj: array<mat4x4<f32>, 6>,
    light: ShadowlabLight,
    // x: the filter (0 none, 1 bilinear, 2 pcf3x3, 3 pcf4x4-jitter, 4 poisson16), y: the kernel's radius
    // in texels, z: the map's side in texels, w: how far a receiver moves towards the light first.
    settings: vec4<f32>,
    // Per layer: world planes to clip planes.
    planes: array<mat4x4<f32>, 6>,
    extra: vec4<f32>,
    // Cascades: x their count (0: the layers are no cascades), y the blend band's share of a cascade,
    // z the first one's near end in view depth.
    cascade: vec4<f32>,
    // The camera's view axis, and minus its dot with the eye: a point's view depth is dot(xyz, p) + w.
    cascade_axis: vec4<f32>,
    // The far end of each cascade in view depth.
    cascade_far: vec4<f32>,
    // Per layer, where its map lies in a shadow atlas: xy its corner in texels, z its side (settings.z);
    // z = 0: the map is the layer itself.
    tiles: array<vec4<f32>, 6>,
};

// 16 points in the unit disk (shadow_core::lookup::POISSON16).
const SHADOWLAB_POISSON16 = array<vec2<f32>, 16>(
    vec2<f32>(0.9306, 0.0506),
    vec2<f32>(-0.9488, 0.0122),
    vec2<f32>(-0.0356, 0.9994),
    vec2<f32>(-0.0246, -0.9163),
    vec2<f32>(0.022, 0.0607),
    vec2<f32>(0.6663, -0.6365),
    vec2<f32>(0.6533, 0.7137),
    vec2<f32>(-0.6883, 0.6873),
    vec2<f32>(-0.6823, -0.6171),
    vec2<f32>(-0.1826, -0.4239),
    vec2<f32>(-0.4766, 0.211),
    vec2<f32>(0.4581, -0.1665),
    vec2<f32>(0.139, 0.5459),
    vec2<f32>(0.5258, 0.2807),
    vec2<f32>(-0.5932, -0.2138),
    vec2<f32>(0.237, -0.5874)
);

// Light `map`'s visibility at world point `p` of the pixel `pixel` (the jittered and Poisson filters
// turn their kernels by a hash of it): 1 lit, 0 shadowed, in between at a filtered edge.
fn shadowlab_map_visibility(
    maps: texture_depth_2d_array,
    cmp: sampler_comparison,
    map: ShadowlabMap,
    p: vec3<f32>,
    pixel: vec2<u32>,
) -> f32 {
    var world = p;
    if (map.settings.w != 0.0) {
        world = world + shadowlab_to_light(map.light, world) * map.settings.w;
    }
    var layer = 0;
    var blend = 0.0;
    if (map.cascade.x > 0.0) {
        let pick = shadowlab_cascade_pick(map, world);
        layer = i32(pick.x);
        blend = pick.y;
    } else if (map.light.kind.x == 2u) {
        layer = shadowlab_cube_face(world - map.light.position.xyz);
    }
    var v = shadowlab_lookup_layer(maps, cmp, map, layer, world, pixel);
    // Cascades fade into the next one over the blend band at their far end.
    if (blend > 0.0) {
        v = v * (1.0 - blend) + shadowlab_lookup_layer(maps, cmp, map, layer + 1, world, pixel) * blend;
    }
    return v;
}

// Twin: shadow_map.wgsl's `compare_bilinear`: the comparison sampler's four taps, in the layer's tile of
// an atlas clamped to the centres of its edge texels.
fn shadowlab_compare_bilinear(
    maps: texture_depth_2d_array,
    cmp: sampler_comparison,
    map: ShadowlabMap,
    layer: i32,
    uv: vec2<f32>,
    depth: f32,
) -> f32 {
    let tile = map.tiles[layer];
    if (tile.z == 0.0) {
        return textureSampleCompareLevel(maps, cmp, uv, layer, depth);
    }
    let n = map.settings.z;
    let at = (clamp(uv * n, vec2<f32>(0.5), vec2<f32>(n - 0.5)) + tile.xy) / f32(textureDimensions(maps).x);
    return textureSampleCompareLevel(maps, cmp, at, 0, depth);
}

// Twin: shadow_map.wgsl's `in_projection` and `shadow_lookup`.
fn shadowlab_lookup_layer(
    maps: texture_depth_2d_array,
    cmp: sampler_comparison,
    map: ShadowlabMap,
    layer: i32,
    world: vec3<f32>,
    pixel: vec2<u32>,
) -> f32 {
    let c = map.proj[layer] * vec4<f32>(world, 1.0);
    let ndc = c.xyz / c.w;
    let uv = vec2<f32>(ndc.x * 0.5 + 0.5, 0.5 - ndc.y * 0.5);
    let depth = ndc.z;
    if (uv.x < 0.0 || uv.x > 1.0 || uv.y < 0.0 || uv.y > 1.0) {
        return 1.0;
    }
    let kind = u32(map.settings.x);
    let radius = map.settings.y;
    let side = map.settings.z;
    let texel = 1.0 / side;
    if (kind == 0u) {
        let n = i32(side);
        let t = clamp(vec2<i32>(floor(uv * side)), vec2<i32>(0), vec2<i32>(n - 1)) + vec2<i32>(map.tiles[layer].xy);
        let stored = textureLoad(maps, t, select(layer, 0, map.tiles[layer].z > 0.0), 0);
        return select(0.0, 1.0, depth <= stored);
    }
    if (kind == 1u) {
        return shadowlab_compare_bilinear(maps, cmp, map, layer, uv, depth);
    }
    var sum = 0.0;
    if (kind == 2u) {
        for (var dy = -1; dy <= 1; dy = dy + 1) {
            for (var dx = -1; dx <= 1; dx = dx + 1) {
                let o = vec2<f32>(f32(dx), f32(dy)) * texel;
                sum = sum + shadowlab_compare_bilinear(maps, cmp, map, layer, uv + o, depth);
            }
        }
        return sum / 9.0;
    }
    if (kind == 3u) {
        var h = shadowlab_pixel_hash(pixel.x, pixel.y);
        for (var j = 0u; j < 4u; j = j + 1u) {
            for (var i = 0u; i < 4u; i = i + 1u) {
                h = shadowlab_pixel_hash(h, j * 4u + i);
                let jx = shadowlab_hash_unit(h);
                let jy = shadowlab_hash_unit((h << 12u) | (h >> 20u));
                let o = (vec2<f32>(f32(i) + jx, f32(j) + jy) * 0.5 - vec2<f32>(1.0)) * radius;
                sum = sum + shadowlab_compare_bilinear(maps, cmp, map, layer, uv + o * texel, depth);
            }
        }
        return sum / 16.0;
    }
    let angle = shadowlab_hash_unit(shadowlab_pixel_hash(pixel.x, pixel.y)) * 6.2831855;
    let s = sin(angle);
    let co = cos(angle);
    for (var k = 0; k < 16; k = k + 1) {
        let q = SHADOWLAB_POISSON16[k];
        let o = vec2<f32>(co * q.x - s * q.y, s * q.x + co * q.y) * radius;
        sum = sum + shadowlab_compare_bilinear(maps, cmp, map, layer, uv + o * texel, depth);
    }
    return sum / 16.0;
}

// Twin: common.wgsl's `to_light`.
fn shadowlab_to_light(light: ShadowlabLight, p: vec3<f32>) -> vec3<f32> {
    if (light.kind.x == 1u) {
        return -light.direction.xyz;
    }
    let d = light.position.xyz - p;
    let len = length(d);
    if (len == 0.0) {
        return vec3<f32>(0.0);
    }
    return d / len;
}

// Twin: shadow_map.wgsl's `cascade_pick`.
fn shadowlab_cascade_pick(map: ShadowlabMap, p: vec3<f32>) -> vec2<f32> {
    let count = i32(map.cascade.x);
    let depth = dot(map.cascade_axis.xyz, p) + map.cascade_axis.w;
    var k = count - 1;
    for (var i = count - 1; i >= 0; i = i - 1) {
        if (depth <= map.cascade_far[i]) {
            k = i;
        }
    }
    var near = map.cascade.z;
    if (k > 0) {
        near = map.cascade_far[k - 1];
    }
    let far = map.cascade_far[k];
    let start = far - map.cascade.y * (far - near);
    var weight = 0.0;
    if (k < count - 1 && depth > start && far > start) {
        weight = min((depth - start) / (far - start), 1.0);
    }
    return vec2<f32>(f32(k), weight);
}

// Twin: shadow_map.wgsl's `cube_face`.
fn shadowlab_cube_face(d: vec3<f32>) -> i32 {
    let a = abs(d);
    if (a.x >= a.y && a.x >= a.z) {
        return select(1, 0, d.x >= 0.0);
    }
    if (a.y >= a.z) {
        return select(3, 2, d.y >= 0.0);
    }
    return select(5, 4, d.z >= 0.0);
}

// Twin: common.wgsl's `pixel_hash`.
fn shadowlab_pixel_hash(x: u32, y: u32) -> u32 {
    var h = (x * 0x8da6b343u) ^ (y * 0xd8163841u);
    h = h ^ (h >> 16u);
    h = h * 0x7feb352du;
    h = h ^ (h >> 15u);
    h = h * 0x846ca68bu;
    return h ^ (h >> 16u);
}

// Twin: common.wgsl's `hash_unit`.
fn shadowlab_hash_unit(h: u32) -> f32 {
    return f32(h >> 8u) * (1.0 / 16777216.0);
}
