// The entry points that draw the side quads and the wedges (wedges.wgsl), their depth tests as the pipeline
// says: after the fragment where the device cannot force them first (edge_entries_early.wgsl).

@fragment
fn fs_quad(in: EdgeVertex) {
    quad_fragment(in);
}

@fragment
fn fs_wedge(in: EdgeVertex) {
    wedge_fragment(in);
}
