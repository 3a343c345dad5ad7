// shadow-map: the light pass (depth only) and the query (twin: shadow_core::lookup).

struct MapParams {
    // One projection, or six cube faces (+X, -X, +Y, -Y, +Z, -Z).
    proj: array<mat4x4<f32>, 6>,
    // The light (point lights: cube faces).
    light: Light,
    // x: unused (the filter is the FILTER constant), y: radius in texels, z: map side,
    // w: receiver offset towards the light (bias=world)
    settings: vec4<f32>,
    // Per projection: world planes to clip planes (inverse transpose of proj), for depth_gradient.
    planes: array<mat4x4<f32>, 6>,
    // Technique-specific (silhouette-map: x = 1 for receiver-plane corner depths).
    extra: vec4<f32>,
    // Cascades (twin: shadow_core::light::Cascades): x their count (0: the projections are no cascades),
    // y the blend fraction, z the first one's near end.
    cascade: vec4<f32>,
    // The camera's view axis, and minus its dot with the eye: a point's view depth is dot(xyz, p) + w.
    cascade_axis: vec4<f32>,
    // The far end of each cascade.
    cascade_far: vec4<f32>,
    // Per projection, where its map lies in a shadow atlas: xy its corner in texels, z its side (the map
    // side above); z = 0: the map is a layer of its own (the projection's index).
    tiles: array<vec4<f32>, 6>,
};

// The lookup filter (0 none, 1 bilinear, 2 pcf3x3, 3 pcf4x4-jitter, 4 poisson16), fixed when the query
// pipeline is made so the other filters' code is compiled out (llvmpipe ran the unfiltered query 7x
// slower with the filter a uniform).
override FILTER: u32 = 0u;

@group(1) @binding(0) var g_position: texture_2d<f32>;
@group(1) @binding(1) var shadow_maps: texture_depth_2d_array;
@group(1) @binding(2) var shadow_cmp: sampler_comparison;
@group(1) @binding(3) var<uniform> map: MapParams;

struct DepthOut {
    @invariant @builtin(position) pos: vec4<f32>,
};

@vertex
fn vs_light_depth(@location(0) p: vec4<f32>, @builtin(instance_index) instance: u32) -> DepthOut {
    var out: DepthOut;
    out.pos = clip_position(instance, p);
    return out;
}

// A triangle over the viewport at the far plane (depth 1, the maps' clear value): drawn with the depth
// test off, it clears one tile of an atlas, where a clear of the render pass would clear them all.
@vertex
fn vs_clear_tile(@builtin(vertex_index) i: u32) -> DepthOut {
    var out: DepthOut;
    out.pos = vec4<f32>(f32(i32(i & 1u) * 4 - 1), f32(i32(i >> 1u) * 4 - 1), 1.0, 1.0);
    return out;
}

struct IdOut {
    @invariant @builtin(position) pos: vec4<f32>,
    @location(0) @interpolate(flat) id: u32,
};

// The light pass with McCool's object-ID channel (volume-reconstruction's `ids`): 1 + the instance's index
// in the frame (`flags.z`), 0 (the clear value) where no caster is (twin: shadow-cpu's
// `render_depth_and_id_maps`).
@vertex
fn vs_light_id(@location(0) p: vec4<f32>, @builtin(instance_index) instance: u32) -> IdOut {
    var out: IdOut;
    out.pos = clip_position(instance, p);
    out.id = instances[instance].flags.z + 1u;
    return out;
}

@fragment
fn fs_light_id(in: IdOut) -> @location(0) u32 {
    return in.id;
}

// The light pass of casters a texture cuts out (`cutout_casters.wgsl`): depth, or depth and ID.
@fragment
fn fs_light_cutout(in: CutoutOut) {
    if (!caster_there(in)) {
        discard;
    }
}

@fragment
fn fs_light_id_cutout(in: CutoutOut) -> @location(0) u32 {
    if (!caster_there(in)) {
        discard;
    }
    return in.id;
}

// Twin: shadow_core::light::cube_face.
fn cube_face(d: vec3<f32>) -> i32 {
    let a = abs(d);
    if (a.x >= a.y && a.x >= a.z) {
        return select(1, 0, d.x >= 0.0);
    }
    if (a.y >= a.z) {
        return select(3, 2, d.y >= 0.0);
    }
    return select(5, 4, d.z >= 0.0);
}

// The layer projection `layer`'s map lies in: its own, or the atlas's one layer.
fn map_layer(layer: i32) -> i32 {
    return select(layer, 0, map.tiles[layer].z > 0.0);
}

// Twin: shadow_core::lookup::compare_texel (within the projection's tile of an atlas, as if it were a map
// of its own).
fn compare_texel(layer: i32, x: i32, y: i32, depth: f32) -> f32 {
    let n = i32(map.settings.z);
    let t = vec2<i32>(clamp(x, 0, n - 1), clamp(y, 0, n - 1)) + vec2<i32>(map.tiles[layer].xy);
    let v = textureLoad(shadow_maps, t, map_layer(layer), 0);
    return select(0.0, 1.0, depth <= v);
}

// Twin: shadow_core::lookup::compare_nearest.
fn compare_nearest(layer: i32, uv: vec2<f32>, depth: f32) -> f32 {
    let t = floor(uv * map.settings.z);
    return compare_texel(layer, i32(t.x), i32(t.y), depth);
}

// Twin: shadow_core::lookup::compare_bilinear, done by the comparison sampler. In an atlas's tile, the
// point is clamped to the centres of the tile's edge texels first, which reads what the sampler's clamp to
// the edge reads in a map of its own.
fn compare_bilinear(layer: i32, uv: vec2<f32>, depth: f32) -> f32 {
    let tile = map.tiles[layer];
    if (tile.z == 0.0) {
        return textureSampleCompareLevel(shadow_maps, shadow_cmp, uv, layer, depth);
    }
    let n = map.settings.z;
    let at = (clamp(uv * n, vec2<f32>(0.5), vec2<f32>(n - 0.5)) + tile.xy) / f32(textureDimensions(shadow_maps).x);
    return textureSampleCompareLevel(shadow_maps, shadow_cmp, at, 0, depth);
}

// Twin: shadow_core::lookup::shadow_lookup.
fn shadow_lookup(layer: i32, uv: vec2<f32>, depth: f32, pixel: vec2<u32>) -> f32 {
    if (uv.x < 0.0 || uv.x > 1.0 || uv.y < 0.0 || uv.y > 1.0) {
        return 1.0;
    }
    let kind = FILTER;
    let radius = map.settings.y;
    let texel = 1.0 / map.settings.z;
    if (kind == 0u) {
        return compare_nearest(layer, uv, depth);
    }
    if (kind == 1u) {
        return compare_bilinear(layer, uv, depth);
    }
    var sum = 0.0;
    if (kind == 2u) {
        for (var dy = -1; dy <= 1; dy = dy + 1) {
            for (var dx = -1; dx <= 1; dx = dx + 1) {
                sum = sum + compare_bilinear(layer, uv + vec2<f32>(f32(dx), f32(dy)) * texel, depth);
            }
        }
        return sum / 9.0;
    }
    if (kind == 3u) {
        var h = pixel_hash(pixel.x, pixel.y);
        for (var j = 0u; j < 4u; j = j + 1u) {
            for (var i = 0u; i < 4u; i = i + 1u) {
                h = pixel_hash(h, j * 4u + i);
                let jx = hash_unit(h);
                let jy = hash_unit((h << 12u) | (h >> 20u));
                let o = (vec2<f32>(f32(i) + jx, f32(j) + jy) * 0.5 - vec2<f32>(1.0)) * radius;
                sum = sum + compare_bilinear(layer, uv + o * texel, depth);
            }
        }
        return sum / 16.0;
    }
    let angle = hash_unit(pixel_hash(pixel.x, pixel.y)) * 6.2831855;
    let s = sin(angle);
    let c = cos(angle);
    for (var k = 0; k < 16; k = k + 1) {
        let p = POISSON16[k];
        let o = vec2<f32>(c * p.x - s * p.y, s * p.x + c * p.y) * radius;
        sum = sum + compare_bilinear(layer, uv + o * texel, depth);
    }
    return sum / 16.0;
}

// The direction towards the light of `map` (common.wgsl's `to_light`).
fn map_to_light(p: vec3<f32>) -> vec3<f32> {
    return to_light(map.light, p);
}

// Where a receiver looks into the maps. Twin: shadow-cpu's `MapPosition`.
struct MapPoint {
    layer: i32,
    uv: vec2<f32>,
    depth: f32,
    // The world point looked up (moved towards the light under bias=world).
    world: vec3<f32>,
};

// The cascade a point reads (x) and the next one's weight in the blend band at its far end (y, 0
// outside it). Twin: shadow_core::light::Cascades::pick.
fn cascade_pick(p: vec3<f32>) -> vec2<f32> {
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

// A world point in projection `layer`: its map coordinates and depth.
fn in_projection(layer: i32, p: vec3<f32>) -> MapPoint {
    let c = map.proj[layer] * vec4<f32>(p, 1.0);
    let ndc = c.xyz / c.w;
    return MapPoint(layer, ndc_to_uv(ndc.xy), ndc.z, p);
}

// Twin: shadow-cpu's `map_position` (Light::to_light times the offset, then the projection).
fn map_point(receiver: vec3<f32>) -> MapPoint {
    var p = receiver;
    if (map.settings.w != 0.0) {
        p = p + map_to_light(p) * map.settings.w;
    }
    var layer = 0;
    if (map.cascade.x > 0.0) {
        layer = i32(cascade_pick(p).x);
    } else if (map.light.kind.x == 2u) {
        layer = cube_face(p - map.light.position.xyz);
    }
    return in_projection(layer, p);
}

// Twin: shadow_core::light::LightProjection::depth_gradient.
fn depth_gradient(layer: i32, p: vec3<f32>, n: vec3<f32>) -> vec2<f32> {
    let c = map.planes[layer] * vec4<f32>(n, -dot(n, p));
    if (abs(c.z) <= 1e-6 * (abs(c.x) + abs(c.y))) {
        return vec2<f32>(0.0);
    }
    return vec2<f32>(-2.0 * c.x / c.z, 2.0 * c.y / c.z);
}

@fragment
fn fs_shadow_map_query(in: FullScreen) -> @location(0) vec4<f32> {
    let px = vec2<i32>(in.pos.xy);
    let g = textureLoad(g_position, px, 0);
    if (g.w == 0.0) {
        return vec4<f32>(1.0);
    }
    let m = map_point(g.xyz);
    var v = shadow_lookup(m.layer, m.uv, m.depth, vec2<u32>(px));
    // Cascades fade into the next one over the blend band at their far end (twin: shadow-cpu's
    // `query_maps`).
    if (map.cascade.x > 0.0) {
        let pick = cascade_pick(m.world);
        if (pick.y > 0.0) {
            let next = in_projection(m.layer + 1, m.world);
            v = v * (1.0 - pick.y) + shadow_lookup(next.layer, next.uv, next.depth, vec2<u32>(px)) * pick.y;
        }
    }
    return vec4<f32>(v);
}
