// edge_texels=off: no receiver is near an edge (and no binding for the edge maps).

fn near_edge(layer: i32, uv: vec2<f32>, depth: f32) -> bool { return false; }
