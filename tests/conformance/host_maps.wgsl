// A host pass that looks into a light's maps itself (the maps module pasted before this file): at every
// pixel its engine drew, the world point from the engine's depth, as shadowlab's import of that depth
// finds it, looked up with `shadowlab_map_visibility`.

struct Camera {
    world_from_clip: mat4x4<f32>,
    // width, height, 1 / width, 1 / height
    size: vec4<f32>,
};

@group(0) @binding(0) var maps: texture_depth_2d_array;
@group(0) @binding(1) var cmp: sampler_comparison;
@group(0) @binding(2) var<uniform> map: ShadowlabMap;
@group(0) @binding(3) var depth: texture_depth_2d;
@group(0) @binding(4) var<uniform> camera: Camera;

@vertex
fn vs_full_screen(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let uv = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4<f32>(uv * 2.0 - 1.0, 0.0, 1.0);
}

@fragment
fn fs_map_visibility(@builtin(position) frag: vec4<f32>) -> @location(0) vec4<f32> {
    let pixel = vec2<u32>(frag.xy);
    let d = textureLoad(depth, pixel, 0);
    if (d >= 1.0) {
        return vec4<f32>(-1.0);
    }
    let ndc = vec2<f32>(frag.x * camera.size.z * 2.0 - 1.0, 1.0 - frag.y * camera.size.w * 2.0);
    let h = camera.world_from_clip * vec4<f32>(ndc, d, 1.0);
    return vec4<f32>(shadowlab_map_visibility(maps, cmp, map, h.xyz / h.w, pixel));
}
