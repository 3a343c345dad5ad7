//! One mesh's adjacency built on every thread: the weld, faces, edges, components and facing runs of a
//! large mesh, each step split over the threads. The steps a batch of small meshes shares with it
//! ([`super::small`]) are here too.

use glam::{Vec3, Vec4};
use rayon::prelude::*;

use super::{ComplexEdge, Edge, FaceUse, Store};
use crate::bounds::Aabb;
use crate::geometry::facing::{self, EDGES, EdgeRun, FACES};
use crate::geometry::weld::weld;
use crate::mesh::{Mesh, face_normal, power_of_two_unit};

/// A mesh's adjacency, every step on all threads.
pub(super) fn build(mesh: &Mesh) -> Store {
    let (positions, remap) = weld(mesh.positions());
    let (triangles, degenerate, planes) = faces(mesh.triangles(), &remap, &positions);
    let (manifold, manifold_faces, lists) = edges(&triangles, &degenerate, positions.len());
    // The components' union-find runs on one thread; the facing bounds fill the others meanwhile.
    let ((component, component_bounds), (face_runs, edge_runs)) = rayon::join(
        || {
            let mut component: Vec<u32> = (0..triangles.len() as u32).collect();
            let count = number_components(&mut component, &manifold_faces, &lists.complex);
            let bounds = component_bounds(&triangles, &component, count as usize, &positions);
            (component, bounds)
        },
        || facing_runs(&planes, &manifold_faces),
    );
    Store {
        positions,
        remap,
        triangles,
        planes,
        degenerate,
        manifold,
        manifold_faces,
        lists,
        component,
        component_bounds,
        face_runs,
        edge_runs,
    }
}

/// [`facing::face_run`] of every run of faces and [`facing::edge_run`] of every run of manifold edges, on
/// all threads.
pub(super) fn facing_runs(planes: &[Vec4], manifold_faces: &[[u32; 2]]) -> (Vec<[Vec4; 2]>, Vec<EdgeRun>) {
    let face_runs = planes.par_chunks(FACES).map(facing::face_run).collect();
    (face_runs, manifold_faces.par_chunks(EDGES).map(facing::edge_run).collect())
}

/// Each face in welded vertices, whether two of its corners weld together, and its plane, in one pass
/// over the faces, each thread filling its own stretch of the three lists.
fn faces(mesh_triangles: &[[u32; 3]], remap: &[u32], positions: &[Vec3]) -> (Vec<[u32; 3]>, Vec<bool>, Vec<Vec4>) {
    const RUN: usize = 4096;
    let n = mesh_triangles.len();
    // Zeroed allocations, whose pages are first touched (and faulted in) by the threads writing them.
    let (mut triangles, mut degenerate) = (vec![[0; 3]; n], vec![false; n]);
    let mut planes: Vec<Vec4> = bytemuck::zeroed_vec(n);
    mesh_triangles
        .par_chunks(RUN)
        .zip(triangles.par_chunks_mut(RUN))
        .zip(degenerate.par_chunks_mut(RUN))
        .zip(planes.par_chunks_mut(RUN))
        .for_each(|(((mesh, triangles), degenerate), planes)| {
            for (((m, t), d), plane) in mesh.iter().zip(triangles).zip(degenerate).zip(planes) {
                (*t, *d, *plane) = face(*m, remap, positions);
            }
        });
    (triangles, degenerate, planes)
}

/// A face in welded vertices, whether two of its corners weld together, and its plane.
pub(super) fn face(mesh_triangle: [u32; 3], remap: &[u32], positions: &[Vec3]) -> ([u32; 3], bool, Vec4) {
    let t = mesh_triangle.map(|i| remap[i as usize]);
    let [a, b, c] = t;
    (t, a == b || b == c || c == a, face_plane(t.map(|i| positions[i as usize])))
}

/// The plane of a face's corners, as [`super::Adjacency::planes`] gives it.
pub(super) fn face_plane(p: [Vec3; 3]) -> Vec4 {
    // The raw normal's length is the square of the mesh's size and the plane offset `n . p` its cube: at
    // coordinates of 1e13 that offset passes f32's range and every facing test of the face would read
    // infinity. Scaled, each test keeps the sign the raw normal gives.
    let n = power_of_two_unit(face_normal(p));
    // Exactly zero for two equal corners; -0.0 folded so the facing test gives exactly 0.
    if n == Vec3::ZERO { Vec4::ZERO } else { n.extend(-n.dot(p[0])) }
}

/// Every edge of the faces that are not degenerate, in the order of its welded endpoints (lower, then
/// higher), sorted into [`super::Adjacency`]'s three lists: the consistently wound manifold edges with their
/// face pairs, and the other edges, in order.
///
/// The edges whose lower endpoint is a vertex `v` belong to the faces at `v`, and a face at `v` has one
/// of them unless `v` is its highest corner. So a counting sort lists, per vertex, the faces of which it
/// is a corner but not the highest one; each vertex then reads its few faces (about four on a closed
/// mesh), writes their edges leaving it upwards as `higher << 32 | use` words, and sorts those by the
/// higher endpoint, then the use. That is linear in the faces, and the order is the one a sort of all
/// the uses would give.
///
/// The vertices are split into one range per thread, and each thread reads every face and keeps the
/// corners in its range: it counts them into its vertices, places them, and reads each vertex's edges
/// off its faces while they are in cache, writing only its own part of every output. Reading the faces
/// once per thread costs far less than merging lists filled by several threads.
fn edges(triangles: &[[u32; 3]], degenerate: &[bool], vertices: usize) -> (Vec<[u32; 2]>, Vec<[u32; 2]>, EdgeLists) {
    let per_range = vertices.div_ceil(rayon::current_num_threads().clamp(1, 64)).max(1);
    let ranges: Vec<std::ops::Range<usize>> =
        (0..vertices).step_by(per_range).map(|lo| lo..(lo + per_range).min(vertices)).collect();
    // Per range, where each of its vertices' faces begin, and how many edges leave its vertices upwards,
    // each counted once per face using it.
    let counts: Vec<(Vec<u32>, usize)> = ranges
        .par_iter()
        .map(|range| {
            let (mut start, mut uses) = (vec![0u32; range.len() + 1], 0);
            each_lower_corner(triangles, degenerate, |_, v, up| {
                // Below the range, the difference wraps past every vertex.
                if let Some(s) = start.get_mut((v as usize).wrapping_sub(range.start) + 1) {
                    *s += 1;
                    uses += up;
                }
            });
            for i in 1..start.len() {
                start[i] += start[i - 1];
            }
            (start, uses)
        })
        .collect();
    // A range of n uses has at most n / 2 manifold edges; each range writes its own into a part of the
    // outputs that size. Zeroed memory is not touched until written, so parts left unused cost nothing.
    let most: usize = counts.iter().map(|(_, n)| n / 2).sum();
    let (mut manifold, mut manifold_faces) = (vec![[0u32; 2]; most], vec![[0u32; 2]; most]);
    let mut corners = vec![0u32; counts.iter().map(|(start, _)| start[start.len() - 1] as usize).sum()];
    let mut parts = Vec::with_capacity(ranges.len());
    let (mut corners_rest, mut edges_rest, mut faces_rest) =
        (corners.as_mut_slice(), manifold.as_mut_slice(), manifold_faces.as_mut_slice());
    for (range, (start, n)) in ranges.iter().zip(&counts) {
        let (faces_at, c) = corners_rest.split_at_mut(start[start.len() - 1] as usize);
        let (edges, e) = edges_rest.split_at_mut(n / 2);
        let (faces, f) = faces_rest.split_at_mut(n / 2);
        parts.push((range.clone(), start, faces_at, edges, faces));
        (corners_rest, edges_rest, faces_rest) = (c, e, f);
    }
    // Per range, how many consistently wound manifold edges it wrote into its part of the outputs, and
    // its other edges.
    let lists: Vec<(usize, EdgeLists)> = parts
        .into_par_iter()
        .map(|(range, start, faces_at, edges, faces)| {
            let mut next = start[..range.len()].to_vec();
            each_lower_corner(triangles, degenerate, |f, v, _| {
                if let Some(slot) = next.get_mut((v as usize).wrapping_sub(range.start)) {
                    faces_at[*slot as usize] = f;
                    *slot += 1;
                }
            });
            let (mut written, mut lists, mut words) = (0, EdgeLists::default(), Vec::new());
            for (lower, w) in range.zip(start.windows(2)) {
                let lower = lower as u32;
                words.clear();
                for &f in &faces_at[w[0] as usize..w[1] as usize] {
                    let t = triangles[f as usize];
                    // The face was listed under this corner of it, so the search finds it.
                    let k = t.iter().position(|&v| v == lower).unwrap_or_default();
                    // The face runs from `lower` up to the corner after it, and down to `lower` from the
                    // corner before it.
                    let (after, before) = (t[(k + 1) % 3], t[(k + 2) % 3]);
                    if after > lower {
                        words.push(u64::from(after) << 32 | u64::from(FaceUse::new(f, false).0));
                    }
                    if before > lower {
                        words.push(u64::from(before) << 32 | u64::from(FaceUse::new(f, true).0));
                    }
                }
                words.sort_unstable();
                for run in words.chunk_by(|x, y| x >> 32 == y >> 32) {
                    let v = [lower, (run[0] >> 32) as u32];
                    match manifold_faces_of(run) {
                        Some(pair) => {
                            (edges[written], faces[written]) = (v, pair);
                            written += 1;
                        }
                        None => lists.add(v, run),
                    }
                }
            }
            (written, lists)
        })
        .collect();
    // Close the gaps the ranges left (none on a closed mesh, where every use is half a manifold edge).
    let (mut at, mut part) = (0, 0);
    for (&(written, _), (_, n)) in lists.iter().zip(&counts) {
        manifold.copy_within(part..part + written, at);
        manifold_faces.copy_within(part..part + written, at);
        (at, part) = (at + written, part + n / 2);
    }
    for list in [&mut manifold, &mut manifold_faces] {
        list.truncate(at);
        list.shrink_to_fit();
    }
    let mut others = EdgeLists::default();
    for (_, range) in lists {
        others.append(range);
    }
    (manifold, manifold_faces, others)
}

/// Calls `each(face, corner, up)` for every corner of every face that is not degenerate but its highest
/// one, with `up` the number of the face's edges that leave the corner upwards (one or two).
fn each_lower_corner(triangles: &[[u32; 3]], degenerate: &[bool], mut each: impl FnMut(u32, u32, usize)) {
    for (f, (&[a, b, c], &d)) in triangles.iter().zip(degenerate).enumerate() {
        if !d {
            for v in [a, b, c] {
                let up = usize::from(a > v) + usize::from(b > v) + usize::from(c > v);
                if up > 0 {
                    each(f as u32, v, up);
                }
            }
        }
    }
}

/// The [`FaceUse`] in the low half of a word of [`edges`].
pub(super) fn face_use(word: u64) -> FaceUse {
    FaceUse(word as u32)
}

/// The edges that are not consistently wound manifold edges (see [`super::Adjacency`]'s lists), in order, with
/// the counts of the two kinds of complex edge.
#[derive(Clone, Debug, Default)]
pub(super) struct EdgeLists {
    pub(super) boundary: Vec<Edge>,
    pub(super) boundary_faces: Vec<FaceUse>,
    pub(super) complex: Vec<ComplexEdge>,
    pub(super) non_manifold: usize,
    pub(super) inconsistent: usize,
}

impl EdgeLists {
    /// Appends `other`'s edges after these.
    fn append(&mut self, other: Self) {
        self.boundary.extend_from_slice(&other.boundary);
        self.boundary_faces.extend_from_slice(&other.boundary_faces);
        self.complex.extend(other.complex);
        self.non_manifold += other.non_manifold;
        self.inconsistent += other.inconsistent;
    }

    /// Puts edge `v`, with its uses `run` (as `higher << 32 | use` words), into the boundary or the
    /// complex list: it is not a consistently wound manifold edge.
    pub(super) fn add(&mut self, v: [u32; 2], run: &[u64]) {
        if let [f] = *run {
            self.boundary.push(Edge { v });
            self.boundary_faces.push(face_use(f));
            return;
        }
        if run.len() == 2 {
            self.inconsistent += 1;
        } else {
            self.non_manifold += 1;
        }
        self.complex.push(ComplexEdge { v, uses: run.iter().map(|&u| face_use(u)).collect() });
    }
}

/// The faces of a consistently wound manifold edge (two uses running opposite ways), the one running
/// along the edge first; `None` for any other edge.
pub(super) fn manifold_faces_of(run: &[u64]) -> Option<[u32; 2]> {
    match *run {
        [f0, f1] if face_use(f0).reversed() != face_use(f1).reversed() => {
            let (fwd, rev) = if face_use(f0).reversed() { (f1, f0) } else { (f0, f1) };
            Some([face_use(fwd).face(), face_use(rev).face()])
        }
        _ => None,
    }
}

/// Numbers the connected components of a mesh's faces through their edges (union-find with path
/// halving) in order of first appearance, in place: `parent` comes in as each face's own index and leaves
/// as each face's component. Returns the count. A face no edge joins to another (a degenerate one, say)
/// is a component of its own.
pub(super) fn number_components(parent: &mut [u32], manifold_faces: &[[u32; 2]], complex: &[ComplexEdge]) -> u32 {
    let root = |parent: &mut [u32], mut f: u32| {
        while parent[f as usize] != f {
            let up = parent[parent[f as usize] as usize];
            parent[f as usize] = up;
            f = up;
        }
        f
    };
    let mut join = |f: u32, g: u32| {
        let (rf, rg) = (root(parent, f), root(parent, g));
        if rf != rg {
            parent[rf.max(rg) as usize] = rf.min(rg);
        }
    };
    for &[f, g] in manifold_faces {
        join(f, g);
    }
    for e in complex {
        for u in &e.uses[1..] {
            join(e.uses[0].face(), u.face());
        }
    }
    // A root joins below the other, and halving only moves a face up its path, so every face's parent is
    // a lesser face (or itself, for a root). In face order, then, a face's parent has already been given
    // its component's number: one pass numbers the components in order of first appearance, in place.
    let mut count = 0;
    for f in 0..parent.len() {
        let p = parent[f] as usize;
        parent[f] = if p == f {
            count += 1;
            count - 1
        } else {
            parent[p]
        };
    }
    count
}

/// The bounds of each of `count` components over `positions`, from the component of each face.
pub(super) fn component_bounds(
    triangles: &[[u32; 3]],
    component: &[u32],
    count: usize,
    positions: &[Vec3],
) -> Vec<Aabb> {
    // Bounds by runs of faces of one component (a mesh's faces come component by component, mostly), the
    // runs found in parallel and merged in order.
    let runs: Vec<Vec<(u32, Aabb)>> = triangles
        .par_chunks(COMPONENT_RUN)
        .zip(component.par_chunks(COMPONENT_RUN))
        .map(|(tris, comps)| {
            let mut runs = Vec::new();
            component_runs(tris, comps, positions, &mut runs);
            runs
        })
        .collect();
    let mut bounds = vec![Aabb::EMPTY; count];
    for (c, b) in runs.into_iter().flatten() {
        bounds[c as usize] = bounds[c as usize].union(b);
    }
    bounds
}

/// The most faces [`component_bounds`] gives one thread at a time.
pub(super) const COMPONENT_RUN: usize = 16384;

/// Appends to `runs` the component and the bounds of each run of consecutive faces of one component.
pub(super) fn component_runs(
    triangles: &[[u32; 3]],
    component: &[u32],
    positions: &[Vec3],
    runs: &mut Vec<(u32, Aabb)>,
) {
    let first = runs.len();
    for (t, &c) in triangles.iter().zip(component) {
        let b = t.iter().fold(Aabb::EMPTY, |b, &v| b.including(positions[v as usize]));
        match runs[first..].last_mut() {
            Some((last, bounds)) if *last == c => *bounds = bounds.union(b),
            _ => runs.push((c, b)),
        }
    }
}
