//! Edge adjacency of a triangle mesh.
//!
//! Positions are welded by exact equality (so `-0.0` and `0.0` are one position and nothing is moved), then
//! every edge is mapped to the faces that use it. Each use records whether the face runs along the edge
//! from its lower welded vertex to its higher one or back; silhouette weights are built from those
//! directions alone, so nothing here trusts the file's claim of being closed or consistently wound:
//! [`Adjacency::closed`] is computed.
//!
//! Edges fall into three lists. Consistently wound manifold edges (two faces, opposite directions) are
//! the bulk, read every frame by the silhouette pass, so they are stored as bare face pairs with the face
//! running along the edge first: the pass needs no direction bits. Boundary edges (one face) come next,
//! and the rest (three or more faces, or two faces running the same way) go to
//! [`Adjacency::complex_edges`].
//!
//! Faces sharing an edge belong to one connected component ([`Adjacency::components`]; sharing a vertex
//! is not enough, so a tree's twigs sprouting from one point stay apart). A component's shadow volume is
//! closed on its own (every face of each of its edges is in it), so it shadows nothing outside its own
//! shadow, which lets a technique skip it wherever that cannot hold the point it counts.

use glam::{Vec3, Vec4};
use rayon::prelude::*;

use super::facing::FacingRuns;
use super::weld::weld;
use crate::bounds::Aabb;
use crate::mesh::{Mesh, face_normal, power_of_two_unit};

/// One face's use of an edge: `face << 1 | reversed`, where `reversed` means the face runs from the
/// edge's higher welded vertex to its lower one.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct FaceUse(u32);

impl FaceUse {
    /// No face (the second slot of a boundary edge).
    pub const NONE: Self = Self(u32::MAX);

    /// A use of `face`, reversed or not.
    #[must_use]
    pub fn new(face: u32, reversed: bool) -> Self {
        Self(face << 1 | u32::from(reversed))
    }
    /// The face index.
    #[must_use]
    pub fn face(self) -> u32 {
        self.0 >> 1
    }
    /// True when the face runs against the edge's stored direction.
    #[must_use]
    pub fn reversed(self) -> bool {
        self.0 & 1 == 1
    }
    /// True for [`FaceUse::NONE`].
    #[must_use]
    pub fn is_none(self) -> bool {
        self == Self::NONE
    }
    /// +1 along the edge, -1 against it.
    #[must_use]
    pub fn direction(self) -> i32 {
        if self.reversed() { -1 } else { 1 }
    }
}

/// An edge's two welded vertices.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct Edge {
    /// Welded vertices, `v[0] < v[1]`.
    pub v: [u32; 2],
}

/// An edge with three or more faces, or with two faces running the same way.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ComplexEdge {
    /// Welded vertices, `v[0] < v[1]`.
    pub v: [u32; 2],
    /// Every face that uses the edge.
    pub uses: Vec<FaceUse>,
}

/// Edge-to-face adjacency of a mesh after welding coincident positions.
#[derive(Clone, Debug)]
pub struct Adjacency {
    positions: Vec<Vec3>,
    remap: Vec<u32>,
    triangles: Vec<[u32; 3]>,
    planes: Vec<Vec4>,
    degenerate: Vec<bool>,
    /// Consistently wound manifold edges, as [`Edge`]s.
    manifold: Vec<[u32; 2]>,
    manifold_faces: Vec<[u32; 2]>,
    boundary: Vec<Edge>,
    boundary_faces: Vec<FaceUse>,
    complex: Vec<ComplexEdge>,
    non_manifold_edges: usize,
    inconsistent_edges: usize,
    /// Per face, its connected component, numbered in order of first appearance.
    component: Vec<u32>,
    /// Per component, the bounds of its welded vertices.
    component_bounds: Vec<Aabb>,
    /// Bounds that decide the facing of runs of faces at once.
    facing_runs: FacingRuns,
}

impl Adjacency {
    /// Builds the adjacency of a mesh.
    #[must_use]
    pub fn build(mesh: &Mesh) -> Self {
        let (positions, remap) = weld(mesh.positions());
        let (triangles, degenerate, planes) = faces(mesh.triangles(), &remap, &positions);

        let (manifold, manifold_faces, lists) = edges(&triangles, &degenerate, positions.len());
        let mut adj = Self {
            component: Vec::new(),
            component_bounds: Vec::new(),
            facing_runs: FacingRuns::default(),
            positions,
            remap,
            triangles,
            planes,
            degenerate,
            manifold,
            manifold_faces,
            boundary: Vec::new(),
            boundary_faces: Vec::new(),
            complex: Vec::new(),
            non_manifold_edges: 0,
            inconsistent_edges: 0,
        };
        for l in lists {
            adj.boundary.extend_from_slice(&l.boundary);
            adj.boundary_faces.extend_from_slice(&l.boundary_faces);
            adj.complex.extend(l.complex);
            adj.non_manifold_edges += l.non_manifold;
            adj.inconsistent_edges += l.inconsistent;
        }
        // The components' union-find runs on one thread; the facing bounds fill the others meanwhile.
        let ((component, component_bounds), facing_runs) =
            rayon::join(|| components(&adj), || FacingRuns::new(&adj.planes, &adj.manifold_faces));
        (adj.component, adj.component_bounds, adj.facing_runs) = (component, component_bounds, facing_runs);
        adj
    }

    /// The same topology over posed positions, one a mesh vertex (as [`crate::deform::pose`] gives them):
    /// the welding, faces, edges and components stay the rest mesh's, and the welded positions, face
    /// planes, component bounds and facing bounds are the pose's. A welded vertex takes the posed position
    /// of the last mesh vertex welded into it, so a pose that parts vertices welded at rest (which a skin
    /// weighting them alike never does) keeps the mesh closed.
    #[must_use]
    pub fn posed(&self, mesh_positions: &[Vec3]) -> Self {
        let mut positions = vec![Vec3::ZERO; self.positions.len()];
        for (&w, &p) in self.remap.iter().zip(mesh_positions) {
            positions[w as usize] = p;
        }
        let planes: Vec<Vec4> =
            self.triangles.par_iter().map(|t| face_plane(t.map(|i| positions[i as usize]))).collect();
        let component_bounds =
            component_bounds(&self.triangles, &self.component, self.component_bounds.len(), &positions);
        let facing_runs = FacingRuns::new(&planes, &self.manifold_faces);
        // The topology is copied field by field: the rest mesh's positions and planes are not copied only
        // to be dropped.
        Self {
            positions,
            planes,
            component_bounds,
            facing_runs,
            remap: self.remap.clone(),
            triangles: self.triangles.clone(),
            degenerate: self.degenerate.clone(),
            manifold: self.manifold.clone(),
            manifold_faces: self.manifold_faces.clone(),
            boundary: self.boundary.clone(),
            boundary_faces: self.boundary_faces.clone(),
            complex: self.complex.clone(),
            non_manifold_edges: self.non_manifold_edges,
            inconsistent_edges: self.inconsistent_edges,
            component: self.component.clone(),
        }
    }

    /// Welded positions.
    #[must_use]
    pub fn positions(&self) -> &[Vec3] {
        &self.positions
    }
    /// Welded vertex of each mesh vertex.
    #[must_use]
    pub fn remap(&self) -> &[u32] {
        &self.remap
    }
    /// The mesh's triangles in welded vertices (same order as the mesh).
    #[must_use]
    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.triangles
    }
    /// Face planes `(n, -n.p0)` with `n = (b - a) x (c - a)` scaled by a power of two so its largest
    /// component lies in [1, 2) (exactly, so facing signs are the raw normal's); all zero for a
    /// degenerate face, which therefore faces no light.
    #[must_use]
    pub fn planes(&self) -> &[Vec4] {
        &self.planes
    }
    /// True for faces with two welded corners equal: they have no edges and cast nothing.
    #[must_use]
    pub fn degenerate(&self) -> &[bool] {
        &self.degenerate
    }
    /// Consistently wound manifold edges.
    #[must_use]
    pub fn manifold_edges(&self) -> &[Edge] {
        bytemuck::cast_slice(&self.manifold)
    }
    /// The two faces of each manifold edge: first the one running from `v[0]` to `v[1]`, then the one
    /// running back.
    #[must_use]
    pub fn manifold_faces(&self) -> &[[u32; 2]] {
        &self.manifold_faces
    }
    /// Edges used by exactly one face.
    #[must_use]
    pub fn boundary_edges(&self) -> &[Edge] {
        &self.boundary
    }
    /// The face of each boundary edge, with its direction.
    #[must_use]
    pub fn boundary_faces(&self) -> &[FaceUse] {
        &self.boundary_faces
    }
    /// Non-manifold and inconsistently wound edges.
    #[must_use]
    pub fn complex_edges(&self) -> &[ComplexEdge] {
        &self.complex
    }
    /// Number of welded vertices.
    #[must_use]
    pub fn vertex_count(&self) -> usize {
        self.positions.len()
    }
    /// Number of distinct edges.
    #[must_use]
    pub fn edge_count(&self) -> usize {
        self.manifold.len() + self.boundary.len() + self.complex.len()
    }
    /// Edges used by exactly one face.
    #[must_use]
    pub fn boundary_edge_count(&self) -> usize {
        self.boundary.len()
    }
    /// Edges used by three or more faces.
    #[must_use]
    pub fn non_manifold_edge_count(&self) -> usize {
        self.non_manifold_edges
    }
    /// Edges used by two faces that run the same way (a flipped triangle).
    #[must_use]
    pub fn inconsistent_edge_count(&self) -> usize {
        self.inconsistent_edges
    }
    /// The connected component of each face (faces sharing an edge are connected), numbered from 0 in
    /// order of first appearance; an edge's component is its faces'.
    #[must_use]
    pub fn components(&self) -> &[u32] {
        &self.component
    }
    /// The bounds of each connected component's vertices, in mesh space.
    #[must_use]
    pub fn component_bounds(&self) -> &[Aabb] {
        &self.component_bounds
    }
    /// Bounds that decide the facing of runs of faces, and of the faces of runs of manifold edges, at
    /// once.
    pub(crate) fn facing_runs(&self) -> &FacingRuns {
        &self.facing_runs
    }
    /// Watertight and consistently wound: every edge has exactly two faces running opposite ways. Closed
    /// meshes cast with weight-1 silhouettes and light-facing caps; all others with Bergeron weights.
    #[must_use]
    pub fn closed(&self) -> bool {
        self.boundary.is_empty() && self.complex.is_empty()
    }
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
                *t = m.map(|i| remap[i as usize]);
                let [a, b, c] = *t;
                *d = a == b || b == c || c == a;
                *plane = face_plane(t.map(|i| positions[i as usize]));
            }
        });
    (triangles, degenerate, planes)
}

/// The plane of a face's corners, as [`Adjacency::planes`] gives it.
fn face_plane(p: [Vec3; 3]) -> Vec4 {
    // The raw normal's length is the square of the mesh's size and the plane offset `n . p` its cube: at
    // coordinates of 1e13 that offset passes f32's range and every facing test of the face would read
    // infinity. Scaled, each test keeps the sign the raw normal gives.
    let n = power_of_two_unit(face_normal(p));
    // Exactly zero for two equal corners; -0.0 folded so the facing test gives exactly 0.
    if n == Vec3::ZERO { Vec4::ZERO } else { n.extend(-n.dot(p[0])) }
}

/// Every edge of the faces that are not degenerate, in the order of its welded endpoints (lower, then
/// higher), sorted into [`Adjacency`]'s three lists: the consistently wound manifold edges with their
/// face pairs, and per range of lower endpoints (in order) the other edges.
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
fn edges(
    triangles: &[[u32; 3]],
    degenerate: &[bool],
    vertices: usize,
) -> (Vec<[u32; 2]>, Vec<[u32; 2]>, Vec<EdgeLists>) {
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
    let lists: Vec<EdgeLists> = parts
        .into_par_iter()
        .map(|(range, start, faces_at, edges, faces)| {
            let mut next = start[..range.len()].to_vec();
            each_lower_corner(triangles, degenerate, |f, v, _| {
                if let Some(slot) = next.get_mut((v as usize).wrapping_sub(range.start)) {
                    faces_at[*slot as usize] = f;
                    *slot += 1;
                }
            });
            let (mut lists, mut words) = (EdgeLists::default(), Vec::new());
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
                            (edges[lists.manifold], faces[lists.manifold]) = (v, pair);
                            lists.manifold += 1;
                        }
                        None => lists.add(v, run),
                    }
                }
            }
            lists
        })
        .collect();
    // Close the gaps the ranges left (none on a closed mesh, where every use is half a manifold edge).
    let (mut at, mut part) = (0, 0);
    for (l, (_, n)) in lists.iter().zip(&counts) {
        manifold.copy_within(part..part + l.manifold, at);
        manifold_faces.copy_within(part..part + l.manifold, at);
        (at, part) = (at + l.manifold, part + n / 2);
    }
    for list in [&mut manifold, &mut manifold_faces] {
        list.truncate(at);
        list.shrink_to_fit();
    }
    (manifold, manifold_faces, lists)
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
fn face_use(word: u64) -> FaceUse {
    FaceUse(word as u32)
}

/// Edges sorted by their uses (see [`Adjacency`]'s lists), for one range of lower endpoints.
#[derive(Default)]
struct EdgeLists {
    /// How many consistently wound manifold edges the range wrote into its part of the outputs.
    manifold: usize,
    boundary: Vec<Edge>,
    boundary_faces: Vec<FaceUse>,
    complex: Vec<ComplexEdge>,
    non_manifold: usize,
    inconsistent: usize,
}

impl EdgeLists {
    /// Puts edge `v`, with its uses `run` (as `higher << 32 | use` words), into the boundary or the
    /// complex list: it is not a consistently wound manifold edge.
    fn add(&mut self, v: [u32; 2], run: &[u64]) {
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
fn manifold_faces_of(run: &[u64]) -> Option<[u32; 2]> {
    match *run {
        [f0, f1] if face_use(f0).reversed() != face_use(f1).reversed() => {
            let (fwd, rev) = if face_use(f0).reversed() { (f1, f0) } else { (f0, f1) };
            Some([face_use(fwd).face(), face_use(rev).face()])
        }
        _ => None,
    }
}

/// The connected components of the faces through their edges (union-find with path halving), and their
/// bounds. A face no edge joins to another (a degenerate one, say) is a component of its own.
fn components(adj: &Adjacency) -> (Vec<u32>, Vec<Aabb>) {
    let mut parent: Vec<u32> = (0..adj.triangles.len() as u32).collect();
    let root = |parent: &mut [u32], mut f: u32| {
        while parent[f as usize] != f {
            let up = parent[parent[f as usize] as usize];
            parent[f as usize] = up;
            f = up;
        }
        f
    };
    let mut join = |f: u32, g: u32| {
        let (rf, rg) = (root(&mut parent, f), root(&mut parent, g));
        if rf != rg {
            parent[rf.max(rg) as usize] = rf.min(rg);
        }
    };
    for &[f, g] in &adj.manifold_faces {
        join(f, g);
    }
    for e in &adj.complex {
        for u in &e.uses[1..] {
            join(e.uses[0].face(), u.face());
        }
    }
    // A root joins below the other, and halving only moves a face up its path, so every face's parent is
    // a lesser face (or itself, for a root). In face order, then, a face's parent has already been given
    // its component's number: one pass numbers the components in order of first appearance, in place.
    let mut component = parent;
    let mut count = 0;
    for f in 0..component.len() {
        let p = component[f] as usize;
        component[f] = if p == f {
            count += 1;
            count - 1
        } else {
            component[p]
        };
    }
    let bounds = component_bounds(&adj.triangles, &component, count as usize, &adj.positions);
    (component, bounds)
}

/// The bounds of each of `count` components over `positions`, from the component of each face.
fn component_bounds(triangles: &[[u32; 3]], component: &[u32], count: usize, positions: &[Vec3]) -> Vec<Aabb> {
    // Bounds by runs of faces of one component (a mesh's faces come component by component, mostly), the
    // runs found in parallel and merged in order.
    let runs: Vec<Vec<(u32, Aabb)>> = triangles
        .par_chunks(16384)
        .zip(component.par_chunks(16384))
        .map(|(tris, comps)| {
            let mut runs: Vec<(u32, Aabb)> = Vec::new();
            for (t, &c) in tris.iter().zip(comps) {
                let b = t.iter().fold(Aabb::EMPTY, |b, &v| b.including(positions[v as usize]));
                match runs.last_mut() {
                    Some((last, bounds)) if *last == c => *bounds = bounds.union(b),
                    _ => runs.push((c, b)),
                }
            }
            runs
        })
        .collect();
    let mut bounds = vec![Aabb::EMPTY; count];
    for (c, b) in runs.into_iter().flatten() {
        bounds[c as usize] = bounds[c as usize].union(b);
    }
    bounds
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::procedural;

    /// Posed positions give the planes, component bounds and silhouettes a mesh built at them has: a
    /// torus moved and squashed (affinely, so welding and faces stay) against the torus built that way.
    #[test]
    fn a_posed_adjacency_is_the_adjacency_of_the_posed_mesh() {
        let mesh = procedural::torus(1.0, 0.25, 24, 12).expect("shape");
        let m =
            glam::Mat4::from_translation(Vec3::new(2.0, -1.0, 4.0)) * glam::Mat4::from_scale(Vec3::new(1.0, 0.5, 2.0));
        let moved = mesh.transformed(m);
        let (built, posed) = (Adjacency::build(&moved), Adjacency::build(&mesh).posed(moved.positions()));
        assert_eq!(posed.positions(), built.positions());
        assert_eq!(posed.planes(), built.planes());
        assert_eq!(posed.component_bounds(), built.component_bounds());
        let light = crate::geometry::LightSource::Point(Vec3::new(0.0, 6.0, 1.0));
        let mode = crate::geometry::silhouette::CastMode::for_mesh(&built);
        let edges = |a: &Adjacency| crate::geometry::silhouette::silhouette(a, light, mode).edges.len();
        assert_eq!(edges(&posed), edges(&built));
        assert!(edges(&posed) > 0);
    }

    #[test]
    fn cube_is_closed_after_welding() {
        // The procedural cuboid has 24 vertices (flat normals); welding leaves 8.
        let adj = Adjacency::build(&procedural::cuboid(Vec3::ONE).expect("shape"));
        assert_eq!(adj.vertex_count(), 8);
        assert_eq!(adj.edge_count(), 18);
        assert!(adj.closed());
    }

    #[test]
    fn components_are_joined_by_edges_not_by_vertices() {
        // Two cubes touching at one corner, and a pair of triangles sharing only a vertex (a bowtie): four
        // components, numbered in order of first appearance, each bounding its own faces.
        let a = procedural::cuboid(Vec3::ONE).expect("shape");
        let b = procedural::cuboid(Vec3::ONE).expect("shape").transformed(glam::Mat4::from_translation(Vec3::ONE));
        let bowtie = Mesh::new(
            vec![
                Vec3::new(5.0, 0.0, 0.0),
                Vec3::new(6.0, 0.0, 0.0),
                Vec3::new(5.5, 1.0, 0.0),
                Vec3::new(6.0, 2.0, 0.0),
                Vec3::new(5.0, 2.0, 0.0),
            ],
            vec![[0, 1, 2], [2, 3, 4]],
        )
        .expect("bowtie");
        let adj = Adjacency::build(&Mesh::merged(&[a, b, bowtie]).expect("three parts"));
        let faces = adj.components();
        assert_eq!(adj.component_bounds().len(), 4);
        assert!(faces[..12].iter().all(|&c| c == 0) && faces[12..24].iter().all(|&c| c == 1));
        assert_eq!(&faces[24..], &[2, 3]);
        assert_eq!(adj.component_bounds()[1], Aabb::new(Vec3::splat(0.5), Vec3::splat(1.5)));
        assert_eq!(adj.component_bounds()[3], Aabb::new(Vec3::new(5.0, 1.0, 0.0), Vec3::new(6.0, 2.0, 0.0)));
    }

    #[test]
    fn plane_has_boundary() {
        let adj = Adjacency::build(&procedural::plane(2.0, 2.0).expect("shape"));
        assert_eq!(adj.boundary_edge_count(), 4);
        assert_eq!(adj.edge_count(), 5);
        assert!(!adj.closed());
    }

    #[test]
    fn three_faces_on_one_edge_are_non_manifold() {
        let p = vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z, Vec3::NEG_Y];
        let mesh = Mesh::new(p, vec![[0, 1, 2], [1, 0, 3], [0, 1, 4]]).unwrap();
        let adj = Adjacency::build(&mesh);
        assert_eq!(adj.non_manifold_edge_count(), 1);
        assert_eq!(adj.complex_edges()[0].uses.len(), 3);
        assert!(!adj.closed());
    }

    #[test]
    fn flipped_triangle_is_inconsistent() {
        let mesh = procedural::cuboid(Vec3::ONE).expect("shape");
        let mut tris = mesh.triangles().to_vec();
        tris[0] = [tris[0][0], tris[0][2], tris[0][1]];
        let flipped = Mesh::new(mesh.positions().to_vec(), tris).unwrap();
        let adj = Adjacency::build(&flipped);
        assert_eq!(adj.inconsistent_edge_count(), 3);
        assert!(!adj.closed());
    }

    #[test]
    fn negative_zero_welds() {
        let p = vec![Vec3::new(-0.0, 0.0, 0.0), Vec3::X, Vec3::Y, Vec3::ZERO];
        let mesh = Mesh::new(p, vec![[0, 1, 2], [3, 2, 1]]).unwrap();
        assert_eq!(Adjacency::build(&mesh).vertex_count(), 3);
    }
}
