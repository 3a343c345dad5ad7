//! Caster masks for `hybrid` (ours, in the spirit of Chan's per-blocker culling, thesis 3.4.3): each
//! connected component's shadow volume is counted only at the silhouette pixels its shadow can hold.
//!
//! A component's volume is closed by itself ([`shadow_core::geometry::volume::VolumePiece`]), so its count
//! is zero at every point outside it. Every point inside lies on a ray from the light through one of the
//! component's casting faces, beyond it: in light space (where rays from the light are points) within the
//! convex hull of those faces' corners, so within any outline of the corners, and farther from the light
//! than the nearest corner. A silhouette pixel outside that shaft (widened by the pixel's own depth and
//! position precision, see `tolerance`) would only ever get increments that cancel, so the piece is not
//! drawn there. Among a tree's thousand twigs or a cloud of cubes, a piece's volume crosses many silhouette
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

use rayon::prelude::*;
use shadow_core::FrameInputs;
use shadow_core::frame::InstanceVolume;
use shadow_core::glam::{Vec2, Vec3, Vec4, Vec4Swizzles};
use shadow_core::light::{LightProjection, LightView};
use shadow_core::stats::ms;
use shadow_core::technique::hard::VolumeCounting;

use super::shadow_volume::{ClipVolume, Runs, counting_state};
use crate::gbuffer::GBuffer;
use crate::raster::{ComputationMask, DepthStencil, ListedDraw, RasterCounters, count_listed, draw_depth_masked};

/// Pieces are counted pixel by pixel while their triangles times their pixels stay at or under this;
/// larger ones go through the whole mask. Measured (CPU, fastest of 10 frames): 2^13 makes tree's volume
/// pass 50% slower and crowd's 2.5 times; from 2^16 to 2^22 tree, cubes and crowd do not change, and
/// primitives' is fastest from 2^20 (1.3-1.5 ms against 2.0-2.4 at 2^16); a sphere of 200 000 triangles
/// is drawn through the whole mask at either end.
const LISTED_TESTS: usize = 1 << 20;

/// Where a piece's shadow can lie in one light projection: the light-space bounds of its finite corners
/// along x, y and both diagonals (an 8-sided outline, so a twig lying across the light's view gets a
/// narrow strip rather than its bounding square), and their least distance from the light.
#[derive(Clone, Copy, Debug)]
struct Shaft {
    lo: Vec4,
    hi: Vec4,
    near: f32,
}

/// A light-space position `(x, y)` along x, y and both diagonals: `(x, y, x + y, x - y)`.
fn outline(xy: Vec2) -> Vec4 {
    Vec4::new(xy.x, xy.y, xy.x + xy.y, xy.x - xy.y)
}

/// A point in a projection's light space: `(x / d, y / d)` for a perspective light, `(x, y)` for an
/// orthographic one, and the distance `d` along the projection's axis; `None` at or behind a perspective
/// light's plane.
fn light_coords(proj: &LightProjection, p: Vec3) -> Option<(Vec2, f32)> {
    let v = proj.view_from_world.transform_point3(p);
    let d = -v.z;
    if proj.orthographic { Some((Vec2::new(v.x, v.y), d)) } else { (d > 0.0).then(|| (Vec2::new(v.x, v.y) / d, d)) }
}

/// The shafts of every piece of every volume, per projection (`None` where a corner reaches the light's
/// plane: the piece may then shadow any pixel of that projection).
#[derive(Default)]
pub struct CasterShafts {
    /// Every piece as (volume, piece within it), in volume order.
    pieces: Vec<(usize, usize)>,
    /// Per piece, per projection.
    shafts: Vec<Vec<Option<Shaft>>>,
}

impl CasterShafts {
    /// The shafts of `volumes` for `light`.
    #[must_use]
    pub fn new(frame: &FrameInputs, light: &LightView, volumes: &[InstanceVolume]) -> Self {
        let pieces: Vec<(usize, usize)> =
            volumes.iter().enumerate().flat_map(|(v, iv)| (0..iv.volume.pieces.len()).map(move |p| (v, p))).collect();
        let shafts = pieces
            .par_iter()
            .map(|&(v, p)| {
                let iv = &volumes[v];
                let inst = &frame.instances[iv.instance];
                let (tris, positions) = (inst.mesh.triangles(), inst.mesh.positions());
                let (vol, piece) = (&iv.volume, &iv.volume.pieces[p]);
                let at = |m: Vec3| inst.world_from_local.transform_point3(m);
                // The piece's finite corners, in world space: its caps' (every silhouette edge borders a
                // casting face), or its sides' without caps.
                let caps = vol.caps_forward[piece.caps_forward.start as usize..piece.caps_forward.end as usize]
                    .iter()
                    .chain(&vol.caps_reversed[piece.caps_reversed.start as usize..piece.caps_reversed.end as usize]);
                let mut corners: Vec<Vec3> =
                    caps.flat_map(|&f| tris[f as usize].map(|v| at(positions[v as usize]))).collect();
                if corners.is_empty() {
                    let sides = &vol.sides[piece.sides.start as usize..piece.sides.end as usize];
                    corners = sides.iter().flatten().filter(|v| v.w != 0.0).map(|v| at(v.truncate())).collect();
                }
                // Widened for the rounding of the transforms.
                let b = piece.bounds.transformed(inst.world_from_local);
                let pad = 1e-5 * (b.size().length() + b.min.abs().max(b.max.abs()).max_element());
                light.projections.iter().map(|proj| shaft(proj, &corners, pad)).collect()
            })
            .collect();
        Self { pieces, shafts }
    }
}

/// The shaft of `corners` (world space) in `proj`, widened by `pad` world units.
fn shaft(proj: &LightProjection, corners: &[Vec3], pad: f32) -> Option<Shaft> {
    let mut s = Shaft { lo: Vec4::INFINITY, hi: Vec4::NEG_INFINITY, near: f32::INFINITY };
    for &c in corners {
        let (xy, d) = light_coords(proj, c)?;
        let o = outline(xy);
        (s.lo, s.hi, s.near) = (s.lo.min(o), s.hi.max(o), s.near.min(d));
    }
    // Corners this close to a perspective light's plane do not bound its view.
    if !proj.orthographic && s.near <= pad {
        return None;
    }
    let side = if proj.orthographic { pad } else { pad / s.near };
    let widen = Vec4::new(side, side, 2.0 * side, 2.0 * side);
    Some(Shaft { lo: s.lo - widen, hi: s.hi + widen, near: s.near - pad })
}

/// How far, in world units, the point a pixel's count is taken at may lie from its G-buffer position, at
/// distance `r` from an eye with near plane `near`: the depth buffer's step there (an infinite
/// projection's depth is `1 - near / z`, so a step of 2^-24 is `z^2 / near * 2^-24`) and a sixth of a
/// pixel sideways (a 512-row view of 45 degrees), both with a wide margin. Also covers the volumes' own
/// snapping and depth rounding, which are of the same size.
fn tolerance(r: f32, near: f32) -> f32 {
    r * (1.0 / 4096.0) + r * r / near * (1.0 / 262_144.0)
}

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

/// A grid over one projection's silhouette pixels in light space, each cell listing the pieces whose
/// shafts, widened by the largest tolerance of those pixels, meet it.
struct Grid {
    origin: Vec2,
    scale: Vec2,
    side: usize,
    /// Per cell, its run of `pieces`.
    starts: Vec<u32>,
    pieces: Vec<u32>,
}

impl Grid {
    /// The grid of `pixels` (some 8 a cell) with the pieces of `shafts` (this projection's shaft of each
    /// piece; the unbounded ones are left out).
    fn new(pixels: &[LightPixel], shafts: &[Option<Shaft>]) -> Self {
        let (lo, hi, widest) = pixels.iter().fold((Vec2::INFINITY, Vec2::NEG_INFINITY, 0.0f32), |(lo, hi, w), p| {
            (lo.min(p.xy), hi.max(p.xy), w.max(p.side))
        });
        let side = ((pixels.len() / 8) as f64).sqrt().clamp(1.0, 256.0) as usize;
        let scale = if pixels.is_empty() { Vec2::ZERO } else { side as f32 / (hi - lo).max(Vec2::splat(1e-30)) };
        let mut grid = Self { origin: lo, scale, side, starts: vec![0; side * side + 1], pieces: Vec::new() };
        if pixels.is_empty() {
            return grid;
        }
        // A pixel within its tolerance of a shaft lies in the shaft widened by the widest tolerance, so
        // the pieces of the pixel's own cell are all it needs to test.
        let cells: Vec<_> = shafts
            .iter()
            .map(|s| s.as_ref().map(|s| grid.cell_range(s.lo.xy() - widest, s.hi.xy() + widest)))
            .collect();
        for ((x0, x1), (y0, y1)) in cells.iter().flatten() {
            for y in *y0..=*y1 {
                for x in *x0..=*x1 {
                    grid.starts[y * side + x + 1] += 1;
                }
            }
        }
        for k in 0..side * side {
            grid.starts[k + 1] += grid.starts[k];
        }
        let mut next = grid.starts.clone();
        grid.pieces = vec![0; grid.starts[side * side] as usize];
        for (piece, range) in cells.iter().enumerate() {
            let Some(((x0, x1), (y0, y1))) = range else { continue };
            for y in *y0..=*y1 {
                for x in *x0..=*x1 {
                    grid.pieces[next[y * side + x] as usize] = piece as u32;
                    next[y * side + x] += 1;
                }
            }
        }
        grid
    }

    /// The cells meeting the box `lo..=hi` (a point when they are equal), as inclusive column and row
    /// ranges, clamped to the grid.
    fn cell_range(&self, lo: Vec2, hi: Vec2) -> ((usize, usize), (usize, usize)) {
        let cell = |v: f32| (v.max(0.0) as usize).min(self.side - 1);
        let (a, b) = ((lo - self.origin) * self.scale, (hi - self.origin) * self.scale);
        ((cell(a.x), cell(b.x)), (cell(a.y), cell(b.y)))
    }

    /// The pieces of the cell holding `xy`.
    fn pieces_at(&self, xy: Vec2) -> &[u32] {
        let ((x, _), (y, _)) = self.cell_range(xy, xy);
        let cell = y * self.side + x;
        &self.pieces[self.starts[cell] as usize..self.starts[cell + 1] as usize]
    }
}

/// Whether a pixel lies within its tolerance of a shaft.
fn in_shaft(s: &Shaft, p: &LightPixel) -> bool {
    let tol = Vec4::new(p.side, p.side, 2.0 * p.side, 2.0 * p.side);
    p.d >= s.near - p.along && p.dop.cmpge(s.lo - tol).all() && p.dop.cmple(s.hi + tol).all()
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
    let grids: Vec<Grid> = per_projection
        .iter()
        .enumerate()
        .map(|(j, pixels)| Grid::new(pixels, &shafts.iter().map(|s| s[j]).collect::<Vec<_>>()))
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
                    let pixel = light_coords(proj, p).map(|(xy, d)| LightPixel {
                        xy,
                        dop: outline(xy),
                        d,
                        side: if proj.orthographic { 2.0 * tol } else { 2.0 * tol / d },
                        along: tol,
                    });
                    row.push((j, pixel, at));
                }
            });
            row
        })
        .collect();
    rows.concat()
}
