// penumbra-map: the cones and sheets drawn into the penumbra map (twin: shadow-soft's penumbra_map/cpu.rs
// `render_penumbra`). Standalone: it reads no camera state. The value is written as fragment depth into a
// depth target cleared to 1, so the depth test's "less" keeps the smallest, at full float precision.

struct PenumbraParams {
    clip_from_world: mat4x4<f32>,
    // x: near, y: far (the light's projection)
    depth: vec4<f32>,
};

@group(0) @binding(0) var<uniform> params: PenumbraParams;
@group(0) @binding(1) var surfaces: texture_depth_2d_array;

struct ConeIn {
    @location(0) position: vec3<f32>,
    // linear depth of the silhouette vertex the corner hangs from
    @location(1) vertex_depth: f32,
};

struct ConeOut {
    @builtin(position) pos: vec4<f32>,
    @location(0) vertex_depth: f32,
};

@vertex
fn vs_cone(v: ConeIn) -> ConeOut {
    var out: ConeOut;
    out.pos = params.clip_from_world * vec4<f32>(v.position, 1.0);
    out.vertex_depth = v.vertex_depth;
    return out;
}

// Twin: shadow_core::light::LightProjection::linear_depth (perspective).
fn linear_depth(d: f32) -> f32 {
    let near = params.depth.x;
    let far = params.depth.y;
    return near * far / (far - d * (far - near));
}

// Twin: shadow-soft's `penumbra_value`.
@fragment
fn fs_penumbra(in: ConeOut) -> @builtin(frag_depth) f32 {
    let z_p = linear_depth(in.pos.z);
    let z_v = in.vertex_depth;
    let z_f = linear_depth(textureLoad(surfaces, vec2<i32>(in.pos.xy), 0, 0));
    if (!(z_p < z_f && z_v < z_f)) {
        discard;
    }
    return clamp((1.0 - z_v / z_p) / (1.0 - z_v / z_f), 0.0, 1.0);
}
