// The engine's G-buffer: depth, world normals and base colour of the scene's meshes, baked into world
// space when they were uploaded.

struct Camera {
    clip_from_world: mat4x4<f32>,
};

@group(0) @binding(0) var<uniform> camera: Camera;

// Material flags of a vertex.
const TWO_SIDED: u32 = 1u;
const CULL_BACK_FACES: u32 = 2u;

struct Varyings {
    @builtin(position) position: vec4<f32>,
    @location(0) normal: vec3<f32>,
    @location(1) base_color: vec3<f32>,
    @location(2) @interpolate(flat) flags: u32,
};

@vertex
fn vs_mesh(
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) base_color: vec3<f32>,
    @location(3) flags: u32,
) -> Varyings {
    var out: Varyings;
    out.position = camera.clip_from_world * vec4<f32>(position, 1.0);
    out.normal = normal;
    out.base_color = base_color;
    out.flags = flags;
    return out;
}

struct Targets {
    @location(0) normal: vec4<f32>,
    @location(1) base_color: vec4<f32>,
};

@fragment
fn fs_mesh(in: Varyings, @builtin(front_facing) front: bool) -> Targets {
    if (!front && (in.flags & CULL_BACK_FACES) != 0u) {
        discard;
    }
    var n = normalize(in.normal);
    // A two-sided surface seen from behind is lit on the side that is seen.
    if (!front && (in.flags & TWO_SIDED) != 0u) {
        n = -n;
    }
    var out: Targets;
    out.normal = vec4<f32>(n, 0.0);
    out.base_color = vec4<f32>(in.base_color, 1.0);
    return out;
}
