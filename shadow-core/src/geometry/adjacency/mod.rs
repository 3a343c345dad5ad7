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
//!
//! A large mesh's adjacency is built on every thread, step by step (`build`). A small one is built on
//! one thread (`small`), and the adjacencies of many small meshes built together
//! ([`Adjacency::build_all`]) share one store, each mesh a stretch of every list: a scene of many small
//! meshes pays for their triangles, not for a set of lists, a thread pool's start and a weld table per
//! mesh.

mod build;
mod small;

use std::ops::Range;
use std::sync::Arc;

use glam::{Vec3, Vec4};
use rayon::prelude::*;

use super::facing::{EdgeRun, FacingRuns};
use crate::bounds::Aabb;
use crate::mesh::Mesh;
use build::EdgeLists;

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

/// The lists of one or more meshes' adjacencies, end to end: each mesh's are a [`Part`] of them.
#[derive(Debug, Default)]
struct Store {
    positions: Vec<Vec3>,
    remap: Vec<u32>,
    triangles: Vec<[u32; 3]>,
    planes: Vec<Vec4>,
    degenerate: Vec<bool>,
    /// Consistently wound manifold edges, as [`Edge`]s.
    manifold: Vec<[u32; 2]>,
    manifold_faces: Vec<[u32; 2]>,
    /// Boundary and complex edges.
    lists: EdgeLists,
    /// Per face, its connected component, numbered in order of first appearance.
    component: Vec<u32>,
    /// Per component, the bounds of its welded vertices.
    component_bounds: Vec<Aabb>,
    /// Bounds that decide the facing of runs of faces, and of the faces of runs of manifold edges, at
    /// once ([`FacingRuns`]).
    face_runs: Vec<[Vec4; 2]>,
    edge_runs: Vec<EdgeRun>,
}

/// Where one mesh's adjacency lies in a [`Store`]: its stretch of each list. Vertex, face and
/// component numbers in a part count from its own start.
#[derive(Clone, Copy, Debug, Default)]
struct Part {
    /// Welded positions.
    vertices: Span,
    /// The remap (one a mesh vertex).
    mesh_vertices: Span,
    /// Triangles, planes, the degenerate flags and the components of faces.
    faces: Span,
    /// Manifold edges and their faces.
    manifold: Span,
    /// Boundary edges and their faces.
    boundary: Span,
    complex: Span,
    /// Component bounds.
    components: Span,
    face_runs: Span,
    edge_runs: Span,
    non_manifold_edges: u32,
    inconsistent_edges: u32,
}

/// A stretch of a list, in half the bytes of a `Range<usize>`: a scene of many small meshes holds one
/// [`Part`] a mesh. (Faces already number under 2^31, [`FaceUse`] holding them in 31 bits.)
#[derive(Clone, Copy, Debug, Default)]
struct Span {
    start: u32,
    end: u32,
}

impl Span {
    /// From `start` to the end of a list of `len`.
    fn to(start: u32, len: usize) -> Self {
        Self { start, end: len as u32 }
    }
    fn range(self) -> Range<usize> {
        self.start as usize..self.end as usize
    }
    fn len(self) -> usize {
        (self.end - self.start) as usize
    }
    fn is_empty(self) -> bool {
        self.end == self.start
    }
}

impl Store {
    /// The whole store as one part.
    fn whole_part(&self) -> Part {
        self.part_since(&Part::default())
    }

    /// The stretch of every list added since the store was `before` (its [`Store::whole_part`] then).
    fn part_since(&self, before: &Part) -> Part {
        let lists = &self.lists;
        Part {
            vertices: Span::to(before.vertices.end, self.positions.len()),
            mesh_vertices: Span::to(before.mesh_vertices.end, self.remap.len()),
            faces: Span::to(before.faces.end, self.triangles.len()),
            manifold: Span::to(before.manifold.end, self.manifold.len()),
            boundary: Span::to(before.boundary.end, lists.boundary.len()),
            complex: Span::to(before.complex.end, lists.complex.len()),
            components: Span::to(before.components.end, self.component_bounds.len()),
            face_runs: Span::to(before.face_runs.end, self.face_runs.len()),
            edge_runs: Span::to(before.edge_runs.end, self.edge_runs.len()),
            non_manifold_edges: lists.non_manifold as u32 - before.non_manifold_edges,
            inconsistent_edges: lists.inconsistent as u32 - before.inconsistent_edges,
        }
    }
}

/// Edge-to-face adjacency of a mesh after welding coincident positions. Cloning shares the lists.
#[derive(Clone, Debug)]
pub struct Adjacency {
    store: Arc<Store>,
    part: Part,
}

/// The most positions, and the most triangles, of a mesh built on one thread.
const SMALL: usize = super::weld::WELD_ALONE;

/// About how many triangles a thread builds in one batch of small meshes.
const BATCH: usize = 8192;

/// True for a mesh built on one thread (and with others in [`Adjacency::build_all`]).
fn is_small(mesh: &Mesh) -> bool {
    mesh.positions().len() <= SMALL && mesh.triangle_count() <= SMALL
}

impl Adjacency {
    /// Builds the adjacency of a mesh: a large one on every thread, a small one on this thread.
    #[must_use]
    pub fn build(mesh: &Mesh) -> Self {
        if is_small(mesh) { small::build_batch(&[mesh]).remove(0) } else { Self::whole(build::build(mesh)) }
    }

    /// Builds the adjacencies of many meshes at once, on every thread: runs of small meshes together
    /// (a thread a run, into one store), each large mesh on its own. The same adjacencies, list by list,
    /// as [`Adjacency::build`] gives each.
    #[must_use]
    pub fn build_all(meshes: &[&Mesh]) -> Vec<Self> {
        let mut jobs: Vec<Range<usize>> = Vec::new();
        let mut start = 0;
        while start < meshes.len() {
            let mut end = start + 1;
            if is_small(meshes[start]) {
                let mut triangles = meshes[start].triangle_count();
                while end < meshes.len() && is_small(meshes[end]) && triangles < BATCH {
                    triangles += meshes[end].triangle_count();
                    end += 1;
                }
            }
            jobs.push(start..end);
            start = end;
        }
        let built: Vec<Vec<Self>> = jobs
            .into_par_iter()
            .map(|job| match &meshes[job] {
                [large] if !is_small(large) => vec![Self::whole(build::build(large))],
                small => small::build_batch(small),
            })
            .collect();
        built.into_iter().flatten().collect()
    }

    /// [`Adjacency::build`] on all threads, whatever the mesh's size: the build a small mesh's must equal.
    #[cfg(test)]
    pub(crate) fn build_on_all_threads(mesh: &Mesh) -> Self {
        Self::whole(build::build(mesh))
    }

    /// True when both hold the same lists, every float to the bit.
    #[cfg(test)]
    pub(crate) fn same_lists(&self, other: &Self) -> bool {
        let bits = |v: &[Vec4]| v.iter().flat_map(|p| p.to_array().map(f32::to_bits)).collect::<Vec<_>>();
        let bits3 = |v: &[Vec3]| v.iter().flat_map(|p| p.to_array().map(f32::to_bits)).collect::<Vec<_>>();
        let bounds = |a: &Self| a.component_bounds().iter().flat_map(|b| [b.min, b.max]).collect::<Vec<_>>();
        let runs = |a: &Self| bits(a.facing_runs().planes.as_flattened());
        bits3(self.positions()) == bits3(other.positions())
            && self.remap() == other.remap()
            && self.triangles() == other.triangles()
            && bits(self.planes()) == bits(other.planes())
            && self.degenerate() == other.degenerate()
            && self.manifold_edges() == other.manifold_edges()
            && self.manifold_faces() == other.manifold_faces()
            && self.boundary_edges() == other.boundary_edges()
            && self.boundary_faces() == other.boundary_faces()
            && self.complex_edges() == other.complex_edges()
            && (self.non_manifold_edge_count(), self.inconsistent_edge_count())
                == (other.non_manifold_edge_count(), other.inconsistent_edge_count())
            && self.components() == other.components()
            && bits3(&bounds(self)) == bits3(&bounds(other))
            && runs(self) == runs(other)
            && self.facing_runs().edges == other.facing_runs().edges
    }

    /// The adjacency that is the whole of `store`.
    fn whole(store: Store) -> Self {
        Self { part: store.whole_part(), store: Arc::new(store) }
    }

    /// The same topology over posed positions, one a mesh vertex (as [`crate::deform::pose`] gives them):
    /// the welding, faces, edges and components stay the rest mesh's, and the welded positions, face
    /// planes, component bounds and facing bounds are the pose's. A welded vertex takes the posed position
    /// of the last mesh vertex welded into it, so a pose that parts vertices welded at rest (which a skin
    /// weighting them alike never does) keeps the mesh closed.
    #[must_use]
    pub fn posed(&self, mesh_positions: &[Vec3]) -> Self {
        let mut positions = vec![Vec3::ZERO; self.vertex_count()];
        for (&w, &p) in self.remap().iter().zip(mesh_positions) {
            positions[w as usize] = p;
        }
        let planes: Vec<Vec4> =
            self.triangles().par_iter().map(|t| build::face_plane(t.map(|i| positions[i as usize]))).collect();
        let component_bounds =
            build::component_bounds(self.triangles(), self.components(), self.component_bounds().len(), &positions);
        let (face_runs, edge_runs) = build::facing_runs(&planes, self.manifold_faces());
        Self::whole(Store {
            positions,
            planes,
            component_bounds,
            face_runs,
            edge_runs,
            remap: self.remap().to_vec(),
            triangles: self.triangles().to_vec(),
            degenerate: self.degenerate().to_vec(),
            manifold: bytemuck::cast_slice(self.manifold_edges()).to_vec(),
            manifold_faces: self.manifold_faces().to_vec(),
            lists: EdgeLists {
                boundary: self.boundary_edges().to_vec(),
                boundary_faces: self.boundary_faces().to_vec(),
                complex: self.complex_edges().to_vec(),
                non_manifold: self.non_manifold_edge_count(),
                inconsistent: self.inconsistent_edge_count(),
            },
            component: self.components().to_vec(),
        })
    }

    /// Welded positions.
    #[must_use]
    pub fn positions(&self) -> &[Vec3] {
        &self.store.positions[self.part.vertices.range()]
    }
    /// Welded vertex of each mesh vertex.
    #[must_use]
    pub fn remap(&self) -> &[u32] {
        &self.store.remap[self.part.mesh_vertices.range()]
    }
    /// The mesh's triangles in welded vertices (same order as the mesh).
    #[must_use]
    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.store.triangles[self.part.faces.range()]
    }
    /// Face planes `(n, -n.p0)` with `n = (b - a) x (c - a)` scaled by a power of two so its largest
    /// component lies in [1, 2) (exactly, so facing signs are the raw normal's); all zero for a
    /// degenerate face, which therefore faces no light.
    #[must_use]
    pub fn planes(&self) -> &[Vec4] {
        &self.store.planes[self.part.faces.range()]
    }
    /// True for faces with two welded corners equal: they have no edges and cast nothing.
    #[must_use]
    pub fn degenerate(&self) -> &[bool] {
        &self.store.degenerate[self.part.faces.range()]
    }
    /// Consistently wound manifold edges.
    #[must_use]
    pub fn manifold_edges(&self) -> &[Edge] {
        bytemuck::cast_slice(&self.store.manifold[self.part.manifold.range()])
    }
    /// The two faces of each manifold edge: first the one running from `v[0]` to `v[1]`, then the one
    /// running back.
    #[must_use]
    pub fn manifold_faces(&self) -> &[[u32; 2]] {
        &self.store.manifold_faces[self.part.manifold.range()]
    }
    /// Edges used by exactly one face.
    #[must_use]
    pub fn boundary_edges(&self) -> &[Edge] {
        &self.store.lists.boundary[self.part.boundary.range()]
    }
    /// The face of each boundary edge, with its direction.
    #[must_use]
    pub fn boundary_faces(&self) -> &[FaceUse] {
        &self.store.lists.boundary_faces[self.part.boundary.range()]
    }
    /// Non-manifold and inconsistently wound edges.
    #[must_use]
    pub fn complex_edges(&self) -> &[ComplexEdge] {
        &self.store.lists.complex[self.part.complex.range()]
    }
    /// Number of welded vertices.
    #[must_use]
    pub fn vertex_count(&self) -> usize {
        self.part.vertices.len()
    }
    /// Number of distinct edges.
    #[must_use]
    pub fn edge_count(&self) -> usize {
        self.part.manifold.len() + self.part.boundary.len() + self.part.complex.len()
    }
    /// Edges used by exactly one face.
    #[must_use]
    pub fn boundary_edge_count(&self) -> usize {
        self.part.boundary.len()
    }
    /// Edges used by three or more faces.
    #[must_use]
    pub fn non_manifold_edge_count(&self) -> usize {
        self.part.non_manifold_edges as usize
    }
    /// Edges used by two faces that run the same way (a flipped triangle).
    #[must_use]
    pub fn inconsistent_edge_count(&self) -> usize {
        self.part.inconsistent_edges as usize
    }
    /// The connected component of each face (faces sharing an edge are connected), numbered from 0 in
    /// order of first appearance; an edge's component is its faces'.
    #[must_use]
    pub fn components(&self) -> &[u32] {
        &self.store.component[self.part.faces.range()]
    }
    /// The bounds of each connected component's vertices, in mesh space.
    #[must_use]
    pub fn component_bounds(&self) -> &[Aabb] {
        &self.store.component_bounds[self.part.components.range()]
    }
    /// Bounds that decide the facing of runs of faces, and of the faces of runs of manifold edges, at
    /// once.
    pub(crate) fn facing_runs(&self) -> FacingRuns<'_> {
        let store = &*self.store;
        FacingRuns {
            planes: &store.face_runs[self.part.face_runs.range()],
            edges: &store.edge_runs[self.part.edge_runs.range()],
        }
    }
    /// Watertight and consistently wound: every edge has exactly two faces running opposite ways. Closed
    /// meshes cast with weight-1 silhouettes and light-facing caps; all others with Bergeron weights.
    #[must_use]
    pub fn closed(&self) -> bool {
        self.part.boundary.is_empty() && self.part.complex.is_empty()
    }
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

    /// A large mesh amid small ones in one call: the large one built on all threads, the small ones in
    /// batches, each the adjacency its own build gives.
    #[test]
    fn building_all_at_once_is_building_each() {
        let sphere = procedural::sphere(1.0, 120, 60).expect("a sphere");
        assert!(!is_small(&sphere));
        let cube = procedural::cuboid(Vec3::ONE).expect("shape");
        let plane = procedural::plane(2.0, 2.0).expect("shape");
        let torus = procedural::torus(1.0, 0.25, 24, 12).expect("shape");
        let mut meshes = vec![&cube, &sphere, &plane];
        meshes.extend(std::iter::repeat_n(&torus, 200));
        meshes.push(&cube);
        let all = Adjacency::build_all(&meshes);
        assert_eq!(all.len(), meshes.len());
        for (adj, mesh) in all.iter().zip(&meshes) {
            assert!(adj.same_lists(&Adjacency::build_on_all_threads(mesh)));
        }
        // The toruses fill more than one batch, and those of a batch share its store.
        let stores = |a: &[Adjacency]| {
            let mut s: Vec<*const Store> = a.iter().map(|a| Arc::as_ptr(&a.store)).collect();
            s.dedup();
            s.len()
        };
        assert!((3..200).contains(&stores(&all[3..203])), "{} stores", stores(&all[3..203]));
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
