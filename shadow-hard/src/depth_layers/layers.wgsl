// Depth layers (twin: depth_layers/cpu.rs): the nearest depth, the second-nearest by
// peeling, and their combination written as depth. After `cutout_casters.wgsl`.

struct LayerParams {
    // x: near, y: far, z: 1 for an orthographic view, w: kind (0 midpoint, 1 second depth, 2 dual)
    view: vec4<f32>,
    // x: z_offset (scene units), y: peel epsilon (NDC)
    settings: vec4<f32>,
};

@group(1) @binding(0) var z1_map: texture_depth_2d;
@group(1) @binding(1) var z2_map: texture_depth_2d;
@group(1) @binding(2) var<uniform> layer: LayerParams;

struct DepthOut {
    @invariant @builtin(position) pos: vec4<f32>,
};

@vertex
fn vs_layer(@location(0) p: vec4<f32>, @builtin(instance_index) instance: u32) -> DepthOut {
    var out: DepthOut;
    out.pos = clip_position(instance, p);
    return out;
}

// Whether a fragment at `pos` lies on the first layer (within epsilon), which the second peels away.
fn on_first_layer(pos: vec4<f32>) -> bool {
    let z1 = textureLoad(z1_map, vec2<i32>(pos.xy), 0);
    return pos.z <= z1 + layer.settings.y;
}

// The second layer: fragments at the first layer's depth are peeled away.
@fragment
fn fs_peel(in: DepthOut) {
    if (on_first_layer(in.pos)) {
        discard;
    }
}

// Both layers of casters a texture cuts out (`cutout_casters.wgsl`): the fragments of clear texels
// are discarded too.
@fragment
fn fs_layer_cutout(in: CutoutOut) {
    if (!caster_there(in)) {
        discard;
    }
}

@fragment
fn fs_peel_cutout(in: CutoutOut) {
    if (!caster_there(in) || on_first_layer(in.pos)) {
        discard;
    }
}

// Twin: shadow_core::light::LightProjection::linear_depth.
fn linear_depth(z: f32) -> f32 {
    let n = layer.view.x;
    let f = layer.view.y;
    if (layer.view.z != 0.0) {
        return n + z * (f - n);
    }
    return n * f / (f - z * (f - n));
}

// Twin: shadow_core::light::LightProjection::ndc_depth.
fn ndc_depth(d: f32) -> f32 {
    let n = layer.view.x;
    let f = layer.view.y;
    if (layer.view.z != 0.0) {
        return (d - n) / (f - n);
    }
    return f * (d - n) / (d * (f - n));
}

// Twin: DepthLayers::combine.
fn combine_layers(l1: f32, l2: f32) -> f32 {
    let kind = u32(layer.view.w);
    if (kind == 0u) {
        return 0.5 * (l1 + l2);
    }
    if (kind == 1u) {
        return l2;
    }
    return l1 + min(0.5 * (l2 - l1), layer.settings.x);
}

@fragment
fn fs_combine(in: FullScreen) -> @builtin(frag_depth) f32 {
    let px = vec2<i32>(in.pos.xy);
    let a = textureLoad(z1_map, px, 0);
    let b = textureLoad(z2_map, px, 0);
    if (a >= 1.0) {
        return 1.0;
    }
    return ndc_depth(combine_layers(linear_depth(a), linear_depth(b)));
}
