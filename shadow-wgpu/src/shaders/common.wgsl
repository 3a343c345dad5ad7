// Shared by every shadowlab shader. Each function names its Rust twin in shadow-core; the cross-backend
// tests keep the two honest.

struct View {
    clip_from_world: mat4x4<f32>,
    eye: vec4<f32>,
    // width, height, 1 / width, 1 / height
    size: vec4<f32>,
};

struct Instance {
    world_from_local: mat4x4<f32>,
    // inverse transpose of the upper 3x3, padded
    normal_from_local: mat4x4<f32>,
    // rgb albedo (linear), two-sided flag in w
    color: vec4<f32>,
    // x: receives shadow, y: mirrored, z: its index in the frame (the buffer holds the instances in their
    // draw order, `draw_order.rs`)
    flags: vec4<u32>,
    // How the material reads its base-colour texture, where the instance reads one: the fields of
    // texel.wgsl's `TexelRule`, in its order.
    texel_row_u: vec4<f32>,
    texel_row_v: vec4<f32>,
    texel_sampler: vec4<u32>,
    texel_alpha: vec4<f32>,
};

struct Light {
    // x: kind (0 spot, 1 directional, 2 point); y, z: in shading, the pixels it reaches, its first and
    // one-past-last column (low 16 bits) and row (high 16 bits)
    kind: vec4<u32>,
    position: vec4<f32>,
    // unit direction the light travels (spot axis)
    direction: vec4<f32>,
    // x: cos outer half-angle, y: cos inner half-angle, z: range (0: none)
    cone: vec4<f32>,
    // colour times intensity
    color: vec4<f32>,
};

@group(0) @binding(0) var<uniform> view: View;
@group(0) @binding(1) var<storage, read> instances: array<Instance>;

// The one clip-space transform of mesh vertices, used by every pass that draws mesh triangles, so a
// surface and its shadow-volume near cap rasterize to identical depths (twin: shadow-cpu's
// `clip_vertices`, with clip_from_world * world_from_local).
fn clip_position(instance: u32, p: vec4<f32>) -> vec4<f32> {
    return view.clip_from_world * (instances[instance].world_from_local * p);
}

// Twin: shadow_core::shading::smoothstep (WGSL's built-in has the same definition).
fn cone_falloff(light: Light, p: vec3<f32>) -> f32 {
    if (light.kind.x != 0u) {
        return 1.0;
    }
    let c = dot(normalize(p - light.position.xyz), light.direction.xyz);
    return smoothstep(light.cone.x, light.cone.y, c);
}

// Twin: shadow_core::scene::Light::to_light.
fn to_light(light: Light, p: vec3<f32>) -> vec3<f32> {
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

// Twin: shadow_core::shading::range_window.
fn range_window(light: Light, p: vec3<f32>) -> f32 {
    let x = length(p - light.position.xyz) / light.cone.z;
    return clamp(1.0 - x * x * x * x, 0.0, 1.0);
}

// Twin: shadow_core::shading::direct.
fn direct_light(light: Light, p: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    let term = light.color.xyz * max(dot(n, to_light(light, p)), 0.0) * cone_falloff(light, p);
    if (light.cone.z > 0.0 && light.kind.x != 1u) {
        return term * range_window(light, p);
    }
    return term;
}

// Twin: shadow_core::image::linear_to_srgb8 (before the unorm write rounds to nearest).
fn linear_to_srgb(v: f32) -> f32 {
    let c = clamp(v, 0.0, 1.0);
    if (c <= 0.0031308) {
        return 12.92 * c;
    }
    return 1.055 * pow(c, 1.0 / 2.4) - 0.055;
}

// Twin: shadow_core::lookup::pixel_hash.
fn pixel_hash(x: u32, y: u32) -> u32 {
    var h = (x * 0x8da6b343u) ^ (y * 0xd8163841u);
    h = h ^ (h >> 16u);
    h = h * 0x7feb352du;
    h = h ^ (h >> 15u);
    h = h * 0x846ca68bu;
    return h ^ (h >> 16u);
}

// Twin: shadow_core::lookup::hash_unit.
fn hash_unit(h: u32) -> f32 {
    return f32(h >> 8u) * (1.0 / 16777216.0);
}

// Twin: shadow_core::light::ndc_to_uv.
fn ndc_to_uv(ndc: vec2<f32>) -> vec2<f32> {
    return vec2<f32>(ndc.x * 0.5 + 0.5, 0.5 - ndc.y * 0.5);
}
