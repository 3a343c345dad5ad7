//! Property tests of adjacency, silhouettes and extrusion on random meshes (DESIGN 9).

use std::collections::HashMap;

use glam::{Vec2, Vec3};
use proptest::prelude::*;

use super::LightSource;
use super::adjacency::Adjacency;
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
