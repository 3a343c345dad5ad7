//! Shadow volume reconstruction from depth maps (McCool 2000): the parts both backends share.
//!
//! The light's depth samples, joined into a mesh and back-projected to world space, are the boundary of the
//! shadow volume: a single surface, star-shaped from the light, so the parity of its crossings between the
//! eye and a visible point tells whether the point is in shadow (section 2), and one stencil bit counts it.
//! Only the mesh's cells across depth discontinuities lie in free space; the rest lie on the visible
//! surfaces, where the depth test would discard them anyway. So:
//!
//! 1. [`edges`]: flag the discontinuities between neighbouring samples (first differences, the
//!    second-derivative thinning and the "sure edge" threshold of section 3.3), code each cell by its
//!    flagged sides, and follow dangling edges into low-contrast contacts (section 3.2);
//! 2. [`mesh`]: emit, cell by cell, the triangles that touch a flagged side, split by the max-diagonal rule
//!    (section 4), with a whole cell for a dangling edge's last cell (Fig. 5's extension by one pixel);
//! 3. [`caps`]: where the eye's near plane cuts the volume, the part of the near-plane facet inside it, as
//!    polygons on that plane (section 6.2), or a global inversion when all of it is inside.
//!
//! **Map space.** The mesh's samples lie on a [`SampleGrid`]: the texel centres of an `N x N` map, as the
//! paper has them, or by default the texel-square grid of [`texel_square_grid`], which gives shadows the
//! size of the shadow map's. Cell `(x, y)` is the square between samples `(x, y)` and `(x + 1, y + 1)`.
//! Every vertex is produced in the light's NDC and taken to world space as a homogeneous point (no
//! division), as the paper computes its cap vertices.
//!
//! **Outside the map** is lit, as the shadow map's lookup has it: [`mesh::border_walls`] closes the volume
//! at the map's border for an eye outside the light's view, and the cap covers only the near-plane facet
//! over the map.

pub mod caps;
pub mod edges;
pub mod mesh;
pub mod projection;

#[cfg(test)]
mod tests;

use glam::{Mat4, Vec2, Vec4};
use rayon::prelude::*;

use edges::EdgeMap;
use shadow_core::light::LightProjection;

/// A triangle of homogeneous world points.
pub type HomTriangle = [Vec4; 3];

/// A light projection's sample grid: where sample `(x, y)` and its NDC depth are in world space.
///
/// Samples sit at the texel centres of an `N x N` map ([`SampleGrid::centres`], the paper's mesh), or
/// half a texel apart over its centres, edge midpoints and corners ([`SampleGrid::texel_squares`]).
#[derive(Clone, Copy, Debug)]
pub struct SampleGrid {
    /// Samples a side.
    pub n: u32,
    /// The map's side in sample spacings.
    map: u32,
    /// Sample `(0, 0)`'s position in sample spacings from the map's top-left corner.
    origin: f32,
    world_from_clip: Mat4,
}

impl SampleGrid {
    /// The texel centres of an `n x n` map of `proj`.
    #[must_use]
    pub fn centres(proj: &LightProjection, n: u32) -> Self {
        Self { n, map: n, origin: 0.5, world_from_clip: proj.clip_from_world.inverse() }
    }

    /// The texel-square grid of an `n x n` map of `proj` less `ring` samples a side (see
    /// [`texel_square_grid`]): `2n + 1 - 2 ring` samples a side, half a texel apart.
    #[must_use]
    pub fn texel_squares(proj: &LightProjection, n: u32, ring: u32) -> Self {
        Self {
            n: 2 * n + 1 - 2 * ring,
            map: 2 * n,
            origin: ring as f32,
            world_from_clip: proj.clip_from_world.inverse(),
        }
    }

    /// Light NDC x, y of map-space position `s` (sample `(x, y)` at integer `s`).
    #[must_use]
    pub fn ndc_xy(&self, s: Vec2) -> Vec2 {
        let uv = (s + Vec2::splat(self.origin)) / self.map as f32;
        Vec2::new(uv.x * 2.0 - 1.0, 1.0 - uv.y * 2.0)
    }

    /// Map-space position of light NDC x, y.
    #[must_use]
    pub fn map_xy(&self, ndc: Vec2) -> Vec2 {
        let uv = Vec2::new(ndc.x * 0.5 + 0.5, 0.5 - ndc.y * 0.5);
        uv * self.map as f32 - Vec2::splat(self.origin)
    }

    /// The homogeneous world point at map-space position `s` and NDC depth `z`, with `w >= 0`.
    ///
    /// The inverse of a perspective projection hands back `w` of either sign (glam's gives `w < 0` over the
    /// whole depth range); `p` and `-p` are one projective point, but a clipper keeps only the `w > 0` one,
    /// so the sign is made positive here.
    #[must_use]
    pub fn world(&self, s: Vec2, z: f32) -> Vec4 {
        let p = self.world_from_clip * self.ndc_xy(s).extend(z).extend(1.0);
        if p.w < 0.0 { -p } else { p }
    }
}

/// The texel-square grid of an `n x n` map of linear depths and its edge flags: `(2n + 1) x (2n + 1)`
/// samples at every texel's centre, edge midpoints and corners, half a texel apart.
///
/// The paper joins the texel centres, so a slope from an occluder sample reaches the receiver behind it
/// only at the next sample: every shadow grows by half a texel against the shadow map's nearest-texel
/// lookup (measured: 1.3 to 1.6 times its mismatch on cylinder, primitives and cubes). Here a centre is its
/// texel's depth, and a midpoint or corner lies on the farthest of the surfaces that meet there (the texels
/// joined by unflagged sides, `edges` being the map's own flags), at their mean depth. So across a
/// discontinuity the slopes lie over the occluder's own texels, and a receiver's shadow is the union of the
/// occluder's texels, as the shadow map has it, a texel-wide twig included (its centre stands alone as a
/// pyramid). A grid segment is flagged when its two samples share no texel.
///
/// `ring` leaves that many samples off every side. A point light's cube faces need 1: their maps are
/// widened until the border texels' centres lie on the faces' shared planes
/// ([`shadow_core::light::LightView::with_seamless_faces`]), and from there in, neighbouring faces sample the
/// shared edge on the same rays, so their surfaces meet without cracks (McCool section 5).
#[must_use]
pub fn texel_square_grid(linear: &[f32], n: u32, edges: &EdgeMap, ring: u32) -> (Vec<f32>, EdgeMap) {
    let m = 2 * n + 1 - 2 * ring;
    // Samples with a flag between their texels (few: O(n) of them) need the surface test; at the others
    // every texel is one surface.
    let mut split = vec![false; (m * m) as usize];
    let mut mark = |sx: u32, sy: u32| {
        if (ring..ring + m).contains(&sx) && (ring..ring + m).contains(&sy) {
            split[((sy - ring) * m + sx - ring) as usize] = true;
        }
    };
    for y in 0..n {
        for x in 0..n {
            if x + 1 < n && edges.u(x, y) {
                (2 * y..=2 * y + 2).for_each(|sy| mark(2 * x + 2, sy));
            }
            if y + 1 < n && edges.v(x, y) {
                (2 * x..=2 * x + 2).for_each(|sx| mark(sx, 2 * y + 2));
            }
        }
    }
    let group = |x: u32, y: u32| surface_at(linear, n, edges, x + ring, y + ring);
    let mut depth = vec![0.0; (m * m) as usize];
    depth.par_chunks_mut(m as usize).enumerate().for_each(|(y, row)| {
        let y = y as u32;
        for (x, d) in row.iter_mut().enumerate() {
            let x = x as u32;
            let g = if split[(y * m + x) as usize] { group(x, y) } else { texels_at(n, x + ring, y + ring) };
            let texels = g.iter().filter(|&&t| t != NO_TEXEL);
            *d = texels.clone().map(|&t| linear[t as usize]).sum::<f32>() / texels.count() as f32;
        }
    });
    // Neighbours share a texel unless one of them lies on a split sample's far surface.
    let mut flags = EdgeMap::empty(m, m);
    let apart = |a: [u32; 4], b: [u32; 4]| !a.iter().any(|&t| t != NO_TEXEL && b.contains(&t));
    for i in (0..m * m).filter(|&i| split[i as usize]) {
        let (x, y) = (i % m, i / m);
        let g = group(x, y);
        let at =
            |x: u32, y: u32| if split[(y * m + x) as usize] { group(x, y) } else { texels_at(n, x + ring, y + ring) };
        if x + 1 < m && apart(g, at(x + 1, y)) {
            flags.set_u(x, y);
        }
        if x > 0 && apart(g, at(x - 1, y)) {
            flags.set_u(x - 1, y);
        }
        if y + 1 < m && apart(g, at(x, y + 1)) {
            flags.set_v(x, y);
        }
        if y > 0 && apart(g, at(x, y - 1)) {
            flags.set_v(x, y - 1);
        }
    }
    (depth, flags)
}

const NO_TEXEL: u32 = u32::MAX;

/// The texel columns (or rows) meeting at grid coordinate `s`: one for a centre, two across a texel
/// border (one again at the map's edge).
fn span(s: u32, n: u32) -> [u32; 2] {
    if s % 2 == 1 { [s / 2; 2] } else { [(s / 2).saturating_sub(1), (s / 2).min(n - 1)] }
}

/// The (up to four) distinct texels meeting at grid sample `(sx, sy)`, padded with [`NO_TEXEL`].
fn texels_at(n: u32, sx: u32, sy: u32) -> [u32; 4] {
    let ([c0, c1], [r0, r1]) = (span(sx, n), span(sy, n));
    let mut out = [r0 * n + c0, r0 * n + c1, r1 * n + c0, r1 * n + c1];
    if c0 == c1 {
        out[1] = NO_TEXEL;
        out[3] = NO_TEXEL;
    }
    if r0 == r1 {
        out[2] = NO_TEXEL;
        out[3] = NO_TEXEL;
    }
    out
}

/// The texels of the farthest surface at grid sample `(sx, sy)`: of the (up to four) texels meeting there,
/// those joined to the farthest by unflagged sides.
fn surface_at(linear: &[f32], n: u32, edges: &EdgeMap, sx: u32, sy: u32) -> [u32; 4] {
    let ([c0, c1], [r0, r1]) = (span(sx, n), span(sy, n));
    let slots = [(c0, r0), (c1, r0), (c0, r1), (c1, r1)];
    // Slots are joined when they are one texel, or neighbours with no flag between them.
    let joined = |a: usize, b: usize| {
        let ((xa, ya), (xb, yb)) = (slots[a], slots[b]);
        (xa, ya) == (xb, yb)
            || (ya == yb && xa.abs_diff(xb) == 1 && !edges.u(xa.min(xb), ya))
            || (xa == xb && ya.abs_diff(yb) == 1 && !edges.v(xa, ya.min(yb)))
    };
    let index = |k: usize| slots[k].1 * n + slots[k].0;
    let far = (0..4).max_by(|&a, &b| linear[index(a) as usize].total_cmp(&linear[index(b) as usize])).unwrap_or(0);
    // The component of `far` in the 2 x 2 (sides 0-1, 2-3, 0-2, 1-3): two rounds reach the diagonal.
    let mut reached = [false; 4];
    reached[far] = true;
    for _ in 0..2 {
        for (a, b) in [(0, 1), (2, 3), (0, 2), (1, 3)] {
            if (reached[a] || reached[b]) && joined(a, b) {
                reached[a] = true;
                reached[b] = true;
            }
        }
    }
    let mut out = [NO_TEXEL; 4];
    for k in 0..4 {
        let t = index(k);
        if reached[k] && !out.contains(&t) {
            out[k] = t;
        }
    }
    out
}

/// The max-diagonal split of a cell (section 4): the quadrilateral is cut across the diagonal whose depth
/// difference is the larger, so the split edge joins the two corners that differ least (45-degree jaggies
/// rather than 90-degree ones). Corners in the order (x, y), (x + 1, y), (x + 1, y + 1), (x, y + 1).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Split {
    /// Split edge from corner 1 to corner 3: triangles (0, 1, 3) and (1, 2, 3).
    AlongBD,
    /// Split edge from corner 0 to corner 2: triangles (0, 1, 2) and (0, 2, 3).
    AlongAC,
}

impl Split {
    /// The split for corner depths `z` (any monotonic depth).
    #[must_use]
    pub fn of(z: [f32; 4]) -> Self {
        if (z[0] - z[2]).abs() >= (z[1] - z[3]).abs() { Self::AlongBD } else { Self::AlongAC }
    }

    /// The two triangles as corner indices, each with the bits of the cell sides it has (see
    /// [`edges::EdgeMap::code`]).
    #[must_use]
    pub fn triangles(self) -> [([usize; 3], u8); 2] {
        match self {
            // (0, 1, 3): top (0-1, bit 0) and left (3-0, bit 3); (1, 2, 3): right (bit 1) and bottom (bit 2).
            Self::AlongBD => [([0, 1, 3], 0b1001), ([1, 2, 3], 0b0110)],
            // (0, 1, 2): top and right; (0, 2, 3): bottom and left.
            Self::AlongAC => [([0, 1, 2], 0b0011), ([0, 2, 3], 0b1100)],
        }
    }
}

/// Corner offsets of a cell, in the order [`Split`] uses.
pub const CELL_CORNERS: [(u32, u32); 4] = [(0, 0), (1, 0), (1, 1), (0, 1)];
