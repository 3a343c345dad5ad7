// The camera G-buffer: world position (w: receives shadow), shading normal, albedo (w: covered), face
// normal.

struct GOut {
    @invariant @builtin(position) pos: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
    // The instance's colour (w: two-sided) and flags (x: receives shadow, y: mirrored), passed on flat
    // rather than read from the instance buffer per fragment: lavapipe loads from a storage buffer lane by
    // lane.
    @location(2) @interpolate(flat) color: vec4<f32>,
    @location(3) @interpolate(flat) flags: vec2<u32>,
};

@vertex
fn vs_gbuffer(@location(0) p: vec4<f32>, @location(1) n: vec4<f32>, @builtin(instance_index) instance: u32) -> GOut {
    var out: GOut;
    let inst = instances[instance];
    out.pos = clip_position(instance, p);
    out.world = (inst.world_from_local * p).xyz;
    out.normal = (inst.normal_from_local * vec4<f32>(n.xyz, 0.0)).xyz;
    out.color = inst.color;
    out.flags = inst.flags.xy;
    return out;
}

struct GTargets {
    @location(0) position: vec4<f32>,
    @location(1) normal: vec4<f32>,
    @location(2) albedo: vec4<f32>,
    @location(3) geometric_normal: vec4<f32>,
};

@fragment
fn fs_gbuffer(in: GOut, @builtin(front_facing) front: bool) -> GTargets {
    // The face normal from the position's screen derivatives (in uniform control flow, before any
    // branch): both differences lie in the triangle's plane, helper lanes included. Twin: the CPU
    // G-buffer's `geometric_normal`, turned towards the viewer likewise.
    var face = normalize(cross(dpdx(in.world), dpdy(in.world)));
    if (dot(face, view.eye.xyz - in.world) < 0.0) {
        face = -face;
    }
    var n = normalize(in.normal);
    // Twin: shadow-cpu's G-buffer resolve turns a two-sided surface's normal to the side that is seen. A
    // mirroring transform winds front faces clockwise, so its `front_facing` is reversed.
    let seen_front = front != (in.flags.y != 0u);
    if (!seen_front && in.color.w != 0.0) {
        n = -n;
    }
    var out: GTargets;
    out.position = vec4<f32>(in.world, f32(in.flags.x));
    out.normal = vec4<f32>(n, 0.0);
    out.albedo = vec4<f32>(in.color.xyz, 1.0);
    out.geometric_normal = vec4<f32>(face, 0.0);
    return out;
}
