// The G-buffer from an engine's own depth and world normals, in place of gbuffer.wgsl's pass: the same
// targets, the position found from the depth through the camera, the engine's normal as both the shading
// normal and the face normal (turned towards the eye), a white albedo, and every covered pixel a receiver.

@group(1) @binding(0) var host_depth: texture_depth_2d;
@group(1) @binding(1) var host_normals: texture_2d<f32>;
@group(1) @binding(2) var<uniform> world_from_clip: mat4x4<f32>;

struct Imported {
    @location(0) position: vec4<f32>,
    @location(1) normal: vec4<f32>,
    @location(2) albedo: vec4<f32>,
    @location(3) geometric_normal: vec4<f32>,
    @builtin(frag_depth) depth: f32,
};

@fragment
fn fs_import(in: FullScreen) -> Imported {
    let pixel = vec2<i32>(in.pos.xy);
    let d = textureLoad(host_depth, pixel, 0);
    // Nothing was drawn here: the targets keep their cleared "not covered".
    if (d >= 1.0) {
        discard;
    }
    // The pixel centre in normalized device coordinates (y up), at the engine's depth.
    let ndc = vec2<f32>(in.pos.x * view.size.z * 2.0 - 1.0, 1.0 - in.pos.y * view.size.w * 2.0);
    let h = world_from_clip * vec4<f32>(ndc, d, 1.0);
    let world = h.xyz / h.w;
    let n = normalize(textureLoad(host_normals, pixel, 0).xyz);
    var face = n;
    if (dot(face, view.eye.xyz - world) < 0.0) {
        face = -face;
    }
    var out: Imported;
    out.position = vec4<f32>(world, 1.0);
    out.normal = vec4<f32>(n, 0.0);
    out.albedo = vec4<f32>(1.0);
    out.geometric_normal = vec4<f32>(face, 0.0);
    out.depth = d;
    return out;
}
