//! Counting draws confined to a short list of pixels each: per caster, the computation mask cut down to
//! the pixels that caster's shadow can hold (`hybrid`'s caster masks).
//!
//! A draw's list is short (tens to hundreds of pixels) and its triangles few (one connected component's
//! shadow volume), so each triangle is tested at the listed pixels in the rows it spans, found by binary
//! search, with the walk's own edge functions, top-left rule and depth plane (the candidate
//! test, [`super::candidates`]): the same fragments, depths and stencil increments as a row walk under a mask
//! holding just those pixels. The draws run in
//! parallel, each counting into deltas of its own list, added into the stencil afterwards (counting ops
//! commute).

use rayon::prelude::*;

use super::candidates::CandidateTest;
use super::{
    CompareFn, DepthKernel, DepthStencil, HALF, ONE, RasterCounters, RasterState, Setup, TriangleSource, guard_band,
    setup,
};

/// A counting draw of some triangle sources at some pixels only.
pub struct ListedDraw<'a> {
    /// The triangles, source by source.
    pub sources: Vec<&'a dyn TriangleSource>,
    /// The only pixels the draw may touch, as indices `y * width + x` into the target, ascending.
    pub pixels: &'a [u32],
}

/// Rasterizes every draw into the stencil of `ds` at its listed pixels only, with the counting state `st`
/// (stencil ops that depend on the depth test alone, as shadow volumes' are).
///
/// # Panics
/// When `st` is not a counting state, or a list is not ascending within the target: caller bugs.
pub fn count_listed(ds: &mut DepthStencil, draws: &[ListedDraw], st: &RasterState) -> RasterCounters {
    let Some(DepthKernel::Count { compare, front, back }) = DepthKernel::for_state(st) else {
        panic!("count_listed needs a counting state (stencil ops that depend on the depth test alone)");
    };
    let clamp = st.depth.is_some_and(|d| d.clamp);
    // One loop per depth test, so the test is not matched per pixel.
    let counted = super::with_depth_test!(compare, pass => count_each(ds, draws, st, (front, back), clamp, pass));
    let mut total = RasterCounters::default();
    for (draw, (delta, c)) in draws.iter().zip(counted) {
        for (&p, d) in draw.pixels.iter().zip(delta) {
            let s = &mut ds.stencil[p as usize];
            *s = s.wrapping_add(d);
        }
        total += c;
    }
    total
}

/// Each draw's stencil increments at its pixels, with its counters.
fn count_each(
    ds: &DepthStencil,
    draws: &[ListedDraw],
    st: &RasterState,
    ops: ((u8, u8), (u8, u8)),
    clamp: bool,
    pass: impl Fn(f32, f32) -> bool + Sync,
) -> Vec<(Vec<u8>, RasterCounters)> {
    let (w, h) = (ds.width, ds.height);
    let guard = guard_band(w, h);
    draws
        .par_iter()
        .map(|draw| {
            let pixels = draw.pixels;
            assert!(
                pixels.windows(2).all(|p| p[0] < p[1]) && pixels.last().is_none_or(|&p| p < w * h),
                "a listed draw's pixels ascending within the target"
            );
            let mut setups: Vec<Setup> = Vec::new();
            for src in &draw.sources {
                src.each(0..src.len(), &mut |t| setup(t, st, w, h, guard, &mut setups));
            }
            let mut c = RasterCounters { triangles: setups.len() as u64, ..RasterCounters::default() };
            let mut delta = vec![0u8; pixels.len()];
            if pixels.is_empty() || setups.is_empty() {
                return (delta, c);
            }
            // The pixels' centres in fixed point (integers, exact in f64), columns and stored depths.
            let centres: Vec<[f64; 2]> =
                pixels.iter().map(|&p| [p % w, p / w].map(|v| (i64::from(v) * ONE + HALF) as f64)).collect();
            let columns: Vec<f32> = pixels.iter().map(|&p| (p % w) as f32).collect();
            let stored: Vec<f32> = pixels.iter().map(|&p| ds.depth[p as usize]).collect();
            for t in &setups {
                // The listed pixels in the rows the triangle spans.
                let first = pixels.partition_point(|&p| p < t.min_y as u32 * w);
                let end = first + pixels[first..].partition_point(|&p| p < (t.max_y as u32 + 1) * w);
                let r = first..end;
                let test = CandidateTest::new(t, ops, clamp, &pass);
                let (fragments, passed) =
                    test.run(&centres[r.clone()], &columns[r.clone()], &stored[r.clone()], &mut delta[r]);
                c.fragments += fragments;
                c.passed += passed;
                c.stencil_updates += test.stencil_updates(fragments, passed);
            }
            (delta, c)
        })
        .collect()
}
