// Shadow volume reconstruction (twin: volume_reconstruction/cpu.rs): the boundary
// rebuilt from the light's depth maps and the near-plane caps, homogeneous world points. Appended to
// shadow_volume.wgsl, whose resolve it shares.

@vertex
fn vs_boundary(@location(0) p: vec4<f32>) -> VolumeOut {
    var out: VolumeOut;
    out.pos = view.clip_from_world * p;
    return out;
}

// Caps lie on the eye's near plane, which would clip them; they are drawn at mid depth with the depth test
// off, every visible surface being behind them anyway (twin: `cap_clip`).
@vertex
fn vs_cap(@location(0) p: vec4<f32>) -> VolumeOut {
    var out: VolumeOut;
    let c = view.clip_from_world * p;
    out.pos = vec4<f32>(c.xy, 0.5 * c.w, c.w);
    return out;
}
