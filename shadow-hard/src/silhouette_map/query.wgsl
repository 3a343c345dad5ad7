// silhouette-map: the query (twin: silhouette_map::points). Appended to shadow_map.wgsl, whose
// bindings, parameters and map_point it shares.

@group(1) @binding(4) var silhouette_points: texture_2d_array<f32>;
@group(1) @binding(5) var g_geometric_normal: texture_2d<f32>;
// Pixels whose corner tests disagreed (the silhouette_pixels counter).
@group(1) @binding(6) var<storage, read_write> silhouette_pixels: atomic<u32>;
// Nearest, clamp to edge: textureGather's four texels are a silhouette texel's four corners.
@group(1) @binding(7) var corner_sampler: sampler;

// Twin: silhouette_map::points::CORNERS (cyclic: (0, 0), (1, 0), (1, 1), (0, 1)).
const CORNERS = array<vec2<f32>, 4>(vec2<f32>(0.0, 0.0), vec2<f32>(1.0, 0.0), vec2<f32>(1.0, 1.0), vec2<f32>(0.0, 1.0));
// Twin: silhouette_map::points::NEIGHBOURS, each between two consecutive corners.
const NEIGHBOURS = array<vec2<i32>, 4>(vec2<i32>(0, -1), vec2<i32>(1, 0), vec2<i32>(0, 1), vec2<i32>(-1, 0));

fn cross2(a: vec2<f32>, b: vec2<f32>) -> f32 {
    return a.x * b.y - a.y * b.x;
}

// Twin: silhouette_map::points::nearest_corner.
fn nearest_corner(f: vec2<f32>) -> i32 {
    if (f.y > 0.5) {
        return select(3, 2, f.x > 0.5);
    }
    return select(0, 1, f.x > 0.5);
}

// Twin: silhouette_map::points::quadrant (the eight pie regions of Fig. 5).
fn quadrant(o: vec2<f32>, n: array<vec2<f32>, 4>, f: vec2<f32>) -> i32 {
    let d = f - o;
    for (var k = 0; k < 4; k = k + 1) {
        let c0 = CORNERS[k] - o;
        let c1 = CORNERS[(k + 1) % 4] - o;
        if (cross2(c0, d) >= 0.0 && cross2(d, c1) > 0.0) {
            return select((k + 1) % 4, k, cross2(n[k] - o, d) <= 0.0);
        }
    }
    return nearest_corner(f);
}

// Twin: point_or_centre.
fn point_or_centre(layer: i32, x: i32, y: i32) -> vec2<f32> {
    let side = i32(textureDimensions(silhouette_points).x);
    if (x < 0 || y < 0 || x >= side || y >= side) {
        return vec2<f32>(0.5);
    }
    let p = textureLoad(silhouette_points, vec2<i32>(x, y), layer, 0).xy;
    return select(p, vec2<f32>(0.5), p.x < 0.0);
}

// Twin: silhouette_map::points::silhouette_lookup. Returns (visibility, 1 if the map decided).
fn silhouette_lookup(layer: i32, uv: vec2<f32>, depth: f32, gradient: vec2<f32>) -> vec2<f32> {
    if (uv.x < 0.0 || uv.x > 1.0 || uv.y < 0.0 || uv.y > 1.0) {
        return vec2<f32>(1.0, 0.0);
    }
    let n = map.settings.z;
    let s = uv * n - vec2<f32>(0.5);
    let side = f32(textureDimensions(silhouette_points).x);
    if (!(s.x >= 0.0 && s.y >= 0.0 && s.x < side && s.y < side)) {
        return vec2<f32>(compare_nearest(layer, uv, depth), 0.0);
    }
    let t = floor(s);
    let f = s - t;
    let ij = vec2<i32>(t);
    // One gather fetches the four corners, sampled at the point between their centres. Its components
    // are (i, j + 1), (i + 1, j + 1), (i + 1, j), (i, j) (the WGSL order): .wzyx is CORNERS order.
    let stored = textureGather(shadow_maps, corner_sampler, (t + vec2<f32>(1.0)) / n, layer).wzyx;
    // The receiver plane's depth at the four corners, in CORNERS order, as one vector.
    let cx = vec4<f32>(0.0, 1.0, 1.0, 0.0);
    let cy = vec4<f32>(0.0, 0.0, 1.0, 1.0);
    let lit = vec4<f32>(depth) + (gradient.x * (cx - f.x) + gradient.y * (cy - f.y)) / n <= stored;
    if (all(lit) || !any(lit)) {
        return vec2<f32>(select(0.0, 1.0, lit.x), 0.0);
    }
    let o = point_or_centre(layer, ij.x, ij.y);
    var nb: array<vec2<f32>, 4>;
    for (var k = 0; k < 4; k = k + 1) {
        let d = NEIGHBOURS[k];
        nb[k] = point_or_centre(layer, ij.x + d.x, ij.y + d.y) + vec2<f32>(d);
    }
    let q = quadrant(o, nb, f);
    return vec2<f32>(select(0.0, 1.0, lit[q]), 1.0);
}

@fragment
fn fs_silhouette_query(in: FullScreen) -> @location(0) vec4<f32> {
    let px = vec2<i32>(in.pos.xy);
    let g = textureLoad(g_position, px, 0);
    if (g.w == 0.0) {
        return vec4<f32>(1.0);
    }
    let m = map_point(g.xyz);
    var gradient = vec2<f32>(0.0);
    if (map.extra.x != 0.0) {
        gradient = depth_gradient(m.layer, m.world, textureLoad(g_geometric_normal, px, 0).xyz);
    }
    let r = silhouette_lookup(m.layer, m.uv, m.depth, gradient);
    if (r.y != 0.0) {
        atomicAdd(&silhouette_pixels, 1u);
    }
    return vec4<f32>(r.x);
}
