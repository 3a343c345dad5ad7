// The moment maps' build (twin: moment_maps/cpu.rs `moment_mips`): the depth map's texels as moments,
// blurred along x, then along y, then averaged 2x2 into each mip level. Follows moments.wgsl.

struct BuildParams {
    // near, far, blur radius in texels, 0.
    depth: vec4<f32>,
};

@group(0) @binding(0) var<uniform> build: BuildParams;
@group(0) @binding(1) var depth_map: texture_depth_2d_array;
@group(0) @binding(2) var source: texture_2d<f32>;

// Twin: moment_maps::cpu::normalized_depth.
fn normalized_depth(ndc: f32) -> f32 {
    let near = build.depth.x;
    let far = build.depth.y;
    let z = near * far / (far - ndc * (far - near));
    return clamp((z - near) / (far - near), 0.0, 1.0);
}

// Each texel's moments, averaged over 2r + 1 texels along x, clamped to the edge.
@fragment
fn fs_moments_x(in: FullScreen) -> @location(0) vec4<f32> {
    let texel = vec2<i32>(in.pos.xy);
    let r = i32(build.depth.z);
    let last = vec2<i32>(textureDimensions(depth_map)) - vec2<i32>(1);
    var sum = vec4<f32>(0.0);
    for (var k = -r; k <= r; k = k + 1) {
        let t = clamp(texel + vec2<i32>(k, 0), vec2<i32>(0), last);
        sum = sum + encode(normalized_depth(textureLoad(depth_map, t, 0, 0)));
    }
    return sum * (1.0 / f32(2 * r + 1));
}

// The same along y, over the x pass.
@fragment
fn fs_blur_y(in: FullScreen) -> @location(0) vec4<f32> {
    let texel = vec2<i32>(in.pos.xy);
    let r = i32(build.depth.z);
    let last = vec2<i32>(textureDimensions(source)) - vec2<i32>(1);
    var sum = vec4<f32>(0.0);
    for (var k = -r; k <= r; k = k + 1) {
        sum = sum + textureLoad(source, clamp(texel + vec2<i32>(0, k), vec2<i32>(0), last), 0);
    }
    return sum * (1.0 / f32(2 * r + 1));
}

// The next mip level: the mean of the 2x2 texels of the level above it, an odd side's last repeated.
@fragment
fn fs_downsample(in: FullScreen) -> @location(0) vec4<f32> {
    let t = 2 * vec2<i32>(in.pos.xy);
    let last = vec2<i32>(textureDimensions(source)) - vec2<i32>(1);
    let a = textureLoad(source, clamp(t, vec2<i32>(0), last), 0);
    let b = textureLoad(source, clamp(t + vec2<i32>(1, 0), vec2<i32>(0), last), 0);
    let c = textureLoad(source, clamp(t + vec2<i32>(0, 1), vec2<i32>(0), last), 0);
    let d = textureLoad(source, clamp(t + vec2<i32>(1, 1), vec2<i32>(0), last), 0);
    return (((a + b) + c) + d) * 0.25;
}
