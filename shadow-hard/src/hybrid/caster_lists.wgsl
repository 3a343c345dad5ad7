// caster_masks: the silhouette pixels the mask pass lists (`y * width + x`), with the counters the
// compute passes add to (the fragments its triangles make at them, its stencil updates, its pixel-triangle
// tests and the pixels whose pairs did not fit, counted alone).

struct Listed {
    pixels: atomic<u32>,
    fragments: atomic<u32>,
    updates: atomic<u32>,
    tests: atomic<u32>,
    alone: atomic<u32>,
    at: array<u32>,
};

@group(1) @binding(8) var<storage, read_write> listed: Listed;
