//! A tile-binned, multi-threaded triangle rasterizer that follows DESIGN 4 to the letter: homogeneous
//! clipping, 8 subpixel bits, the top-left fill rule, counter-clockwise front faces, perspective-correct
//! barycentrics, f32 depth with Vulkan's float depth bias, depth clamp, culling, 8-bit two-sided stencil
//! and a per-fragment closure writing a colour target of any type.
//!
//! Triangles are set up in parallel batches, binned in submission order into bands of [`BAND_ROWS`]
//! rows, and the bands are rasterized in parallel. Every band owns its rows of every target and walks its
//! triangles in submission order, so the output does not depend on the thread count.

/// Evaluates `$body` with `$pass` bound to the depth test of `$compare` as a closure `(new, stored) ->
/// bool` of its own type, so a loop over pixels is compiled once per test rather than matching the test
/// per pixel.
macro_rules! with_depth_test {
    ($compare:expr, $pass:ident => $body:expr) => {
        match $compare {
            CompareFn::Never => {
                let $pass = |_: f32, _: f32| false;
                $body
            }
            CompareFn::Less => {
                let $pass = |z: f32, s: f32| z < s;
                $body
            }
            CompareFn::LessEqual => {
                let $pass = |z: f32, s: f32| z <= s;
                $body
            }
            CompareFn::Equal => {
                let $pass = |z: f32, s: f32| z == s;
                $body
            }
            CompareFn::Greater => {
                let $pass = |z: f32, s: f32| z > s;
                $body
            }
            CompareFn::GreaterEqual => {
                let $pass = |z: f32, s: f32| z >= s;
                $body
            }
            CompareFn::NotEqual => {
                let $pass = |z: f32, s: f32| z != s;
                $body
            }
            CompareFn::Always => {
                let $pass = |_: f32, _: f32| true;
                $body
            }
        }
    };
}
use with_depth_test;

mod candidates;
pub mod clip;
mod listed;
pub mod mask;
mod masked;
mod rows;
mod setup;
mod source;
mod spans;
pub mod state;

use rayon::prelude::*;
use shadow_core::Image;

pub use listed::{ListedDraw, count_listed};
pub use mask::ComputationMask;
use masked::masked_rows;
use rows::{BandRows, DepthKernel, Path, RowStart, depth_origin, raster_band, row_base, row_depth, row_fast};
use setup::{Setup, guard_band, setup};
pub use source::{Batch, Indexed, Soup, SourceTriangle, TriangleSource};
use spans::EdgeWalk;
pub use state::*;

/// Rows per band of the binning grid.
pub const BAND_ROWS: u32 = 16;
/// Subpixel bits of the fixed-point screen coordinates.
pub const SUBPIXEL_BITS: u32 = 8;
const ONE: i64 = 1 << SUBPIXEL_BITS;
const HALF: i64 = ONE / 2;
/// Triangles set up at once: bounds the memory of a draw whatever its size.
const BATCH: usize = 1 << 15;
/// Triangles a thread sets up in one go.
const SETUP_JOB: usize = 256;

/// A depth buffer with an 8-bit stencil, row-major from the top-left.
#[derive(Clone, Debug, PartialEq)]
pub struct DepthStencil {
    width: u32,
    height: u32,
    /// Depth per pixel.
    pub depth: Vec<f32>,
    /// Stencil per pixel.
    pub stencil: Vec<u8>,
}

impl DepthStencil {
    /// A buffer cleared to `depth` and `stencil`.
    #[must_use]
    pub fn new(width: u32, height: u32, depth: f32, stencil: u8) -> Self {
        let n = width as usize * height as usize;
        Self { width, height, depth: vec![depth; n], stencil: vec![stencil; n] }
    }

    /// A buffer over existing storage.
    ///
    /// # Panics
    /// When either vector is not `width * height` long: a caller bug.
    #[must_use]
    pub fn from_parts(width: u32, height: u32, depth: Vec<f32>, stencil: Vec<u8>) -> Self {
        let n = width as usize * height as usize;
        assert!(depth.len() == n && stencil.len() == n, "depth-stencil storage of the wrong size");
        Self { width, height, depth, stencil }
    }

    /// A buffer holding an existing depth image and a cleared stencil.
    #[must_use]
    pub fn from_depth(depth: &Image<f32>, stencil: u8) -> Self {
        Self {
            width: depth.width(),
            height: depth.height(),
            depth: depth.data().to_vec(),
            stencil: vec![stencil; depth.data().len()],
        }
    }

    /// Width in pixels.
    #[must_use]
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height in pixels.
    #[must_use]
    pub fn height(&self) -> u32 {
        self.height
    }

    /// The depth as an image.
    #[must_use]
    pub fn depth_image(&self) -> Image<f32> {
        Image::from_vec(self.width, self.height, self.depth.clone())
            .unwrap_or_else(|| unreachable!("sizes match by construction"))
    }

    /// The depth as an image, consuming the buffer.
    #[must_use]
    pub fn into_depth_image(self) -> Image<f32> {
        let (w, h) = (self.width, self.height);
        Image::from_vec(w, h, self.depth).unwrap_or_else(|| unreachable!("sizes match by construction"))
    }
}

/// A fragment handed to the closure.
#[derive(Clone, Copy, Debug)]
pub struct Fragment<'t> {
    /// Pixel column.
    pub x: u32,
    /// Pixel row.
    pub y: u32,
    /// Depth after bias (and clamp).
    pub depth: f32,
    /// Primitive id of the source triangle.
    pub prim: u32,
    /// Front-facing (after the source's flip).
    pub front_facing: bool,
    /// Where the barycentrics come from.
    weights: Weights<'t>,
}

/// What [`Fragment::bary`] works from: the pixel's edge functions in the triangle's setup, or nothing
/// (a flat draw's closure is asked once per primitive, about no pixel).
#[derive(Clone, Copy, Debug)]
enum Weights<'t> {
    Centroid,
    At { edges: [i64; 3], setup: &'t Setup },
}

impl Fragment<'_> {
    /// Perspective-correct barycentrics in the source triangle (before clipping); the centroid's for the
    /// fragment a flat draw asks about. Worked out when asked: most closures never read them, and a dozen
    /// multiplies and a division at every fragment is a large share of a draw whose closure is cheap.
    #[must_use]
    #[inline]
    pub fn bary(&self) -> [f32; 3] {
        match self.weights {
            Weights::Centroid => [1.0 / 3.0; 3],
            Weights::At { edges, setup: t } => bary_at(edges, t),
        }
    }

    /// [`Self::bary`] at the centres of the pixels one to the right and one down, on the triangle's
    /// plane whether or not they lie inside it: what the triangle interpolates changes by the difference
    /// from the fragment's own across one pixel, the pixel's footprint in it. The centroid's for a flat
    /// draw's fragment.
    #[must_use]
    #[inline]
    pub fn bary_beside(&self) -> [[f32; 3]; 2] {
        match self.weights {
            Weights::Centroid => [[1.0 / 3.0; 3]; 2],
            Weights::At { edges, setup: t } => [
                bary_at(std::array::from_fn(|k| edges[k] + t.a[k] * ONE), t),
                bary_at(std::array::from_fn(|k| edges[k] + t.b[k] * ONE), t),
            ],
        }
    }
}

/// The perspective-correct barycentrics in the source triangle of the point whose edge functions in the
/// setup `t` are `edges`: the weights of the clipped corners, then of the source triangle's.
#[inline]
fn bary_at(edges: [i64; 3], t: &Setup) -> [f32; 3] {
    let q = [0, 1, 2].map(|k| edges[k] as f32 * t.inv_area * t.inv_w[k]);
    let s = 1.0 / (q[0] + q[1] + q[2]);
    [0, 1, 2].map(|k| (q[0] * t.bary[0][k] + q[1] * t.bary[1][k] + q[2] * t.bary[2][k]) * s)
}

/// Rasterizes `src` into `ds` and `color`. The closure gives the colour of a fragment or `None` to
/// discard it; `blend` merges it into the stored colour.
///
/// # Panics
/// When `color` is not the size of `ds`: a caller bug.
pub fn draw<T, S, F, B>(
    ds: &mut DepthStencil,
    color: &mut Image<T>,
    src: &S,
    st: &RasterState,
    shader: F,
    blend: B,
) -> RasterCounters
where
    T: Copy + Send,
    S: TriangleSource + ?Sized,
    F: Fn(&Fragment) -> Option<T> + Sync,
    B: Fn(&mut T, T) + Sync,
{
    draw_with(ds, color, src, st, (Path::General, None), shader, blend)
}

/// A draw whose colour is one value per primitive, `value(prim)`: a visibility buffer of primitive ids, an
/// object-ID map. Depth tests and writes take the fast kernel's branch-free loop and store the triangle's
/// value where they pass, with no fragment closure and no interpolation per fragment. The same depths and
/// colours as [`draw`] with `|f| Some(value(f.prim))`, early tests and plain assignment, which it falls
/// back to for a state the fast kernel does not take (a stencil test, a depth test that does not write).
///
/// # Panics
/// When `color` is not the size of `ds`: a caller bug.
pub fn draw_flat<T, S, V>(
    ds: &mut DepthStencil,
    color: &mut Image<T>,
    src: &S,
    st: &RasterState,
    value: V,
) -> RasterCounters
where
    T: Copy + Send,
    S: TriangleSource + ?Sized,
    V: Fn(u32) -> T + Sync,
{
    let shader = |f: &Fragment| Some(value(f.prim));
    let path = match DepthKernel::for_state(st) {
        Some(k @ DepthKernel::Depth { write: true, .. }) => Path::Flat(k),
        _ => Path::General,
    };
    draw_with(ds, color, src, st, (path, None), shader, |d, v| *d = v)
}

/// Depth (and stencil) only: shadow-map renders and shadow-volume counting take branch-free inner loops.
pub fn draw_depth<S: TriangleSource + ?Sized>(ds: &mut DepthStencil, src: &S, st: &RasterState) -> RasterCounters {
    draw_depth_masked(ds, src, st, None)
}

/// [`draw_depth`] confined to the pixels of a computation mask (Chan, thesis 3.2), rejected as coarsely
/// as the mask allows before any depth or stencil work: a triangle is not binned into a band where its
/// bounds meet no masked-in tile; with a fast kernel (depth tests, stencil counting) its tile rows are
/// tested against the mask's tiles and only those meeting a masked-in one are walked, row by row, each
/// span cut to the mask's runs. The same fragments, depths and counters as the unmasked draw at the
/// masked-in pixels; only masked-in fragments are counted.
///
/// # Panics
/// When the mask is not the size of `ds`: a caller bug.
pub fn draw_depth_masked<S: TriangleSource + ?Sized>(
    ds: &mut DepthStencil,
    src: &S,
    st: &RasterState,
    mask: Option<&ComputationMask>,
) -> RasterCounters {
    if let Some(m) = mask {
        assert_eq!(m.size(), (ds.width, ds.height), "a computation mask the size of the target");
    }
    let mut none = Image::new(ds.width, ds.height, ());
    let path = DepthKernel::for_state(st).map_or(Path::General, Path::Depth);
    draw_with(ds, &mut none, src, st, (path, mask), |_| Some(()), |_, _| {})
}

/// Depth peeling (Everitt, "Interactive Order-Independent Transparency", 2001): a depth-only draw that
/// discards every fragment not more than `epsilon` beyond the depth `under` holds at its pixel, before
/// the depth test, so a peeled fragment leaves no depth. With a writing depth test and no stencil it
/// takes a branch-free inner loop like [`draw_depth`]'s; the same depths and counters as [`draw`] with
/// `|f| (f.depth > under[f] + epsilon).then_some(())` and late fragment tests, which it falls back to
/// for any other state.
///
/// # Panics
/// When `under` is not the size of `ds`: a caller bug.
pub fn draw_depth_peeled<S: TriangleSource + ?Sized>(
    ds: &mut DepthStencil,
    src: &S,
    st: &RasterState,
    under: &Image<f32>,
    epsilon: f32,
) -> RasterCounters {
    assert_eq!((under.width(), under.height()), (ds.width, ds.height), "a layer to peel the size of the target");
    let st = &RasterState { early_tests: false, ..*st };
    let mut none = Image::new(ds.width, ds.height, ());
    match DepthKernel::for_state(st) {
        Some(DepthKernel::Depth { compare, write: true }) => {
            let path = Path::Peel { compare, epsilon, under: under.data() };
            draw_with(ds, &mut none, src, st, (path, None), |_| Some(()), |_, _| {})
        }
        _ => draw(ds, &mut none, src, st, |f| (f.depth > *under.get(f.x, f.y) + epsilon).then_some(()), |_, _| {}),
    }
}

fn draw_with<T, S, F, B>(
    ds: &mut DepthStencil,
    color: &mut Image<T>,
    src: &S,
    st: &RasterState,
    (path, mask): (Path<'_>, Option<&ComputationMask>),
    shader: F,
    blend: B,
) -> RasterCounters
where
    T: Copy + Send,
    S: TriangleSource + ?Sized,
    F: Fn(&Fragment) -> Option<T> + Sync,
    B: Fn(&mut T, T) + Sync,
{
    let (w, h) = (ds.width, ds.height);
    assert!(
        color.width() == w && color.height() == h,
        "colour target {}x{} for a {w}x{h} depth buffer",
        color.width(),
        color.height()
    );
    let guard = guard_band(w, h);
    let bands = h.div_ceil(BAND_ROWS) as usize;
    let band_px = (BAND_ROWS * w) as usize;
    let mut total = RasterCounters::default();
    let mut bins: Vec<Vec<u32>> = vec![Vec::new(); bands];
    for start in (0..src.len()).step_by(BATCH) {
        let end = (start + BATCH).min(src.len());
        // Per-job lists joined with one copy (a `Setup` is some 300 bytes; a flattening collect moves each
        // twice more).
        let parts: Vec<Vec<Setup>> = (0..(end - start).div_ceil(SETUP_JOB))
            .into_par_iter()
            .map(|job| {
                let (first, mut acc) = (start + job * SETUP_JOB, Vec::new());
                src.each(first..(first + SETUP_JOB).min(end), &mut |t| setup(t, st, w, h, guard, &mut acc));
                acc
            })
            .collect();
        let setups = parts.concat();
        total.triangles += setups.len() as u64;
        for b in &mut bins {
            b.clear();
        }
        for (i, t) in setups.iter().enumerate() {
            for band in (t.min_y as u32 / BAND_ROWS)..=(t.max_y as u32 / BAND_ROWS) {
                let (y0, y1) =
                    ((band * BAND_ROWS).max(t.min_y as u32), ((band + 1) * BAND_ROWS - 1).min(t.max_y as u32));
                if mask.is_none_or(|m| m.any_in(t.min_x as u32, y0, t.max_x as u32, y1)) {
                    bins[band as usize].push(i as u32);
                }
            }
        }
        let counters = ds
            .depth
            .par_chunks_mut(band_px)
            .zip(ds.stencil.par_chunks_mut(band_px))
            .zip(color.data_mut().par_chunks_mut(band_px))
            .zip(bins.par_iter())
            .enumerate()
            .map(|(band, (((depth, stencil), col), bin))| {
                let mut c = RasterCounters::default();
                let y0 = band as i32 * BAND_ROWS as i32;
                let mut rows = BandRows { depth, stencil, color: col, y0, width: w as usize };
                for &t in bin {
                    raster_band(&setups[t as usize], &mut rows, st, (path, mask), (&shader, &blend), &mut c);
                }
                c
            })
            .reduce(RasterCounters::default, |mut a, b| {
                a += b;
                a
            });
        total += counters;
    }
    total
}

#[cfg(test)]
mod tests;
