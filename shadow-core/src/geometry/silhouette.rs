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
    let unlit: i8 = match mode {
        CastMode::Closed => 0,
        CastMode::Bergeron => -1,
    };
    // +1 facing the light, `unlit` facing away, 0 in its plane: written without a branch, and with the
    // light's kind matched once, not per face.
    let sign = |f: f32| i8::from(f > 0.0) + i8::from(f < 0.0) * unlit;
    let mut weights = vec![0i8; adj.planes().len()];
    weights.par_chunks_mut(8192).zip(adj.planes().par_chunks(8192)).for_each(|(w, planes)| match light {
        LightSource::Point(l) => {
            for (w, p) in w.iter_mut().zip(planes) {
                *w = sign(p.truncate().dot(l) + p.w);
            }
        }
        LightSource::Directional(d) => {
            for (w, p) in w.iter_mut().zip(planes) {
                *w = sign(-p.truncate().dot(d));
            }
        }
    });
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
    let face_weights = face_weights(adj, light, mode);
    let w = &face_weights;
    let use_weight = |u: FaceUse| i32::from(w[u.face() as usize]) * u.direction();
    // Manifold edges: the first face runs along the edge, the second against it. Only the face pairs are
    // read until an edge turns out to be a silhouette.
    let mut edges: Vec<SilhouetteEdge> = adj
        .manifold_faces()
        .par_chunks(16384)
        .zip(adj.manifold_edges().par_chunks(16384))
        .flat_map_iter(|(faces, edges)| {
            faces.iter().zip(edges).filter_map(|(&[f0, f1], e)| {
                let weight = i32::from(w[f0 as usize]) - i32::from(w[f1 as usize]);
                if weight == 0 { None } else { oriented(e.v, weight, f0) }
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
}
