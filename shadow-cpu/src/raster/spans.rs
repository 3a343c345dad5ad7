//! Which columns of a row a set-up triangle covers: exactly, row after row ([`EdgeWalk`], the rasterizer's
//! spans, solving the edge functions with the top-left rule, `E_k(256 x + 128, py) + tl_k >= 0`), and as a
//! cheap superset over a slab of rows ([`slab_columns`], to test a tile row against a mask).

#[cfg(test)]
use super::setup::{ceil_div, floor_div};
use super::{HALF, ONE, Setup};

/// The columns of row `py` (fixed point) inside all three edges, solved by division: what [`EdgeWalk`]
/// steps to, row after row.
#[cfg(test)]
pub(super) fn span(t: &Setup, py: i64) -> Option<(i32, i32)> {
    let (mut lo, mut hi) = (i64::from(t.min_x), i64::from(t.max_x));
    for k in 0..3 {
        // E_k(256 x + 128) + tl >= 0  <=>  256 a x >= -(b py + c + tl) - 128 a.
        let kk = t.b[k] * py + t.c[k] + t.tl[k];
        let num = -kk - HALF * t.a[k];
        let den = ONE * t.a[k];
        match den.signum() {
            1 => lo = lo.max(ceil_div(num, den)),
            -1 => hi = hi.min(floor_div(num, den)),
            _ if kk < 0 => return None,
            _ => {}
        }
    }
    (lo <= hi).then_some((lo as i32, hi as i32))
}

/// `floor(m / d)` for `d > 0` while `m` moves by the same amount every row: a quotient and a remainder
/// stepped with additions, exactly, as a DDA walks an edge.
#[derive(Clone, Copy, Debug)]
struct FloorStep {
    q: i64,
    r: i64,
    step_q: i64,
    step_r: i64,
    d: i64,
}

impl FloorStep {
    fn new(m: i64, step: i64, d: i64) -> Self {
        Self { q: m.div_euclid(d), r: m.rem_euclid(d), step_q: step.div_euclid(d), step_r: step.rem_euclid(d), d }
    }

    #[inline(always)]
    fn next_row(&mut self) {
        self.r += self.step_r;
        let carry = i64::from(self.r >= self.d);
        self.r -= carry * self.d;
        self.q += self.step_q + carry;
    }
}

/// What one edge function says about a row's columns.
#[derive(Clone, Copy, Debug)]
enum EdgeBound {
    /// Inside from this column on (`a > 0`).
    From(FloorStep),
    /// Inside up to this column (`a < 0`).
    To(FloorStep),
    /// A horizontal edge (`a = 0`): the row is inside while its edge function `kk` is not negative.
    Rows { kk: i64, step: i64 },
}

/// A triangle's spans row after row: the columns of each row inside all three edges, with three
/// divisions where the walk starts and additions after (`E_k(256 x + 128) + tl >= 0` solved for `x`,
/// each bound's numerator moving by `-b * 256` a row).
#[derive(Clone, Copy, Debug)]
pub(super) struct EdgeWalk {
    edges: [EdgeBound; 3],
    min_x: i64,
    max_x: i64,
}

impl EdgeWalk {
    /// The walk of `t` from row `y`.
    pub(super) fn new(t: &Setup, y: i32) -> Self {
        let py = i64::from(y) * ONE + HALF;
        let edges = std::array::from_fn(|k| {
            let kk = t.b[k] * py + t.c[k] + t.tl[k];
            let (num, num_step, den) = (-kk - HALF * t.a[k], -t.b[k] * ONE, ONE * t.a[k]);
            match den.signum() {
                // ceil(num / den) = floor((num + den - 1) / den).
                1 => EdgeBound::From(FloorStep::new(num + den - 1, num_step, den)),
                // floor(num / den) = floor(-num / -den).
                -1 => EdgeBound::To(FloorStep::new(-num, -num_step, -den)),
                _ => EdgeBound::Rows { kk, step: t.b[k] * ONE },
            }
        });
        Self { edges, min_x: i64::from(t.min_x), max_x: i64::from(t.max_x) }
    }

    /// The current row's columns, then on to the next row.
    #[inline(always)]
    pub(super) fn next_row(&mut self) -> Option<(i32, i32)> {
        let (mut lo, mut hi, mut rows) = (self.min_x, self.max_x, true);
        for e in &mut self.edges {
            match e {
                EdgeBound::From(f) => {
                    lo = lo.max(f.q);
                    f.next_row();
                }
                EdgeBound::To(f) => {
                    hi = hi.min(f.q);
                    f.next_row();
                }
                EdgeBound::Rows { kk, step } => {
                    rows &= *kk >= 0;
                    *kk += *step;
                }
            }
        }
        (rows && lo <= hi).then_some((lo as i32, hi as i32))
    }
}

/// A superset of the columns rows `ya..=yb` have inside the triangle, clamped to its bounds, or `None`
/// when it has none there: the x extent of the triangle cut to the slab between the rows' centres, whose
/// corners are triangle corners inside the slab or points on its two lines (in the triangle's cross
/// sections there). Floating point from the edges' precomputed row crossings (far below a pixel off for
/// fixed-point inputs), widened by a pixel each side, so a whole tile row of a triangle is tested against
/// a mask with a few multiply-adds, not a walk of its rows.
pub(super) fn slab_columns(t: &Setup, ya: i32, yb: i32) -> Option<(i32, i32)> {
    let (pa, pb) = (i64::from(ya) * ONE + HALF, i64::from(yb) * ONE + HALF);
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for k in 0..3 {
        if (pa..=pb).contains(&t.fy[k]) {
            lo = lo.min(t.fx[k] as f64);
            hi = hi.max(t.fx[k] as f64);
        }
    }
    for py in [pa, pb] {
        // The cross section at py: E_k(px, py) = a px + b py + c >= 0 for every edge.
        let (mut l, mut r) = (f64::NEG_INFINITY, f64::INFINITY);
        for k in 0..3 {
            let x = t.x_at[k].0 + t.x_at[k].1 * py as f64;
            match t.a[k].signum() {
                1 => l = l.max(x),
                -1 => r = r.min(x),
                _ if t.b[k] * py + t.c[k] < 0 => r = f64::NEG_INFINITY,
                _ => {}
            }
        }
        if l <= r + ONE as f64 {
            lo = lo.min(l);
            hi = hi.max(r);
        }
    }
    if lo > hi + ONE as f64 {
        return None;
    }
    let first = ((lo - HALF as f64) / ONE as f64).floor() as i64 - 1;
    let last = ((hi - HALF as f64) / ONE as f64).ceil() as i64 + 1;
    let (first, last) = (first.max(i64::from(t.min_x)), last.min(i64::from(t.max_x)));
    (first <= last).then_some((first as i32, last as i32))
}
