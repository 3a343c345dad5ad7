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
        let triangles: Vec<[u32; 3]> = mesh.triangles().iter().map(|t| t.map(|i| remap[i as usize])).collect();
        let degenerate: Vec<bool> = triangles.iter().map(|&[a, b, c]| a == b || b == c || c == a).collect();
        let planes: Vec<Vec4> = triangles
            .par_iter()
            .map(|t| {
                let p = t.map(|i| positions[i as usize]);
                let n = power_of_two_unit(face_normal(p));
                // Exactly zero for two equal corners; -0.0 folded so the facing test gives exactly 0.
                if n == Vec3::ZERO { Vec4::ZERO } else { n.extend(-n.dot(p[0])) }
            })
            .collect();

        // Every directed edge of every non-degenerate face, keyed by its welded endpoints.
        let mut uses: Vec<(u64, FaceUse)> = triangles
            .par_iter()
            .enumerate()
            .filter(|(f, _)| !degenerate[*f])
            .flat_map_iter(|(f, &[a, b, c])| {
                [(a, b), (b, c), (c, a)].into_iter().map(move |(u, v)| {
                    let key = u64::from(u.min(v)) << 32 | u64::from(u.max(v));
                    (key, FaceUse::new(f as u32, u > v))
                })
            })
            .collect();
        uses.par_sort_unstable();

        let mut adj = Self {
            component: Vec::new(),
            component_bounds: Vec::new(),
            positions,
            remap,
            triangles,
            planes,
            degenerate,
            manifold: Vec::with_capacity(uses.len() / 2),
            manifold_faces: Vec::with_capacity(uses.len() / 2),
            boundary: Vec::new(),
            boundary_faces: Vec::new(),
            complex: Vec::new(),
            non_manifold_edges: 0,
            inconsistent_edges: 0,
        };
        for run in uses.chunk_by(|x, y| x.0 == y.0) {
            let v = [(run[0].0 >> 32) as u32, run[0].0 as u32];
            match *run {
                [(_, f)] => {
                    adj.boundary.push(Edge { v });
                    adj.boundary_faces.push(f);
                }
                [(_, f0), (_, f1)] if f0.reversed() != f1.reversed() => {
                    adj.manifold.push(Edge { v });
                    let (fwd, rev) = if f0.reversed() { (f1, f0) } else { (f0, f1) };
                    adj.manifold_faces.push([fwd.face(), rev.face()]);
                }
                _ => {
                    if run.len() == 2 {
                        adj.inconsistent_edges += 1;
                    } else {
                        adj.non_manifold_edges += 1;
                    }
                    adj.complex.push(ComplexEdge { v, uses: run.iter().map(|u| u.1).collect() });
                }
            }
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
    // Roots are each component's least face, so numbering them in face order numbers the components in
    // order of first appearance.
    let mut number = vec![u32::MAX; parent.len()];
    let mut bounds = Vec::new();
    let mut component = Vec::with_capacity(parent.len());
    for (f, t) in adj.triangles.iter().enumerate() {
        let r = root(&mut parent, f as u32) as usize;
        if number[r] == u32::MAX {
            number[r] = bounds.len() as u32;
            bounds.push(Aabb::EMPTY);
        }
        let k = number[r] as usize;
        bounds[k] = t.iter().fold(bounds[k], |b, &v| b.including(adj.positions[v as usize]));
        component.push(k as u32);
    }
    (component, bounds)
}

fn weld(positions: &[Vec3]) -> (Vec<Vec3>, Vec<u32>) {
    let mut map: HashMap<[u32; 3], u32, BuildHasherDefault<WeldHasher>> =
        HashMap::with_capacity_and_hasher(positions.len(), BuildHasherDefault::default());
    let mut welded = Vec::with_capacity(positions.len());
    let remap = positions
        .iter()
        .map(|&p| {
            *map.entry(weld_key(p)).or_insert_with(|| {
                welded.push(p);
                (welded.len() - 1) as u32
            })
        })
        .collect();
    (welded, remap)
}

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
