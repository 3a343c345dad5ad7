// hybrid's edge_texels=on: the map of the nearest silhouette edge's depth per texel (drawn by vs_edge, the
// quads shadow_core::geometry::silhouette::edge_texel_quads makes) and the test that reads it (twin:
// shadow_core::lookup::near_edge). With edge_texels=off, query.wgsl gets edges_off.wgsl instead.

@group(1) @binding(6) var edge_maps: texture_depth_2d_array;

// Twin: shadow_core::lookup::EDGE_MARGIN.
const EDGE_MARGIN: f32 = 1e-5;

fn near_edge(layer: i32, uv: vec2<f32>, depth: f32) -> bool {
    if (uv.x < 0.0 || uv.x > 1.0 || uv.y < 0.0 || uv.y > 1.0) {
        return false;
    }
    let n = i32(map.settings.z) - 1;
    let st = uv * map.settings.z - vec2<f32>(0.5);
    let x = i32(floor(st.x));
    let y = i32(floor(st.y));
    var near = false;
    for (var k = 0; k < 4; k = k + 1) {
        let t = vec2<i32>(clamp(x + k % 2, 0, n), clamp(y + k / 2, 0, n));
        near = near || textureLoad(edge_maps, t, layer, 0) < depth - EDGE_MARGIN;
    }
    return near;
}
