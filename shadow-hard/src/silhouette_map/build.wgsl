// silhouette-map: pass 2, the silhouette points (twin: points::PointMap::store), and the
// count of non-empty texels. Standalone: it reads no camera state, so it does not take common.wgsl.

// Twin: silhouette_map::points::MapSegment, in texel space.
struct Segment {
    // a.xy, b.xy
    ends: vec4<f32>,
    // x: NDC depth at a, y: at b
    depth: vec4<f32>,
};

struct BuildParams {
    // x: depth-map side N, y: silhouette-map side N - 1, z: corner margin, w: layer (light projection)
    settings: vec4<f32>,
};

@group(0) @binding(0) var<storage, read> segments: array<Segment>;
@group(0) @binding(1) var depth_maps: texture_depth_2d_array;
@group(0) @binding(2) var<uniform> build: BuildParams;

struct QuadOut {
    @builtin(position) pos: vec4<f32>,
    @location(0) @interpolate(flat) segment: u32,
};

struct PointOut {
    @location(0) point: vec2<f32>,
    // The point's own depth: with a less-or-equal depth test a texel keeps the point nearest the light.
    @builtin(frag_depth) depth: f32,
};

// Each segment (instance) is drawn as a rectangle around it, wide enough that every texel whose square,
// enlarged by the margin, the segment touches has its centre inside: conservative rasterization by
// widened quads, as section 3.1 does it. Silhouette texel (i, j) spans [i, i + 1] x [j, j + 1] in texel
// space, so texel space is the target's pixel space.
@vertex
fn vs_segment_quad(@builtin(vertex_index) v: u32, @builtin(instance_index) s: u32) -> QuadOut {
    let seg = segments[s];
    let a = seg.ends.xy;
    let b = seg.ends.zw;
    var dir = vec2<f32>(1.0, 0.0);
    let len = length(b - a);
    if (len > 0.0) {
        dir = (b - a) / len;
    }
    let side = vec2<f32>(-dir.y, dir.x);
    // A texel touched by the segment has its centre within (0.5 + margin) * sqrt(2) of it; a little more.
    let w = (0.5 + build.settings.z) * 1.4142135 + 0.0625;
    let corner = array<u32, 6>(0u, 1u, 2u, 2u, 1u, 3u)[v];
    let end = select(a - dir * w, b + dir * w, corner >= 2u);
    let p = end + side * select(-w, w, (corner & 1u) == 1u);
    let m = build.settings.y;
    var out: QuadOut;
    out.pos = vec4<f32>(p.x / m * 2.0 - 1.0, 1.0 - p.y / m * 2.0, 0.5, 1.0);
    out.segment = s;
    return out;
}

// Twin: silhouette_map::points::choose_point. Returns (point, depth, 1) or w = 0 for none.
fn choose_point(seg: Segment, texel: vec2<f32>, margin: f32) -> vec4<f32> {
    let a = seg.ends.xy - texel;
    let b = seg.ends.zw - texel;
    var t = 0.0;
    if (inside(a, margin)) {
        t = 0.0;
    } else if (inside(b, margin)) {
        t = 1.0;
    } else {
        let t0 = diagonal_crossing(a, b, a.x - a.y, b.x - b.y, margin);
        let t1 = diagonal_crossing(a, b, a.x + a.y - 1.0, b.x + b.y - 1.0, margin);
        if (t0 >= 0.0 && t1 >= 0.0) {
            t = 0.5 * (t0 + t1);
        } else if (t0 >= 0.0) {
            t = t0;
        } else if (t1 >= 0.0) {
            t = t1;
        } else {
            return vec4<f32>(0.0);
        }
    }
    let p = clamp(a + (b - a) * t, vec2<f32>(0.0), vec2<f32>(1.0));
    return vec4<f32>(p, seg.depth.x + (seg.depth.y - seg.depth.x) * t, 1.0);
}

fn inside(p: vec2<f32>, margin: f32) -> bool {
    return p.x >= -margin && p.y >= -margin && p.x <= 1.0 + margin && p.y <= 1.0 + margin;
}

// The parameter where the segment crosses a diagonal (fa, fb: the diagonal's equation at the ends), if
// inside the enlarged texel; -1 for none.
fn diagonal_crossing(a: vec2<f32>, b: vec2<f32>, fa: f32, fb: f32, margin: f32) -> f32 {
    if (fa == fb) {
        return -1.0;
    }
    let t = fa / (fa - fb);
    if (t >= 0.0 && t <= 1.0 && inside(a + (b - a) * t, margin)) {
        return t;
    }
    return -1.0;
}

@fragment
fn fs_silhouette_point(in: QuadOut) -> PointOut {
    let texel = floor(in.pos.xy);
    let hit = choose_point(segments[in.segment], texel, build.settings.z);
    if (hit.w == 0.0) {
        discard;
    }
    // Section 3.1: a point farther from the light than all four corner samples is hidden.
    let ij = vec2<i32>(texel);
    let layer = i32(build.settings.w);
    let far = max(
        max(textureLoad(depth_maps, ij, layer, 0), textureLoad(depth_maps, ij + vec2<i32>(1, 0), layer, 0)),
        max(textureLoad(depth_maps, ij + vec2<i32>(0, 1), layer, 0), textureLoad(depth_maps, ij + vec2<i32>(1, 1), layer, 0)),
    );
    if (hit.z > far) {
        discard;
    }
    var out: PointOut;
    out.point = hit.xy;
    out.depth = hit.z;
    return out;
}

@group(0) @binding(3) var counted_points: texture_2d<f32>;
@group(0) @binding(4) var<storage, read_write> texel_count: atomic<u32>;
var<workgroup> group_count: atomic<u32>;

// The silhouette_texels counter: non-empty texels of one layer, summed per workgroup first.
@compute @workgroup_size(8, 8)
fn cs_count_texels(@builtin(global_invocation_id) id: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    if (li == 0u) {
        atomicStore(&group_count, 0u);
    }
    workgroupBarrier();
    let size = textureDimensions(counted_points);
    if (id.x < size.x && id.y < size.y && textureLoad(counted_points, id.xy, 0).x >= 0.0) {
        atomicAdd(&group_count, 1u);
    }
    workgroupBarrier();
    if (li == 0u) {
        atomicAdd(&texel_count, atomicLoad(&group_count));
    }
}
