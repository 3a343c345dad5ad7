// scissor_tile=0: no marks (and no binding for them).

fn mark_tile(px: vec2<i32>) {}
