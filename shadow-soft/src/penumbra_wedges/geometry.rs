//! The geometry both backends draw (shared, built on the host): per silhouette edge of the casters (found
//! from the light's centre by shadow-core), its hard volume's side quad and its penumbra wedge, and the
//! light centre's count at the eye.
//!
//! **Side quads** `(b, a, a_inf, b_inf)`, extruded from the centre to infinity as shadow-core's volumes
//! are: counted z-pass from the eye, they give the hard shadow volume's count at every receiver. Each
//! query draws them half a pixel of its view larger than they are ([`WedgeGeometry::side_quads`]); which
//! pixels they hold is decided per fragment.
//!
//! **Wedges.** The receivers for which edge `a -> b` cuts the light's disc are those behind the edge from
//! some point of the sphere. They lie inside four planes, each through the edge or one of its ends and
//! tangent to the sphere with the sphere behind it (a plane at distance `R` from the centre, the light on
//! its outer side, holds every line from the sphere through a point of the plane on its inner side beyond
//! that point):
//!
//! - the front and back planes, through the edge's line;
//! - a side plane at each end, turned from the plane through the end and the centre by the light's
//!   angular radius there, away from the edge (it holds the end's cone of shadow, so the wedge is
//!   conservative where a plane through the end alone would cut the cone).
//!
//! Their intersection is a convex polyhedron with the edge as its apex and four rays to infinity; drawn
//! with back faces only, against the G-buffer's depth with the test "greater", it reaches every receiver
//! inside it exactly once. The paper's wedges are the same four planes; here the far cap lies at
//! infinity, as the volumes' does.
//!
//! An edge whose line passes through the light (no plane through it is tangent) has no wedge: it is left
//! out, and counted; its hard edge stays.

use std::cmp::Ordering;
use std::collections::BTreeMap;

use shadow_core::FrameInputs;
use shadow_core::geometry::adjacency::Adjacency;
use shadow_core::geometry::silhouette::Silhouette;
use shadow_core::glam::{Mat4, Vec3, Vec4};
use shadow_core::scene::Camera;
use shadow_core::technique::settings::DepthBias;

use super::coverage::SphereLight;

/// A silhouette edge as the wedges use it: its ends in world space, oriented as shadow-core orients them
/// (the light-facing faces run along it), and its weight, negative in a mirrored instance, whose faces
/// wind the other way in world space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WedgeEdge {
    /// Start.
    pub a: Vec3,
    /// End.
    pub b: Vec3,
    /// Signed multiplicity.
    pub weight: f32,
    /// The sum its terms go to.
    pub layer: Layer,
    /// Its wedge's planes ([`wedge_planes`]; all zero where it has none, so it is never drawn).
    pub planes: [Vec4; 4],
}

/// The sums a receiver's occluded share is made of. A closed mesh casts from its light-facing faces
/// alone. An open one casts, as Bergeron's rule has the volumes do, from every face turned towards the
/// light; but where a ray crosses it twice (both walls of the teapot's body) that counts the light twice
/// over the penumbra. So its light-facing faces and its faces turned around are kept apart: each is a
/// boundary of faces, so each sum is an exact winding integral of its own, and the receiver takes the
/// larger (a single-sided sheet is in one of them; a ray through an opening that the one misses, the
/// other holds).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Layer {
    /// Closed meshes' silhouettes.
    Closed = 0,
    /// Open meshes' light-facing faces, as wound.
    Facing = 1,
    /// Open meshes' faces that face away, turned around.
    Turned = 2,
}

/// How many [`Layer`]s there are.
pub const LAYERS: usize = 3;

/// What both backends draw for one light.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct WedgeGeometry {
    /// The casters' silhouette edges.
    pub edges: Vec<WedgeEdge>,
    /// The wedges' faces, wound counter-clockwise seen from outside, homogeneous as the quads.
    pub hulls: Vec<[Vec4; 3]>,
    /// The edge of each wedge face.
    pub hull_edges: Vec<u32>,
    /// The casters' silhouettes, for the count at an eye.
    pub silhouettes: Vec<(usize, Silhouette)>,
    /// The light's centre.
    pub centre: Vec3,
    /// Edges whose line passes through the light: no wedge.
    pub without_wedge: usize,
}

/// How much larger than the side quads they cover the quads are drawn, in pixels of the view: the
/// fragment decides exactly which pixels a quad holds (`coverage::crosses_quad`), the rasterizer only has
/// to reach them, whatever its snapping of corners to its sub-pixel grid (Vulkan allows a grid as coarse
/// as a sixteenth of a pixel). A margin in proportion to the quad instead leaves the thin quads of short
/// edges, a fraction of a pixel wide, within that snapping of the pixels they hold, and a pixel they lose
/// is a full step of the count: a dark speck in the light.
pub const QUAD_MARGIN_PIXELS: f32 = 0.5;

/// How large a view's pixels are where the side quads are drawn ([`WedgeGeometry::side_quads`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PixelScale {
    /// The eye.
    pub eye: Vec3,
    /// A pixel's width per unit of distance from the eye at the view's centre, `2 tan(fov_y / 2) / height`
    /// (pixels off the centre subtend less, so a width of this many holds at least as many there).
    pub per_distance: f32,
}

impl PixelScale {
    /// The pixels of `camera`'s view `height` pixels high.
    #[must_use]
    pub fn of(camera: &Camera, height: u32) -> Self {
        Self { eye: camera.eye, per_distance: 2.0 * (camera.fov_y * 0.5).tan() / height.max(1) as f32 }
    }
}

/// The depth bias the side quads are drawn with against the G-buffer's depth, test "less": a quad that
/// meets the eye's ray behind the receiver adds nothing (the receiver and the eye are on one side of it),
/// so the test only saves the work there; pulled this far towards the eye (Vulkan's units of the
/// format's resolution, and of the quad's depth slope per pixel), it keeps every fragment whose crossing
/// is within rounding of the receiver, where the fragment's own triple products decide.
pub const QUAD_DEPTH_BIAS: DepthBias = DepthBias { constant: -64.0, slope: -4.0, clamp: 0.0 };

/// Faces per wedge: two each for the front and back planes and the cap at infinity, one per end.
pub const HULL_TRIANGLES: usize = 8;

impl WedgeGeometry {
    /// The quads and wedges of `silhouettes` (from `FrameInputs::caster_silhouettes`).
    #[must_use]
    pub fn build(frame: &FrameInputs, silhouettes: Vec<(usize, Silhouette)>, light: SphereLight) -> Self {
        let mut out = Self { centre: light.centre, ..Self::default() };
        for (i, silhouette) in &silhouettes {
            let inst = &frame.instances[*i];
            let adj = &inst.adjacency;
            let at = |v: u32| inst.world_from_local.transform_point3(adj.positions()[v as usize]);
            let sign = if inst.mirrored { -1.0 } else { 1.0 };
            let chains = if adj.closed() {
                vec![(Layer::Closed, silhouette.edges.iter().map(|e| (e.a, e.b, e.weight)).collect())]
            } else {
                let faces = &silhouette.face_weights;
                vec![(Layer::Facing, boundary(adj, faces, 1)), (Layer::Turned, boundary(adj, faces, -1))]
            };
            for (layer, chain) in chains {
                for (a, b, weight) in chain {
                    out.push(at(a), at(b), (sign * weight as f32, layer), light);
                }
            }
        }
        out.silhouettes = silhouettes;
        out
    }

    /// The light centre's count at `eye` in each [`Layer`], what z-pass counting starts from: the casting
    /// faces of `frame` that the segment from the eye to the centre passes through.
    #[must_use]
    pub fn eye_counts(&self, frame: &FrameInputs, eye: Vec3) -> [f32; LAYERS] {
        let mut counts = [0.0; LAYERS];
        for (i, silhouette) in &self.silhouettes {
            crossings(frame, *i, silhouette, (eye, self.centre), &mut counts);
        }
        counts
    }

    fn push(&mut self, a: Vec3, b: Vec3, (weight, layer): (f32, Layer), light: SphereLight) {
        let index = self.edges.len() as u32;
        let planes = wedge_planes(a, b, light);
        self.edges.push(WedgeEdge { a, b, weight, layer, planes: planes.unwrap_or([Vec4::ZERO; 4]) });
        match planes {
            Some(planes) => {
                self.hulls.extend(faces(a, b, light, planes));
                self.hull_edges.extend([index; HULL_TRIANGLES]);
            }
            None => self.without_wedge += 1,
        }
    }
}

impl WedgeGeometry {
    /// Each edge's side quad `(b, a, a_inf, b_inf)` as two triangles of homogeneous world points (w = 0
    /// at infinity), triangles `2 i` and `2 i + 1` edge `i`'s, drawn [`QUAD_MARGIN_PIXELS`] larger than
    /// it is in the view of `pixels`.
    #[must_use]
    pub fn side_quads(&self, pixels: PixelScale) -> Vec<[Vec4; 3]> {
        let mut quads = Vec::with_capacity(2 * self.edges.len());
        for e in &self.edges {
            quads.extend(side_quad(e.a, e.b, self.centre, pixels));
        }
        quads
    }
}

/// The side quad of edge `a -> b` from a light centred at `c`, grown by [`QUAD_MARGIN_PIXELS`] in the view
/// of `pixels`: the edge moved towards the light, and each end's ray to infinity moved outwards, by a
/// margin of that many pixels at the end's distance from the eye or from the light, whichever is larger.
/// Along an end's ray, `s` times its distance from the light beyond the end, the ray's shift grows to
/// `(1 + s)` margins while the point's distance from the eye grows by at most `s` times that distance, so
/// the margin holds along the whole ray, out to the ray's direction at infinity.
fn side_quad(a: Vec3, b: Vec3, c: Vec3, pixels: PixelScale) -> [[Vec4; 3]; 2] {
    let grown = |v: Vec3, other: Vec3| {
        let margin = QUAD_MARGIN_PIXELS * pixels.per_distance * (v - pixels.eye).length().max((v - c).length());
        // Square to the end's ray, away from the other end; square to the edge, towards the light.
        let out = (v - other).reject_from(v - c).normalize_or_zero();
        let toward = (c - v).reject_from(other - v).normalize_or_zero();
        // Where the ray moved out meets the edge moved towards the light: back along the ray by as much
        // as brings the corner `margin` nearer the light than the edge.
        // (Where the light is nearly on the edge's line that would be past half way to the light; there
        // the ends move out and towards the light alone.)
        let back = margin * (1.0 - out.dot(toward)) / (c - v).dot(toward);
        if (0.0..=0.5).contains(&back) { v + out * margin + (c - v) * back } else { v + (out + toward) * margin }
    };
    let (qa, qb) = (grown(a, b), grown(b, a));
    let (a_inf, b_inf) = ((qa - c).extend(0.0), (qb - c).extend(0.0));
    [[qb.extend(1.0), qa.extend(1.0), a_inf], [qb.extend(1.0), a_inf, b_inf]]
}

/// A plane through `point` with unit normal `n`, as `(n, -n . point)`: positive on the inner side.
fn plane(n: Vec3, point: Vec3) -> Vec4 {
    n.extend(-n.dot(point))
}

/// The four planes bounding the wedge of edge `a -> b` (front, back, side at `a`, side at `b`), inner
/// sides positive; `None` when the edge's line passes through the light.
#[must_use]
pub fn wedge_planes(a: Vec3, b: Vec3, light: SphereLight) -> Option<[Vec4; 4]> {
    let (c, radius) = (light.centre, light.radius);
    let along = (b - a).try_normalize()?;
    let to_c = c - a;
    let off_line = to_c - along * to_c.dot(along);
    let rho = off_line.length();
    if rho <= radius * (1.0 + 1e-4) || (c - b).length() <= radius {
        return None;
    }
    // Through the line: n = alpha e + beta f with n . (c - a) = -radius.
    let e = off_line / rho;
    let f = along.cross(e);
    let alpha = -radius / rho;
    let beta = (1.0 - alpha * alpha).sqrt();
    let front = plane(e * alpha + f * beta, a);
    let back = plane(e * alpha - f * beta, a);
    // Through an end: towards the light by -radius / distance, the rest square to it, leaning along the
    // edge (inward).
    let end = |p: Vec3, inward: Vec3| {
        let to_c = c - p;
        let dist = to_c.length();
        let axis = to_c / dist;
        let across = (inward - axis * inward.dot(axis)).normalize_or_zero();
        let k = radius / dist;
        plane(-axis * k + across * (1.0 - k * k).sqrt(), p)
    };
    Some([front, back, end(a, along), end(b, -along)])
}

/// The faces of edge `a -> b`'s wedge, outward and counter-clockwise; `None` as for [`wedge_planes`].
#[must_use]
pub fn wedge(a: Vec3, b: Vec3, light: SphereLight) -> Option<[[Vec4; 3]; HULL_TRIANGLES]> {
    wedge_planes(a, b, light).map(|planes| faces(a, b, light, planes))
}

/// The faces of the wedge of edge `a -> b` bounded by `planes` (front, back, side at `a`, side at `b`).
fn faces(
    a: Vec3,
    b: Vec3,
    light: SphereLight,
    [front, back, side_a, side_b]: [Vec4; 4],
) -> [[Vec4; 3]; HULL_TRIANGLES] {
    // The rays where the side planes meet the front and back planes, pointing away from the light.
    let ray = |p1: Vec4, p2: Vec4, from: Vec3| {
        let d = p1.truncate().cross(p2.truncate()).normalize();
        let d = if d.dot(from - light.centre) < 0.0 { -d } else { d };
        d.extend(0.0)
    };
    let (fa, ba) = (ray(front, side_a, a), ray(back, side_a, a));
    let (fb, bb) = (ray(front, side_b, b), ray(back, side_b, b));
    let (a4, b4) = (a.extend(1.0), b.extend(1.0));
    // A point strictly inside: beyond the edge's middle along the rays' mean.
    let mean = (fa + ba + fb + bb).truncate().normalize();
    let inner = ((a + b) * 0.5 + mean * (a - b).length().max(1.0)).extend(1.0);
    let faces = [
        [a4, b4, fb],
        [a4, fb, fa],
        [a4, b4, bb],
        [a4, bb, ba],
        [a4, fa, ba],
        [b4, fb, bb],
        [fa, fb, bb],
        [fa, bb, ba],
    ];
    // Counter-clockwise from outside: the interior point lies behind each face, which for homogeneous
    // points (w >= 0) is a positive determinant of the face's corners and the point.
    faces.map(|[p, q, r]| if Mat4::from_cols(p, q, r, inner).determinant() > 0.0 { [p, q, r] } else { [p, r, q] })
}

/// The boundary of an open mesh's faces whose cast weight is `side` (1: facing the light, as wound; -1:
/// facing away, turned around): oriented edges in welded vertices with their multiplicity, in a fixed
/// order.
fn boundary(adj: &Adjacency, weights: &[i8], side: i8) -> Vec<(u32, u32, u32)> {
    // Per undirected edge (lower vertex first), the sum of the faces running along it minus those
    // running back.
    let mut sums: BTreeMap<(u32, u32), i32> = BTreeMap::new();
    for (tri, _) in adj.triangles().iter().zip(weights).filter(|&(_, &w)| w == side) {
        for k in 0..3 {
            let (a, b) = if side > 0 { (tri[k], tri[(k + 1) % 3]) } else { (tri[(k + 1) % 3], tri[k]) };
            match a.cmp(&b) {
                Ordering::Less => *sums.entry((a, b)).or_default() += 1,
                Ordering::Greater => *sums.entry((b, a)).or_default() -= 1,
                Ordering::Equal => {}
            }
        }
    }
    sums.into_iter()
        .filter(|&(_, s)| s != 0)
        .map(|((a, b), s)| if s > 0 { (a, b, s.unsigned_abs()) } else { (b, a, s.unsigned_abs()) })
        .collect()
}

/// Adds to `counts` instance `i`'s casting faces that the segment `from -> to` passes through, each in its
/// layer.
fn crossings(
    frame: &FrameInputs,
    i: usize,
    silhouette: &Silhouette,
    (from, to): (Vec3, Vec3),
    counts: &mut [f32; LAYERS],
) {
    let inst = &frame.instances[i];
    let (from, to) = (inst.local_from_world.transform_point3(from), inst.local_from_world.transform_point3(to));
    let adj = &inst.adjacency;
    let positions = adj.positions();
    for (tri, &w) in adj.triangles().iter().zip(&silhouette.face_weights) {
        let layer = match (adj.closed(), w) {
            (_, 0) => continue,
            (true, _) => Layer::Closed,
            (false, 1) => Layer::Facing,
            (false, _) => Layer::Turned,
        };
        if segment_hits(from, to, tri.map(|v| positions[v as usize])) {
            counts[layer as usize] += 1.0;
        }
    }
}

/// Whether the segment `from -> to` crosses the triangle (Moeller-Trumbore).
fn segment_hits(from: Vec3, to: Vec3, [p0, p1, p2]: [Vec3; 3]) -> bool {
    let d = to - from;
    let (e1, e2) = (p1 - p0, p2 - p0);
    let q = d.cross(e2);
    let det = e1.dot(q);
    if det.abs() < f32::MIN_POSITIVE {
        return false;
    }
    let s = from - p0;
    let u = s.dot(q) / det;
    let r = s.cross(e1);
    let v = d.dot(r) / det;
    let t = e2.dot(r) / det;
    u >= 0.0 && v >= 0.0 && u + v <= 1.0 && (0.0..=1.0).contains(&t)
}

#[cfg(test)]
mod tests {
    use super::super::coverage::wedge_area;
    use super::*;
    use shadow_core::lookup::{hash_unit, pixel_hash};

    const LIGHT: SphereLight = SphereLight { centre: Vec3::new(0.3, 5.0, -0.2), radius: 0.4 };

    /// A pseudo-random point in the box `[-4, 4] x [-1, 4] x [-4, 4]`.
    fn point(seed: u32, i: u32) -> Vec3 {
        let h = |k: u32| hash_unit(pixel_hash(seed, i * 3 + k));
        Vec3::new(8.0 * h(0) - 4.0, 5.0 * h(1) - 1.0, 8.0 * h(2) - 4.0)
    }

    #[test]
    fn every_receiver_an_edge_covers_part_of_the_light_for_lies_inside_its_wedge() {
        let edges = [
            (Vec3::new(-1.0, 2.0, 1.0), Vec3::new(1.0, 2.2, 1.0)),
            (Vec3::new(0.5, 1.5, -1.0), Vec3::new(0.4, 3.0, 0.2)),
            (Vec3::new(2.0, 3.5, 0.0), Vec3::new(2.0, 3.5, 0.05)),
        ];
        for (k, &(a, b)) in edges.iter().enumerate() {
            let planes = wedge_planes(a, b, LIGHT).expect("the line misses the light");
            let (mut covered, mut outside) = (0, 0);
            for i in 0..20_000 {
                let p = point(k as u32, i);
                let inside = planes.iter().all(|pl| pl.dot(p.extend(1.0)) >= -1e-4);
                if wedge_area(p, a, b, LIGHT).abs() > 1e-6 {
                    covered += 1;
                    assert!(inside, "edge {k}: {p} has {} of the light but is outside", wedge_area(p, a, b, LIGHT));
                } else if !inside {
                    outside += 1;
                }
            }
            assert!(covered > 20 && outside > 1000, "edge {k}: {covered} covered, {outside} outside");
        }
    }

    #[test]
    fn a_side_quad_is_drawn_its_margin_beyond_every_point_it_holds() {
        // Each point of the quad (beyond the edge, between the centre's rays through its ends) lies inside
        // the drawn quad, in its plane, by at least the margin at the point's distance from the eye: half
        // a pixel there. Short edges and long, eyes near and far.
        let c = LIGHT.centre;
        for k in 0..300 {
            let (a, far, eye) = (point(20, 3 * k), point(20, 3 * k + 1), point(20, 3 * k + 2));
            let b = a + (far - a) * [0.002, 0.05, 1.0][k as usize % 3];
            let pixels = PixelScale { eye: eye * [0.5, 1.0, 8.0][k as usize / 3 % 3], per_distance: 2e-3 };
            let [[qb, qa, _], _] = side_quad(a, b, c, pixels);
            let (qa, qb) = (qa.truncate(), qb.truncate());
            let normal = (a - c).cross(b - c).normalize();
            // In-plane normals of the drawn quad's three sides, pointing inwards.
            let inward = |from: Vec3, along: Vec3, towards: Vec3| {
                let n = along.cross(normal).normalize();
                if n.dot(towards - from) > 0.0 { n } else { -n }
            };
            let sides = [
                (c, inward(c, qa - c, qb)),
                (c, inward(c, qb - c, qa)),
                (qa, inward(qa, qb - qa, a + (a - c) + (b - a) * 0.5)),
            ];
            for i in 0..50 {
                let (t, s) = (hash_unit(pixel_hash(k, 2 * i)), 4.0 * hash_unit(pixel_hash(k, 2 * i + 1)));
                let on_edge = a + (b - a) * t;
                let x = on_edge + (on_edge - c) * s;
                let margin = QUAD_MARGIN_PIXELS * pixels.per_distance * (x - pixels.eye).length();
                for (n, &(from, inwards)) in sides.iter().enumerate() {
                    let inside = (x - from).dot(inwards);
                    assert!(
                        inside >= 0.999 * margin,
                        "case {k}, point {i}, side {n}: {inside} inside, margin {margin}"
                    );
                }
            }
        }
    }

    #[test]
    fn the_wedge_faces_close_around_the_wedge_facing_out() {
        let (a, b) = (Vec3::new(-1.0, 2.0, 1.0), Vec3::new(1.0, 2.2, 1.0));
        let faces = wedge(a, b, LIGHT).expect("a wedge");
        let planes = wedge_planes(a, b, LIGHT).expect("planes");
        // A point inside all four planes is behind every face (each face's corners and the point make a
        // positive determinant); one outside is in front of some face.
        let behind_all =
            |p: Vec3| faces.iter().all(|&[q, r, s]| Mat4::from_cols(q, r, s, p.extend(1.0)).determinant() > 0.0);
        for i in 0..2000 {
            let p = point(9, i);
            let inside = planes.iter().all(|pl| pl.dot(p.extend(1.0)) > 1e-3);
            let outside = planes.iter().any(|pl| pl.dot(p.extend(1.0)) < -1e-3);
            if inside {
                assert!(behind_all(p), "{p} inside the planes but in front of a face");
            } else if outside {
                assert!(!behind_all(p), "{p} outside the planes but behind every face");
            }
        }
    }

    #[test]
    fn an_open_sheet_is_the_boundary_of_its_faces_on_the_side_it_casts_from() {
        // A square of two triangles: the shared diagonal cancels, the four sides remain, turned around
        // when the faces cast turned.
        let square = shadow_core::Mesh::new(
            vec![Vec3::ZERO, Vec3::X, Vec3::new(1.0, 0.0, 1.0), Vec3::Z],
            vec![[0, 1, 2], [0, 2, 3]],
        )
        .expect("a square");
        let adj = Adjacency::build(&square);
        let facing = boundary(&adj, &[1, 1], 1);
        assert!(facing.iter().all(|&(_, _, w)| w == 1), "{facing:?}");
        let mut sides: Vec<(u32, u32)> = facing.iter().map(|&(a, b, _)| (a, b)).collect();
        sides.sort_unstable();
        assert_eq!(sides, [(0, 1), (1, 2), (2, 3), (3, 0)]);
        let turned = boundary(&adj, &[-1, -1], -1);
        assert!(turned.iter().all(|&(a, b, _)| facing.contains(&(b, a, 1))) && turned.len() == 4);
        assert!(boundary(&adj, &[1, 1], -1).is_empty(), "no face casts turned");
    }

    #[test]
    fn an_edge_whose_line_meets_the_light_has_no_wedge() {
        let (a, b) = (Vec3::new(0.3, 2.0, -0.2), Vec3::new(0.3, 3.0, -0.2));
        assert!(wedge_planes(a, b, LIGHT).is_none());
    }
}
