// Shading and composition (twin: shadow-cpu's shade.rs): Lambert, ambient 0.15, cone falloff, sRGB.

@group(1) @binding(0) var g_position: texture_2d<f32>;
@group(1) @binding(1) var g_normal: texture_2d<f32>;
@group(1) @binding(2) var g_albedo: texture_2d<f32>;
@group(1) @binding(3) var visibility: texture_2d_array<f32>;
// The frame's lights, `count.x` of them (MAX_LIGHTS in frame.rs).
struct Lights {
    count: vec4<u32>,
    items: array<Light, 256>,
};

@group(1) @binding(4) var<uniform> lights: Lights;

const AMBIENT: f32 = 0.15;
const BACKGROUND: vec3<f32> = vec3<f32>(0.02, 0.025, 0.04);

// Into a target that stores sRGB-encoded values as they are (a Unorm format).
@fragment
fn fs_shade(in: FullScreen) -> @location(0) vec4<f32> {
    let c = shaded(vec2<i32>(in.pos.xy));
    return vec4<f32>(linear_to_srgb(c.x), linear_to_srgb(c.y), linear_to_srgb(c.z), 1.0);
}

// Into an sRGB format, whose stores encode: linear values.
@fragment
fn fs_shade_linear(in: FullScreen) -> @location(0) vec4<f32> {
    return vec4<f32>(shaded(vec2<i32>(in.pos.xy)), 1.0);
}

// The linear colour at pixel `px`: every light's term times its visibility, over the ambient.
fn shaded(px: vec2<i32>) -> vec3<f32> {
    let albedo = textureLoad(g_albedo, px, 0);
    var c = BACKGROUND;
    if (albedo.w > 0.0) {
        let p = textureLoad(g_position, px, 0).xyz;
        let n = textureLoad(g_normal, px, 0).xyz;
        var direct = vec3<f32>(0.0);
        for (var i = 0u; i < lights.count.x; i = i + 1u) {
            // A light adds nothing outside the pixels it reaches: the same sum without its term.
            let k = lights.items[i].kind;
            let lo = vec2<u32>(k.y & 0xffffu, k.y >> 16u);
            let hi = vec2<u32>(k.z & 0xffffu, k.z >> 16u);
            let at = vec2<u32>(px);
            if (any(at < lo) || any(at >= hi)) {
                continue;
            }
            let v = textureLoad(visibility, px, i32(i), 0).x;
            direct = direct + direct_light(lights.items[i], p, n) * v;
        }
        c = albedo.xyz * (vec3<f32>(AMBIENT) + direct);
    }
    return c;
}

// Counts receiver pixels (covered_pixels) through an occlusion query: only receivers survive.
@fragment
fn fs_receivers(in: FullScreen) -> @location(0) vec4<f32> {
    if (textureLoad(g_position, vec2<i32>(in.pos.xy), 0).w == 0.0) {
        discard;
    }
    return vec4<f32>(0.0);
}
