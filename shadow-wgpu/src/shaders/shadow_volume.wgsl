// Stencil shadow volumes: the volume pass (stencil only) and the resolve (twin: shadow-cpu's
// passes::volumes).

@group(1) @binding(0) var g_position: texture_2d<f32>;

struct VolumeOut {
    @invariant @builtin(position) pos: vec4<f32>,
};

// Sides and caps are homogeneous points in the mesh's space (w = 0 at infinity); near caps are the mesh's
// own vertices, transformed exactly as the G-buffer transformed them.
@vertex
fn vs_volume(@location(0) p: vec4<f32>, @builtin(instance_index) instance: u32) -> VolumeOut {
    var out: VolumeOut;
    out.pos = clip_position(instance, p);
    return out;
}

// Drawn with the stencil test "count != 0": shadowed receivers get 0; everything else keeps the cleared 1.
@fragment
fn fs_volume_resolve(in: FullScreen) -> @location(0) vec4<f32> {
    let g = textureLoad(g_position, vec2<i32>(in.pos.xy), 0);
    if (g.w == 0.0) {
        discard;
    }
    return vec4<f32>(0.0);
}
