// Shadow volumes found and extruded on the GPU (twin: shadow-core's geometry::silhouette and
// geometry::volume; the Rust side is passes::extrusion). Per casting instance and light, two compute
// passes find what casts: `cs_faces` weighs every face and lists the caps, `cs_edges` sums the weights
// of each edge's faces and lists the silhouette edges as side records. The lists are appended to with
// atomics, so their order varies; the stencil's wrapping counts do not depend on it. The vertex shaders
// then draw the lists through indirect draws whose counts the appends wrote: sides from the records,
// near caps from the mesh's own vertices (as the G-buffer drew them), far caps from the same vertices
// sent to infinity.

// One instance's extrusion for one light.
struct Extrusion {
    // The light in the instance's mesh space, homogeneous: a position (w = 1), or the direction parallel
    // light travels (w = 0).
    light: vec4<f32>,
    // x: the instance's slot in the instance buffer, y: its mesh's faces, z: its edges, w: 1 when every
    // face casts turned towards the light (Bergeron: an open mesh), 0 when lit faces alone cast (a closed
    // one).
    counts: vec4<u32>,
    // x: 1 when caps are built (z-fail), y: the first word of the instance's draw arguments, z: its first
    // side record, w: its first face weight.
    bases: vec4<u32>,
    // The first index of its near caps cast as wound (x), its near caps cast turned around (y) and its
    // far caps (z).
    caps: vec4<u32>,
};

// Words of an instance's draw arguments: the sides' `draw_indirect` arguments, then the
// `draw_indexed_indirect` ones of near caps as wound, near caps turned around and far caps, then the
// number of silhouette edges (a counter).
const ARG_SIDES: u32 = 0u;
const ARG_NEAR_FORWARD: u32 = 4u;
const ARG_NEAR_REVERSED: u32 = 9u;
const ARG_FAR: u32 = 14u;
const ARG_EDGES: u32 = 19u;

// The draws' bindings (group 1; binding 0 is the resolve's).
@group(1) @binding(1) var<uniform> extrusion: Extrusion;
@group(1) @binding(2) var<storage, read> welded: array<vec4<f32>>;
@group(1) @binding(3) var<storage, read> edges: array<vec4<u32>>;
@group(1) @binding(4) var<storage, read> side_records: array<u32>;

// The compute passes' bindings (group 2).
@group(2) @binding(0) var<uniform> job: Extrusion;
@group(2) @binding(1) var<storage, read> planes: array<vec4<f32>>;
@group(2) @binding(2) var<storage, read> edge_list: array<vec4<u32>>;
@group(2) @binding(3) var<storage, read> face_uses: array<u32>;
@group(2) @binding(4) var<storage, read> mesh_indices: array<u32>;
@group(2) @binding(5) var<storage, read_write> weights: array<i32>;
@group(2) @binding(6) var<storage, read_write> records: array<u32>;
@group(2) @binding(7) var<storage, read_write> cap_indices: array<u32>;
@group(2) @binding(8) var<storage, read_write> args: array<atomic<u32>>;

const WORKGROUP: u32 = 64u;

// The item a compute invocation handles; dispatches wider than the device's most workgroups per
// dimension spill into y.
fn item(id: vec3<u32>, groups: vec3<u32>) -> u32 {
    return id.y * groups.x * WORKGROUP + id.x;
}

// Twin: LightSource::facing, with the products and sums in the same order, so the two agree on which
// faces cast wherever the hardware does not fuse a product into a sum (where it does, they can differ
// only on faces within rounding of holding the light in their plane).
fn facing(plane: vec4<f32>) -> f32 {
    let l = job.light;
    let d = plane.x * l.x + plane.y * l.y + plane.z * l.z;
    if (l.w == 0.0) {
        return -d;
    }
    return d + plane.w;
}

// Twin: silhouette::face_weights. A face whose plane holds the light casts nothing.
fn face_weight(plane: vec4<f32>) -> i32 {
    let f = facing(plane);
    if (f > 0.0) {
        return 1;
    }
    if (f < 0.0 && job.counts.w == 1u) {
        return -1;
    }
    return 0;
}

// Appends one triangle's indices to the cap list whose count is argument word `count`.
fn append_cap(count: u32, first: u32, t: vec3<u32>) {
    let at = first + atomicAdd(&args[job.bases.y + count], 3u);
    cap_indices[at] = t.x;
    cap_indices[at + 1u] = t.y;
    cap_indices[at + 2u] = t.z;
}

// Weighs each face and, for z-fail, lists its caps (twin: volume::extrude's caps and
// ShadowVolume::far_caps): a face cast as wound is a near cap as wound and a far cap turned around; a face
// cast turned around is a near cap drawn with its fronts swapped and a far cap as wound.
@compute @workgroup_size(64)
fn cs_faces(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let f = item(id, groups);
    if (f >= job.counts.y) {
        return;
    }
    let w = face_weight(planes[f]);
    weights[job.bases.w + f] = w;
    if (job.bases.x == 0u || w == 0) {
        return;
    }
    let t = vec3<u32>(mesh_indices[3u * f], mesh_indices[3u * f + 1u], mesh_indices[3u * f + 2u]);
    if (w > 0) {
        append_cap(ARG_NEAR_FORWARD, job.caps.x, t);
        append_cap(ARG_FAR, job.caps.z, t.xzy);
    } else {
        append_cap(ARG_NEAR_REVERSED, job.caps.y, t);
        append_cap(ARG_FAR, job.caps.z, t);
    }
}

// Sums each edge's face weights, each times the face's direction along the edge (twin:
// silhouette::silhouette); a silhouette edge of weight k is listed k times, its sign in the top bit (set:
// the edge runs from its second vertex to its first).
@compute @workgroup_size(64)
fn cs_edges(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let e = item(id, groups);
    if (e >= job.counts.z) {
        return;
    }
    let edge = edge_list[e];
    var w = 0;
    for (var k = 0u; k < edge.w; k++) {
        let u = face_uses[edge.z + k];
        let fw = weights[job.bases.w + (u >> 1u)];
        w += select(fw, -fw, (u & 1u) == 1u);
    }
    if (w == 0) {
        return;
    }
    atomicAdd(&args[job.bases.y + ARG_EDGES], 1u);
    let n = u32(abs(w));
    let per = side_vertices();
    let first = job.bases.z + atomicAdd(&args[job.bases.y + ARG_SIDES], n * per) / per;
    let record = e | select(0u, 0x80000000u, w < 0);
    for (var k = 0u; k < n; k++) {
        records[first + k] = record;
    }
}

// Vertices per side record: a quad, or one triangle under parallel light (both far corners are the
// light's direction; vs_side reads the same from its own binding).
fn side_vertices() -> u32 {
    return select(6u, 3u, job.light.w == 0.0);
}

// Twin: LightSource::extrude.
fn to_infinity(p: vec3<f32>) -> vec4<f32> {
    let l = extrusion.light;
    if (l.w == 0.0) {
        return vec4<f32>(l.xyz, 0.0);
    }
    return vec4<f32>(p - l.xyz, 0.0);
}

// A side: record v / 6 (v / 3 under parallel light) as the outward quad (b, a, a_inf, b_inf), the
// triangles (b, a, a_inf) and (b, a_inf, b_inf), in the corners' order volume::extrude gives them.
@vertex
fn vs_side(@builtin(vertex_index) v: u32) -> VolumeOut {
    let per = select(6u, 3u, extrusion.light.w == 0.0);
    let record = side_records[extrusion.bases.z + v / per];
    let edge = edges[record & 0x7fffffffu];
    var a = edge.x;
    var b = edge.y;
    if ((record >> 31u) == 1u) {
        a = edge.y;
        b = edge.x;
    }
    var p: vec4<f32>;
    switch (v % per) {
        case 0u, 3u: {
            p = welded[b];
        }
        case 1u: {
            p = welded[a];
        }
        case 2u, 4u: {
            p = to_infinity(welded[a].xyz);
        }
        default: {
            p = to_infinity(welded[b].xyz);
        }
    }
    var out: VolumeOut;
    out.pos = clip_position(extrusion.counts.x, p);
    return out;
}

// A near cap: the mesh's own vertex, transformed as the G-buffer transformed it.
@vertex
fn vs_near(@location(0) p: vec4<f32>) -> VolumeOut {
    var out: VolumeOut;
    out.pos = clip_position(extrusion.counts.x, p);
    return out;
}

// A far cap: the mesh's vertex sent to infinity away from the light.
@vertex
fn vs_far(@location(0) p: vec4<f32>) -> VolumeOut {
    var out: VolumeOut;
    out.pos = clip_position(extrusion.counts.x, to_infinity(p.xyz));
    return out;
}
