// shadowlab's lights' visibility, read in a host's own shader. The texture is `FrameRecorder::visibility`
// after `record` or `record_visibility`: an R32Float array with one layer per light of the frame, in the
// frame's order, of the recorded view's size; 1 where the light reaches the pixel's surface, 0 where it is
// shadowed, in between in a soft shadow's penumbra. Bind it as `texture_2d_array<f32>` (it is not
// filterable: read it with textureLoad, as here).
//
// Plain WGSL with no bindings of its own: paste it before the host's shader, or compose it with naga_oil
// under the name `shadowlab::visibility` (`shadow_wgpu::host_wgsl::VISIBILITY_IMPORT_PATH`) and import
// what you use (`#import shadowlab::visibility::shadowlab_visibility_at`).

// Light `light`'s visibility at pixel `pixel` of the recorded view (x right, y down from its top-left).
fn shadowlab_visibility(visibility: texture_2d_array<f32>, pixel: vec2<u32>, light: u32) -> f32 {
    return textureLoad(visibility, pixel, light, 0).x;
}

// Light `light`'s visibility at the fragment whose `@builtin(position)` is `frag_position`, for a pass
// drawn at the recorded view's size (a forward pass or a full-screen shading pass).
fn shadowlab_visibility_at(visibility: texture_2d_array<f32>, frag_position: vec4<f32>, light: u32) -> f32 {
    return shadowlab_visibility(visibility, vec2<u32>(frag_position.xy), light);
}

// The number of layers the visibility holds: the frame's lights (a frame without lights still has one).
fn shadowlab_light_count(visibility: texture_2d_array<f32>) -> u32 {
    return textureNumLayers(visibility);
}
