struct Case {
    uv: vec2<f32>,
    dx: vec2<f32>,
    dy: vec2<f32>,
    pad: vec2<f32>,
    rule: TexelRule,
};

// x: first level, y: second level, z: magnified, w: passes the alpha test; the first level's taps
// (lo.x, lo.y, hi.x, hi.y); x: the second level's weight, y: the filtered alpha.
struct Pick {
    levels: vec4<u32>,
    taps: vec4<i32>,
    values: vec4<f32>,
};

@group(0) @binding(0) var tex: texture_2d<f32>;
@group(0) @binding(1) var<storage, read> cases: array<Case>;
@group(0) @binding(2) var<storage, read_write> picks: array<Pick>;

@compute @workgroup_size(64)
fn cs_texel(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if (i >= arrayLength(&cases)) {
        return;
    }
    let c = cases[i];
    let at = texel_transform_point(c.rule, c.uv);
    let dx = texel_transform_vector(c.rule, c.dx);
    let dy = texel_transform_vector(c.rule, c.dy);
    let levels = texel_levels_of(tex, c.rule, dx, dy);
    let kind = select(c.rule.sampler.y, c.rule.sampler.x, levels.magnified);
    let taps = texel_taps(c.rule, texel_level_size(tex, levels.first), at, kind);
    let alpha = texel_sample(tex, c.rule, c.uv, c.dx, c.dy).w;
    let passes = texel_alpha_passes(tex, c.rule, c.uv, c.dx, c.dy);
    picks[i] = Pick(
        vec4<u32>(levels.first, levels.second, u32(levels.magnified), u32(passes)),
        vec4<i32>(taps.lo, taps.hi),
        vec4<f32>(levels.blend, alpha, 0.0, 0.0),
    );
}
