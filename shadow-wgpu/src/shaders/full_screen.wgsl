// A triangle covering the screen; uv with (0, 0) at the top-left.
struct FullScreen {
    @builtin(position) pos: vec4<f32>,
};

@vertex
fn vs_full_screen(@builtin(vertex_index) i: u32) -> FullScreen {
    let x = f32(i32(i & 1u) * 4 - 1);
    let y = f32(i32(i >> 1u) * 4 - 1);
    var out: FullScreen;
    out.pos = vec4<f32>(x, y, 0.0, 1.0);
    return out;
}
