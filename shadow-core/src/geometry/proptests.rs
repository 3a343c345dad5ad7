//! Property tests of adjacency, silhouettes and extrusion on random meshes (DESIGN 9).

use std::collections::HashMap;

use glam::{Vec2, Vec3};
use proptest::prelude::*;
use proptest::test_runner::TestCaseError;

use super::LightSource;
use super::adjacency::{Adjacency, FaceUse};
use super::silhouette::{CastMode, silhouette};
use super::volume::tests::{all_triangles, edge_balance};
use super::volume::{Caps, extrude};
use crate::mesh::Mesh;
use crate::procedural;

/// A closed star-shaped mesh: a lathe sphere with every ring radius and height jittered.
fn closed_mesh() -> impl Strategy<Value = Mesh> {
    (3u32..12, 3usize..9, prop::collection::vec(0.3f32..1.5, 12)).prop_map(|(segments, rings, jitter)| {
        let profile: Vec<Vec2> = (0..=rings)
            .map(|i| {
                let phi = std::f32::consts::PI * i as f32 / rings as f32;
                let r = if i == 0 || i == rings { 0.0 } else { phi.sin() * jitter[i % jitter.len()] };
                Vec2::new(r, -phi.cos() * jitter[(i + 5) % jitter.len()])
            })
            .collect();
        procedural::lathe(&profile, segments, false).expect("a lathe of finite points")
    })
}

/// Any triangle soup over a few shared points: boundaries, non-manifold, flipped and degenerate edges
/// included (not all of its triangles degenerate, which `Mesh` refuses).
fn open_mesh() -> impl Strategy<Value = Mesh> {
    (
        prop::collection::vec(prop::array::uniform3(-1.0f32..1.0), 4..10),
        prop::collection::vec(prop::array::uniform3(0u32..100), 1..30),
    )
        .prop_filter_map("a mesh needs a triangle with an area", |(points, tris)| {
            let n = points.len() as u32;
            let positions = points.into_iter().map(Vec3::from).collect();
            let triangles = tris.into_iter().map(|t| t.map(|i| i % n)).collect();
            // Indices are in range by construction; only an all-degenerate soup is refused.
            Mesh::new(positions, triangles).ok()
        })
}

/// A triangle soup whose positions repeat: drawn from a few points, one of them `-0.0` beside `0.0`, so the
/// weld joins vertices; edges of every kind, as in [`open_mesh`].
fn welded_mesh() -> impl Strategy<Value = Mesh> {
    (
        prop::collection::vec(prop::array::uniform3(-1.0f32..1.0), 2..6),
        prop::collection::vec(0usize..8, 4..40),
        prop::collection::vec(prop::array::uniform3(0u32..100), 1..40),
    )
        .prop_filter_map("a mesh needs a triangle with an area", |(mut pool, picks, tris)| {
            pool.extend([[0.0, 0.0, 0.0], [-0.0, 0.0, -0.0]]);
            let positions: Vec<Vec3> = picks.iter().map(|&i| Vec3::from(pool[i % pool.len()])).collect();
            let n = positions.len() as u32;
            Mesh::new(positions, tris.into_iter().map(|t| t.map(|i| i % n)).collect()).ok()
        })
}

/// Welded positions, each vertex's welded index, and each edge's endpoints with its uses.
type Plain = (Vec<Vec3>, Vec<u32>, Vec<([u32; 2], Vec<FaceUse>)>);

/// The weld and the edge lists the plain way: one map in position order, and one sort of every use by
/// its edge's endpoints, then the use.
fn plainly(mesh: &Mesh) -> Plain {
    let key = |p: Vec3| [p.x, p.y, p.z].map(|c| if c == 0.0 { 0 } else { c.to_bits() });
    let (mut welded, mut ids) = (Vec::new(), HashMap::new());
    let remap: Vec<u32> = mesh
        .positions()
        .iter()
        .map(|&p| {
            *ids.entry(key(p)).or_insert_with(|| {
                welded.push(p);
                welded.len() as u32 - 1
            })
        })
        .collect();
    let mut uses = Vec::new();
    for (f, t) in mesh.triangles().iter().enumerate() {
        let [a, b, c] = t.map(|i| remap[i as usize]);
        if a == b || b == c || c == a {
            continue;
        }
        for (u, v) in [(a, b), (b, c), (c, a)] {
            uses.push(([u.min(v), u.max(v)], FaceUse::new(f as u32, u > v)));
        }
    }
    uses.sort_unstable();
    let edges = uses.chunk_by(|x, y| x.0 == y.0).map(|run| (run[0].0, run.iter().map(|u| u.1).collect())).collect();
    (welded, remap, edges)
}

fn light() -> impl Strategy<Value = LightSource> {
    (prop::array::uniform3(-4.0f32..4.0), any::<bool>()).prop_map(|(p, directional)| {
        let v = Vec3::from(p);
        if directional {
            LightSource::Directional(v.normalize_or(Vec3::NEG_Y))
        } else {
            LightSource::Point(v * 2.0 + Vec3::splat(0.01))
        }
    })
}

/// Undirected edge -> (forward uses, reverse uses), counted straight from the triangles.
fn brute_force_uses(adj: &Adjacency) -> HashMap<(u32, u32), (u32, u32)> {
    let mut uses = HashMap::new();
    for (f, &[a, b, c]) in adj.triangles().iter().enumerate() {
        if adj.degenerate()[f] {
            continue;
        }
        for (u, v) in [(a, b), (b, c), (c, a)] {
            let e = uses.entry((u.min(v), u.max(v))).or_insert((0, 0));
            if u < v { e.0 += 1 } else { e.1 += 1 }
        }
    }
    uses
}

/// [`Adjacency::build`] against [`plainly`]: the weld, every edge in its list in the sort's order, and
/// the components.
fn same_as_plainly(mesh: &Mesh) -> Result<(), TestCaseError> {
    let adj = Adjacency::build(mesh);
    let (welded, remap, edges) = plainly(mesh);
    prop_assert_eq!(adj.positions(), &welded[..]);
    prop_assert_eq!(adj.remap(), &remap[..]);
    // Every edge, in the sort's order, in the list its uses put it in.
    let (mut manifold, mut boundary, mut complex) = (0, 0, 0);
    for (v, uses) in &edges {
        let reversed = |k: usize| uses[k].reversed();
        if uses.len() == 2 && reversed(0) != reversed(1) {
            prop_assert_eq!(adj.manifold_edges()[manifold].v, *v);
            let faces = if reversed(0) { [uses[1], uses[0]] } else { [uses[0], uses[1]] };
            prop_assert_eq!(adj.manifold_faces()[manifold], faces.map(|u| u.face()));
            manifold += 1;
        } else if uses.len() == 1 {
            prop_assert_eq!((adj.boundary_edges()[boundary].v, adj.boundary_faces()[boundary]), (*v, uses[0]));
            boundary += 1;
        } else {
            prop_assert_eq!(&adj.complex_edges()[complex].uses, uses);
            prop_assert_eq!(adj.complex_edges()[complex].v, *v);
            complex += 1;
        }
    }
    prop_assert_eq!(
        (manifold, boundary, complex),
        (adj.manifold_edges().len(), adj.boundary_edges().len(), adj.complex_edges().len())
    );
    // Components: faces joined through every edge's uses, numbered in order of first appearance.
    let mut root: Vec<usize> = (0..adj.triangles().len()).collect();
    let find = |root: &Vec<usize>, mut f: usize| {
        while root[f] != f {
            f = root[f];
        }
        f
    };
    for (_, uses) in &edges {
        for u in &uses[1..] {
            let (a, b) = (find(&root, uses[0].face() as usize), find(&root, u.face() as usize));
            root[a.max(b)] = a.min(b);
        }
    }
    let mut numbers = HashMap::new();
    let plain: Vec<u32> = (0..root.len())
        .map(|f| {
            let next = numbers.len() as u32;
            *numbers.entry(find(&root, f)).or_insert(next)
        })
        .collect();
    prop_assert_eq!(adj.components(), &plain[..]);
    Ok(())
}

#[test]
fn a_mesh_of_many_vertex_runs_is_built_as_the_plain_way_builds_it() {
    // Over 16384 welded vertices, so the edges are sorted in several runs and the runs joined.
    let sphere = procedural::sphere(1.0, 400, 200).expect("a sphere");
    assert!(Adjacency::build(&sphere).vertex_count() > 3 * 16384);
    same_as_plainly(&sphere).expect("the same adjacency");
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    #[test]
    fn manifold_edges_have_two_opposite_faces(mesh in prop_oneof![closed_mesh(), open_mesh()]) {
        let adj = Adjacency::build(&mesh);
        let uses = brute_force_uses(&adj);
        let runs = |f: u32, a: u32, b: u32| {
            let t = adj.triangles()[f as usize];
            (0..3).any(|k| t[k] == a && t[(k + 1) % 3] == b)
        };
        for (e, &[f0, f1]) in adj.manifold_edges().iter().zip(adj.manifold_faces()) {
            prop_assert_eq!(uses[&(e.v[0], e.v[1])], (1, 1));
            prop_assert!(runs(f0, e.v[0], e.v[1]) && runs(f1, e.v[1], e.v[0]));
        }
        for (e, u) in adj.boundary_edges().iter().zip(adj.boundary_faces()) {
            let (fwd, rev) = uses[&(e.v[0], e.v[1])];
            prop_assert_eq!(fwd + rev, 1);
            let ok = if u.reversed() { runs(u.face(), e.v[1], e.v[0]) } else { runs(u.face(), e.v[0], e.v[1]) };
            prop_assert!(ok);
        }
        let boundary = uses.values().filter(|(f, r)| f + r == 1).count();
        let non_manifold = uses.values().filter(|(f, r)| f + r > 2).count();
        prop_assert_eq!(adj.boundary_edge_count(), boundary);
        prop_assert_eq!(adj.non_manifold_edge_count(), non_manifold);
        prop_assert_eq!(adj.edge_count(), uses.len());
    }

    #[test]
    fn the_weld_and_the_edges_are_those_of_one_map_and_one_sort(
        mesh in prop_oneof![closed_mesh(), open_mesh(), welded_mesh()]
    ) {
        same_as_plainly(&mesh)?;
    }

    /// Small meshes built together, on one thread into one store, are each the mesh built alone on
    /// all threads.
    #[test]
    fn a_batch_of_small_meshes_is_each_mesh_built_alone(
        meshes in prop::collection::vec(prop_oneof![closed_mesh(), open_mesh(), welded_mesh()], 1..6)
    ) {
        let refs: Vec<&Mesh> = meshes.iter().collect();
        for (adj, mesh) in Adjacency::build_all(&refs).iter().zip(&meshes) {
            prop_assert!(adj.same_lists(&Adjacency::build_on_all_threads(mesh)));
        }
    }

    #[test]
    fn closed_silhouettes_form_closed_loops(mesh in closed_mesh(), light in light()) {
        let adj = Adjacency::build(&mesh);
        prop_assert!(adj.closed());
        let s = silhouette(&adj, light, CastMode::Closed);
        let mut flow: HashMap<u32, i64> = HashMap::new();
        for e in &s.edges {
            prop_assert_eq!(e.weight, 1);
            *flow.entry(e.a).or_default() += 1;
            *flow.entry(e.b).or_default() -= 1;
        }
        prop_assert!(flow.values().all(|&f| f == 0));
    }

    #[test]
    fn weights_sum_to_zero_around_every_vertex(mesh in prop_oneof![closed_mesh(), open_mesh()], light in light()) {
        let adj = Adjacency::build(&mesh);
        let s = silhouette(&adj, light, CastMode::Bergeron);
        let mut flow: HashMap<u32, i64> = HashMap::new();
        for e in &s.edges {
            *flow.entry(e.a).or_default() += i64::from(e.weight);
            *flow.entry(e.b).or_default() -= i64::from(e.weight);
        }
        prop_assert!(flow.values().all(|&f| f == 0));
    }

    #[test]
    fn volumes_are_closed_and_consistently_oriented(mesh in prop_oneof![closed_mesh(), open_mesh()], light in light()) {
        let adj = Adjacency::build(&mesh);
        let mode = CastMode::for_mesh(&adj);
        let s = silhouette(&adj, light, mode);
        let vol = extrude(&adj, &s, light, Caps::Both);
        prop_assert!(edge_balance(&all_triangles(&adj, &vol)).is_empty());
    }
}
