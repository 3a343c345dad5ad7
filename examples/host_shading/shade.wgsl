// The engine's deferred shading: Lambert over an ambient term, each light's direct light scaled by the
// visibility shadowlab recorded for it (`shadowlab_visibility`, from the module pasted before this file).

struct Light {
    // xyz: position (spot and point lights)
    position: vec4<f32>,
    // xyz: the unit direction the light travels (spot axis, directional light)
    direction: vec4<f32>,
    // rgb: colour times intensity
    color: vec4<f32>,
    // x: cos of the cone's half-angle, y: cos of its inner cone's, z: range (0: none),
    // w: kind (0 spot, 1 directional, 2 point)
    cone: vec4<f32>,
};

struct Shading {
    world_from_clip: mat4x4<f32>,
    // width, height, 1 / width, 1 / height
    size: vec4<f32>,
    // rgb: background; w: ambient
    background: vec4<f32>,
    // x: the number of lights
    count: vec4<u32>,
};

@group(0) @binding(0) var<uniform> shading: Shading;
@group(0) @binding(1) var<storage, read> lights: array<Light>;
@group(0) @binding(2) var depth: texture_depth_2d;
@group(0) @binding(3) var normals: texture_2d<f32>;
@group(0) @binding(4) var base_colors: texture_2d<f32>;
@group(0) @binding(5) var visibility: texture_2d_array<f32>;

@vertex
fn vs_full_screen(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let uv = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4<f32>(uv * 2.0 - 1.0, 0.0, 1.0);
}

fn direct_light(light: Light, p: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    let kind = u32(light.cone.w);
    var to_light = -light.direction.xyz;
    var window = 1.0;
    if (kind != 1u) {
        let d = light.position.xyz - p;
        to_light = normalize(d);
        if (light.cone.z > 0.0) {
            let x = length(d) / light.cone.z;
            window = clamp(1.0 - x * x * x * x, 0.0, 1.0);
        }
    }
    var falloff = 1.0;
    if (kind == 0u) {
        falloff = smoothstep(light.cone.x, light.cone.y, dot(-to_light, light.direction.xyz));
    }
    return light.color.rgb * max(dot(n, to_light), 0.0) * falloff * window;
}

@fragment
fn fs_shade(@builtin(position) frag: vec4<f32>) -> @location(0) vec4<f32> {
    let pixel = vec2<u32>(frag.xy);
    let d = textureLoad(depth, pixel, 0);
    if (d >= 1.0) {
        return vec4<f32>(shading.background.rgb, 1.0);
    }
    let ndc = vec2<f32>(frag.x * shading.size.z * 2.0 - 1.0, 1.0 - frag.y * shading.size.w * 2.0);
    let h = shading.world_from_clip * vec4<f32>(ndc, d, 1.0);
    let p = h.xyz / h.w;
    let n = textureLoad(normals, pixel, 0).xyz;
    var direct = vec3<f32>(0.0);
    for (var i = 0u; i < shading.count.x; i++) {
        direct += direct_light(lights[i], p, n) * shadowlab_visibility(visibility, pixel, i);
    }
    // Linear: the target's sRGB format encodes it.
    return vec4<f32>(textureLoad(base_colors, pixel, 0).rgb * (shading.background.w + direct), 1.0);
}
