//! Caster shafts for `hybrid`'s caster masks (ours, shared by both backends): where in light space one
//! connected component's shadow can lie.
//!
//! A component's volume is closed by itself ([`shadow_core::geometry::volume::VolumePiece`]), so its count is
//! zero at every point outside it. Every point inside lies on a ray from the light through one of the
//! component's casting faces, beyond it: in light space (where rays from the light are points) within the
//! convex hull of those faces' corners, so within any outline of the corners, and farther from the light
//! than the nearest corner. That outline and distance are the piece's *shaft*. A receiver outside it,
//! widened by the receiver's own precision ([`tolerance`]), would only ever get increments from the piece
//! that cancel, so a backend need not count the piece there.

use glam::{Vec2, Vec3, Vec4};
use rayon::prelude::*;

use shadow_core::FrameInputs;
use shadow_core::frame::InstanceVolume;
use shadow_core::light::{LightProjection, LightView};

/// Where a piece's shadow can lie in one light projection: the light-space bounds of its finite corners
/// along x, y and both diagonals (an 8-sided outline, so a twig lying across the light's view gets a
/// narrow strip rather than its bounding square), and their least distance from the light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Shaft {
    /// The least `outline` of the corners.
    pub lo: Vec4,
    /// The greatest `outline` of the corners.
    pub hi: Vec4,
    /// The least distance of the corners along the projection's axis.
    pub near: f32,
}

/// A light-space position `(x, y)` along x, y and both diagonals: `(x, y, x + y, x - y)`.
#[must_use]
#[inline]
pub fn outline(xy: Vec2) -> Vec4 {
    Vec4::new(xy.x, xy.y, xy.x + xy.y, xy.x - xy.y)
}

/// A point in a projection's light space: `(x / d, y / d)` for a perspective light, `(x, y)` for an
/// orthographic one, and the distance `d` along the projection's axis; `None` at or behind a perspective
/// light's plane.
#[must_use]
#[inline]
pub fn light_coords(proj: &LightProjection, p: Vec3) -> Option<(Vec2, f32)> {
    let v = proj.view_from_world.transform_point3(p);
    let d = -v.z;
    if proj.orthographic { Some((Vec2::new(v.x, v.y), d)) } else { (d > 0.0).then(|| (Vec2::new(v.x, v.y) / d, d)) }
}

/// How far, in world units, the point a pixel's count is taken at may lie from its G-buffer position, at
/// distance `r` from an eye with near plane `near`: the depth buffer's step there (an infinite
/// projection's depth is `1 - near / z`, so a step of 2^-24 is `z^2 / near * 2^-24`) and a sixth of a
/// pixel sideways (a 512-row view of 45 degrees), both with a wide margin. Also covers the volumes' own
/// snapping and depth rounding, which are of the same size.
#[must_use]
#[inline]
pub fn tolerance(r: f32, near: f32) -> f32 {
    r * (1.0 / 4096.0) + r * r / near * (1.0 / 262_144.0)
}

/// The light-space tolerance of a point at distance `d` along a projection from the light whose world
/// tolerance is `tol`: sideways in the projection's `xy` units, and along the light.
#[must_use]
#[inline]
pub fn light_tolerance(proj: &LightProjection, tol: f32, d: f32) -> (f32, f32) {
    (if proj.orthographic { 2.0 * tol } else { 2.0 * tol / d }, tol)
}

impl Shaft {
    /// Whether a point whose light-space position has the [`outline`] `o`, at distance `d`, with
    /// light-space tolerances `side` and `along` ([`light_tolerance`]), lies within them of the shaft.
    #[must_use]
    #[inline]
    pub fn holds(&self, o: Vec4, d: f32, side: f32, along: f32) -> bool {
        let tol = Vec4::new(side, side, 2.0 * side, 2.0 * side);
        d >= self.near - along && o.cmpge(self.lo - tol).all() && o.cmple(self.hi + tol).all()
    }
}

/// The shafts of every piece of every volume, per projection (`None` where a corner reaches the light's
/// plane: the piece may then shadow any pixel of that projection).
#[derive(Clone, Debug, Default)]
pub struct CasterShafts {
    /// Every piece as (volume, piece within it), in volume order.
    pub pieces: Vec<(usize, usize)>,
    /// Per piece, per projection.
    pub shafts: Vec<Vec<Option<Shaft>>>,
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

/// A grid over a light-space rectangle, each cell listing the pieces whose boxes meet it; a box reaching
/// beyond the grid is listed in its border cells, which is where a point beyond it looks. Both backends'
/// caster masks bin their shafts in one, each box widened by the largest tolerance of the points that
/// look: the CPU over its silhouette pixels' bounds, the GPU (which cannot see those) over the light's
/// view.
#[derive(Clone, Debug)]
pub struct ShaftGrid {
    /// The rectangle's least corner.
    pub origin: Vec2,
    /// Cells per light-space unit.
    pub scale: Vec2,
    /// Cells along each side.
    pub side: usize,
    /// Per cell (row by row), where its run of `pieces` starts, and one more.
    pub starts: Vec<u32>,
    /// The cells' pieces, a run per cell, ascending.
    pub pieces: Vec<u32>,
}

impl ShaftGrid {
    /// `side` x `side` cells over `lo..=hi` (one cell where that is empty), listing piece `k` in the cells
    /// `boxes[k]` meets (nowhere for `None`).
    #[must_use]
    pub fn new(lo: Vec2, hi: Vec2, side: usize, boxes: &[Option<(Vec2, Vec2)>]) -> Self {
        let (origin, scale, side) = if lo.cmple(hi).all() {
            let side = side.max(1);
            (lo, side as f32 / (hi - lo).max(Vec2::splat(1e-30)), side)
        } else {
            (Vec2::ZERO, Vec2::ZERO, 1)
        };
        let mut grid = Self { origin, scale, side, starts: vec![0; side * side + 1], pieces: Vec::new() };
        let cells: Vec<_> = boxes.iter().map(|b| b.map(|(lo, hi)| grid.cell_range(lo, hi))).collect();
        // A counting sort: the runs' lengths, their starts, then the pieces in order.
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
    #[must_use]
    pub fn cell_range(&self, lo: Vec2, hi: Vec2) -> ((usize, usize), (usize, usize)) {
        let cell = |v: f32| (v.max(0.0) as usize).min(self.side - 1);
        let (a, b) = ((lo - self.origin) * self.scale, (hi - self.origin) * self.scale);
        ((cell(a.x), cell(b.x)), (cell(a.y), cell(b.y)))
    }

    /// The cell holding `xy` (casters.wgsl's lookup is its twin).
    #[must_use]
    #[inline]
    pub fn cell_of(&self, xy: Vec2) -> usize {
        let ((x, _), (y, _)) = self.cell_range(xy, xy);
        y * self.side + x
    }

    /// The pieces of the cell holding `xy`.
    #[must_use]
    #[inline]
    pub fn pieces_at(&self, xy: Vec2) -> &[u32] {
        let cell = self.cell_of(xy);
        &self.pieces[self.starts[cell] as usize..self.starts[cell + 1] as usize]
    }
}
