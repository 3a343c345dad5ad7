// scissor_tile=N: the mask pass marks the tile of each silhouette pixel (map.extra: x the tile side in
// pixels, y the tiles per row).

@group(1) @binding(7) var<storage, read_write> tile_marks: array<atomic<u32>>;

fn mark_tile(px: vec2<i32>) {
    let t = vec2<u32>(px) / u32(map.extra.x);
    atomicStore(&tile_marks[t.y * u32(map.extra.y) + t.x], 1u);
}
