//! Silhouette edges of a mesh for one light (Crow 1977; weights after Bergeron 1986, as McCool 2000
//! section 1.3 states them).
//!
//! Each face gets a signed weight, and an edge's weight is the sum over its faces of the face weight times
//! the face's direction along the edge. This is the boundary of the 2-chain "faces that cast", so the
//! silhouette always closes up (weights sum to zero around every vertex), whatever the mesh:
//!
//! - **closed** meshes: the light-facing faces cast with weight 1, the others with 0. Manifold edges
//!   between a lit and an unlit face get weight 1; everything else cancels. These are the usual loops.
//! - **open or non-manifold** meshes (Bergeron): every face casts, turned to face the light (weight +1 when
//!   it faces the light, -1 when it faces away). Boundary edges get weight 1, shared silhouette edges
//!   weight 2, and shared edges between faces turned the same way cancel. The stencil count at a point is
//!   then the number of faces between it and the light.
//!
//! A silhouette edge `a -> b` runs the way the casting faces run along it after they were turned towards
//! the light; [`crate::geometry::volume`] extrudes it into the outward-facing quad `(b, a, a_inf, b_inf)`.

use rayon::prelude::*;

use super::LightSource;
use super::adjacency::{Adjacency, FaceUse};
use super::facing::{EDGES, FACES, Facing};

/// An oriented silhouette edge in welded vertices, with its multiplicity.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SilhouetteEdge {
    /// Start vertex (welded).
    pub a: u32,
    /// End vertex (welded).
    pub b: u32,
    /// How many times the side quad counts (1 for closed meshes; 1 or 2, more at non-manifold edges, for
    /// open ones).
    pub weight: u32,
    /// A face using the edge: the edge's connected component is this face's
    /// ([`Adjacency::components`]).
    pub face: u32,
}

/// How a mesh's faces cast (chosen from [`Adjacency::closed`] unless forced).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CastMode {
    /// Light-facing faces only, weight 1.
    Closed,
    /// Every face, turned towards the light (Bergeron).
    Bergeron,
}

impl CastMode {
    /// The right mode for a mesh: [`CastMode::Closed`] only when it is closed and consistently wound.
    #[must_use]
    pub fn for_mesh(adj: &Adjacency) -> Self {
        if adj.closed() { Self::Closed } else { Self::Bergeron }
    }
}

/// The silhouette of one mesh for one light, and the signed cast weight of every face.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Silhouette {
    /// Oriented silhouette edges.
    pub edges: Vec<SilhouetteEdge>,
    /// Per face: +1 casts as wound, -1 casts turned around, 0 does not cast.
    pub face_weights: Vec<i8>,
}

impl Silhouette {
    /// Sum of the edge weights: the number of side quads the volume will have.
    #[must_use]
    pub fn weighted_len(&self) -> usize {
        self.edges.iter().map(|e| e.weight as usize).sum()
    }
}

/// Signed cast weight of every face for the light (see the module notes). A face whose plane holds the
/// light (or a degenerate face, whose plane is zero) casts nothing: weight 0.
#[must_use]
pub fn face_weights(adj: &Adjacency, light: LightSource, mode: CastMode) -> Vec<i8> {
    weights(adj, light, mode, &adj.facing_runs().facing(light))
}

/// [`face_weights`], given the facing of each run of faces: a decided run's faces all take its weight,
/// and only the faces of the others are tested.
fn weights(adj: &Adjacency, light: LightSource, mode: CastMode, facing: &[Facing]) -> Vec<i8> {
    let unlit: i8 = match mode {
        CastMode::Closed => 0,
        CastMode::Bergeron => -1,
    };
    // +1 facing the light, `unlit` facing away, 0 in its plane.
    let sign = move |f: f32| i8::from(f > 0.0) + i8::from(f < 0.0) * unlit;
    let mut weights = vec![0i8; adj.planes().len()];
    weights.par_chunks_mut(FACES).zip(adj.planes().par_chunks(FACES)).zip(facing).with_min_len(64).for_each(
        |((w, planes), facing)| match facing {
            Facing::Front => w.fill(1),
            Facing::Back => w.fill(unlit),
            Facing::Mixed => {
                for (w, &p) in w.iter_mut().zip(planes) {
                    *w = sign(light.facing(p));
                }
            }
        },
    );
    weights
}

fn oriented(v: [u32; 2], w: i32, face: u32) -> Option<SilhouetteEdge> {
    match w {
        0 => None,
        w if w > 0 => Some(SilhouetteEdge { a: v[0], b: v[1], weight: w as u32, face }),
        w => Some(SilhouetteEdge { a: v[1], b: v[0], weight: w.unsigned_abs(), face }),
    }
}

/// Silhouette edges of the mesh for the light, in `mode` (see [`CastMode::for_mesh`]).
#[must_use]
pub fn silhouette(adj: &Adjacency, light: LightSource, mode: CastMode) -> Silhouette {
    let runs = adj.facing_runs();
    let facing = runs.facing(light);
    let face_weights = weights(adj, light, mode, &facing);
    let facing = &facing;
    let w = &face_weights;
    let use_weight = |u: FaceUse| i32::from(w[u.face() as usize]) * u.direction();
    // Manifold edges: the first face runs along the edge, the second against it. A run of edges whose
    // faces all lie in runs of one decided facing holds no silhouette edge and is not read; in the others,
    // only the face pairs are read until an edge turns out to be a silhouette.
    let mut edges: Vec<SilhouetteEdge> =
        adj.manifold_faces()
            .par_chunks(EDGES)
            .zip(adj.manifold_edges().par_chunks(EDGES))
            .enumerate()
            .with_min_len(256)
            .filter(|(run, _)| !runs.edges_uniform(*run, facing))
            .flat_map_iter(|(_, (faces, edges))| {
                faces.iter().zip(edges).filter_map(|(&[f0, f1], e)| {
                    oriented(e.v, i32::from(w[f0 as usize]) - i32::from(w[f1 as usize]), f0)
                })
            })
            .collect();
    edges.extend(
        adj.boundary_edges()
            .iter()
            .zip(adj.boundary_faces())
            .filter_map(|(e, &u)| oriented(e.v, use_weight(u), u.face())),
    );
    edges.extend(
        adj.complex_edges()
            .iter()
            .filter_map(|e| oriented(e.v, e.uses.iter().map(|&u| use_weight(u)).sum(), e.uses[0].face())),
    );
    Silhouette { edges, face_weights }
}

#[cfg(test)]
mod tests {
    use std::collections::HashMap;

    use glam::Vec3;

    use super::*;
    use crate::procedural;

    fn cube() -> Adjacency {
        Adjacency::build(&procedural::cuboid(Vec3::splat(2.0)).expect("shape"))
    }

    /// Net weighted out-degree of every vertex: zero everywhere for a closed loop set.
    fn net_flow(edges: &[SilhouetteEdge]) -> HashMap<u32, i64> {
        let mut flow = HashMap::new();
        for e in edges {
            *flow.entry(e.a).or_insert(0) += i64::from(e.weight);
            *flow.entry(e.b).or_insert(0) -= i64::from(e.weight);
        }
        flow
    }

    #[test]
    fn cube_from_a_corner_has_one_loop_of_six() {
        let adj = cube();
        let s = silhouette(&adj, LightSource::Point(Vec3::new(5.0, 6.0, 7.0)), CastMode::Closed);
        assert_eq!(s.edges.len(), 6);
        assert!(s.edges.iter().all(|e| e.weight == 1));
        assert!(net_flow(&s.edges).values().all(|&f| f == 0));
        // One loop: following a -> b from any edge visits all six edges before returning.
        let next: HashMap<u32, u32> = s.edges.iter().map(|e| (e.a, e.b)).collect();
        assert_eq!(next.len(), 6);
        let start = s.edges[0].a;
        let (mut v, mut steps) = (next[&start], 1);
        while v != start {
            v = next[&v];
            steps += 1;
        }
        assert_eq!(steps, 6);
    }

    #[test]
    fn cube_face_on_directional_has_four() {
        let s = silhouette(&cube(), LightSource::Directional(Vec3::NEG_Y), CastMode::Closed);
        assert_eq!(s.edges.len(), 4);
        assert!(net_flow(&s.edges).values().all(|&f| f == 0));
        // The top face is lit: the loop runs the way the top face winds (counter-clockwise from above).
        for e in &s.edges {
            let (a, b) = (cube().positions()[e.a as usize], cube().positions()[e.b as usize]);
            assert_eq!(a.y, 1.0);
            let mid = (a + b) * 0.5;
            let along = b - a;
            // Counter-clockwise seen from +Y: the outward direction (mid) is to the right of the edge.
            assert!(along.cross(Vec3::new(mid.x, 0.0, mid.z)).y < 0.0);
        }
    }

    #[test]
    fn open_plane_casts_with_boundary_weight_one() {
        let adj = Adjacency::build(&procedural::plane(2.0, 2.0).expect("shape"));
        assert_eq!(CastMode::for_mesh(&adj), CastMode::Bergeron);
        let above = silhouette(&adj, LightSource::Point(Vec3::new(0.0, 3.0, 0.0)), CastMode::Bergeron);
        assert_eq!(above.edges.len(), 4);
        assert!(above.edges.iter().all(|e| e.weight == 1));
        // Lit from below, the plane casts all the same (turned around): same edges, reversed.
        let below = silhouette(&adj, LightSource::Point(Vec3::new(0.0, -3.0, 0.0)), CastMode::Bergeron);
        assert_eq!(below.edges.len(), 4);
        for e in &below.edges {
            assert!(above.edges.iter().any(|f| f.a == e.b && f.b == e.a));
        }
    }

    #[test]
    fn open_shared_silhouette_edges_weigh_two() {
        // A folded strip: two faces sharing an edge, one facing the light, one facing away.
        let p = vec![Vec3::ZERO, Vec3::X, Vec3::new(0.5, 1.0, 0.0), Vec3::new(0.5, 0.2, -1.0)];
        let mesh = crate::Mesh::new(p, vec![[0, 1, 2], [1, 0, 3]]).unwrap();
        let adj = Adjacency::build(&mesh);
        let s = silhouette(&adj, LightSource::Point(Vec3::new(0.5, 0.3, 5.0)), CastMode::Bergeron);
        assert_eq!(s.face_weights, vec![1, -1]);
        let shared = s.edges.iter().find(|e| (e.a.min(e.b), e.a.max(e.b)) == (0, 1)).unwrap();
        assert_eq!(shared.weight, 2);
        assert!(net_flow(&s.edges).values().all(|&f| f == 0));
    }

    /// Each face's weight tested on its own, as the module notes define it.
    fn face_by_face(adj: &Adjacency, light: LightSource, mode: CastMode) -> Vec<i8> {
        let unlit = if mode == CastMode::Closed { 0 } else { -1 };
        let sign = |f: f32| {
            if f > 0.0 {
                1
            } else if f < 0.0 {
                unlit
            } else {
                0
            }
        };
        adj.planes().iter().map(|&p| sign(light.facing(p))).collect()
    }

    /// Lights off the mesh, on its vertices (in the planes of the faces around each), and parallel light
    /// along its edges (in the planes of the faces beside each), for a mesh of size `scale`.
    fn lights(adj: &Adjacency, scale: f32) -> Vec<LightSource> {
        let mut lights = vec![
            LightSource::Point(Vec3::new(2.0, 4.0, 1.5) * scale),
            LightSource::Point(Vec3::new(0.0, 1.5, 0.0) * scale),
            LightSource::Point(Vec3::new(0.1, -0.2, 0.05) * scale),
            LightSource::Directional(Vec3::new(0.3, -0.8, 0.2)),
            LightSource::Directional(Vec3::NEG_Y),
        ];
        let p = adj.positions();
        for &[a, b] in adj.manifold_edges().iter().step_by(997).map(|e| &e.v) {
            lights.push(LightSource::Point(p[a as usize]));
            lights.push(LightSource::Directional(p[b as usize] - p[a as usize]));
        }
        lights
    }

    #[test]
    fn runs_decided_at_once_change_no_weight_and_no_edge() {
        // Sizes where the planes are ordinary, where their normals are subnormal, and where they overflow.
        let sphere = procedural::sphere(1.0, 96, 48).expect("a sphere");
        for scale in [1.0, 1e-18, 1e15, 1e25] {
            let m =
                glam::Mat4::from_scale(Vec3::splat(scale)) * glam::Mat4::from_translation(Vec3::new(0.3, -0.1, 0.2));
            let adj = Adjacency::build(&sphere.transformed(m));
            assert!(adj.closed());
            for light in lights(&adj, scale) {
                for mode in [CastMode::Closed, CastMode::Bergeron] {
                    let plain = face_by_face(&adj, light, mode);
                    assert_eq!(face_weights(&adj, light, mode), plain, "{light:?} at scale {scale}");
                    let edges: Vec<SilhouetteEdge> = adj
                        .manifold_edges()
                        .iter()
                        .zip(adj.manifold_faces())
                        .filter_map(|(e, &[f0, f1])| {
                            oriented(e.v, i32::from(plain[f0 as usize]) - i32::from(plain[f1 as usize]), f0)
                        })
                        .collect();
                    assert_eq!(silhouette(&adj, light, mode), Silhouette { edges, face_weights: plain });
                }
            }
        }
    }

    #[test]
    fn a_light_off_the_mesh_decides_most_runs_at_once() {
        // A run of 64 faces spans 29 degrees of a ring of this sphere.
        let adj = Adjacency::build(&procedural::sphere(1.0, 400, 200).expect("a sphere"));
        let facing = adj.facing_runs().facing(LightSource::Point(Vec3::new(2.0, 4.0, 1.5)));
        let mixed = facing.iter().filter(|&&f| f == Facing::Mixed).count();
        let edge_runs = adj.manifold_faces().len().div_ceil(EDGES);
        let skipped = (0..edge_runs).filter(|&r| adj.facing_runs().edges_uniform(r, &facing)).count();
        assert!(mixed * 4 < facing.len(), "{mixed} of {} face runs undecided", facing.len());
        assert!(skipped * 2 > edge_runs, "{skipped} of {edge_runs} edge runs skipped");
    }
}
