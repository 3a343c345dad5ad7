// A host's fragment shader that reads every light's visibility through the host module, for host_wgsl's
// tests: the module (or naga_oil's import of it) goes before this file.

@group(0) @binding(0) var visibility: texture_2d_array<f32>;

@fragment
fn fs_main(@builtin(position) pos: vec4<f32>) -> @location(0) vec4<f32> {
    var lit = 0.0;
    for (var i = 0u; i < shadowlab_light_count(visibility); i++) {
        lit += shadowlab_visibility_at(visibility, pos, i);
    }
    return vec4<f32>(vec3<f32>(lit), 1.0);
}
