// hybrid's edge_texels=paired: the cells (squares between four texel centres) that two silhouette edges
// or more enter, with the nearest one's depth (1 elsewhere; hybrid::edge_map::edge_cells,
// side one more than the map's), and the test that reads them (twin: shadow_core::lookup::near_edge_pair).

@group(1) @binding(6) var edge_cells: texture_2d_array<f32>;

// Twin: shadow_core::lookup::EDGE_MARGIN.
const EDGE_MARGIN: f32 = 1e-5;

fn near_edge(layer: i32, uv: vec2<f32>, depth: f32) -> bool {
    if (uv.x < 0.0 || uv.x > 1.0 || uv.y < 0.0 || uv.y > 1.0) {
        return false;
    }
    let n = i32(map.settings.z);
    // Twin: shadow_core::lookup::cell_of.
    let c = clamp(vec2<i32>(floor(uv * map.settings.z + vec2<f32>(0.5))), vec2<i32>(0), vec2<i32>(n));
    let nearest = textureLoad(edge_cells, c, layer, 0).r;
    if (nearest >= depth - EDGE_MARGIN) {
        return false;
    }
    // Hidden when all four texels hold a surface nearer than the nearest edge.
    var hidden = true;
    for (var k = 0; k < 4; k = k + 1) {
        let t = vec2<i32>(clamp(c.x - 1 + k % 2, 0, n - 1), clamp(c.y - 1 + k / 2, 0, n - 1));
        hidden = hidden && textureLoad(shadow_maps, t, layer, 0) < nearest - EDGE_MARGIN;
    }
    return !hidden;
}
