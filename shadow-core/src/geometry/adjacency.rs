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

use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

use glam::{Vec3, Vec4};
use rayon::prelude::*;

use crate::bounds::Aabb;
use crate::mesh::{Mesh, face_normal};

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
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
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
    manifold: Vec<Edge>,
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
}

#[derive(Default)]
struct WeldHasher(u64);

impl Hasher for WeldHasher {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.write_u32(u32::from(b));
        }
    }
    fn write_u32(&mut self, v: u32) {
        // Multiply-rotate mixing: positions are not adversarial, and this is ~5x faster than SipHash here.
        self.0 = (self.0.rotate_left(26) ^ u64::from(v)).wrapping_mul(0x9e37_79b9_7f4a_7c15);
    }
}

/// Bit pattern of a position with `-0.0` folded into `0.0`, so the two weld.
fn weld_key(p: Vec3) -> [u32; 3] {
    [p.x, p.y, p.z].map(|c| if c == 0.0 { 0 } else { c.to_bits() })
}

/// `n` scaled by the power of two that brings its largest component into [1, 2).
///
/// The raw normal's length is the square of the mesh's size, and the plane offset `n . p` its cube: at
/// coordinates of 1e13 that offset passes f32's range (3.4e38) and every facing test of the face reads
/// infinity. Scaling by a power of two is exact, and every product and sum of the facing test scales by
/// the same power, so each test keeps the sign the raw normal gives wherever that did not overflow.
/// Normals too small to scale into range unharmed (subnormal components) are left as they are.
fn power_of_two_unit(n: Vec3) -> Vec3 {
    let largest = n.abs().max_element();
    if !(largest.is_normal() && largest.is_finite()) {
        return n;
    }
    // largest = 2^e * m with m in [1, 2); 2^-e is a normal f32 for every e of a normal f32 but the top one.
    let e = ((largest.to_bits() >> 23) & 0xff) as i32 - 127;
    if e >= 127 {
        return n;
    }
    n * f32::from_bits(((127 - e) as u32) << 23)
}

impl Adjacency {
    /// Builds the adjacency of a mesh.
    #[must_use]
    pub fn build(mesh: &Mesh) -> Self {
        let (positions, remap) = weld(mesh.positions());
        let triangles: Vec<[u32; 3]> = mesh.triangles().par_iter().map(|t| t.map(|i| remap[i as usize])).collect();
        let degenerate: Vec<bool> = triangles.par_iter().map(|&[a, b, c]| a == b || b == c || c == a).collect();
        let planes: Vec<Vec4> = triangles
            .par_iter()
            .map(|t| {
                let p = t.map(|i| positions[i as usize]);
                let n = power_of_two_unit(face_normal(p));
                // Exactly zero for two equal corners; -0.0 folded so the facing test gives exactly 0.
                if n == Vec3::ZERO { Vec4::ZERO } else { n.extend(-n.dot(p[0])) }
            })
            .collect();

        let uses = EdgeUses::gather(&triangles, &degenerate, positions.len());

        // The edges of each run of vertices sorted into the three lists at once, the runs' lists then
        // joined in order.
        let lists: Vec<EdgeLists> = (0..positions.len())
            .step_by(EdgeLists::VERTICES)
            .collect::<Vec<_>>()
            .into_par_iter()
            .map(|first| {
                let mut lists = EdgeLists::default();
                for (v, run) in uses.edges(first..(first + EdgeLists::VERTICES).min(positions.len())) {
                    lists.add(v, run);
                }
                lists
            })
            .collect();
        let manifold = lists.iter().map(|l| l.manifold.len()).sum();
        let mut adj = Self {
            component: Vec::new(),
            component_bounds: Vec::new(),
            positions,
            remap,
            triangles,
            planes,
            degenerate,
            manifold: Vec::with_capacity(manifold),
            manifold_faces: Vec::with_capacity(manifold),
            boundary: Vec::new(),
            boundary_faces: Vec::new(),
            complex: Vec::new(),
            non_manifold_edges: 0,
            inconsistent_edges: 0,
        };
        for l in lists {
            adj.manifold.extend_from_slice(&l.manifold);
            adj.manifold_faces.extend_from_slice(&l.manifold_faces);
            adj.boundary.extend_from_slice(&l.boundary);
            adj.boundary_faces.extend_from_slice(&l.boundary_faces);
            adj.complex.extend(l.complex);
            adj.non_manifold_edges += l.non_manifold;
            adj.inconsistent_edges += l.inconsistent;
        }
        (adj.component, adj.component_bounds) = components(&adj);
        adj
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
        &self.manifold
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
    /// Watertight and consistently wound: every edge has exactly two faces running opposite ways. Closed
    /// meshes cast with weight-1 silhouettes and light-facing caps; all others with Bergeron weights.
    #[must_use]
    pub fn closed(&self) -> bool {
        self.boundary.is_empty() && self.complex.is_empty()
    }
}

/// Every face's use of each of its edges, grouped by edge in the order of the edges' welded endpoints
/// (lower, then higher) and, within an edge, of the uses. A counting sort on the lower endpoint puts each
/// use into its vertex's bucket; a bucket holds a handful of uses (about six on a closed mesh), sorted
/// in place by the higher endpoint and the use. That is linear in the faces, where a comparison sort of
/// all the uses (three million for a million faces) took most of the build; and the order is the one
/// such a sort gives, so the edge lists come out the same.
struct EdgeUses {
    /// Per welded vertex, where its bucket begins in `uses`; one more entry closes the last.
    start: Vec<u32>,
    /// Each use with the higher endpoint of its edge, in the buckets of the lower.
    uses: Vec<(u32, FaceUse)>,
}

impl EdgeUses {
    /// Buckets of at most this many vertices are sorted as one task.
    const CHUNK: usize = 8192;

    fn gather(triangles: &[[u32; 3]], degenerate: &[bool], vertices: usize) -> Self {
        // Each run of faces buckets its own uses, all runs at once; the buckets are then merged vertex by
        // vertex, and each merged bucket sorted, so the runs' number does not change the result.
        let runs = rayon::current_num_threads().clamp(1, 8);
        let per_run = triangles.len().div_ceil(runs).max(1);
        let local: Vec<Self> = triangles
            .par_chunks(per_run)
            .zip(degenerate.par_chunks(per_run))
            .enumerate()
            .map(|(k, (t, d))| Self::bucket(t, d, k * per_run, vertices))
            .collect();
        let mut start = vec![0u32; vertices + 1];
        for v in 0..vertices {
            start[v + 1] = start[v] + local.iter().map(|l| l.start[v + 1] - l.start[v]).sum::<u32>();
        }
        let mut uses = vec![(0, FaceUse::NONE); start[vertices] as usize];
        // The buckets of each run of CHUNK vertices, split off one after the other, filled and sorted in
        // parallel.
        let mut chunks = Vec::with_capacity(vertices.div_ceil(Self::CHUNK));
        let mut rest = uses.as_mut_slice();
        for first in (0..vertices).step_by(Self::CHUNK) {
            let last = (first + Self::CHUNK).min(vertices);
            let (chunk, tail) = rest.split_at_mut((start[last] - start[first]) as usize);
            chunks.push((first..last, chunk));
            rest = tail;
        }
        chunks.into_par_iter().for_each(|(range, chunk)| {
            let mut at = 0;
            for v in range {
                let from = at;
                for l in &local {
                    let bucket = &l.uses[l.start[v] as usize..l.start[v + 1] as usize];
                    chunk[at..at + bucket.len()].copy_from_slice(bucket);
                    at += bucket.len();
                }
                chunk[from..at].sort_unstable();
            }
        });
        Self { start, uses }
    }

    /// The uses of `triangles` (the first numbered `base`) in buckets by lower endpoint, unsorted within.
    fn bucket(triangles: &[[u32; 3]], degenerate: &[bool], base: usize, vertices: usize) -> Self {
        let edges = |&[a, b, c]: &[u32; 3]| [(a, b), (b, c), (c, a)];
        let cast = triangles.iter().zip(degenerate).enumerate().filter(|(_, (_, d))| !**d);
        let mut start = vec![0u32; vertices + 1];
        for (_, (t, _)) in cast.clone() {
            for (u, v) in edges(t) {
                start[u.min(v) as usize + 1] += 1;
            }
        }
        for i in 1..start.len() {
            start[i] += start[i - 1];
        }
        let mut next = start.clone();
        let mut uses = vec![(0, FaceUse::NONE); start[vertices] as usize];
        for (f, (t, _)) in cast {
            for (u, v) in edges(t) {
                let slot = &mut next[u.min(v) as usize];
                uses[*slot as usize] = (u.max(v), FaceUse::new((base + f) as u32, u > v));
                *slot += 1;
            }
        }
        Self { start, uses }
    }

    /// Each edge whose lower endpoint is in `lower`: its welded endpoints (lower first) and its uses,
    /// each with the higher endpoint.
    fn edges(&self, lower: std::ops::Range<usize>) -> impl Iterator<Item = ([u32; 2], &[(u32, FaceUse)])> {
        let first = lower.start;
        self.start[lower.start..=lower.end].windows(2).enumerate().flat_map(move |(k, w)| {
            self.uses[w[0] as usize..w[1] as usize]
                .chunk_by(|x, y| x.0 == y.0)
                .map(move |run| ([(first + k) as u32, run[0].0], run))
        })
    }
}

/// Edges sorted by their uses (see [`Adjacency`]'s lists), for one run of lower endpoints.
#[derive(Default)]
struct EdgeLists {
    manifold: Vec<Edge>,
    manifold_faces: Vec<[u32; 2]>,
    boundary: Vec<Edge>,
    boundary_faces: Vec<FaceUse>,
    complex: Vec<ComplexEdge>,
    non_manifold: usize,
    inconsistent: usize,
}

impl EdgeLists {
    /// Lower endpoints a task sorts the edges of.
    const VERTICES: usize = 16384;

    /// Puts edge `v` with its uses `run` into its list.
    fn add(&mut self, v: [u32; 2], run: &[(u32, FaceUse)]) {
        match *run {
            [(_, f)] => {
                self.boundary.push(Edge { v });
                self.boundary_faces.push(f);
            }
            [(_, f0), (_, f1)] if f0.reversed() != f1.reversed() => {
                self.manifold.push(Edge { v });
                let (fwd, rev) = if f0.reversed() { (f1, f0) } else { (f0, f1) };
                self.manifold_faces.push([fwd.face(), rev.face()]);
            }
            _ => {
                if run.len() == 2 {
                    self.inconsistent += 1;
                } else {
                    self.non_manifold += 1;
                }
                self.complex.push(ComplexEdge { v, uses: run.iter().map(|u| u.1).collect() });
            }
        }
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
    // at most the face and each root is its component's least face. In face order, then, a face's parent
    // already points at its root, and a root comes before the rest of its component: one pass finds every
    // face's root and numbers the components in order of first appearance.
    let mut component = vec![0u32; parent.len()];
    let mut count = 0;
    for f in 0..parent.len() {
        let r = parent[parent[f] as usize];
        parent[f] = r;
        component[f] = if r as usize == f {
            count += 1;
            count - 1
        } else {
            component[r as usize]
        };
    }
    // Bounds by runs of faces of one component (a mesh's faces come component by component, mostly), the
    // runs found in parallel and merged in order.
    let runs: Vec<Vec<(u32, Aabb)>> = adj
        .triangles
        .par_chunks(16384)
        .zip(component.par_chunks(16384))
        .map(|(tris, comps)| {
            let mut runs: Vec<(u32, Aabb)> = Vec::new();
            for (t, &c) in tris.iter().zip(comps) {
                let b = t.iter().fold(Aabb::EMPTY, |b, &v| b.including(adj.positions[v as usize]));
                match runs.last_mut() {
                    Some((last, bounds)) if *last == c => *bounds = bounds.union(b),
                    _ => runs.push((c, b)),
                }
            }
            runs
        })
        .collect();
    let mut bounds = vec![Aabb::EMPTY; count as usize];
    for (c, b) in runs.into_iter().flatten() {
        bounds[c as usize] = bounds[c as usize].union(b);
    }
    (component, bounds)
}

/// Welds equal positions (by [`weld_key`]): the distinct positions in order of first appearance, and each
/// position's index among them.
///
/// One hash map over half a million positions misses the cache on nearly every insert. So the positions
/// are first split by their hash's top bits into [`WELD_PARTS`] parts (a counting sort that keeps each
/// part in position order); each part, a few thousand keys that stay in cache, is welded on its own and
/// in parallel, giving every position the first position with its key; a prefix count over those firsts
/// then numbers them in order of first appearance, as one map in position order would.
fn weld(positions: &[Vec3]) -> (Vec<Vec3>, Vec<u32>) {
    let n = positions.len();
    let keys: Vec<[u32; 3]> = positions.par_iter().map(|&p| weld_key(p)).collect();
    let part = |k: &[u32; 3]| {
        let mut h = WeldHasher::default();
        k.iter().for_each(|&c| h.write_u32(c));
        (h.finish() >> (64 - WELD_PARTS.trailing_zeros())) as usize
    };
    let parts: Vec<u16> = keys.par_iter().map(|k| part(k) as u16).collect();
    let mut start = vec![0usize; WELD_PARTS + 1];
    for &p in &parts {
        start[usize::from(p) + 1] += 1;
    }
    for i in 1..start.len() {
        start[i] += start[i - 1];
    }
    let mut next = start.clone();
    let mut order = vec![0u32; n];
    for (i, &p) in parts.iter().enumerate() {
        order[next[usize::from(p)]] = i as u32;
        next[usize::from(p)] += 1;
    }
    // Per part, for each of its positions (in position order) the first position with the same key.
    let firsts: Vec<Vec<u32>> = start
        .par_windows(2)
        .map(|w| {
            let members = &order[w[0]..w[1]];
            let mut map: HashMap<[u32; 3], u32, BuildHasherDefault<WeldHasher>> =
                HashMap::with_capacity_and_hasher(members.len(), BuildHasherDefault::default());
            members.iter().map(|&i| *map.entry(keys[i as usize]).or_insert(i)).collect()
        })
        .collect();
    let mut first = vec![0u32; n];
    for (w, part) in start.windows(2).zip(&firsts) {
        for (&i, &f) in order[w[0]..w[1]].iter().zip(part) {
            first[i as usize] = f;
        }
    }
    // Number the first positions in order; every other takes its first's number.
    let mut number = vec![0u32; n];
    let mut welded = Vec::new();
    for (i, &f) in first.iter().enumerate() {
        if f as usize == i {
            number[i] = welded.len() as u32;
            welded.push(positions[i]);
        }
    }
    let remap = first.par_iter().map(|&f| number[f as usize]).collect();
    (welded, remap)
}

/// How many parts [`weld`] splits the positions into (a power of two).
const WELD_PARTS: usize = 256;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::procedural;

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
