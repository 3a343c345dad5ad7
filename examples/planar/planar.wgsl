// The planar shadow's one pass: the casters squashed onto the plane y = plane_y (their clip positions made
// on the host) write visibility 0 over the receivers that lie on that plane.
@group(0) @binding(0) var g_position: texture_2d<f32>;
@group(0) @binding(1) var<uniform> plane_y: vec4<f32>;

@vertex
fn vs(@location(0) p: vec4<f32>) -> @builtin(position) vec4<f32> {
    return p;
}

@fragment
fn fs(@builtin(position) pos: vec4<f32>) -> @location(0) vec4<f32> {
    let g = textureLoad(g_position, vec2<i32>(pos.xy), 0);
    if (g.w == 0.0 || abs(g.y - plane_y.x) >= 1e-3) {
        discard;
    }
    return vec4<f32>(0.0);
}
