// The camera G-buffer: world position (w: receives shadow), shading normal, albedo (w: covered), face
// normal. Instances whose material reads a texture are drawn by the `_textured` entries: the texel's
// colour tints the albedo, and a masked material's clear texels are left out (the surface behind shows).

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

fn gbuffer_vertex(p: vec4<f32>, n: vec4<f32>, instance: u32) -> GOut {
    var out: GOut;
    let inst = instances[instance];
    out.pos = clip_position(instance, p);
    out.world = (inst.world_from_local * p).xyz;
    out.normal = (inst.normal_from_local * vec4<f32>(n.xyz, 0.0)).xyz;
    out.color = inst.color;
    out.flags = inst.flags.xy;
    return out;
}

@vertex
fn vs_gbuffer(@location(0) p: vec4<f32>, @location(1) n: vec4<f32>, @builtin(instance_index) instance: u32) -> GOut {
    return gbuffer_vertex(p, n, instance);
}

struct GTargets {
    @location(0) position: vec4<f32>,
    @location(1) normal: vec4<f32>,
    @location(2) albedo: vec4<f32>,
    @location(3) geometric_normal: vec4<f32>,
};

fn gbuffer_targets(in: GOut, front: bool) -> GTargets {
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

@fragment
fn fs_gbuffer(in: GOut, @builtin(front_facing) front: bool) -> GTargets {
    return gbuffer_targets(in, front);
}

// The material's base-colour texture (`textures.rs`; group 2 in every pass that reads one).
@group(2) @binding(0) var base_color_texture: texture_2d<f32>;

struct GOutTextured {
    @invariant @builtin(position) pos: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) @interpolate(flat) color: vec4<f32>,
    @location(3) @interpolate(flat) flags: vec2<u32>,
    @location(4) uv: vec2<f32>,
    // The instance's `TexelRule`, field by field.
    @location(5) @interpolate(flat) row_u: vec4<f32>,
    @location(6) @interpolate(flat) row_v: vec4<f32>,
    @location(7) @interpolate(flat) sampler: vec4<u32>,
    @location(8) @interpolate(flat) alpha: vec4<f32>,
};

@vertex
fn vs_gbuffer_textured(
    @location(0) p: vec4<f32>,
    @location(1) n: vec4<f32>,
    @location(2) uv: vec2<f32>,
    @builtin(instance_index) instance: u32,
) -> GOutTextured {
    let g = gbuffer_vertex(p, n, instance);
    let inst = instances[instance];
    return GOutTextured(
        g.pos, g.world, g.normal, g.color, g.flags, uv,
        inst.texel_row_u, inst.texel_row_v, inst.texel_sampler, inst.texel_alpha,
    );
}

// Twin: shadow-cpu's G-buffer of a textured surface: the texel over the pixel's footprint (how the
// coordinates change a pixel to the right and down) tints the albedo; where a masked material's alpha
// test fails, the surface is not there.
@fragment
fn fs_gbuffer_textured(in: GOutTextured, @builtin(front_facing) front: bool) -> GTargets {
    let rule = TexelRule(in.row_u, in.row_v, in.sampler, in.alpha);
    let dx = dpdxFine(in.uv);
    let dy = dpdyFine(in.uv);
    var out = gbuffer_targets(GOut(in.pos, in.world, in.normal, in.color, in.flags), front);
    let texel = texel_sample(base_color_texture, rule, in.uv, dx, dy);
    if (rule.alpha.x * texel.w < rule.alpha.y) {
        discard;
    }
    out.albedo = vec4<f32>(in.color.xyz * texel.xyz, 1.0);
    return out;
}
