// A host's fragment shader that looks into a light's maps through the maps module, for host_wgsl's
// tests: the module goes before this file.

@group(0) @binding(0) var maps: texture_depth_2d_array;
@group(0) @binding(1) var cmp: sampler_comparison;
@group(0) @binding(2) var<uniform> map: ShadowlabMap;
@group(0) @binding(3) var positions: texture_2d<f32>;

@fragment
fn fs_main(@builtin(position) pos: vec4<f32>) -> @location(0) vec4<f32> {
    let pixel = vec2<u32>(pos.xy);
    let p = textureLoad(positions, pixel, 0).xyz;
    return vec4<f32>(shadowlab_map_visibility(maps, cmp, map, p, pixel));
}
