// The entry points that draw the side quads and the wedges (wedges.wgsl), their depth tests forced before
// the fragment: one that writes storage otherwise runs whatever its test says.

@fragment @early_depth_test(force)
fn fs_quad(in: EdgeVertex) {
    quad_fragment(in);
}

@fragment @early_depth_test(force)
fn fs_wedge(in: EdgeVertex) {
    wedge_fragment(in);
}
