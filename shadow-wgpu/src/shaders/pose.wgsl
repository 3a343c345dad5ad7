// Posing skinned and morphed meshes on the GPU (twin: shadow-core's `deform::pose` and
// `Adjacency::posed`), once a frame, into buffers every pass reads in place of the rest mesh's.
//
// `cs_pose` moves each vertex as the CPU does, in the same order: the morph targets first (the base plus
// each target's displacement times its weight, target after target, zero weights skipped), then the skin
// (the weighted sum of the vertex's joint matrices in the order it names them, applied to the morphed
// position; the normal by that sum's cofactor matrix), then the normal normalized (zero stays zero).
// `cs_weld` gives each welded vertex the posed position of the last mesh vertex welded to it, and
// `cs_planes` each face its plane over the welded positions, scaled by a power of two as the CPU's
// adjacency scales it, so the extrusion finds silhouettes of the pose.

const WORKGROUP: u32 = 64u;

struct Shape {
    // Vertices, morph targets, joints (0: not skinned), welded vertices.
    counts: vec4<u32>,
    // Faces.
    faces: vec4<u32>,
}

struct SkinVertex {
    joints: vec4<u32>,
    weights: vec4<f32>,
}

struct TargetVertex {
    position: vec4<f32>,
    normal: vec4<f32>,
}

@group(0) @binding(0) var<uniform> shape: Shape;
@group(0) @binding(1) var<storage, read> rest_positions: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read> rest_normals: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read> skin: array<SkinVertex>;
// Target-major: target t's displacement of vertex v at t * vertices + v.
@group(0) @binding(4) var<storage, read> targets: array<TargetVertex>;
// The joint matrices (four columns each), then the morph weights, four to an element.
@group(0) @binding(5) var<storage, read> pose: array<vec4<f32>>;
@group(0) @binding(6) var<storage, read_write> posed_positions: array<vec4<f32>>;
@group(0) @binding(7) var<storage, read_write> posed_normals: array<vec4<f32>>;

@group(1) @binding(0) var<uniform> weld_shape: Shape;
@group(1) @binding(1) var<storage, read> positions: array<vec4<f32>>;
// Per welded vertex, the mesh vertex whose position it takes.
@group(1) @binding(2) var<storage, read> weld: array<u32>;
// Per face, its welded corners (xyz).
@group(1) @binding(3) var<storage, read> faces: array<vec4<u32>>;
@group(1) @binding(4) var<storage, read_write> welded: array<vec4<f32>>;
@group(1) @binding(5) var<storage, read_write> planes: array<vec4<f32>>;

fn item(id: vec3<u32>, groups: vec3<u32>) -> u32 {
    return id.x + id.y * groups.x * WORKGROUP;
}

fn joint_matrix(j: u32) -> mat4x4<f32> {
    let at = 4u * min(j, shape.counts.z - 1u);
    return mat4x4<f32>(pose[at], pose[at + 1u], pose[at + 2u], pose[at + 3u]);
}

fn morph_weight(t: u32) -> f32 {
    return pose[4u * shape.counts.z + t / 4u][t % 4u];
}

// The inverse transpose times the determinant, its sign turned for a mirroring matrix.
fn cofactor(m: mat3x3<f32>) -> mat3x3<f32> {
    let c = mat3x3<f32>(cross(m[1], m[2]), cross(m[2], m[0]), cross(m[0], m[1]));
    if determinant(m) < 0.0 {
        return c * -1.0;
    }
    return c;
}

@compute @workgroup_size(WORKGROUP)
fn cs_pose(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let v = item(id, groups);
    let vertices = shape.counts.x;
    if v >= vertices {
        return;
    }
    var p = rest_positions[v].xyz;
    var n = rest_normals[v].xyz;
    for (var t = 0u; t < shape.counts.y; t++) {
        let w = morph_weight(t);
        if w != 0.0 {
            let d = targets[t * vertices + v];
            p += d.position.xyz * w;
            n += d.normal.xyz * w;
        }
    }
    if shape.counts.z > 0u {
        let s = skin[v];
        var m = mat4x4<f32>(vec4<f32>(0.0), vec4<f32>(0.0), vec4<f32>(0.0), vec4<f32>(0.0));
        for (var k = 0u; k < 4u; k++) {
            if s.weights[k] != 0.0 {
                m += joint_matrix(s.joints[k]) * s.weights[k];
            }
        }
        p = (m * vec4<f32>(p, 1.0)).xyz;
        n = cofactor(mat3x3<f32>(m[0].xyz, m[1].xyz, m[2].xyz)) * n;
    }
    let size = length(n);
    let unit = select(vec3<f32>(0.0), n * (1.0 / size), size > 0.0 && size < 3.4e38);
    posed_positions[v] = vec4<f32>(p, 1.0);
    posed_normals[v] = vec4<f32>(unit, 0.0);
}

@compute @workgroup_size(WORKGROUP)
fn cs_weld(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let w = item(id, groups);
    if w >= weld_shape.counts.w {
        return;
    }
    welded[w] = positions[weld[w]];
}

// `n` scaled by the power of two that brings its largest component into [1, 2) (shadow-core's
// `power_of_two_unit`): zero, subnormal, infinite and the largest binades are left as they are.
fn power_of_two_unit(n: vec3<f32>) -> vec3<f32> {
    let largest = max(abs(n.x), max(abs(n.y), abs(n.z)));
    let e = i32((bitcast<u32>(largest) >> 23u) & 0xffu) - 127;
    if e <= -127 || e >= 127 {
        return n;
    }
    return n * bitcast<f32>(u32(127 - e) << 23u);
}

@compute @workgroup_size(WORKGROUP)
fn cs_planes(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let f = item(id, groups);
    if f >= weld_shape.faces.x {
        return;
    }
    let t = faces[f];
    let a = welded[t.x].xyz;
    let n = power_of_two_unit(cross(welded[t.y].xyz - a, welded[t.z].xyz - a));
    if all(n == vec3<f32>(0.0)) {
        planes[f] = vec4<f32>(0.0);
    } else {
        planes[f] = vec4<f32>(n, -dot(n, a));
    }
}
