//! Smoothie construction (Chan, thesis 4.2 step 3), shared by both backends: from the casters' silhouette
//! edges (shadow-core's extraction) to triangles in a light projection's map space, each knowing what its
//! alpha is measured from.
//!
//! Everything is in map coordinates `uv` (`[0, 1]` across the map, y down, as
//! `shadow_core::light::LightProjection::uv_depth` gives them) with the light's NDC depth: `t`, the
//! smoothie size, is a distance in `uv` (the thesis's "normalized screen space"). A smoothie keeps the
//! depth of the silhouette it hangs from: it is a sheet at the blocker, extended outward.

use shadow_core::FrameInputs;
use shadow_core::geometry::adjacency::Adjacency;
use shadow_core::geometry::silhouette::Silhouette;
use shadow_core::glam::{Mat4, Vec2, Vec3};
use shadow_core::light::LightProjection;

/// What a smoothie triangle's alpha is measured from (before the remap): the linear ramp of an edge, or
/// the radial one of a corner (Fig. 4-6).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Ramp {
    /// A smoothie edge: alpha is the distance past the silhouette edge through `origin`, along the unit
    /// `outward` normal, over `t`.
    Edge {
        /// A point of the silhouette edge, in `uv`.
        origin: Vec2,
        /// The edge's unit normal pointing away from the blocker, in `uv`.
        outward: Vec2,
    },
    /// A smoothie corner: alpha is the distance from the silhouette vertex over `t`.
    Corner {
        /// The silhouette vertex, in `uv`.
        vertex: Vec2,
    },
}

impl Ramp {
    /// The linear alpha at map point `p`, clamped to `[0, 1]`.
    #[must_use]
    pub fn alpha(&self, p: Vec2, t: f32) -> f32 {
        let a = match *self {
            Self::Edge { origin, outward } => (p - origin).dot(outward),
            Self::Corner { vertex } => (p - vertex).length(),
        };
        (a / t).clamp(0.0, 1.0)
    }
}

/// One smoothie triangle: corners as `(u, v, NDC depth)` and its ramp.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SmoothieTriangle {
    /// Corners: map coordinates and the light's NDC depth.
    pub corners: [Vec3; 3],
    /// What its alpha is measured from.
    pub ramp: Ramp,
}

/// The smoothies of one light projection, and what was built.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Smoothies {
    /// Edges, then corners.
    pub triangles: Vec<SmoothieTriangle>,
    /// Silhouette edges seen by the projection (each gives one smoothie edge).
    pub edges: usize,
    /// Silhouette vertices with more than two silhouette edges (the thesis's special case).
    pub special_vertices: usize,
}

/// The largest angle one corner sector spans: its quad's far corner stays within `2 t` of the vertex.
const MAX_SECTOR: f32 = std::f32::consts::FRAC_PI_3;

/// A silhouette edge in map space: its ends (`uv` and depth) and its outward normal.
#[derive(Clone, Copy, Debug)]
struct MapEdge {
    ends: [Vec3; 2],
    outward: Vec2,
}

/// Builds the smoothies of the casters' `silhouettes` (from `FrameInputs::caster_silhouettes` for the
/// light) in one of its projections, of size `t` in `uv`.
///
/// The outward side of an edge comes from its orientation: shadow-core orients a silhouette edge the way
/// the light-facing faces run along it, counter-clockwise seen from the light, so the blocker lies to
/// its left in the light's NDC and outward is to its right (to its left in a mirrored instance, whose
/// faces wind the other way in world space).
#[must_use]
pub fn build(frame: &FrameInputs, silhouettes: &[(usize, Silhouette)], proj: &LightProjection, t: f32) -> Smoothies {
    let mut out = Smoothies::default();
    for (i, silhouette) in silhouettes {
        let inst = &frame.instances[*i];
        let adj = &inst.adjacency;
        let world = |v: u32| inst.world_from_local.transform_point3(adj.positions()[v as usize]);
        let in_front = |p: Vec3| (proj.clip_from_world * p.extend(1.0)).w > 0.0;
        let map = |p: Vec3| {
            let (uv, depth) = proj.uv_depth(p);
            uv.extend(depth)
        };
        // Per welded vertex: the map edges that end there.
        let mut at_vertex: std::collections::HashMap<u32, Vec<MapEdge>> = std::collections::HashMap::new();
        for e in &silhouette.edges {
            let (a, b) = (world(e.a), world(e.b));
            if !in_front(a) || !in_front(b) {
                continue;
            }
            let (ma, mb) = (map(a), map(b));
            let along = (mb - ma).truncate();
            if along.length_squared() == 0.0 {
                continue;
            }
            // Right of a -> b in NDC (y up) is (dy, -dx); uv flips y, so in uv it is (-dy, dx).
            let right = Vec2::new(-along.y, along.x).normalize();
            let outward = if inst.mirrored { -right } else { right };
            let edge = MapEdge { ends: [ma, mb], outward };
            push_edge(&mut out.triangles, &edge, t);
            out.edges += 1;
            at_vertex.entry(e.a).or_default().push(edge);
            at_vertex.entry(e.b).or_default().push(edge);
        }
        for (v, edges) in &at_vertex {
            let vertex = map(world(*v));
            match edges.len() {
                2 => push_corner(&mut out.triangles, vertex, edges[0].outward, edges[1].outward, t),
                n if n > 2 => {
                    out.special_vertices += 1;
                    let normal = vertex_normal(adj, *v, inst.world_from_local);
                    push_special_corner(&mut out.triangles, vertex, edges, world(*v), normal, proj, t);
                }
                _ => {}
            }
        }
    }
    out
}

/// The centroid of the casters' silhouette edges' midpoints, in world space (`None` without edges): where
/// the blockers are, as far as smoothies are concerned.
#[must_use]
pub fn silhouette_centre(frame: &FrameInputs, silhouettes: &[(usize, Silhouette)]) -> Option<Vec3> {
    let (mut sum, mut n) = (Vec3::ZERO, 0usize);
    for (i, silhouette) in silhouettes {
        let inst = &frame.instances[*i];
        let at = |v: u32| inst.world_from_local.transform_point3(inst.adjacency.positions()[v as usize]);
        for e in &silhouette.edges {
            sum += (at(e.a) + at(e.b)) * 0.5;
            n += 1;
        }
    }
    (n > 0).then(|| sum / n as f32)
}

/// The smoothie edge: the silhouette edge extended outward by `t` into a rectangle (two triangles), at
/// the silhouette's depths.
fn push_edge(out: &mut Vec<SmoothieTriangle>, e: &MapEdge, t: f32) {
    let [a, b] = e.ends;
    let shift = (e.outward * t).extend(0.0);
    let ramp = Ramp::Edge { origin: a.truncate(), outward: e.outward };
    out.push(SmoothieTriangle { corners: [a, b, b + shift], ramp });
    out.push(SmoothieTriangle { corners: [a, b + shift, a + shift], ramp });
}

/// The corner of a vertex with two silhouette edges: the wedge between their outward normals, the smaller
/// way round, covered by quads whose far corners are where neighbouring directions' lines at distance `t`
/// meet, so the disc of radius `t` about the vertex is covered there (Fig. 4-6). Where the edges turn
/// inward the wedge lies inside their smoothies, whose lower alpha wins the minimum.
fn push_corner(out: &mut Vec<SmoothieTriangle>, vertex: Vec3, n0: Vec2, n1: Vec2, t: f32) {
    let angle = n0.angle_to(n1);
    let sectors = (angle.abs() / MAX_SECTOR).ceil().max(1.0) as usize;
    let ramp = Ramp::Corner { vertex: vertex.truncate() };
    let dir = |k: usize| Vec2::from_angle(angle * k as f32 / sectors as f32).rotate(n0);
    for k in 0..sectors {
        let (d0, d1) = (dir(k), dir(k + 1));
        let far = (d0 + d1) / (1.0 + d0.dot(d1));
        let at = |d: Vec2| vertex + (d * t).extend(0.0);
        out.push(SmoothieTriangle { corners: [vertex, at(d0), at(far)], ramp });
        out.push(SmoothieTriangle { corners: [vertex, at(far), at(d1)], ramp });
    }
}

/// The thesis's special case, a vertex with more than two silhouette edges: the adjacent faces' normals
/// averaged into `normal`, projected into the map and given length `t`, is the point every adjacent
/// smoothie edge's outer corner at the vertex is joined to by a triangle. A normal that projects to a
/// point (it runs along the light's rays) leaves the vertex with its edges only.
fn push_special_corner(
    out: &mut Vec<SmoothieTriangle>,
    vertex: Vec3,
    edges: &[MapEdge],
    world: Vec3,
    normal: Vec3,
    proj: &LightProjection,
    t: f32,
) {
    let (tip, _) = proj.uv_depth(world + normal * 1e-3 * world.length().max(1.0));
    let along = tip - vertex.truncate();
    if along.length_squared() <= f32::EPSILON * f32::EPSILON {
        return;
    }
    let apex = vertex + (along.normalize() * t).extend(0.0);
    let ramp = Ramp::Corner { vertex: vertex.truncate() };
    for e in edges {
        let outer = vertex + (e.outward * t).extend(0.0);
        out.push(SmoothieTriangle { corners: [vertex, outer, apex], ramp });
    }
}

/// The average of the unit normals of the faces around welded vertex `v`, in world space.
fn vertex_normal(adj: &Adjacency, v: u32, world_from_local: Mat4) -> Vec3 {
    let sum: Vec3 = adj
        .triangles()
        .iter()
        .zip(adj.planes())
        .filter(|(tri, _)| tri.contains(&v))
        .map(|(_, plane)| plane.truncate().normalize_or_zero())
        .sum();
    (shadow_core::affine::normal_matrix(world_from_local) * sum).normalize_or_zero()
}

#[cfg(test)]
mod tests {
    use shadow_core::glam::{Mat4, Vec2, Vec3};
    use shadow_core::procedural;
    use shadow_core::scene::{Camera, Light, Material, Scene};

    use super::*;

    /// A frame of one caster under a spot light straight above it.
    fn frame_of(mesh: shadow_core::Mesh, transform: Mat4) -> FrameInputs {
        let mut scene = Scene::new();
        let mesh = scene.add_mesh(mesh);
        let material = scene.add_material(Material::colored("grey", Vec3::splat(0.5)));
        scene.add_instance("caster", mesh, material, transform).unwrap();
        let camera = scene.add_camera(Camera::look_at(Vec3::new(0.0, 3.0, 4.0), Vec3::ZERO, 45.0));
        scene.add_light(Light::spot(Vec3::new(0.0, 4.0, 0.0), Vec3::ZERO, 60.0));
        FrameInputs::from_scene(&scene, camera).unwrap()
    }

    fn smoothies_of(frame: &FrameInputs, t: f32) -> (Smoothies, Vec2) {
        let light = frame.light_view(&frame.lights[0]).unwrap();
        let silhouettes = frame.caster_silhouettes(&light);
        let proj = &light.projections[0];
        (build(frame, &silhouettes, proj, t), proj.uv_depth(Vec3::ZERO).0)
    }

    #[test]
    fn edges_extend_away_from_the_blocker_and_corners_close_the_gaps() {
        // A cube seen from above: four silhouette edges (the top face's outline seen from the light), each
        // extended away from the cube's centre, and four convex corners.
        for (name, transform) in [("plain", Mat4::IDENTITY), ("mirrored", Mat4::from_scale(Vec3::new(-1.0, 1.0, 1.0)))]
        {
            let frame = frame_of(procedural::cuboid(Vec3::splat(1.0)).expect("shape"), transform);
            let (s, centre) = smoothies_of(&frame, 0.02);
            assert_eq!(s.edges, 4, "{name}");
            for tri in &s.triangles {
                if let Ramp::Edge { origin, outward } = tri.ramp {
                    assert!((origin - centre).dot(outward) > 0.0, "{name}: an edge extends inward");
                    // The far side of the rectangle is t out.
                    let far = tri.corners.iter().map(|c| (c.truncate() - origin).dot(outward)).fold(0.0, f32::max);
                    assert!((far - 0.02).abs() < 1e-5, "{name}: width {far}");
                }
            }
            // Every point at distance t / 2 around the outline's corner is covered by some smoothie.
            let corner_triangles = s.triangles.iter().filter(|t| matches!(t.ramp, Ramp::Corner { .. })).count();
            assert!(corner_triangles >= 8, "{name}: {corner_triangles} corner triangles");
            let outline: Vec<Vec2> = s
                .triangles
                .iter()
                .filter_map(|t| match t.ramp {
                    Ramp::Corner { vertex } => Some(vertex),
                    Ramp::Edge { .. } => None,
                })
                .collect();
            for &v in &outline {
                let away = (v - centre).normalize();
                let p = v + away * 0.01;
                let covered = s.triangles.iter().any(|t| inside(p, t.corners.map(|c| c.truncate())));
                assert!(covered, "{name}: the diagonal past a corner is not covered");
            }
        }
    }

    /// Whether `p` lies in the triangle `c` (either winding).
    fn inside(p: Vec2, c: [Vec2; 3]) -> bool {
        let side = |a: Vec2, b: Vec2| (b - a).perp_dot(p - a);
        let s = [side(c[0], c[1]), side(c[1], c[2]), side(c[2], c[0])];
        s.iter().all(|&v| v >= 0.0) || s.iter().all(|&v| v <= 0.0)
    }

    #[test]
    fn vertices_with_more_than_two_silhouette_edges_join_their_edges_to_the_averaged_normal() {
        // Two cubes sharing one corner vertex diagonally make a vertex with four silhouette edges: the
        // thesis's special case, one triangle per adjacent edge to the apex t out along the normal.
        let a = procedural::cuboid(Vec3::splat(1.0))
            .expect("shape")
            .transformed(Mat4::from_translation(Vec3::new(0.5, 0.0, 0.5)));
        let b = procedural::cuboid(Vec3::splat(1.0))
            .expect("shape")
            .transformed(Mat4::from_translation(Vec3::new(-0.5, 0.0, -0.5)));
        let mesh = shadow_core::Mesh::merged([&a, &b]).unwrap();
        let frame = frame_of(mesh, Mat4::IDENTITY);
        let (s, _) = smoothies_of(&frame, 0.02);
        assert!(s.special_vertices >= 1, "no special vertex: {s:?}");
    }

    #[test]
    fn ramps_run_from_the_silhouette_to_t() {
        let edge = Ramp::Edge { origin: Vec2::ZERO, outward: Vec2::X };
        assert_eq!(edge.alpha(Vec2::new(0.05, 3.0), 0.1), 0.5);
        assert_eq!(edge.alpha(Vec2::new(-0.05, 0.0), 0.1), 0.0);
        assert_eq!(edge.alpha(Vec2::new(0.5, 0.0), 0.1), 1.0);
        let corner = Ramp::Corner { vertex: Vec2::ZERO };
        assert!((corner.alpha(Vec2::new(0.03, 0.04), 0.1) - 0.5).abs() < 1e-6);
    }
}
