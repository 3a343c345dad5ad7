//! What one silhouette edge adds to a receiver's occluded fraction of the light, exactly for the
//! silhouette as the light's centre sees it (WGSL twin: coverage.wgsl).
//!
//! Seen from a receiver `p`, the light is a disc: the cone the sphere subtends, cut by the plane through
//! its centre `c` square to `c - p`. The casters' silhouette loops project onto that plane, and the
//! occluded share of the disc is the integral over it of the loops' winding number. Winding at a point
//! `x` of the disc is winding at the centre (the hard shadow volume's count at `p`) plus the signed
//! crossings of the segment `c -> x` with the projected edges, so the occluded area splits into the
//! count times the whole disc plus, per edge, the part of the disc that lies beyond the edge as seen from
//! the centre, within the two rays through its ends. That part is zero unless the projected edge cuts the
//! disc: the edge's *wedge* bounds the receivers for which it does.
//!
//! In the projected edge's own frame (`s` along it, `h` the centre's distance from its line, both in
//! disc radii), the part beyond the edge is the circular segment between the chord `|s| <= k`,
//! `k = sqrt(1 - h^2)`, and the arc, cut to the edge's span `[s_a, s_b]`:
//!
//! `area = (-h (s2 - s1) - (atan2(h, s2) - atan2(h, s1))) / 2`, `s1, s2` the chord's ends clamped to the
//! span.
//!
//! Its sign is `h`'s, and `h`'s sign is the side of the plane through the edge and the light's centre
//! that `p` is on: the same triple product decides whether `p` is inside that edge's side of the hard
//! volume (`inside`), so the count's step as `p` crosses the side and the area's step (half the disc one
//! way, half the other) cancel exactly, on both backends, whatever the rounding.

use shadow_core::glam::{Vec3, Vec4};

/// The spherical light: centre and radius.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SphereLight {
    /// Centre.
    pub centre: Vec3,
    /// Radius.
    pub radius: f32,
}

/// How close to the receiver, as a fraction of its distance to the light, an edge is cut before it is
/// projected: what is nearer projects beyond the disc (unless it touches the receiver's own line to the
/// light, where it is part of the receiver's own surface).
pub const NEAR: f32 = 1e-3;

/// The triple product `((a - p) x (b - p)) . (c - p)`: positive when `p` lies on the inner side of the
/// plane through the edge `a -> b` and the light's centre `c`, the side a hard shadow volume's side quad
/// from that edge faces away from.
#[must_use]
pub fn side(p: Vec3, a: Vec3, b: Vec3, c: Vec3) -> f32 {
    (a - p).cross(b - p).dot(c - p)
}

/// Whether `p` is inside the side of the hard volume through edge `a -> b` (`side > 0`).
#[must_use]
pub fn inside(p: Vec3, a: Vec3, b: Vec3, c: Vec3) -> bool {
    side(p, a, b, c) > 0.0
}

/// Which side of the plane through `eye`, `v` and `c` the point `p` is on: `det(v - eye, c - eye, p - eye)`.
/// Two side quads meeting at a silhouette vertex `v` share the ray from it, and both ask this one
/// expression which side of that ray the eye's ray to `p` passes, so exactly one of them is crossed.
#[must_use]
pub fn around(eye: Vec3, v: Vec3, c: Vec3, p: Vec3) -> f32 {
    (v - eye).cross(c - eye).dot(p - eye)
}

/// Whether two signed values are on the same side of zero (zero on the negative side).
fn same(s: f32, reference: f32) -> bool {
    (s > 0.0) == (reference > 0.0)
}

/// Whether the eye's ray towards `p` meets the side quad of edge `a -> b` (the part of the plane through
/// the edge and the light's centre `c` beyond the edge, between the rays from `c` through its ends),
/// tested against the three planes through the eye that bound the quad's image. The quads are drawn a
/// little larger than they are, and this decides, so that where two quads meet the same expression
/// ([`around`]) gives the pixel to one of them, whatever the rasterizer's rounding.
#[must_use]
pub fn crosses_quad(p: Vec3, eye: Vec3, a: Vec3, b: Vec3, c: Vec3) -> bool {
    let beyond = |x: Vec3| (a - eye).cross(b - eye).dot(x - eye);
    same(around(eye, a, c, p), around(eye, a, c, b))
        && same(around(eye, b, c, p), around(eye, b, c, a))
        && same(beyond(p), beyond(a + (a - c)))
}

/// What the side quad of edge `a -> b` adds to the light centre's count at `p`, per unit weight: z-pass,
/// +1 where the eye's ray enters the volume through it before reaching `p`, -1 where it leaves.
#[must_use]
pub fn count_step(p: Vec3, eye: Vec3, a: Vec3, b: Vec3, c: Vec3) -> f32 {
    let step = f32::from(u8::from(inside(p, a, b, c))) - f32::from(u8::from(inside(eye, a, b, c)));
    if step != 0.0 && crosses_quad(p, eye, a, b, c) { step } else { 0.0 }
}

/// The light as a receiver sees it: the disc the sphere's cone cuts from the plane through its centre
/// square to the receiver's line to it.
#[derive(Clone, Copy)]
struct Disc {
    /// From the receiver to the centre.
    w: Vec3,
    /// Its length.
    dist: f32,
    /// Its direction.
    axis: Vec3,
    /// The disc's radius: the cone's edge at distance `dist`.
    r: f32,
}

impl Disc {
    /// The disc `light` shows a receiver at `p`; `None` inside the sphere, which it sees whole.
    fn seen_from(p: Vec3, light: SphereLight) -> Option<Self> {
        let w = light.centre - p;
        let dist = w.length();
        (dist > light.radius).then(|| Self {
            w,
            dist,
            axis: w / dist,
            r: light.radius * dist / (dist * dist - light.radius * light.radius).sqrt(),
        })
    }

    /// The length of `n`'s part in the light's plane, in disc radii: a plane through the receiver with
    /// normal `n` cuts the light's plane along the chord `n . w / across(n)` radii from the centre.
    fn across(&self, n: Vec3) -> f32 {
        (n - self.axis * n.dot(self.axis)).length() * self.r
    }
}

/// The signed fraction of the light's disc that lies beyond edge `a -> b` seen from the centre, as `p`
/// sees the edge, per unit weight: negative on the inner side, where the edge takes back the part of the
/// count's whole disc that it leaves uncovered. Zero outside the edge's wedge.
#[must_use]
pub fn wedge_area(p: Vec3, a: Vec3, b: Vec3, light: SphereLight) -> f32 {
    let Some(disc) = Disc::seen_from(p, light) else { return 0.0 };
    let Disc { w, dist, axis, r } = disc;
    let near = NEAR * dist;
    let (za, zb) = ((a - p).dot(axis), (b - p).dot(axis));
    if za < near && zb < near {
        return 0.0;
    }
    // Cut the edge where it comes nearer than `near` (the plane keeps the projected line: a line of the
    // plane through `p` and the edge).
    let cut = |from: Vec3, z_from: f32, to: Vec3, z_to: f32| from + (to - from) * ((near - z_from) / (z_to - z_from));
    let (a2, za2) = if za < near { (cut(a, za, b, zb), near) } else { (a, za) };
    let (b2, zb2) = if zb < near { (cut(b, zb, a, za), near) } else { (b, zb) };
    let project = |x: Vec3, z: f32| (x - p) * (dist / z) - w;
    let (pa, pb) = (project(a2, za2), project(b2, zb2));
    let along = pb - pa;
    let len = along.length();
    if len == 0.0 {
        return 0.0;
    }
    let dir = along / len;
    let (sa, sb) = (pa.dot(dir) / r, pb.dot(dir) / r);
    // The centre's distance from the projected line, from the plane through `p` and the edge (normal
    // n), signed by `side` itself.
    let across = disc.across((a - p).cross(b - p));
    let s = side(p, a, b, light.centre);
    if across == 0.0 {
        return 0.0;
    }
    let magnitude = s.abs() / across;
    if magnitude >= 1.0 {
        return 0.0;
    }
    let h = if s > 0.0 { magnitude } else { -magnitude };
    let k = (1.0 - h * h).sqrt();
    let (s1, s2) = ((-k).max(sa).min(sb), k.max(sa).min(sb));
    let twice = -h * (s2 - s1) - (h.atan2(s2) - h.atan2(s1));
    -twice / (2.0 * std::f32::consts::PI)
}

/// [`wedge_area`] where `p` lies inside the edge's wedge `planes` (inner sides positive), and 0 without
/// computing it elsewhere: the wedge holds every receiver the edge covers part of the light for, and the
/// four plane tests cost less than the area, at the many fragments of a wedge's back faces whose receiver
/// is in front of it.
#[must_use]
pub fn wedge_term(p: Vec3, a: Vec3, b: Vec3, planes: &[Vec4; 4], light: SphereLight) -> f32 {
    if planes.iter().all(|plane| plane.dot(p.extend(1.0)) >= 0.0) { wedge_area(p, a, b, light) } else { 0.0 }
}

/// The share of the light's disc below the receiver's horizon (the plane through `p` square to its unit
/// face normal `n`): the part of the disc beyond the chord where that plane cuts the light's plane,
/// `(acos d - d sqrt(1 - d^2)) / pi` for the centre `d` radii above it. The reference counts these
/// directions as blocked, and on a convex caster they are exactly its own shadow near the terminator,
/// which the silhouette of the light's centre has no edge for.
#[must_use]
pub fn horizon_share(p: Vec3, n: Vec3, light: SphereLight) -> f32 {
    let Some(disc) = Disc::seen_from(p, light) else { return 0.0 };
    let across = disc.across(n);
    let above = n.dot(disc.w);
    if across <= above.abs() {
        return if above > 0.0 { 0.0 } else { 1.0 };
    }
    let d = above / across;
    (d.acos() - d * (1.0 - d * d).sqrt()) / std::f32::consts::PI
}

#[cfg(test)]
mod tests {
    use super::*;

    const LIGHT: SphereLight = SphereLight { centre: Vec3::new(0.0, 4.0, 0.0), radius: 0.5 };

    /// The occluded share at `p` of a square caster at height 2, x in `x0..x0 + 8`, z in -4..4, as the
    /// technique sums it: the count at `p` from the side planes (the square's loop holds the centre when
    /// `p` is inside all four) plus the four edges' areas. The loop runs counter-clockwise seen from the
    /// light (above), as shadow-core orients a light-facing face's edges.
    fn square_share(p: Vec3, x0: f32) -> f32 {
        let corners = [
            Vec3::new(x0, 2.0, 4.0),
            Vec3::new(x0 + 8.0, 2.0, 4.0),
            Vec3::new(x0 + 8.0, 2.0, -4.0),
            Vec3::new(x0, 2.0, -4.0),
        ];
        let edges: Vec<(Vec3, Vec3)> = (0..4).map(|i| (corners[i], corners[(i + 1) % 4])).collect();
        let count = f32::from(u8::from(edges.iter().all(|&(a, b)| inside(p, a, b, LIGHT.centre))));
        count + edges.iter().map(|&(a, b)| wedge_area(p, a, b, LIGHT)).sum::<f32>()
    }

    #[test]
    fn a_straight_edge_covers_half_the_light_under_it_and_all_or_none_beyond_its_penumbra() {
        // The edge x = 0 at height 2, halfway to the light: its penumbra on the ground is 2 * 0.5 wide
        // (similar triangles), centred under the edge's shadow at x = 0.
        let at = |x: f32| square_share(Vec3::new(x, 0.0, 0.0), 0.0);
        assert!((at(0.0) - 0.5).abs() < 1e-4, "under the hard edge: {}", at(0.0));
        assert!((at(-0.6)).abs() < 1e-6, "lit beyond the penumbra: {}", at(-0.6));
        assert!((at(0.6) - 1.0).abs() < 1e-6, "umbra: {}", at(0.6));
        // Either side of the hard edge, where the count steps, the share is continuous and symmetric.
        for x in [1e-6f32, 1e-3, 0.1, 0.3, 0.49] {
            let (inner, outer) = (at(x), at(-x));
            assert!((inner + outer - 1.0).abs() < 1e-4, "x = {x}: {inner} + {outer}");
            assert!(inner > 0.5 && outer < 0.5, "x = {x}: {inner}, {outer}");
        }
        // Under the centre the light's plane is level, so an edge at x = -1/8 projects to the chord
        // x = -1/4 of the cone's disc, radius 0.5 * 4 / sqrt(16 - 0.25); the share beyond a chord at
        // distance d (in radii) is (acos d - d sqrt(1 - d^2)) / pi, and the receiver sees the rest.
        let d: f32 = 0.25 / (0.5 * 4.0 / 15.75f32.sqrt());
        let beyond = (d.acos() - d * (1.0 - d * d).sqrt()) / std::f32::consts::PI;
        let share = square_share(Vec3::ZERO, -0.125);
        assert!((share - (1.0 - beyond)).abs() < 1e-5, "{share} against {}", 1.0 - beyond);
    }

    #[test]
    fn the_count_step_and_the_area_step_cancel_on_the_side_plane() {
        // Receivers on either side of the plane through the edge and the centre, as near as f32 allows.
        let (a, b) = (Vec3::new(0.0, 2.0, 4.0), Vec3::new(0.0, 2.0, -4.0));
        for x in [0.0f32, f32::EPSILON, -f32::EPSILON, 1e-7, -1e-7] {
            let p = Vec3::new(x, 0.0, 0.3);
            let count = f32::from(u8::from(inside(p, a, b, LIGHT.centre)));
            let share = count + wedge_area(p, a, b, LIGHT);
            assert!((share - 0.5).abs() < 1e-3, "x = {x}: {share}");
        }
    }

    #[test]
    fn the_horizon_hides_the_part_of_the_light_below_it() {
        let (up, p) = (Vec3::Y, Vec3::new(0.0, 4.0, 3.0));
        assert!((horizon_share(p, up, LIGHT) - 0.5).abs() < 1e-6, "level with the centre: half");
        assert_eq!(horizon_share(Vec3::ZERO, up, LIGHT), 0.0, "under the light: none");
        assert_eq!(horizon_share(Vec3::ZERO, -up, LIGHT), 1.0, "facing away: all");
        let tilted = horizon_share(Vec3::new(0.0, 3.9, 3.0), up, LIGHT);
        assert!(tilted > 0.0 && tilted < 0.5, "the centre a little above: {tilted}");
    }

    #[test]
    fn an_edge_outside_the_disc_adds_nothing() {
        let (a, b) = (Vec3::new(0.0, 2.0, 4.0), Vec3::new(0.0, 2.0, -4.0));
        assert_eq!(wedge_area(Vec3::new(-3.0, 0.0, 0.0), a, b, LIGHT), 0.0);
        assert_eq!(wedge_area(Vec3::new(3.0, 0.0, 0.0), a, b, LIGHT), 0.0);
        // Behind the receiver (the receiver above the edge): nothing either.
        assert_eq!(wedge_area(Vec3::new(0.0, 3.0, 0.0), a, b, LIGHT), 0.0);
    }
}
