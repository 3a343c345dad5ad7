//! A set-up triangle tested at a list of candidate pixels instead of walked row by row: the caster
//! masks' listed draws ([`super::listed`]) count each small volume piece only at the silhouette pixels its
//! shaft holds.

use super::{ONE, Setup, depth_origin, row_depth};

/// A set-up triangle's test at candidate pixels, as the row walk tests each of its rows' pixels: the walk's
/// edge functions (top-left rule included) and depth plane, with what is the same for every pixel hoisted.
/// In f64 the edge functions' integer terms (far under 2^53) are exact, with no 64-bit integer multiplies;
/// `py - fy0` is an exact integer rounded to f32 as the walk's i64 is, so the depth is `row_base` and
/// `RowDepth::at`'s f32 arithmetic, bit for bit.
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
