//! Caster masks for `hybrid` (ours, in the spirit of Chan's per-blocker culling, thesis 3.4.3): each
//! connected component's shadow volume is counted only at the silhouette pixels its shadow can hold.
//!
//! A component's volume is closed by itself, so its count is zero outside its *shaft*
//! ([`crate::hybrid::shafts`], shared with the GPU's caster masks): a silhouette pixel outside it (widened
//! by the pixel's own depth and position precision, [`crate::hybrid::shafts::tolerance`]) would only ever get
//! increments that cancel, so the piece is not drawn there. Among a tree's thousand twigs or a cloud of cubes, a piece's volume crosses many silhouette
//! pixels on screen (the shadows of the others, seen through it) and can shadow only a few.
//!
//! Per frame: each piece's shaft (per light projection) goes into the cells of a grid over the silhouette pixels' light-space positions; each pixel tests the pieces of its
//! cell and joins the lists of those whose shaft holds it. A piece with no pixel is skipped; a short list
//! is counted pixel by pixel ([`count_listed`]); a piece whose list times its triangles is large (the
//! ground, a big single mesh) is drawn through the whole mask as before.
//!
//! This is not Chan's 3.4.3, which culls a blocker whose volume is hidden everywhere (measured: 18% of
//! cubes' casters, none of tree's); here a caster is kept only where its own shadow can be, pixel by pixel.

use std::time::Instant;

use crate::hybrid::shafts::{CasterShafts, Shaft, ShaftGrid, light_coords, light_tolerance, outline, tolerance};
use rayon::prelude::*;
use shadow_core::FrameInputs;
use shadow_core::frame::InstanceVolume;
use shadow_core::geometry::volume::VolumeCounting;
use shadow_core::glam::{Vec2, Vec4, Vec4Swizzles};
use shadow_core::light::LightView;
use shadow_core::stats::ms;

use shadow_cpu::GBuffer;
use shadow_cpu::passes::volumes::{ClipVolume, Runs, counting_state};
use shadow_cpu::raster::{ComputationMask, DepthStencil, ListedDraw, RasterCounters, count_listed, draw_depth_masked};

/// Pieces are counted pixel by pixel while their triangles times their pixels stay at or under this;
/// larger ones go through the whole mask. Measured (CPU, fastest of 10 frames): 2^13 makes tree's volume
/// pass 50% slower and crowd's 2.5 times; from 2^16 to 2^22 tree, cubes and crowd do not change, and
/// primitives' is fastest from 2^20 (1.3-1.5 ms against 2.0-2.4 at 2^16); a sphere of 200 000 triangles
/// is drawn through the whole mask at either end.
const LISTED_TESTS: usize = 1 << 20;

/// A silhouette pixel in light space.
#[derive(Clone, Copy)]
struct LightPixel {
    xy: Vec2,
    /// `outline(xy)`.
    dop: Vec4,
    d: f32,
    /// Its tolerance in light space: sideways (in `xy`'s units) and along the light.
    side: f32,
    along: f32,
}

/// The grid of one projection's silhouette `pixels` in light space (some 8 a cell) with the pieces of
/// `shafts` (this projection's shaft of each piece; the unbounded ones are left out), each widened by the
/// largest tolerance of those pixels: a pixel within its tolerance of a shaft lies in the widened shaft,
/// so the pieces of the pixel's own cell are all it needs to test.
fn pixel_grid(pixels: &[LightPixel], shafts: &[Option<Shaft>]) -> ShaftGrid {
    let (lo, hi, widest) = pixels.iter().fold((Vec2::INFINITY, Vec2::NEG_INFINITY, 0.0f32), |(lo, hi, w), p| {
        (lo.min(p.xy), hi.max(p.xy), w.max(p.side))
    });
    let side = ((pixels.len() / 8) as f64).sqrt().clamp(1.0, 256.0) as usize;
    // No pixel looks in a grid without pixels: nothing to list.
    let boxes: Vec<_> = if pixels.is_empty() {
        Vec::new()
    } else {
        shafts.iter().map(|s| s.as_ref().map(|s| (s.lo.xy() - widest, s.hi.xy() + widest))).collect()
    };
    ShaftGrid::new(lo, hi, side, &boxes)
}

/// Whether a pixel lies within its tolerance of a shaft.
fn in_shaft(s: &Shaft, p: &LightPixel) -> bool {
    s.holds(p.dop, p.d, p.side, p.along)
}

/// Per piece, the silhouette pixels its shadow may hold, ascending. `pixels` are the mask's in target
/// order, with their projection and light-space position (`None` at or behind a perspective light's plane,
/// which, conservatively, every piece may reach: seldom a silhouette pixel); a piece unbounded in a
/// projection may shadow any of that projection's pixels.
fn piece_lists(pixels: &[(usize, Option<LightPixel>, u32)], shafts: &[&[Option<Shaft>]]) -> Vec<Vec<u32>> {
    let projections = shafts.first().map_or(0, |s| s.len());
    let mut per_projection: Vec<Vec<LightPixel>> = vec![Vec::new(); projections];
    for (j, p, _) in pixels {
        per_projection[*j].extend(p);
    }
    let grids: Vec<ShaftGrid> = per_projection
        .iter()
        .enumerate()
        .map(|(j, pixels)| pixel_grid(pixels, &shafts.iter().map(|s| s[j]).collect::<Vec<_>>()))
        .collect();
    let unbounded: Vec<Vec<u32>> = (0..projections)
        .map(|j| (0..shafts.len() as u32).filter(|&k| shafts[k as usize][j].is_none()).collect())
        .collect();
    // (piece, pixel) pairs in target order, so each piece's run comes out ascending.
    let pairs: Vec<(u32, u32)> = pixels
        .par_chunks(1024)
        .flat_map_iter(|chunk| {
            let mut out = Vec::new();
            for &(j, p, at) in chunk {
                let Some(p) = p else {
                    out.extend((0..shafts.len() as u32).map(|k| (k, at)));
                    continue;
                };
                let near = grids[j].pieces_at(p.xy).iter().filter(|&&k| {
                    // Cells list bounded pieces only.
                    shafts[k as usize][j].as_ref().is_some_and(|s| in_shaft(s, &p))
                });
                out.extend(near.chain(&unbounded[j]).map(|&k| (k, at)));
            }
            out
        })
        .collect();
    let mut lists = vec![Vec::new(); shafts.len()];
    for (k, at) in pairs {
        lists[k as usize].push(at);
    }
    lists
}

/// What the caster masks did in a frame.
#[derive(Clone, Copy, Debug, Default)]
pub struct CasterStats {
    /// Pieces of all volumes.
    pub pieces: usize,
    /// Pieces whose shadow holds no silhouette pixel: not drawn.
    pub skipped: usize,
    /// Pieces counted at their own pixels.
    pub listed: usize,
    /// Their pixels, all together.
    pub listed_pixels: usize,
    /// Milliseconds spent binning the pixels and listing each piece's.
    pub listing_ms: f64,
}

/// Counts the z-fail volumes through `mask`, each piece only at the silhouette pixels its shadow can hold
/// (see the module notes); the same stencil as [`super::shadow_volume::rasterize_volumes`] under the mask.
pub fn count_volumes(
    frame: &FrameInputs,
    light: &LightView,
    g: &GBuffer,
    volumes: &[InstanceVolume],
    shafts: &CasterShafts,
    mask: &ComputationMask,
    ds: &mut DepthStencil,
) -> (RasterCounters, CasterStats) {
    let t = Instant::now();
    let pixels = light_pixels(light, g, mask);
    let pieces = &shafts.pieces;
    let piece_shafts: Vec<&[Option<Shaft>]> = shafts.shafts.iter().map(Vec::as_slice).collect();
    let lists = piece_lists(&pixels, &piece_shafts);
    let listing_ms = ms(t.elapsed());
    let clips: Vec<ClipVolume> = volumes.par_iter().map(|iv| ClipVolume::new(frame, g, iv, true)).collect();
    let runs = |v: usize, p: usize| -> Runs {
        let piece = &volumes[v].volume.pieces[p];
        let r = |r: &std::ops::Range<u32>| r.start as usize..r.end as usize;
        [r(&piece.sides), r(&piece.caps_forward), r(&piece.caps_reversed)]
    };
    let mut stats = CasterStats { pieces: pieces.len(), listing_ms, ..CasterStats::default() };
    // Per volume, the runs of its pieces drawn through the whole mask.
    let mut masked: Vec<Vec<Runs>> = vec![Vec::new(); volumes.len()];
    let mut listed = Vec::new();
    for (&(v, p), list) in pieces.iter().zip(&lists) {
        let r = runs(v, p);
        let triangles = r[0].len() + 2 * (r[1].len() + r[2].len());
        if list.is_empty() {
            stats.skipped += 1;
        } else if triangles * list.len() <= LISTED_TESTS {
            stats.listed += 1;
            stats.listed_pixels += list.len();
            listed.push((clips[v].draws(r), list.as_slice()));
        } else {
            masked[v].push(r);
        }
    }
    let draws: Vec<ListedDraw> = listed
        .iter()
        .map(|(d, pixels)| ListedDraw { sources: d.iter().map(|d| d.source()).collect(), pixels })
        .collect();
    let state = counting_state(VolumeCounting::ZFail);
    let mut c = count_listed(ds, &draws, &state);
    for ((clip, runs), iv) in clips.iter().zip(&masked).zip(volumes) {
        if runs.is_empty() {
            continue;
        }
        let gathered;
        let (clip, runs) = if runs.len() == iv.volume.pieces.len() {
            (clip, clip.whole())
        } else {
            gathered = clip.gathered(runs);
            (&gathered, gathered.whole())
        };
        for d in &clip.draws(runs) {
            c += draw_depth_masked(ds, d.source(), &state, Some(mask));
        }
    }
    (c, stats)
}

/// The mask's pixels in target order, each with its projection, its light-space position there (`None`
/// at or behind a perspective light's plane) and its index.
fn light_pixels(light: &LightView, g: &GBuffer, mask: &ComputationMask) -> Vec<(usize, Option<LightPixel>, u32)> {
    let (w, h) = mask.size();
    let (eye, near) = (g.camera.eye, g.camera.near);
    let rows: Vec<Vec<(usize, Option<LightPixel>, u32)>> = (0..h)
        .into_par_iter()
        .map(|y| {
            let mut row = Vec::new();
            mask.each_run(y, 0, w.saturating_sub(1), |a, b| {
                for x in a..=b {
                    let at = y * w + x;
                    let p = g.position.data()[at as usize];
                    let j = light.projection_index(p);
                    let proj = &light.projections[j];
                    let tol = tolerance(p.distance(eye), near);
                    let pixel = light_coords(proj, p).map(|(xy, d)| {
                        let (side, along) = light_tolerance(proj, tol, d);
                        LightPixel { xy, dop: outline(xy), d, side, along }
                    });
                    row.push((j, pixel, at));
                }
            });
            row
        })
        .collect();
    rows.concat()
}
