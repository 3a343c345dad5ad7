// caster_masks=on, the fragment passes: the mask pass lists its pixels and leaves every pixel's class in
// `counts`, where the answer reads it outside the mask; a listed pixel the compute passes gave a count
// other than 0 is shadowed.

@group(1) @binding(9) var<storage, read_write> counts: array<i32>;

fn remember_class(px: vec2<i32>, c: u32) {
    counts[u32(px.y) * u32(view.size.x) + u32(px.x)] = i32(c);
}

fn remembered_class(px: vec2<i32>) -> u32 {
    return u32(counts[u32(px.y) * u32(view.size.x) + u32(px.x)]);
}

fn list_pixel(px: vec2<i32>) {
    listed.at[atomicAdd(&listed.pixels, 1u)] = u32(px.y) * u32(view.size.x) + u32(px.x);
}

fn listed_shadowed(px: vec2<i32>) -> bool {
    return counts[u32(px.y) * u32(view.size.x) + u32(px.x)] != 0;
}
