//! A computation mask's pixels ordered around one point of the screen, the image of the light, so that a
//! shadow volume's side is tested only at the masked-in pixels near it.
//!
//! Every side of a shadow volume lies in a plane through the light, and a plane through a point projects
//! to a line through that point's image: in screen space the sides of all volumes belong to one pencil of
//! lines through the light's image (a vanishing point for a directional light). A side is a sliver
//! between two of those lines, often hundreds of rows long and a pixel wide, and a row walk pays for every
//! row of it, masked in or not. Seen from the pencil's apex, though, it spans an angle of a few
//! thousandths of a radian and a band of distances, and the masked-in pixels it can cover are the few in
//! that angle and band. The pixels are sorted by angle and cut into buckets of 32 consecutive
//! ones, each sorted by distance, so a triangle's candidates are found by binary searches; each is then
//! tested against the triangle's own edge functions (top-left rule included) and depth plane, so exactly
//! the walk's fragments, depths and counters come out. A triangle with more candidates than it has rows
//! (a cap facing the eye, a triangle around or near the apex) is walked as before.
//!
//! Only for counting kernels (stencil increments and decrements that depend on the depth test alone):
//! they commute, so the triangles can be taken in any order, each thread counting into its own deltas,
//! added up afterwards.

use std::f64::consts::PI;
use std::ops::Range;

use glam::{DVec2, Vec4};
use rayon::prelude::*;

use super::{CompareFn, HALF, ONE, RasterCounters, Setup, depth_origin, row_depth};
use crate::raster::ComputationMask;

/// Pixels per angle bucket: fewer cut a sliver's angle closer, more cost more searches per triangle.
const BUCKET: usize = 32;
/// Widening of a triangle's angle, in radians: far above the rounding of `atan2` in f64 and far below a
/// pixel's angle anywhere on a target up to 16384 pixels from the apex (6e-5).
const ANGLE_EPS: f64 = 1e-9;
/// A triangle whose corners span this much of a half turn seen from the apex, or which has a corner this
/// close to it (pixels), is walked: its angle would not bound it safely, nor cheaply.
const MAX_SPREAD: f64 = PI - 1e-3;
const MIN_APEX_DISTANCE: f64 = 2.0;
/// Walked instead when a triangle has more candidates than this many per row it spans (a pixel test
/// costs a fraction of a row's walk step and mask lookup).
const PIXELS_PER_ROW: usize = 4;
/// Masks holding more than this fraction of their target are not ordered: sorting them is then a large
/// share of a frame, and most triangles would be walked anyway.
pub const MAX_DENSITY: f64 = 0.5;

/// Where clip-space point `p` lands on a `w x h` target, in pixels (top-left origin, y down, the
/// mapping the rasterizer snaps to fixed point), or `None` at or near infinity: `|w|` under 1e-6 of the
/// point's size, or more than ten million pixels out.
#[must_use]
pub fn screen_point(p: Vec4, w: u32, h: u32) -> Option<DVec2> {
    let p = p.as_dvec4();
    let s = DVec2::new((p.x / p.w * 0.5 + 0.5) * f64::from(w), (0.5 - p.y / p.w * 0.5) * f64::from(h));
    // NaN (a zero point, or w = 0 over it) fails both tests.
    (p.w.abs() > 1e-6 * p.truncate().length() && s.abs().max_element() < 1e7).then_some(s)
}

/// The masked-in pixels of a mask sorted by their angle around an apex, in buckets sorted by distance.
#[derive(Clone, Debug, PartialEq)]
pub struct Pencil {
    /// The apex in pixels, top-left origin, y down (pixel centres at half-integers).
    apex: DVec2,
    /// Per bucket of [`BUCKET`] pixels (the last may hold fewer), the least and the greatest angle of its
    /// pixels' centres around the apex, in `[-pi, pi]`; both ascending from bucket to bucket.
    angle_min: Vec<f64>,
    angle_max: Vec<f64>,
    /// Per bucket, the unit direction at its least angle: the ray a bucket's angles start from.
    start_dirs: Vec<DVec2>,
    /// Per pixel, bucket by bucket and by distance within a bucket: the squared distance of its centre
    /// from the apex, the centre in the rasterizer's fixed point (integers, exact in f64), its column and
    /// its index in the target.
    dist2: Vec<f64>,
    centres: Vec<[f64; 2]>,
    columns: Vec<f32>,
    at: Vec<u32>,
}

/// A set-up triangle seen from the apex, in pixels relative to it: what bounds the distances of its
/// points within an angle.
struct Polar {
    /// Each edge as a start, a direction and the sign that makes `sign * cross(direction, x - start)`
    /// positive inside.
    edges: [(DVec2, DVec2, f64); 3],
    /// The corners and the edges' points nearest the apex (where on the edge), by angle and distance: the
    /// extremes of the distance within an angle are among these and the angle's two rays' crossings.
    marks: [(f64, f64); 6],
    /// The angles the triangle spans, widened by [`ANGLE_EPS`], in `[-pi, pi]`: `lo > hi` when they cross
    /// the branch cut.
    angles: (f64, f64),
    /// The unit directions of the corners at the two ends of the span.
    ends: [DVec2; 2],
}

impl Polar {
    /// `t` around `apex`, or `None` when the triangle surrounds or nearly meets it.
    fn new(t: &Setup, apex: DVec2) -> Option<Self> {
        let corner = |k: usize| DVec2::new(t.fx[k] as f64, t.fy[k] as f64) / ONE as f64 - apex;
        let c = [corner(0), corner(1), corner(2)];
        if c.iter().any(|d| d.length() < MIN_APEX_DISTANCE) {
            return None;
        }
        let base = c[0].y.atan2(c[0].x);
        // Angles relative to corner 0 (the sign from the cross product): within a half turn of each other
        // when the triangle does not surround the apex, and then the triangle lies in their span.
        let rel = c.map(|d| c[0].perp_dot(d).atan2(c[0].dot(d)));
        let by_angle = |i: &usize, j: &usize| rel[*i].total_cmp(&rel[*j]);
        let (k_lo, k_hi) = ((0..3).min_by(by_angle).unwrap_or(0), (0..3).max_by(by_angle).unwrap_or(0));
        let (lo, hi) = (rel[k_lo], rel[k_hi]);
        if hi - lo >= MAX_SPREAD {
            return None;
        }
        let wrap = |a: f64| {
            if a > PI {
                a - 2.0 * PI
            } else if a < -PI {
                a + 2.0 * PI
            } else {
                a
            }
        };
        let orientation = (c[1] - c[0]).perp_dot(c[2] - c[0]).signum();
        let edges = [0, 1, 2].map(|k| (c[k], c[(k + 1) % 3] - c[k], orientation));
        let mut marks = [(0.0, 0.0); 6];
        for k in 0..3 {
            marks[k] = (wrap(base + rel[k]), c[k].length());
            // The edge's point nearest the apex: a corner's mark again unless it is inside the edge.
            let (p, e, _) = edges[k];
            let s = -p.dot(e) / e.length_squared();
            marks[3 + k] = if s > 0.0 && s < 1.0 {
                let foot = p + e * s;
                (foot.y.atan2(foot.x), foot.length())
            } else {
                marks[k]
            };
        }
        Some(Self {
            edges,
            marks,
            angles: (wrap(base + lo - ANGLE_EPS), wrap(base + hi + ANGLE_EPS)),
            ends: [c[k_lo].normalize(), c[k_hi].normalize()],
        })
    }

    /// Where the ray from the apex along the unit direction `u` is inside the triangle, as distances.
    fn ray(&self, u: DVec2) -> Option<(f64, f64)> {
        let (mut t0, mut t1) = (0.0f64, f64::INFINITY);
        for &(p, e, sign) in &self.edges {
            // Inside where sign * cross(e, t u - p) >= 0, i.e. a t >= b.
            let (a, b) = (sign * e.perp_dot(u), sign * e.perp_dot(p));
            if a > 0.0 {
                t0 = t0.max(b / a);
            } else if a < 0.0 {
                t1 = t1.min(b / a);
            } else if b > 0.0 {
                return None;
            }
        }
        (t0 <= t1).then_some((t0, t1))
    }

    /// The squared distances the triangle's points span within the angles from `lo` to `hi` (no branch
    /// cut between), given where the rays at both ends are inside it ([`Polar::ray`]), widened by a
    /// millionth of a pixel for rounding; `None` when it has none there.
    fn distances(&self, (lo, ray_lo): Span, (hi, ray_hi): Span) -> Option<(f64, f64)> {
        let (mut near, mut far) = (f64::INFINITY, f64::NEG_INFINITY);
        for (a, b) in [ray_lo, ray_hi].into_iter().flatten() {
            (near, far) = (near.min(a), far.max(b));
        }
        for &(a, d) in &self.marks {
            if a >= lo - ANGLE_EPS && a <= hi + ANGLE_EPS {
                (near, far) = (near.min(d), far.max(d));
            }
        }
        (near <= far).then(|| ((near - 1e-6).max(0.0).powi(2), (far + 1e-6).powi(2)))
    }
}

/// A set-up triangle's test at candidate pixels, as the row walk tests each of its rows' pixels: the walk's
/// edge functions (top-left rule included) and depth plane, with what is the same for every pixel hoisted.
/// In f64 the edge functions' integer terms (far under 2^53) are exact, with no 64-bit integer multiplies;
/// `py - fy0` is an exact integer rounded to f32 as the walk's i64 is, so the depth is `row_base` and
/// `depth_at`'s f32 arithmetic, bit for bit.
pub(super) struct CandidateTest<'a, P> {
    t: &'a Setup,
    edge: [(f64, f64, f64); 3],
    origin: f32,
    fy0: f64,
    /// The `(pass, depth fail)` stencil increments of the triangle's facing.
    ops: (u8, u8),
    clamp: bool,
    pass: P,
}

impl<'a, P: Fn(f32, f32) -> bool> CandidateTest<'a, P> {
    /// The test of `t` with the `(pass, depth fail)` increments of front and back faces, the depth clamped
    /// when asked, and `pass` the depth test of a fragment's depth against the stored one.
    pub(super) fn new(t: &'a Setup, (front, back): ((u8, u8), (u8, u8)), clamp: bool, pass: P) -> Self {
        Self {
            t,
            edge: [0, 1, 2].map(|k| (t.a[k] as f64, t.b[k] as f64, (t.c[k] + t.tl[k]) as f64)),
            origin: depth_origin(t),
            fy0: t.fy[0] as f64,
            ops: if t.front { front } else { back },
            clamp,
            pass,
        }
    }

    /// Tests the candidates (pixel centres in fixed point, their columns and stored depths), adding each
    /// covered one's increment to its `delta`; returns how many were covered and how many of those passed.
    #[inline(always)]
    pub(super) fn run(&self, centres: &[[f64; 2]], columns: &[f32], stored: &[f32], delta: &mut [u8]) -> (u64, u64) {
        let (t, (dp, df)) = (self.t, self.ops);
        let (mut fragments, mut passed) = (0u64, 0u64);
        for (((&[px, py], &x), &stored), delta) in centres.iter().zip(columns).zip(stored).zip(delta) {
            // Branch-free: which candidates a sliver covers is a coin toss.
            let inside = self.edge.iter().fold(true, |inside, &(a, b, c)| inside & (a * px + b * py + c >= 0.0));
            let z = row_depth(t, self.origin, ((py - self.fy0) as f32) / ONE as f32) + t.dzdx * x;
            let pass = (self.pass)(if self.clamp { z.clamp(0.0, 1.0) } else { z }, stored);
            let op = if pass { dp } else { df };
            *delta = delta.wrapping_add(op * u8::from(inside));
            fragments += u64::from(inside);
            passed += u64::from(inside & pass);
        }
        (fragments, passed)
    }

    /// The stencil updates among `fragments` covered candidates of which `passed` passed.
    pub(super) fn stencil_updates(&self, fragments: u64, passed: u64) -> u64 {
        let (dp, df) = self.ops;
        (if dp != 0 { passed } else { 0 }) + if df != 0 { fragments - passed } else { 0 }
    }
}

/// A counting kernel's depth test and its `(pass, depth fail)` stencil increments for front and back faces
/// (`DepthKernel::Count`).
pub(super) type Counting = (CompareFn, (u8, u8), (u8, u8));

/// An angle and where the ray from the apex at that angle is inside a triangle, as distances.
type Span = (f64, Option<(f64, f64)>);

/// Which triangles of a draw a [`Pencil`] takes, with their candidate pixels, and which are walked.
pub(super) struct Plan {
    /// Per taken triangle, its index and its span of `ranges`.
    taken: Vec<(u32, Range<u32>)>,
    /// Runs of candidate positions in the pencil's order.
    ranges: Vec<Range<u32>>,
    /// The triangles left to the row walk (taken by the caller).
    pub(super) walked: Vec<u32>,
}

impl Pencil {
    /// The masked-in pixels of `mask` around the image of `apex_clip` (clip space, homogeneous), or `None`
    /// when that image is at or near infinity ([`screen_point`]), or the mask is empty or holds more
    /// than [`MAX_DENSITY`] of the target (most triangles would have too many candidates to be taken).
    #[must_use]
    pub fn new(mask: &ComputationMask, apex_clip: Vec4) -> Option<Self> {
        let (w, h) = mask.size();
        let apex = screen_point(apex_clip, w, h)?;
        let n = mask.count();
        if n == 0 || n as f64 > MAX_DENSITY * f64::from(w) * f64::from(h) {
            return None;
        }
        let mut sorted: Vec<(f64, f64, [u32; 2])> = (0..h)
            .into_par_iter()
            .flat_map_iter(|y| {
                let mut row = Vec::new();
                mask.each_run(y, 0, w.saturating_sub(1), |a, b| {
                    for x in a..=b {
                        let d = DVec2::new(f64::from(x) + 0.5, f64::from(y) + 0.5) - apex;
                        row.push((d.y.atan2(d.x), d.length_squared(), [x, y]));
                    }
                });
                row
            })
            .collect();
        sorted.par_sort_unstable_by(|p, q| p.0.total_cmp(&q.0).then(p.2.cmp(&q.2)));
        let (angle_min, angle_max): (Vec<f64>, Vec<f64>) =
            sorted.chunks(BUCKET).map(|b| (b[0].0, b[b.len() - 1].0)).unzip();
        sorted.par_chunks_mut(BUCKET).for_each(|b| b.sort_unstable_by(|p, q| p.1.total_cmp(&q.1).then(p.2.cmp(&q.2))));
        let start_dirs = angle_min.iter().map(|&a| DVec2::from_angle(a)).collect();
        Some(Self {
            apex,
            start_dirs,
            angle_min,
            angle_max,
            dist2: sorted.iter().map(|p| p.1).collect(),
            centres: sorted.iter().map(|&(_, _, [x, y])| [x, y].map(|v| (i64::from(v) * ONE + HALF) as f64)).collect(),
            columns: sorted.iter().map(|&(_, _, [x, _])| x as f32).collect(),
            at: sorted.iter().map(|&(_, _, [x, y])| y * w + x).collect(),
        })
    }

    /// How many pixels are ordered.
    #[must_use]
    pub fn len(&self) -> usize {
        self.at.len()
    }

    /// True when the mask has no pixel.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.at.is_empty()
    }

    /// Appends to `out` the runs of candidates for `t` among the buckets meeting the angles `[lo, hi]`
    /// (within `[-pi, pi]`, with `ends` the unit directions there): per bucket, the pixels within the
    /// distances `t` spans between that bucket's first angle and the next one's. Returns how many they
    /// are, or at once more than `limit` buckets hold when more than `limit` buckets meet the angles
    /// (searching them would cost more than a walk).
    fn candidates(
        &self,
        t: &Polar,
        (lo, hi): (f64, f64),
        ends: [DVec2; 2],
        limit: usize,
        out: &mut Vec<Range<u32>>,
    ) -> usize {
        let first = self.angle_max.partition_point(|&a| a < lo);
        let last = self.angle_min.partition_point(|&a| a <= hi);
        if first >= last {
            return 0;
        }
        if last - first > limit {
            return limit * BUCKET + 1;
        }
        let mut n = 0;
        // Each bucket's sector runs from its first angle to the next bucket's (a superset of its pixels'
        // angles), cut to [lo, hi]; neighbours share the ray between them.
        let ray = |(a, u): (f64, DVec2)| (a, t.ray(u));
        let mut from = (self.angle_min[first] <= lo).then(|| ray((lo, ends[0])));
        for b in first..last {
            let start = from.unwrap_or_else(|| ray((self.angle_min[b], self.start_dirs[b])));
            let end = ray(match self.angle_min.get(b + 1) {
                Some(&a) if a < hi => (a, self.start_dirs[b + 1]),
                _ => (hi, ends[1]),
            });
            from = Some(end);
            let Some((near, far)) = t.distances(start, end) else { continue };
            let begin = b * BUCKET;
            let bucket = &self.dist2[begin..(begin + BUCKET).min(self.len())];
            let (near, far) = (bucket.partition_point(|&d| d < near), bucket.partition_point(|&d| d <= far));
            if near < far {
                n += far - near;
                out.push((begin + near) as u32..(begin + far) as u32);
            }
        }
        n
    }

    /// Whether `t` is taken here, with the runs of pixels that may lie inside it appended to `out`; not
    /// when it surrounds or nearly meets the apex, or has more candidates than walking its rows would cost.
    fn take(&self, t: &Setup, out: &mut Vec<Range<u32>>) -> bool {
        let Some(polar) = Polar::new(t, self.apex) else { return false };
        let ((lo, hi), [u_lo, u_hi]) = (polar.angles, polar.ends);
        let mark = out.len();
        let rows = (t.max_y - t.min_y + 1) as usize;
        let n = if lo <= hi {
            self.candidates(&polar, (lo, hi), [u_lo, u_hi], rows, out)
        } else {
            let cut = DVec2::NEG_X;
            self.candidates(&polar, (lo, PI), [u_lo, cut], rows, out)
                + self.candidates(&polar, (-PI, hi), [cut, u_hi], rows, out)
        };
        if n > rows * PIXELS_PER_ROW {
            out.truncate(mark);
            return false;
        }
        true
    }

    /// Which of `setups` are taken here, with their candidates, and which are walked.
    pub(super) fn plan(&self, setups: &[Setup]) -> Plan {
        let parts: Vec<Plan> = setups
            .par_chunks(512)
            .enumerate()
            .map(|(chunk, part)| {
                let mut plan = Plan { taken: Vec::new(), ranges: Vec::new(), walked: Vec::new() };
                for (i, t) in part.iter().enumerate() {
                    let index = (chunk * 512 + i) as u32;
                    let mark = plan.ranges.len() as u32;
                    if self.take(t, &mut plan.ranges) {
                        plan.taken.push((index, mark..plan.ranges.len() as u32));
                    } else {
                        plan.walked.push(index);
                    }
                }
                plan
            })
            .collect();
        let mut plan = Plan { taken: Vec::new(), ranges: Vec::new(), walked: Vec::new() };
        for part in parts {
            let offset = plan.ranges.len() as u32;
            plan.taken.extend(part.taken.into_iter().map(|(i, r)| (i, r.start + offset..r.end + offset)));
            plan.ranges.extend(part.ranges);
            plan.walked.extend(part.walked);
        }
        plan
    }

    /// Counts the triangles the plan takes into `stencil` against `depth`: each tested at its candidate
    /// pixels, as the row walk tests each of its rows' pixels.
    pub(super) fn count(
        &self,
        setups: &[Setup],
        plan: &Plan,
        (compare, front, back): Counting,
        clamp: bool,
        (depth, stencil): (&[f32], &mut [u8]),
    ) -> RasterCounters {
        // Nothing to gather or add up for a draw the pencil took nothing of (most of a many-instance
        // scene's draws).
        if plan.taken.is_empty() {
            return RasterCounters::default();
        }
        // One loop per depth test, so the test is not matched per candidate.
        let (deltas, c) =
            super::with_depth_test!(compare, pass => self.deltas(setups, plan, (front, back), clamp, depth, pass));
        for (&at, d) in self.at.iter().zip(deltas) {
            let s = &mut stencil[at as usize];
            *s = s.wrapping_add(d);
        }
        c
    }

    /// The stencil increments of the taken triangles per pixel in the pencil's order, with their counters;
    /// `pass` is the depth test of a fragment's depth against the stored one.
    fn deltas(
        &self,
        setups: &[Setup],
        plan: &Plan,
        (front, back): ((u8, u8), (u8, u8)),
        clamp: bool,
        depth: &[f32],
        pass: impl Fn(f32, f32) -> bool + Sync,
    ) -> (Vec<u8>, RasterCounters) {
        // The stored depths in the pencil's order: read in sequence, not scattered along the rays.
        let depth: Vec<f32> = self.at.iter().map(|&at| depth[at as usize]).collect();
        let chunk = plan.taken.len().div_ceil(rayon::current_num_threads() * 4).max(64);
        plan.taken
            .par_chunks(chunk)
            .map(|part| {
                let mut delta = vec![0u8; self.len()];
                let mut c = RasterCounters::default();
                for (ti, ranges) in part {
                    let test = CandidateTest::new(&setups[*ti as usize], (front, back), clamp, &pass);
                    let (mut fragments, mut passed) = (0, 0);
                    for r in &plan.ranges[ranges.start as usize..ranges.end as usize] {
                        let r = r.start as usize..r.end as usize;
                        let (f, p) = test.run(
                            &self.centres[r.clone()],
                            &self.columns[r.clone()],
                            &depth[r.clone()],
                            &mut delta[r],
                        );
                        (fragments, passed) = (fragments + f, passed + p);
                    }
                    c.fragments += fragments;
                    c.pencil_triangles += 1;
                    c.passed += passed;
                    c.stencil_updates += test.stencil_updates(fragments, passed);
                }
                (delta, c)
            })
            .reduce(
                || (vec![0u8; self.len()], RasterCounters::default()),
                |(mut a, mut ca), (b, cb)| {
                    for (a, b) in a.iter_mut().zip(b) {
                        *a = a.wrapping_add(b);
                    }
                    ca += cb;
                    (a, ca)
                },
            )
    }
}
