//! Software capping at the eye's near plane (McCool section 6.2).
//!
//! Where the reconstructed boundary crosses the eye's near plane, the polygons in front of it are clipped
//! away and the parity of every pixel looking out of the volume's inside flips. Inverting globally is wrong
//! (Fig. 7): only the part of the near-plane facet inside the volume should flip. So the facet is carried
//! into the light's map, the samples it covers are classified against the near plane, and:
//!
//! - all inside (the near-plane point on every sample's ray lies behind the sample): invert globally;
//! - none inside: nothing;
//! - mixed: cap polygons on the near plane over the inside part, cell by cell. Within a cell the
//!   reconstructed surface is the two triangles of its [`Split`], and in the light's NDC both it and the
//!   near plane are planar, so the inside part of each triangle is the triangle clipped by one line (the
//!   paper's 32 cases, 2 splits times 16 classifications, fall out of that clip). Runs of whole inside
//!   cells in a row become one rectangle.
//!
//! A near-plane point counts as inside when it is behind the surface on its light ray, inside the light's
//! depth range: before the light's near plane it is outside the frustum, and past the far plane only the
//! far plane itself lies there, which the reconstruction never emits. Cap vertices are homogeneous world
//! points (no division), so a near plane seen edge-on by the light sends them towards infinity as it
//! should.

use glam::{Mat4, Vec2, Vec4};

use super::{CELL_CORNERS, HomTriangle, SampleGrid, Split};
use shadow_core::light::LightProjection;

/// The cap of one light projection.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Cap {
    /// Every near-plane point over the map is inside the volume: flip every pixel.
    pub invert_all: bool,
    /// Otherwise, the inside part of the near-plane facet, on the near plane.
    pub triangles: Vec<HomTriangle>,
    /// Samples classified against the near plane.
    pub samples: usize,
}

/// The near-plane facet of a view as a convex polygon in `proj`'s map space, clipped to the light's depth
/// range; also whether the clip took anything away.
fn facet_in_map(eye_clip_from_world: Mat4, proj: &LightProjection, grid: &SampleGrid) -> (Vec<Vec2>, bool) {
    let eye_inv = eye_clip_from_world.inverse();
    let mut poly: Vec<Vec4> = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
        .iter()
        .map(|&(x, y)| proj.clip_from_world * (eye_inv * Vec4::new(x, y, 0.0, 1.0)))
        .collect();
    let before = poly.len();
    let mut clipped = false;
    // 0 <= z <= w in the light's clip space.
    for plane in [Vec4::Z, Vec4::W - Vec4::Z] {
        let dist: Vec<f32> = poly.iter().map(|p| p.dot(plane)).collect();
        if dist.iter().any(|&d| d < 0.0) {
            clipped = true;
        }
        let mut next = Vec::with_capacity(poly.len() + 1);
        for i in 0..poly.len() {
            let (a, b, da, db) = (poly[i], poly[(i + 1) % poly.len()], dist[i], dist[(i + 1) % poly.len()]);
            if da >= 0.0 {
                next.push(a);
            }
            if (da >= 0.0) != (db >= 0.0) {
                next.push(a + (b - a) * (da / (da - db)));
            }
        }
        poly = next;
    }
    let pts = poly.iter().filter(|c| c.w > 0.0).map(|c| grid.map_xy(Vec2::new(c.x / c.w, c.y / c.w))).collect();
    (pts, clipped || poly.len() != before)
}

/// A map-space polygon clipped to the square of sample positions, `[0, n - 1]^2`.
fn facet_over_samples(facet: &[Vec2], n: u32) -> Vec<Vec2> {
    let hi = (n - 1) as f32;
    let sides = [
        Affine { a: Vec2::X, b: 0.0 },
        Affine { a: Vec2::Y, b: 0.0 },
        Affine { a: -Vec2::X, b: hi },
        Affine { a: -Vec2::Y, b: hi },
    ];
    sides.iter().fold(facet.to_vec(), |poly, &f| if poly.len() < 3 { poly } else { clip(&poly, f) })
}

/// One affine function over map space, `f(s) = a.s + b`.
#[derive(Clone, Copy, Debug)]
struct Affine {
    a: Vec2,
    b: f32,
}

impl Affine {
    fn at(self, s: Vec2) -> f32 {
        self.a.dot(s) + self.b
    }

    /// The affine function through three points' values.
    fn through(p: [Vec2; 3], v: [f32; 3]) -> Self {
        let (e1, e2) = (p[1] - p[0], p[2] - p[0]);
        let det = e1.perp_dot(e2);
        let (d1, d2) = (v[1] - v[0], v[2] - v[0]);
        let a = if det == 0.0 { Vec2::ZERO } else { Vec2::new(d1 * e2.y - d2 * e1.y, e1.x * d2 - e2.x * d1) / det };
        Self { a, b: v[0] - a.dot(p[0]) }
    }
}

/// Clips a convex polygon to `f > 0` (the crossing on each edge found from its lower endpoint in (x, y)
/// order, so the two triangles sharing an edge agree on it bit for bit).
fn clip(poly: &[Vec2], f: Affine) -> Vec<Vec2> {
    let mut out = Vec::with_capacity(poly.len() + 1);
    for i in 0..poly.len() {
        let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
        let (fa, fb) = (f.at(a), f.at(b));
        if fa > 0.0 {
            out.push(a);
        }
        if (fa > 0.0) != (fb > 0.0) {
            let ((p, fp), (q, fq)) = if (a.x, a.y) <= (b.x, b.y) { ((a, fa), (b, fb)) } else { ((b, fb), (a, fa)) };
            out.push(p + (q - p) * (fp / (fp - fq)));
        }
    }
    out
}

/// The cap for the view `eye_clip_from_world` over one projection's `N x N` map (`ndc`: NDC depths with
/// their bias; `split_depth`: the depths the reconstruction's split rule used).
#[must_use]
pub fn near_plane_cap(
    eye_clip_from_world: Mat4,
    proj: &LightProjection,
    grid: &SampleGrid,
    ndc: &[f32],
    split_depth: &[f32],
) -> Cap {
    let n = grid.n;
    // The eye's near plane (clip z = 0) in the light's NDC: c.x x + c.y y + c.z z + c.w = 0.
    let c = proj.clip_plane_from_world_plane * eye_clip_from_world.row(2);
    if c.z.abs() <= 1e-6 * (c.x.abs() + c.y.abs()) || n < 2 {
        // Seen edge-on from the light, the facet covers no area of the map.
        return Cap::default();
    }
    let (facet, clipped) = facet_in_map(eye_clip_from_world, proj, grid);
    // Only the part over the sample square has samples to test; off it is lit (no cap), which the border
    // walls of `mesh::border_walls` agree with.
    let square = facet_over_samples(&facet, n);
    if square.len() < 3 {
        return Cap::default();
    }
    let within = square.len() == facet.len()
        && facet.iter().all(|p| p.x >= 0.0 && p.y >= 0.0 && p.x <= (n - 1) as f32 && p.y <= (n - 1) as f32);
    let near = NearPlane::new(eye_clip_from_world, c, grid, ndc);
    let (lo, hi) = square.iter().fold((Vec2::INFINITY, Vec2::NEG_INFINITY), |(lo, hi), &p| (lo.min(p), hi.max(p)));
    let last = (n - 2) as f32;
    let (x0, y0) = (lo.x.floor().clamp(0.0, last) as u32, lo.y.floor().clamp(0.0, last) as u32);
    let (x1, y1) = (hi.x.floor().clamp(0.0, last) as u32, hi.y.floor().clamp(0.0, last) as u32);

    let mut cap = Cap { samples: ((x1 - x0 + 2) * (y1 - y0 + 2)) as usize, ..Cap::default() };
    let mut all_inside = true;
    for y in y0..=y1 {
        // A run of whole inside cells, from its first column.
        let mut run: Option<u32> = None;
        for x in x0..=x1 {
            let corners = CELL_CORNERS.map(|(dx, dy)| (x + dx, y + dy));
            if corners.iter().all(|&(cx, cy)| near.inside(cx, cy)) {
                run.get_or_insert(x);
                continue;
            }
            all_inside = false;
            if let Some(start) = run.take() {
                near.rectangle(start, x, y, &mut cap.triangles);
            }
            near.partial_cell(corners, split_depth, &mut cap.triangles);
        }
        if let Some(start) = run {
            near.rectangle(start, x1 + 1, y, &mut cap.triangles);
        }
    }
    if all_inside && within && !clipped {
        return Cap { invert_all: true, triangles: Vec::new(), samples: cap.samples };
    }
    cap
}

/// The eye's near plane seen from one light projection: its NDC depth over map space, and the map's
/// samples to test against it.
struct NearPlane<'a> {
    /// The near plane in world space (the eye's clip-space `z = 0`).
    plane: Vec4,
    /// Its NDC depth over map space, an affine function.
    zn: Affine,
    grid: &'a SampleGrid,
    ndc: &'a [f32],
}

impl<'a> NearPlane<'a> {
    /// `c`: the near plane in the light's NDC, `c.x x + c.y y + c.z z + c.w = 0`, with `c.z` not zero.
    fn new(eye_clip_from_world: Mat4, c: Vec4, grid: &'a SampleGrid, ndc: &'a [f32]) -> Self {
        let p = [Vec2::ZERO, Vec2::X, Vec2::Y];
        let zn = Affine::through(
            p,
            p.map(|s| {
                let q = grid.ndc_xy(s);
                -(c.x * q.x + c.y * q.y + c.w) / c.z
            }),
        );
        Self { plane: eye_clip_from_world.row(2), zn, grid, ndc }
    }

    fn sample(&self, x: u32, y: u32) -> usize {
        (y * self.grid.n + x) as usize
    }

    /// Whether the near-plane point on sample `(x, y)`'s ray is inside the volume: within the light's
    /// depth range and behind the sample.
    fn inside(&self, x: u32, y: u32) -> bool {
        let z = self.zn.at(Vec2::new(x as f32, y as f32));
        (0.0..=1.0).contains(&z) && z > self.ndc[self.sample(x, y)]
    }

    /// The cap vertex over map point `s`: where the light ray through `s` meets the near plane. Lifting
    /// `(s, zn(s))` through the inverse projection would put it there too, but a perspective map's NDC
    /// depth is nearly 1 a few near distances out, so f32 loses the point along the ray; the line through
    /// the ray's light-near and light-far points meets the plane exactly: `p = (L.b) a - (L.a) b` has
    /// `L.p = 0`.
    fn lift(&self, s: Vec2) -> Vec4 {
        let (a, b) = (self.grid.world(s, 0.0), self.grid.world(s, 1.0));
        let p = a * self.plane.dot(b) - b * self.plane.dot(a);
        if p.w < 0.0 { -p } else { p }
    }

    /// Two triangles over the whole cells of row `y` from column `start` up to `end`.
    fn rectangle(&self, start: u32, end: u32, y: u32, out: &mut Vec<HomTriangle>) {
        let q =
            [(start, y), (end, y), (end, y + 1), (start, y + 1)].map(|(x, y)| self.lift(Vec2::new(x as f32, y as f32)));
        out.push([q[0], q[1], q[2]]);
        out.push([q[0], q[2], q[3]]);
    }

    /// The inside part of a cell whose corners are not all inside: each triangle of the cell's split,
    /// clipped to behind the reconstructed surface and within the light's depth range.
    fn partial_cell(&self, corners: [(u32, u32); 4], split_depth: &[f32], out: &mut Vec<HomTriangle>) {
        let split = Split::of(corners.map(|(cx, cy)| split_depth[self.sample(cx, cy)]));
        let pos = corners.map(|(cx, cy)| Vec2::new(cx as f32, cy as f32));
        for (tri, _) in split.triangles() {
            let p = tri.map(|k| pos[k]);
            let surface = Affine::through(p, tri.map(|k| self.ndc[self.sample(corners[k].0, corners[k].1)]));
            let zn = self.zn;
            let behind = Affine { a: zn.a - surface.a, b: zn.b - surface.b };
            let past_near = zn;
            let before_far = Affine { a: -zn.a, b: 1.0 - zn.b };
            let mut poly = p.to_vec();
            for f in [behind, past_near, before_far] {
                if poly.len() < 3 {
                    break;
                }
                poly = clip(&poly, f);
            }
            for k in 1..poly.len().saturating_sub(1) {
                out.push([self.lift(poly[0]), self.lift(poly[k]), self.lift(poly[k + 1])]);
            }
        }
    }
}
