//! The rasterizer's inner loops: one triangle over the rows of one band, by the path its state allows
//! (a depth-only kernel, a flat value, depth peeling, or the general path of a fragment closure with
//! depth, stencil and blending), each row's coverage from the triangle's edge walk.

use super::{
    CompareFn, ComputationMask, EdgeWalk, Fragment, HALF, ONE, RasterCounters, RasterState, Setup, StencilFace,
    StencilOp, Weights, masked_rows,
};

pub(super) struct BandRows<'a, T> {
    pub(super) depth: &'a mut [f32],
    pub(super) stencil: &'a mut [u8],
    pub(super) color: &'a mut [T],
    pub(super) y0: i32,
    pub(super) width: usize,
}

/// The depths along one row: at column `x`, `z_row + dzdx x` (`z_row` the depth at column 0's centre),
/// clamped to [0, 1] when asked. In a form a row loop runs without a branch per fragment: the clamp as
/// bounds that are infinite when it is off (the same value as `f32::clamp`, NaN and -0 included). The
/// loops that vectorize count passes in a u32 (a row is at most
/// [`MAX_TARGET_SIDE`](crate::context::MAX_TARGET_SIDE) wide): a 64-bit count would halve the lanes.
#[derive(Clone, Copy)]
pub(super) struct RowDepth {
    pub(super) z_row: f32,
    pub(super) dzdx: f32,
    pub(super) lo: f32,
    pub(super) hi: f32,
}

impl RowDepth {
    #[inline(always)]
    pub(super) fn new(t: &Setup, row: RowStart) -> Self {
        let (lo, hi) = if row.clamp { (0.0, 1.0) } else { (f32::NEG_INFINITY, f32::INFINITY) };
        Self { z_row: row.z_row, dzdx: t.dzdx, lo, hi }
    }

    /// The depth at column `x`.
    #[inline(always)]
    pub(super) fn at(&self, x: i32) -> f32 {
        let z = self.z_row + self.dzdx * x as f32;
        if z < self.lo {
            self.lo
        } else if z > self.hi {
            self.hi
        } else {
            z
        }
    }
}

/// The depth of a row at the centre of column 0, bias included: the one place depth is interpolated, so
/// every draw of a triangle gives it bit-identical depths. `py` is the row's centre in fixed point.
#[inline(always)]
pub(super) fn row_base(t: &Setup, py: i64) -> f32 {
    row_depth(t, depth_origin(t), (py - t.fy[0]) as f32 / ONE as f32)
}

/// The part of [`row_base`] every row of `t` shares: the depth plane at column 0's centre and corner 0's
/// height, without the bias.
#[inline(always)]
pub(super) fn depth_origin(t: &Setup) -> f32 {
    t.z0 + t.dzdx * ((HALF - t.fx[0]) as f32 / ONE as f32)
}

/// [`row_base`] from [`depth_origin`] and the row's height above corner 0 in pixels.
#[inline(always)]
pub(super) fn row_depth(t: &Setup, origin: f32, dy: f32) -> f32 {
    origin + t.dzdy * dy + t.offset
}

/// A stencil op as an 8-bit wrapping increment, when it is one (Keep, IncrementWrap, DecrementWrap).
pub(super) fn as_delta(op: StencilOp) -> Option<u8> {
    match op {
        StencilOp::Keep => Some(0),
        StencilOp::IncrementWrap => Some(1),
        StencilOp::DecrementWrap => Some(255),
        _ => None,
    }
}

/// The fast inner loops of depth-only draws: plain depth tests, or stencil counting where the op depends
/// only on the depth test (shadow volumes). `None` when the state needs the general loop.
#[derive(Clone, Copy)]
pub(super) enum DepthKernel {
    Depth { compare: CompareFn, write: bool },
    Count { compare: CompareFn, front: (u8, u8), back: (u8, u8) },
}

impl DepthKernel {
    pub(super) fn for_state(st: &RasterState) -> Option<Self> {
        let d = st.depth?;
        match &st.stencil {
            None => Some(Self::Depth { compare: d.compare, write: d.write }),
            Some(s) => {
                let counting = |f: &StencilFace| {
                    (f.compare == CompareFn::Always).then_some(())?;
                    Some((as_delta(f.pass)?, as_delta(f.depth_fail)?))
                };
                (s.write_mask == 0xff && !d.write).then_some(())?;
                Some(Self::Count { compare: d.compare, front: counting(&s.front)?, back: counting(&s.back)? })
            }
        }
    }
}

/// Where a row's span starts: its depth base, the clamp flag and the first column.
#[derive(Clone, Copy)]
pub(super) struct RowStart {
    pub(super) z_row: f32,
    pub(super) clamp: bool,
    pub(super) xs: i32,
}

/// How a draw treats its fragments.
#[derive(Clone, Copy)]
pub(super) enum Path<'a> {
    /// One at a time through the fragment closure and every test of the state.
    General,
    /// Depth (and stencil) only, through a fast kernel.
    Depth(DepthKernel),
    /// Depth tests that write, through the fast kernel, and where they pass the colour the fragment
    /// closure gives the primitive ([`draw_flat`]); other kernels take the general path.
    Flat(DepthKernel),
    /// A writing depth test behind a peeled layer ([`draw_depth_peeled`]): `under` is that layer's
    /// depths, row by row over the whole target.
    Peel { compare: CompareFn, epsilon: f32, under: &'a [f32] },
}

impl Fragment<'_> {
    /// The fragment a flat draw's closure is asked about: only `prim` and `front_facing` are the
    /// triangle's.
    pub(super) fn of_primitive(t: &Setup) -> Self {
        Self { x: 0, y: 0, depth: 0.0, prim: t.prim, front_facing: t.front, weights: Weights::Centroid }
    }
}

/// One row of a flat draw ([`draw_flat`]): a writing depth test and the primitive's `value` where it
/// passes. Branch-free, as [`row_fast`].
#[inline(always)]
pub(super) fn row_flat<T>(
    t: &Setup,
    compare: CompareFn,
    row: RowStart,
    depth: &mut [f32],
    color: &mut [T],
    value: T,
    c: &mut RasterCounters,
) where
    T: Copy,
{
    let z = RowDepth::new(t, row);
    let passed = with_depth_test!(compare, test => {
        let mut passed = 0u32;
        for (i, (d, col)) in depth.iter_mut().zip(&mut *color).enumerate() {
            let z = z.at(row.xs + i as i32);
            let pass = test(z, *d);
            *d = if pass { z } else { *d };
            *col = if pass { value } else { *col };
            passed += u32::from(pass);
        }
        passed
    });
    c.fragments += depth.len() as u64;
    c.passed += u64::from(passed);
}

/// One row of a peeling draw ([`draw_depth_peeled`]): a fragment passes when it lies more than
/// `epsilon` beyond the peeled layer and passes the depth test; its depth is then written. Branch-free,
/// as [`row_fast`].
#[inline(always)]
pub(super) fn row_peel(
    t: &Setup,
    (compare, epsilon): (CompareFn, f32),
    row: RowStart,
    depth: &mut [f32],
    under: &[f32],
    c: &mut RasterCounters,
) {
    let z = RowDepth::new(t, row);
    let passed = with_depth_test!(compare, test => {
        let mut passed = 0u32;
        for (i, (d, u)) in depth.iter_mut().zip(under).enumerate() {
            let z = z.at(row.xs + i as i32);
            let pass = (z > *u + epsilon) & test(z, *d);
            *d = if pass { z } else { *d };
            passed += u32::from(pass);
        }
        passed
    });
    c.fragments += depth.len() as u64;
    c.passed += u64::from(passed);
}

/// One row of a depth-only draw with a fast kernel. Branch-free, so the compiler can vectorize it.
#[inline(always)]
pub(super) fn row_fast(
    t: &Setup,
    k: DepthKernel,
    row: RowStart,
    depth: &mut [f32],
    stencil: &mut [u8],
    c: &mut RasterCounters,
) {
    let z = RowDepth::new(t, row);
    let n = depth.len() as u64;
    c.fragments += n;
    let passed = match k {
        DepthKernel::Depth { compare, write: true } => with_depth_test!(compare, test => {
            let mut passed = 0u32;
            for (i, d) in depth.iter_mut().enumerate() {
                let z = z.at(row.xs + i as i32);
                let pass = test(z, *d);
                *d = if pass { z } else { *d };
                passed += u32::from(pass);
            }
            passed
        }),
        DepthKernel::Depth { compare, write: false } => with_depth_test!(compare, test => {
            let mut passed = 0u32;
            for (i, d) in depth.iter().enumerate() {
                passed += u32::from(test(z.at(row.xs + i as i32), *d));
            }
            passed
        }),
        DepthKernel::Count { compare, front, back } => {
            let (dp, df) = if t.front { front } else { back };
            let passed = with_depth_test!(compare, test => {
                let mut passed = 0u32;
                for (i, (d, s)) in depth.iter().zip(&mut *stencil).enumerate() {
                    let pass = test(z.at(row.xs + i as i32), *d);
                    *s = s.wrapping_add(if pass { dp } else { df });
                    passed += u32::from(pass);
                }
                passed
            });
            let counted = u64::from(passed);
            c.stencil_updates += if dp != 0 { counted } else { 0 } + if df != 0 { n - counted } else { 0 };
            passed
        }
    };
    c.passed += u64::from(passed);
}

#[inline(always)]
pub(super) fn raster_band<T, F, B>(
    t: &Setup,
    rows: &mut BandRows<'_, T>,
    st: &RasterState,
    (path, mask): (Path<'_>, Option<&ComputationMask>),
    (shader, blend): (&F, &B),
    c: &mut RasterCounters,
) where
    T: Copy,
    F: Fn(&Fragment) -> Option<T>,
    B: Fn(&mut T, T),
{
    let band_rows = (rows.depth.len() / rows.width) as i32;
    let y_lo = t.min_y.max(rows.y0);
    let y_hi = t.max_y.min(rows.y0 + band_rows - 1);
    let clamp = st.depth.is_some_and(|d| d.clamp);
    if let (Some(m), Path::Depth(k)) = (mask, path) {
        masked_rows(t, rows, k, clamp, m, (y_lo, y_hi), c);
        return;
    }
    let mut walk = EdgeWalk::new(t, y_lo);
    for y in y_lo..=y_hi {
        let py = i64::from(y) * ONE + HALF;
        let Some((xs, xe)) = walk.next_row() else { continue };
        let z_row = row_base(t, py);
        let row = (y - rows.y0) as usize * rows.width;
        let mut run = |a: i32, b: i32| {
            let (lo, hi) = (row + a as usize, row + b as usize + 1);
            let start = RowStart { z_row, clamp, xs: a };
            match path {
                Path::Depth(k) => row_fast(t, k, start, &mut rows.depth[lo..hi], &mut rows.stencil[lo..hi], c),
                Path::Peel { compare, epsilon, under } => {
                    let at = rows.y0 as usize * rows.width;
                    let under = &under[at + lo..at + hi];
                    row_peel(t, (compare, epsilon), start, &mut rows.depth[lo..hi], under, c);
                }
                Path::Flat(DepthKernel::Depth { compare, write: true }) => {
                    if let Some(v) = shader(&Fragment::of_primitive(t)) {
                        row_flat(t, compare, start, &mut rows.depth[lo..hi], &mut rows.color[lo..hi], v, c);
                    }
                }
                _ => row_general(t, rows, st, (y, py, row), (start, b), (shader, blend), c),
            }
        };
        match mask {
            None => run(xs, xe),
            Some(m) => m.each_run(y as u32, xs as u32, xe as u32, |a, b| run(a as i32, b as i32)),
        }
    }
}

/// Columns `start.xs..=xe` of row `y` (`py` its centre in fixed point, `row` its first index in the band)
/// through the general per-fragment path.
#[inline(always)]
pub(super) fn row_general<T, F, B>(
    t: &Setup,
    rows: &mut BandRows<'_, T>,
    st: &RasterState,
    (y, py, row): (i32, i64, usize),
    (start, xe): (RowStart, i32),
    (shader, blend): (&F, &B),
    c: &mut RasterCounters,
) where
    F: Fn(&Fragment) -> Option<T>,
    B: Fn(&mut T, T),
{
    let (xs, z) = (start.xs, RowDepth::new(t, start));
    let px0 = i64::from(xs) * ONE + HALF;
    let mut e: [i64; 3] = std::array::from_fn(|k| t.a[k] * px0 + t.b[k] * py + t.c[k]);
    let step: [i64; 3] = t.a.map(|a| a * ONE);
    for x in xs..=xe {
        let depth = z.at(x);
        let here = e;
        for (e, s) in e.iter_mut().zip(step) {
            *e += s;
        }
        c.fragments += 1;
        let frag = || Fragment {
            x: x as u32,
            y: y as u32,
            depth,
            prim: t.prim,
            front_facing: t.front,
            weights: Weights::At { edges: here, setup: t },
        };
        let i = row + x as usize;
        let mut value = None;
        if !st.early_tests {
            value = shader(&frag());
            if value.is_none() {
                continue;
            }
        }
        if let Some(s) = &st.stencil {
            let face = if t.front { s.front } else { s.back };
            let stored = rows.stencil[i];
            let op = if !face.compare.test(s.reference & s.read_mask, stored & s.read_mask) {
                Some(face.fail)
            } else if st.depth.is_some_and(|d| !d.compare.test(depth, rows.depth[i])) {
                Some(face.depth_fail)
            } else {
                None
            };
            if let Some(op) = op {
                if op != StencilOp::Keep {
                    rows.stencil[i] = (stored & !s.write_mask) | (op.apply(stored, s.reference) & s.write_mask);
                    c.stencil_updates += 1;
                }
                continue;
            }
            if face.pass != StencilOp::Keep {
                rows.stencil[i] = (stored & !s.write_mask) | (face.pass.apply(stored, s.reference) & s.write_mask);
                c.stencil_updates += 1;
            }
        } else if let Some(d) = &st.depth
            && !d.compare.test(depth, rows.depth[i])
        {
            continue;
        }
        if st.early_tests {
            value = shader(&frag());
            if value.is_none() {
                continue;
            }
        }
        c.passed += 1;
        if let Some(d) = &st.depth
            && d.write
        {
            rows.depth[i] = depth;
        }
        if let Some(v) = value {
            blend(&mut rows.color[i], v);
        }
    }
}
