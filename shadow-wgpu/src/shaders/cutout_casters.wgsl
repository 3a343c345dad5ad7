// The light passes' stages for casters a texture cuts out (twin: shadow-cpu's alpha-tested light passes):
// the texel over one map texel's footprint (how the coordinates change a texel to the right and down)
// decides whether the caster is there, and the fragment stages discard the fragments of clear texels.
// After common.wgsl and texel.wgsl.

// The caster's base-colour texture (group 2, as in every pass that reads a material's texture).
@group(2) @binding(0) var caster_texture: texture_2d<f32>;

struct CutoutOut {
    @invariant @builtin(position) pos: vec4<f32>,
    @location(0) uv: vec2<f32>,
    // The instance's `TexelRule`, field by field, and its ID (1 + its index in the frame).
    @location(1) @interpolate(flat) row_u: vec4<f32>,
    @location(2) @interpolate(flat) row_v: vec4<f32>,
    @location(3) @interpolate(flat) sampler: vec4<u32>,
    @location(4) @interpolate(flat) alpha: vec4<f32>,
    @location(5) @interpolate(flat) id: u32,
};

@vertex
fn vs_light_cutout(@location(0) p: vec4<f32>, @location(2) uv: vec2<f32>, @builtin(instance_index) instance: u32) -> CutoutOut {
    let inst = instances[instance];
    return CutoutOut(
        clip_position(instance, p), uv, inst.texel_row_u, inst.texel_row_v, inst.texel_sampler, inst.texel_alpha,
        inst.flags.z + 1u,
    );
}

// Whether the caster is there at the fragment: uniform control flow up to the derivatives.
fn caster_there(in: CutoutOut) -> bool {
    let rule = TexelRule(in.row_u, in.row_v, in.sampler, in.alpha);
    return texel_alpha_passes(caster_texture, rule, in.uv, dpdxFine(in.uv), dpdyFine(in.uv));
}
