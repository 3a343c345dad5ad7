//! The row walk of a triangle under a computation mask, for the fast depth-only kernels.

use super::spans::{EdgeWalk, slab_columns};
use super::{BandRows, DepthKernel, HALF, ONE, RasterCounters, RowStart, Setup, row_base, row_fast};
use crate::raster::ComputationMask;

/// Rows `y_lo..=y_hi` of a triangle under a computation mask, with a fast kernel: a tile row at a time,
/// tested whole against the mask's tiles (the triangle's bounds first, then its own columns there,
/// [`slab_columns`]), and where a masked-in tile meets it, row by row, each row's span ([`EdgeWalk`], the
/// row walk's own) cut to the mask's runs a word of bits at a time. A tile row with nothing masked in
/// costs two table lookups, a row of one a walk step and a word or two of bits, so the work follows the
/// mask, not the triangle's rows or the silhouette pixels it does not cover. Same fragments, depths and
/// counters as the row walk.
pub(super) fn masked_rows<T>(
    t: &Setup,
    rows: &mut BandRows<'_, T>,
    k: DepthKernel,
    clamp: bool,
    m: &ComputationMask,
    (y_lo, y_hi): (i32, i32),
    c: &mut RasterCounters,
) {
    /// Rows a walk steps through rather than starting anew (three divisions a start, one addition an
    /// edge a row).
    const STEP_AHEAD: i32 = 32;
    let tile = m.tile() as i32;
    let mut walk: Option<(EdgeWalk, i32)> = None;
    let mut y = y_lo;
    while y <= y_hi {
        let end = (y - y % tile + tile - 1).min(y_hi);
        let masked_in = m.any_in(t.min_x as u32, y as u32, t.max_x as u32, end as u32)
            && slab_columns(t, y, end).is_some_and(|(a, b)| m.any_in(a as u32, y as u32, b as u32, end as u32));
        if masked_in {
            let mut w = match walk {
                Some((mut w, at)) if y - at <= STEP_AHEAD => {
                    for _ in at..y {
                        w.next_row();
                    }
                    w
                }
                _ => EdgeWalk::new(t, y),
            };
            for ry in y..=end {
                let Some((xs, xe)) = w.next_row() else { continue };
                let py = i64::from(ry) * ONE + HALF;
                let row = (ry - rows.y0) as usize * rows.width;
                let mut z_row = None;
                m.each_run(ry as u32, xs as u32, xe as u32, |a, b| {
                    let (lo, hi) = (row + a as usize, row + b as usize + 1);
                    let start = RowStart { z_row: *z_row.get_or_insert_with(|| row_base(t, py)), clamp, xs: a as i32 };
                    row_fast(t, k, start, &mut rows.depth[lo..hi], &mut rows.stencil[lo..hi], c);
                });
            }
            walk = Some((w, end + 1));
        }
        y = end + 1;
    }
}
