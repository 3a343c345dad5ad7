//! Template reconstruction of the shadow volume boundary (McCool section 4, Fig. 5).
//!
//! Each marked cell is split by the max-diagonal rule ([`Split`]) and emits the triangles that have a
//! flagged side: such a triangle joins samples on both sides of a discontinuity, so it spans the free space
//! between an occluder's edge and what lies behind it. The other triangle of the cell joins samples on one
//! surface and would lie on it, where the depth test discards it, so it is left out. A cell with a dangling
//! edge emits both triangles, which carries the edge one cell on (the table of Fig. 5 "designed to extend
//! dangling edges by one pixel"). Cells are visited in ascending order, so both backends get the same
//! triangles in the same order.

use glam::{Vec2, Vec4};

use super::edges::{EdgeMap, dangling};
use super::{CELL_CORNERS, HomTriangle, SampleGrid, Split};

/// The reconstructed boundary of one light projection.
#[derive(Clone, Debug, Default)]
pub struct Reconstruction {
    /// Triangles of homogeneous world points.
    pub triangles: Vec<HomTriangle>,
    /// How many cells emitted any.
    pub cells: usize,
}

/// The shadow volume boundary of an `N x N` map: `ndc` holds the NDC depths (the bias already in them),
/// `split_depth` the depths the split rule compares (linear depths), `edges` the flags. `offset` moves
/// every vertex that far away from the light, in world units (the `bias=world` translation of section 2);
/// `light` is where the light's rays start (a position, or for a directional light its direction with
/// w = 0).
#[must_use]
pub fn reconstruct(
    ndc: &[f32],
    split_depth: &[f32],
    edges: &EdgeMap,
    grid: &SampleGrid,
    offset: f32,
    light: Vec4,
) -> Reconstruction {
    let n = grid.n;
    let mut out = Reconstruction::default();
    for cell in edges.marked_cells() {
        let (x, y) = (cell % (n - 1), cell / (n - 1));
        let code = edges.code(x, y);
        let at = |k: usize| ((y + CELL_CORNERS[k].1) * n + x + CELL_CORNERS[k].0) as usize;
        let split = Split::of([0, 1, 2, 3].map(|k| split_depth[at(k)]));
        let vertex = |k: usize| {
            let (dx, dy) = CELL_CORNERS[k];
            let p = grid.world(Vec2::new((x + dx) as f32, (y + dy) as f32), ndc[at(k)]);
            if offset == 0.0 { p } else { moved_away(p, light, offset) }
        };
        let mut emitted = false;
        for (corners, sides) in split.triangles() {
            if code & sides != 0 || dangling(code) {
                out.triangles.push(corners.map(vertex));
                emitted = true;
            }
        }
        out.cells += usize::from(emitted);
    }
    out
}

/// The walls that close the volume at the map's border: from each border sample pair straight back to the
/// light's far plane (two triangles a pair; none where both samples are background, at the far plane).
///
/// One projection's reconstructed surface is open at the border of its map, and the paper needs no more
/// because its eye looks out from inside the light's view. An eye outside it (a spot light's frustum, a
/// directional light's fitted box) sees into the volume through the frustum's sides, and a ray entering
/// there behind an occluder crosses no polygon without these walls. Outside the map is lit, as the shadow
/// map's lookup has it, so the walls bound the shadowed side. A point light's six faces cover every
/// direction, and their walls would meet in pairs on the shared planes, so it has none.
#[must_use]
pub fn border_walls(ndc: &[f32], grid: &SampleGrid, offset: f32, light: Vec4) -> Vec<HomTriangle> {
    let n = grid.n;
    if n < 2 {
        return Vec::new();
    }
    let last = n - 1;
    // The border samples in order around the map.
    let ring: Vec<(u32, u32)> = (0..last)
        .map(|x| (x, 0))
        .chain((0..last).map(|y| (last, y)))
        .chain((0..last).map(|x| (last - x, last)))
        .chain((0..last).map(|y| (0, last - y)))
        .collect();
    let depth = |(x, y): (u32, u32)| ndc[(y * n + x) as usize];
    let at = |(x, y): (u32, u32), z: f32| {
        let p = grid.world(Vec2::new(x as f32, y as f32), z);
        if offset == 0.0 || z >= 1.0 { p } else { moved_away(p, light, offset) }
    };
    let mut out = Vec::new();
    for (i, &a) in ring.iter().enumerate() {
        let b = ring[(i + 1) % ring.len()];
        let (za, zb) = (depth(a).min(1.0), depth(b).min(1.0));
        if za >= 1.0 && zb >= 1.0 {
            continue;
        }
        let q = [at(a, za), at(b, zb), at(b, 1.0), at(a, 1.0)];
        out.push([q[0], q[1], q[2]]);
        out.push([q[0], q[2], q[3]]);
    }
    out
}

/// A homogeneous world point moved `offset` further from the light along the light's ray through it.
fn moved_away(p: Vec4, light: Vec4, offset: f32) -> Vec4 {
    if p.w == 0.0 {
        return p;
    }
    let q = p.truncate() / p.w;
    let dir =
        if light.w == 0.0 { light.truncate().normalize_or_zero() } else { (q - light.truncate()).normalize_or_zero() };
    (q + dir * offset).extend(1.0)
}
