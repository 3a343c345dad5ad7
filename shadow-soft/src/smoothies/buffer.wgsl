// smoothies: the smoothie buffer passes (twin: shadow-soft's smoothies/cpu.rs `render_buffer`). Standalone:
// it reads no camera state. Pass 1 keeps the nearest smoothie depth in its depth target; pass 2 writes
// the remapped alpha as fragment depth into a second depth target, so the depth test's "less" is the
// thesis's minimum blending, at full float precision.

struct BufferParams {
    // x: near, y: far, z: 1 for an orthographic projection, w: map side in texels
    depth: vec4<f32>,
    // x: smoothie size t (map coordinates), y: 1 to remap alpha (Eq. 4.1)
    smoothie: vec4<f32>,
};

@group(0) @binding(0) var<uniform> params: BufferParams;
@group(0) @binding(1) var blockers: texture_depth_2d_array;

struct SmoothieIn {
    // u, v (map coordinates) and the light's NDC depth
    @location(0) corner: vec3<f32>,
    // 0: an edge (ramp: origin, outward normal), 1: a corner (ramp: vertex, unused)
    @location(1) kind: f32,
    @location(2) ramp: vec4<f32>,
};

struct SmoothieOut {
    @builtin(position) pos: vec4<f32>,
    @location(0) @interpolate(flat) kind: f32,
    @location(1) @interpolate(flat) ramp: vec4<f32>,
};

@vertex
fn vs_smoothie(v: SmoothieIn) -> SmoothieOut {
    var out: SmoothieOut;
    out.pos = vec4<f32>(2.0 * v.corner.x - 1.0, 1.0 - 2.0 * v.corner.y, v.corner.z, 1.0);
    out.kind = v.kind;
    out.ramp = v.ramp;
    return out;
}

// Twin: shadow_core::light::LightProjection::linear_depth.
fn linear_depth(d: f32) -> f32 {
    let near = params.depth.x;
    let far = params.depth.y;
    if (params.depth.z != 0.0) {
        return near + d * (far - near);
    }
    return near * far / (far - d * (far - near));
}

// Twin: shadow-soft's `Ramp::alpha`.
fn ramp_alpha(kind: f32, ramp: vec4<f32>, p: vec2<f32>) -> f32 {
    var a = length(p - ramp.xy);
    if (kind == 0.0) {
        a = dot(p - ramp.xy, ramp.zw);
    }
    return clamp(a / params.smoothie.x, 0.0, 1.0);
}

// The fragment's alpha after Eq. 4.1, or -1 where the smoothie lies behind the blockers' surface (b/r >= 1).
fn smoothie_alpha(in: SmoothieOut) -> f32 {
    let p = in.pos.xy / params.depth.w;
    let a = ramp_alpha(in.kind, in.ramp, p);
    let ratio = linear_depth(in.pos.z) / linear_depth(textureLoad(blockers, vec2<i32>(in.pos.xy), 0, 0));
    if (ratio >= 1.0) {
        return -1.0;
    }
    if (params.smoothie.y != 0.0) {
        return clamp(a / (1.0 - ratio), 0.0, 1.0);
    }
    return a;
}

@fragment
fn fs_smoothie_depth(in: SmoothieOut) {
    if (smoothie_alpha(in) < 0.0) {
        discard;
    }
}

@fragment
fn fs_smoothie_alpha(in: SmoothieOut) -> @builtin(frag_depth) f32 {
    let a = smoothie_alpha(in);
    if (a < 0.0) {
        discard;
    }
    return a;
}
