// Shadow volumes found and extruded on the GPU (twin: shadow-core's geometry::silhouette and
// geometry::volume; the Rust side is passes::extrusion). The casting instances of one mesh that wind alike
// are a run, and per run and light two compute passes find what casts, an invocation a face or an edge of
// one of the run's instances: `cs_faces` weighs every face and lists the caps, `cs_edges` sums the
// weights of each edge's faces and lists the silhouette edges. Each list holds records (the instance
// within the run, then the face or edge) appended with atomics, so their order varies; the stencil's
// wrapping counts do not depend on it. The vertex shaders then draw a run's lists through indirect draws
// whose counts the appends wrote, a draw a list: sides from the edges' welded corners, near caps from the
// mesh's own vertices (as the G-buffer drew them), far caps from the same vertices sent to infinity.

// One run: its instances' mesh and where its lists are.
struct Run {
    // x: its first job, y: its jobs (instances), z: its mesh's faces, w: its edges.
    counts: vec4<u32>,
    // x: 1 when every face casts turned towards the light (Bergeron: an open mesh), 0 when lit faces
    // alone cast (a closed one); y: the first word of its draw arguments, z: its first side record, w: its
    // first face weight.
    bases: vec4<u32>,
    // The first record of its near caps cast as wound (x), its near caps cast turned around (y) and its
    // far caps (z).
    caps: vec4<u32>,
    unused: vec4<u32>,
};

// One casting instance for one light.
struct Job {
    // The light in the instance's mesh space, homogeneous: a position (w = 1), or the direction parallel
    // light travels (w = 0).
    light: vec4<f32>,
    // x: the instance's slot in the instance buffer, y: 1 when caps are built (z-fail).
    info: vec4<u32>,
};

// Words of a run's draw arguments: the `draw_indirect` arguments of its sides, its near caps as wound,
// its near caps turned around and its far caps, then the number of silhouette edges (a counter). The caps'
// first vertex is three times their list's first record.
const ARG_SIDES: u32 = 0u;
const ARG_NEAR_FORWARD: u32 = 4u;
const ARG_NEAR_REVERSED: u32 = 8u;
const ARG_FAR: u32 = 12u;
const ARG_EDGES: u32 = 16u;

// The top bit of a record's second word: a side's edge runs from its second vertex to its first; a far
// cap's face is drawn turned around.
const TURNED: u32 = 0x80000000u;

// The draws' bindings (group 1; binding 0 is the resolve's).
@group(1) @binding(1) var<uniform> run: Run;
@group(1) @binding(2) var<storage, read> jobs: array<Job>;
@group(1) @binding(3) var<storage, read> welded: array<vec4<f32>>;
@group(1) @binding(4) var<storage, read> edges: array<vec4<u32>>;
@group(1) @binding(5) var<storage, read> list: array<vec2<u32>>;
@group(1) @binding(6) var<storage, read> positions: array<vec4<f32>>;
@group(1) @binding(7) var<storage, read> indices: array<u32>;

// The compute passes' bindings (group 2).
@group(2) @binding(0) var<uniform> batch: Run;
@group(2) @binding(1) var<storage, read> lights: array<Job>;
@group(2) @binding(2) var<storage, read> planes: array<vec4<f32>>;
@group(2) @binding(3) var<storage, read> edge_list: array<vec4<u32>>;
@group(2) @binding(4) var<storage, read> face_uses: array<u32>;
@group(2) @binding(5) var<storage, read> mesh_indices: array<u32>;
@group(2) @binding(6) var<storage, read_write> weights: array<i32>;
@group(2) @binding(7) var<storage, read_write> records: array<vec2<u32>>;
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
fn facing(l: vec4<f32>, plane: vec4<f32>) -> f32 {
    let d = plane.x * l.x + plane.y * l.y + plane.z * l.z;
    if (l.w == 0.0) {
        return -d;
    }
    return d + plane.w;
}

// Twin: silhouette::face_weights. A face whose plane holds the light casts nothing.
fn face_weight(l: vec4<f32>, plane: vec4<f32>) -> i32 {
    let f = facing(l, plane);
    if (f > 0.0) {
        return 1;
    }
    if (f < 0.0 && batch.bases.x == 1u) {
        return -1;
    }
    return 0;
}

// Appends a cap record to the list whose draw arguments start at word `word` (their count in vertices)
// and whose records start at `first`.
fn append_cap(word: u32, first: u32, record: vec2<u32>) {
    records[first + atomicAdd(&args[batch.bases.y + word], 3u) / 3u] = record;
}

// Weighs each face of each of the run's instances and, for z-fail, lists its caps (twin: volume::extrude's
// caps and ShadowVolume::far_caps): a face cast as wound is a near cap as wound and a far cap turned
// around; a face cast turned around is a near cap drawn with its fronts swapped and a far cap as wound.
@compute @workgroup_size(64)
fn cs_faces(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = item(id, groups);
    let faces = batch.counts.z;
    if (i >= batch.counts.y * faces) {
        return;
    }
    let j = i / faces;
    let f = i % faces;
    let job = lights[batch.counts.x + j];
    let w = face_weight(job.light, planes[f]);
    weights[batch.bases.w + i] = w;
    if (job.info.y == 0u || w == 0) {
        return;
    }
    if (w > 0) {
        append_cap(ARG_NEAR_FORWARD, batch.caps.x, vec2<u32>(j, f));
        append_cap(ARG_FAR, batch.caps.z, vec2<u32>(j, f | TURNED));
    } else {
        append_cap(ARG_NEAR_REVERSED, batch.caps.y, vec2<u32>(j, f));
        append_cap(ARG_FAR, batch.caps.z, vec2<u32>(j, f));
    }
}

// Sums each edge's face weights, each times the face's direction along the edge (twin:
// silhouette::silhouette), for each of the run's instances; a silhouette edge of weight k is listed k
// times, its sign in the top bit (set: the edge runs from its second vertex to its first).
@compute @workgroup_size(64)
fn cs_edges(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = item(id, groups);
    if (i >= batch.counts.y * batch.counts.w) {
        return;
    }
    let j = i / batch.counts.w;
    let e = i % batch.counts.w;
    let edge = edge_list[e];
    let faces = batch.bases.w + j * batch.counts.z;
    var w = 0;
    for (var k = 0u; k < edge.w; k++) {
        let u = face_uses[edge.z + k];
        let fw = weights[faces + (u >> 1u)];
        w += select(fw, -fw, (u & 1u) == 1u);
    }
    if (w == 0) {
        return;
    }
    atomicAdd(&args[batch.bases.y + ARG_EDGES], 1u);
    let n = u32(abs(w));
    let per = side_vertices(lights[batch.counts.x].light);
    let first = batch.bases.z + atomicAdd(&args[batch.bases.y + ARG_SIDES], n * per) / per;
    let record = vec2<u32>(j, e | select(0u, TURNED, w < 0));
    for (var k = 0u; k < n; k++) {
        records[first + k] = record;
    }
}

// Vertices per side record: a quad, or one triangle under parallel light (both far corners are the
// light's direction). Every job of a run has the same light.
fn side_vertices(light: vec4<f32>) -> u32 {
    return select(6u, 3u, light.w == 0.0);
}

// Twin: LightSource::extrude.
fn to_infinity(l: vec4<f32>, p: vec3<f32>) -> vec4<f32> {
    if (l.w == 0.0) {
        return vec4<f32>(l.xyz, 0.0);
    }
    return vec4<f32>(p - l.xyz, 0.0);
}

// A side: record v / 6 (v / 3 under parallel light) as the outward quad (b, a, a_inf, b_inf), the
// triangles (b, a, a_inf) and (b, a_inf, b_inf), in the corners' order volume::extrude gives them.
@vertex
fn vs_side(@builtin(vertex_index) v: u32) -> VolumeOut {
    let per = side_vertices(jobs[run.counts.x].light);
    let record = list[run.bases.z + v / per];
    let job = jobs[run.counts.x + record.x];
    let edge = edges[record.y & ~TURNED];
    var a = edge.x;
    var b = edge.y;
    if ((record.y & TURNED) != 0u) {
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
            p = to_infinity(job.light, welded[a].xyz);
        }
        default: {
            p = to_infinity(job.light, welded[b].xyz);
        }
    }
    var out: VolumeOut;
    out.pos = clip_position(job.info.x, p);
    return out;
}

// Corner `c` of cap record `record`'s face, turned around where the record says: the mesh's vertex.
fn cap_corner(record: vec2<u32>, c: u32) -> vec4<f32> {
    let turned = (record.y & TURNED) != 0u;
    let corner = select(c, (3u - c) % 3u, turned);
    return positions[indices[3u * (record.y & ~TURNED) + corner]];
}

// A near cap: the mesh's own vertex, transformed as the G-buffer transformed it.
@vertex
fn vs_near(@builtin(vertex_index) v: u32) -> VolumeOut {
    let record = list[v / 3u];
    var out: VolumeOut;
    out.pos = clip_position(jobs[run.counts.x + record.x].info.x, cap_corner(record, v % 3u));
    return out;
}

// A far cap: the mesh's vertex sent to infinity away from the light.
@vertex
fn vs_far(@builtin(vertex_index) v: u32) -> VolumeOut {
    let record = list[v / 3u];
    let job = jobs[run.counts.x + record.x];
    var out: VolumeOut;
    out.pos = clip_position(job.info.x, to_infinity(job.light, cap_corner(record, v % 3u).xyz));
    return out;
}
