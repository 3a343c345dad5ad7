// The moment maps' query (twin: moment_maps/cpu.rs and `MomentMap::visibility`). Follows shadow_map.wgsl,
// whose bindings 0 to 3 it shares, pcss's search.wgsl (the blocker search, the geometric normals at
// binding 4) and moments.wgsl; map.extra holds x = k (the light's radius in map coordinates at unit
// distance), y = near, z = far, w = the light-bleeding reduction.

@group(1) @binding(5) var moments: texture_2d<f32>;

// The side of the box whose per-axis variance is a disc's of radius 1.
const BOX_PER_DISC_RADIUS: f32 = 1.7320508;

// The mip chain sits in one texture, read at its only level: level 0 at the origin, each level below
// it in a column to its right, top down. (A texel fetch whose mip level differs between neighbouring
// pixels read the wrong level on lavapipe, in blocks along the lines where the level changes.)
fn level_size(level: i32) -> i32 {
    return max(i32(map.settings.z) >> u32(level), 1);
}

fn level_origin(level: i32) -> vec2<i32> {
    if (level == 0) {
        return vec2<i32>(0);
    }
    var y = 0;
    for (var l = 1; l < level; l = l + 1) {
        y = y + level_size(l);
    }
    return vec2<i32>(i32(map.settings.z), y);
}

// Bilinear moments of mip `level` at `uv`, between texel centres, clamped to the level's edge.
fn moment_bilinear(uv: vec2<f32>, level: i32) -> vec4<f32> {
    let size = level_size(level);
    let origin = level_origin(level);
    let p = uv * f32(size) - 0.5;
    let i = floor(p);
    let f = p - i;
    let t = vec2<i32>(i);
    let last = vec2<i32>(size - 1);
    let a = textureLoad(moments, origin + clamp(t, vec2<i32>(0), last), 0);
    let b = textureLoad(moments, origin + clamp(t + vec2<i32>(1, 0), vec2<i32>(0), last), 0);
    let c = textureLoad(moments, origin + clamp(t + vec2<i32>(0, 1), vec2<i32>(0), last), 0);
    let d = textureLoad(moments, origin + clamp(t + vec2<i32>(1, 1), vec2<i32>(0), last), 0);
    let top = a + f.x * (b - a);
    let bottom = c + f.x * (d - c);
    return top + f.y * (bottom - top);
}

// Trilinear moments at `uv` from the mip levels whose texels are nearest `footprint`.
fn moment_trilinear(uv: vec2<f32>, footprint: f32) -> vec4<f32> {
    let top = f32(firstLeadingBit(u32(map.settings.z)));
    let level = min(log2(max(footprint * map.settings.z, 1.0)), top);
    let l0 = floor(level);
    let a = moment_bilinear(uv, i32(l0));
    if (level == l0) {
        return a;
    }
    let b = moment_bilinear(uv, i32(l0) + 1);
    return a + (level - l0) * (b - a);
}

// The moments averaged over a square of side `side` around `uv`: a 4x4 grid of trilinear taps, each
// from the level whose texels are a grid cell wide.
fn moment_average(uv: vec2<f32>, side: f32) -> vec4<f32> {
    let cell = side / 4.0;
    var sum = vec4<f32>(0.0);
    for (var j = 0; j < 4; j = j + 1) {
        for (var i = 0; i < 4; i = i + 1) {
            let offset = (vec2<f32>(f32(i), f32(j)) + 0.5) * cell - 0.5 * side;
            sum = sum + moment_trilinear(uv + offset, cell);
        }
    }
    return sum * (1.0 / 16.0);
}

@fragment
fn fs_moment_query(in: FullScreen) -> @location(0) vec4<f32> {
    let px = vec2<i32>(in.pos.xy);
    let g = textureLoad(g_position, px, 0);
    if (g.w == 0.0) {
        return vec4<f32>(1.0);
    }
    let m = map_point(g.xyz);
    if (m.uv.x < 0.0 || m.uv.x > 1.0 || m.uv.y < 0.0 || m.uv.y > 1.0) {
        return vec4<f32>(1.0);
    }
    let gradient = depth_gradient(m.layer, m.world, textureLoad(g_geometric_normal, px, 0).xyz);
    let z_b = pcss_blockers(m.layer, m.uv, m.depth, gradient, vec2<u32>(px));
    if (z_b < 0.0) {
        return vec4<f32>(1.0);
    }
    let k = map.extra.x;
    let near = map.extra.y;
    let far = map.extra.z;
    let z_r = pcss_linear(m.depth);
    let side = BOX_PER_DISC_RADIUS * k * max(z_r - z_b, 0.0) / (z_b * z_r);
    let t = clamp((z_r - near) / (far - near), 0.0, 1.0);
    return vec4<f32>(linstep(map.extra.w, 1.0, moment_visibility(moment_average(m.uv, side), t)));
}
