// penumbra-wedges on the GPU (twin: cpu.rs): the side quads and the wedges drawn over the G-buffer, each
// fragment adding its edge's term to the receiver's occluded share in fixed point (there is no float
// atomic or float blending everywhere, and integer sums come out the same in any order), then the
// resolve.

struct WedgeParams {
    // centre, radius
    light: vec4<f32>,
    eye: vec4<f32>,
    // the light centre's count at the eye in each layer (closed, facing, turned)
    eye_counts: vec4<f32>,
    // width, height
    size: vec4<u32>,
};

// The buffer's units per unit of occluded share.
const SCALE: f32 = 1048576.0;

@group(1) @binding(0) var g_position: texture_2d<f32>;
@group(1) @binding(1) var<storage, read_write> occluded: array<atomic<i32>>;
@group(1) @binding(2) var<uniform> params: WedgeParams;
@group(1) @binding(3) var g_geometric_normal: texture_2d<f32>;
@group(1) @binding(4) var<storage, read> edges: array<Edge>;
// With casters cut out by their texture: the visibility their map leaves each pixel (fs_resolve_cutouts).
@group(1) @binding(5) var cutout_visibility: texture_2d<f32>;

struct Edge {
    // a, weight
    a: vec4<f32>,
    // b, layer
    b: vec4<f32>,
    // the wedge's planes, inner sides positive
    planes: array<vec4<f32>, 4>,
};

struct EdgeVertex {
    @builtin(position) pos: vec4<f32>,
    @location(0) @interpolate(flat) edge: u32,
};

@vertex
fn vs_edge(@location(0) p: vec4<f32>, @location(1) edge: u32) -> EdgeVertex {
    var out: EdgeVertex;
    out.pos = view.clip_from_world * p;
    out.edge = edge;
    return out;
}

// The receiver under a fragment, or w = 0 where there is none.
fn receiver(pos: vec4<f32>) -> vec4<f32> {
    return textureLoad(g_position, vec2<i32>(pos.xy), 0);
}

// Pixel `pos`'s sum in `layer`: the layers one view after another.
fn sum_index(pos: vec4<f32>, layer: u32) -> u32 {
    return (layer * params.size.y + u32(pos.y)) * params.size.x + u32(pos.x);
}

fn add(pos: vec4<f32>, e: Edge, term: f32) {
    atomicAdd(&occluded[sum_index(pos, u32(e.b.w))], i32(round(e.a.w * term * SCALE)));
}

fn sum(pos: vec4<f32>, layer: u32) -> f32 {
    return params.eye_counts[layer] + f32(atomicLoad(&occluded[sum_index(pos, layer)])) / SCALE;
}

// The side quads' fragments (entry point `fs_quad`, in edge_entries.wgsl).
fn quad_fragment(in: EdgeVertex) {
    let g = receiver(in.pos);
    if (g.w != 0.0) {
        let e = edges[in.edge];
        add(in.pos, e, count_step(g.xyz, params.eye.xyz, e.a.xyz, e.b.xyz, params.light.xyz));
    }
}

// The wedges' fragments (entry point `fs_wedge`).
fn wedge_fragment(in: EdgeVertex) {
    let g = receiver(in.pos);
    if (g.w != 0.0) {
        let e = edges[in.edge];
        add(in.pos, e, wedge_term(g.xyz, e.a.xyz, e.b.xyz, e.planes, params.light.xyz, params.light.w));
    }
}

// The soft visibility of the receiver `g` at `pos`.
fn soft_visibility(pos: vec4<f32>, g: vec4<f32>) -> f32 {
    let n = textureLoad(g_geometric_normal, vec2<i32>(pos.xy), 0).xyz;
    let horizon = horizon_share(g.xyz, n, params.light.xyz, params.light.w);
    let share = sum(pos, 0u) + max(sum(pos, 1u), sum(pos, 2u)) + horizon;
    return clamp(1.0 - share, 0.0, 1.0);
}

@fragment
fn fs_resolve(in: FullScreen) -> @location(0) vec4<f32> {
    let g = receiver(in.pos);
    if (g.w == 0.0) {
        discard;
    }
    return vec4<f32>(soft_visibility(in.pos, g), 0.0, 0.0, 0.0);
}

// The soft visibility times the cut-out casters' map's.
@fragment
fn fs_resolve_cutouts(in: FullScreen) -> @location(0) vec4<f32> {
    let g = receiver(in.pos);
    if (g.w == 0.0) {
        discard;
    }
    let cutouts = textureLoad(cutout_visibility, vec2<i32>(in.pos.xy), 0).x;
    return vec4<f32>(soft_visibility(in.pos, g) * cutouts, 0.0, 0.0, 0.0);
}
