//! Silhouette edges as a light-space map, for `hybrid`'s `edge_texels` (both backends): what Chan's rule
//! cannot see between a shadow map's texel centres.
//!
//! [`edge_cells`]: the squares between four texel centres, a bilinear lookup's footprint, that two
//! segments or more enter, with the nearest one's depth. A straight edge alone across
//!   such a square leaves texel centres on both of its sides, where the depth tests then disagree, so Chan's
//!   rule already sends the receiver to the volumes; only a sliver, a gap or a corner between two edges
//!   can hide between the centres. Every vertex of a silhouette loop ends two segments, so "two enter"
//!   also holds where a loop turns.

use glam::{DVec2, Vec3, Vec4};

use rayon::prelude::*;

use shadow_core::image::Image;
use shadow_core::light::LightProjection;
use shadow_core::lookup::{floor, hidden};

/// A world segment clipped to a projection's view: its ends in NDC, and whether clipping cut each one.
struct Clipped {
    ends: [Vec3; 2],
    cut: [bool; 2],
}

/// `[a, b]` clipped to `proj`'s near plane and to its sides widened by `margin` (NDC), so no rasterizer sees
/// coordinates far outside the view (cube faces see edges that pass behind them); `None` when nothing is
/// left.
fn clip_to_view(proj: &LightProjection, [a, b]: [Vec3; 2], margin: f32) -> Option<Clipped> {
    // Clip w is the distance along the axis in a perspective view, 1 in an orthographic one.
    let near_w = if proj.orthographic { 0.0 } else { proj.near };
    let side = 1.0 + margin;
    let planes = [
        (Vec4::W, near_w),
        (Vec4::new(-1.0, 0.0, 0.0, side), 0.0),
        (Vec4::new(1.0, 0.0, 0.0, side), 0.0),
        (Vec4::new(0.0, -1.0, 0.0, side), 0.0),
        (Vec4::new(0.0, 1.0, 0.0, side), 0.0),
    ];
    let (ca, cb) = (proj.clip_from_world * a.extend(1.0), proj.clip_from_world * b.extend(1.0));
    // Liang-Barsky: each plane k . p >= offset keeps a range of t along ca + t (cb - ca).
    let (mut t0, mut t1) = (0.0f32, 1.0f32);
    for (plane, offset) in planes {
        let (da, db) = (plane.dot(ca) - offset, plane.dot(cb) - offset);
        if da < 0.0 && db < 0.0 {
            return None;
        }
        if da < 0.0 {
            t0 = t0.max(da / (da - db));
        } else if db < 0.0 {
            t1 = t1.min(da / (da - db));
        }
    }
    if t0 > t1 {
        return None;
    }
    let (pa, pb) = (ca.lerp(cb, t0), ca.lerp(cb, t1));
    Some(Clipped { ends: [pa.truncate() / pa.w, pb.truncate() / pb.w], cut: [t0 > 0.0, t1 < 1.0] })
}

/// Stands for a cut end in a cell's first segments: never a segment [`may_hide`] can clear.
const CUT: u32 = u32::MAX;

/// How far past a square's sides a segment still counts as entering it, in texels: a segment along a
/// texel row, or through a texel centre, touches the squares on both sides, whichever way rounding goes.
const CELL_REACH: f32 = 1e-3;

/// The cell map of world segments for an `res x res` map of projection `proj` (`hybrid`'s
/// `edge_texels=paired`; read by [`shadow_core::lookup::near_edge_pair`]): `(res + 1)` square, pixel `(x, y)` the
/// square whose corners are texels `(x - 1, y - 1)` and `(x, y)` ([`shadow_core::lookup::cell_of`]; those along
/// the sides are half outside the map, where a lookup's texels clamp). Where two segments or more enter a
/// cell and may cut off a part of it that holds none of its corners (`may_hide`), it holds the least NDC
/// depth any of them has inside it; 1 elsewhere. An end that clipping to the view made (a segment through
/// the light's near plane) counts as a second segment at its cell, since its loop's other segment through
/// that end was cut elsewhere.
///
/// With `map`, the classifying map, cells that [`hidden`] says are hidden behind the surfaces at their
/// four texels are left out at once, as the lookup would leave them out (the GPU, whose map stays on the
/// GPU, passes none and leaves them to the lookup).
///
/// Every cell a segment touches is visited once: row by row of cells, the columns its stretch in that
/// row spans; the depth inside a cell comes from the segment's two ends there (NDC depth is affine along
/// a projected segment).
#[must_use]
pub fn edge_cells(segments: &[[Vec3; 2]], proj: &LightProjection, res: u32, map: Option<&Image<f32>>) -> Image<f32> {
    let side = res + 1;
    // NDC to cell coordinates: cell (x, y) spans [x, x + 1] x [y, y + 1].
    let n = res as f32;
    let to_cells = |p: Vec3| Vec3::new((p.x * 0.5 + 0.5) * n + 0.5, (0.5 - p.y * 0.5) * n + 0.5, p.z);
    // The segments in view, in cell coordinates, and which of their ends clipping made.
    let kept: Vec<([Vec3; 2], [bool; 2])> = segments
        .par_iter()
        .with_min_len(1024)
        .filter_map(|&segment| clip_to_view(proj, segment, 8.0 / n).map(|c| (c.ends.map(to_cells), c.cut)))
        .collect();
    // Strips of cell rows, each walked by one task over every segment that reaches it: a cell belongs to
    // one strip, which meets its segments in their order, so each cell's first two are the same as one
    // walk over the whole map would find.
    let strip_rows = side.div_ceil(4 * rayon::current_num_threads() as u32).max(16) as usize;
    let mut out = Image::new(side, side, 1.0f32);
    out.data_mut().par_chunks_mut(strip_rows * side as usize).enumerate().for_each(|(k, strip)| {
        let y0 = (k * strip_rows) as i64;
        cell_strip(&kept, side, y0, strip, map);
    });
    out
}

/// [`edge_cells`] over the rows of cells from `y0` that `strip` holds.
fn cell_strip(kept: &[([Vec3; 2], [bool; 2])], side: u32, y0: i64, strip: &mut [f32], map: Option<&Image<f32>>) {
    let width = i64::from(side);
    let y1 = y0 + strip.len() as i64 / width; // one past the strip's last row
    let cells = strip.len();
    // Per cell: the segments entering it (saturating), the least depth any has inside it, and the first two
    // of them (indices into `kept`, or a cut end), which the tests of pairs read.
    let (mut count, mut depth, mut first) = (vec![0u8; cells], vec![1.0f32; cells], vec![[CUT; 2]; cells]);
    // The cells two segments or more enter, in the order they were reached.
    let mut pairs: Vec<u32> = Vec::new();
    let mut enter = |x: i64, y: i64, z: f32, id: u32| {
        if (0..width).contains(&x) && (y0..y1).contains(&y) {
            let i = ((y - y0) * width + x) as usize;
            let k = count[i];
            if k < 2 {
                first[i][usize::from(k)] = id;
            }
            count[i] = k.saturating_add(1);
            depth[i] = depth[i].min(z.clamp(0.0, 1.0));
            if k == 1 {
                pairs.push(i as u32);
            }
        }
    };
    for (id, &([a, b], cut)) in kept.iter().enumerate() {
        let id = id as u32;
        // Row by row: the stretch of the segment within the row (widened by CELL_REACH), then the cells
        // its x range spans, each with the least depth over its part of the stretch (depth is affine in x
        // along it).
        let dy = b.y - a.y;
        let rows = floor(a.y.min(b.y) - CELL_REACH).max(y0)..=floor(a.y.max(b.y) + CELL_REACH).min(y1 - 1);
        for y in rows {
            let (lo, hi) = (y as f32 - CELL_REACH, y as f32 + 1.0 + CELL_REACH);
            let (p, q) = if dy.abs() < 1e-12 {
                (a, b)
            } else {
                let (s, t) = ((lo - a.y) / dy, (hi - a.y) / dy);
                let (s, t) = (s.min(t).max(0.0), s.max(t).min(1.0));
                if s > t {
                    continue;
                }
                (a.lerp(b, s), a.lerp(b, t))
            };
            let (p, q) = if p.x <= q.x { (p, q) } else { (q, p) };
            let slope = if q.x - p.x > 1e-12 { (q.z - p.z) / (q.x - p.x) } else { 0.0 };
            let z = |x: f32| p.z + (x.clamp(p.x, q.x) - p.x) * slope;
            let columns = floor(p.x - CELL_REACH).max(0)..=floor(q.x + CELL_REACH).min(width - 1);
            for x in columns {
                let (u, v) = (x as f32 - CELL_REACH, x as f32 + 1.0 + CELL_REACH);
                enter(x, y, z(u).min(z(v)), id);
            }
        }
        for (end, cut) in [a, b].into_iter().zip(cut) {
            if cut {
                enter(floor(end.x), floor(end.y), end.z, CUT);
            }
        }
    }
    for i in pairs {
        let (x, y, nearest) = (i % side, y0 as u32 + i / side, depth[i as usize]);
        if map.is_some_and(|m| hidden(m, x, y, nearest)) {
            continue;
        }
        let [s, t] = first[i as usize];
        let cleared = count[i as usize] == 2
            && s != CUT
            && t != CUT
            && !may_hide(i64::from(x), i64::from(y), [kept[s as usize].0, kept[t as usize].0]);
        if !cleared {
            strip[i as usize] = nearest;
        }
    }
}

/// Whether two segments entering cell `(x, y)` (cell coordinates: it spans `[x, x + 1] x [y, y + 1]`, its
/// corners the texel centres a lookup there reads) may cut off a part of it that holds none of its
/// corners, where Chan's rule cannot see them. No, exactly, for the two cases that make most pairs:
///
/// - a silhouette loop turning inside the cell (the segments share an end there, their other ends lie
///   outside): its two parts of the cell each hold a corner unless both segments leave through the same
///   side;
/// - two chords (no end inside): each part of the cell between them must hold a corner, the corners'
///   sides of the two lines naming the parts that do, the chords' ends and their crossing those that
///   exist.
///
/// Anything else (an end inside that is not shared, a corner or an end within a hair of a line or a side)
/// may.
fn may_hide(x: i64, y: i64, segments: [[Vec3; 2]; 2]) -> bool {
    const EPS: f64 = 1e-4;
    let origin = DVec2::new(x as f64, y as f64);
    let [[a0, b0], [a1, b1]] = segments.map(|s| s.map(|p| DVec2::new(f64::from(p.x), f64::from(p.y)) - origin));
    let inside = |p: DVec2, by: f64| p.cmpgt(DVec2::splat(by)).all() && p.cmplt(DVec2::splat(1.0 - by)).all();
    let near_cell = |p: DVec2| inside(p, -EPS);
    let ends_in = [a0, b0, a1, b1].into_iter().filter(|&p| near_cell(p)).count();
    match ends_in {
        0 => chords_may_hide([a0, b0], [a1, b1], EPS),
        2 => {
            // A shared end (the same vertex, bit for bit), well inside, the other ends outside.
            let turn = [(a0, b0, a1, b1), (a0, b0, b1, a1), (b0, a0, a1, b1), (b0, a0, b1, a1)]
                .into_iter()
                .find(|&(v, _, w, _)| v == w);
            let Some((v, p, _, q)) = turn else { return true };
            if !inside(v, EPS) || near_cell(p) || near_cell(q) {
                return true;
            }
            match (exit_side(v, p, EPS), exit_side(v, q, EPS)) {
                (Some(s), Some(t)) => s == t,
                _ => true,
            }
        }
        _ => true,
    }
}

/// The side of the unit square (0 to 3 around it) through which the segment from `v`, inside, to `p`,
/// outside, leaves; `None` within `eps` of a corner.
fn exit_side(v: DVec2, p: DVec2, eps: f64) -> Option<u8> {
    let d = p - v;
    let reach = |v: f64, d: f64| {
        if d > 0.0 {
            (1.0 - v) / d
        } else if d < 0.0 {
            -v / d
        } else {
            f64::INFINITY
        }
    };
    let (tx, ty) = (reach(v.x, d.x), reach(v.y, d.y));
    let e = v + d * tx.min(ty);
    let along = if tx < ty { e.y } else { e.x };
    if along < eps || along > 1.0 - eps || (tx - ty).abs() < eps {
        return None;
    }
    Some(match (tx < ty, if tx < ty { d.x > 0.0 } else { d.y > 0.0 }) {
        (true, true) => 1,
        (true, false) => 3,
        (false, true) => 2,
        (false, false) => 0,
    })
}

/// Whether two segments that cross the unit square with no end in it may cut off a part of it holding
/// none of its corners ([`may_hide`]'s second case).
fn chords_may_hide(s: [DVec2; 2], t: [DVec2; 2], eps: f64) -> bool {
    let (Some(p), Some(q)) = (chord(s), chord(t)) else { return true };
    // Which side of a chord's line a point is on: 0 within eps.
    let side = |[a, b]: [DVec2; 2], c: DVec2| {
        let d = b - a;
        let v = d.perp_dot(c - a);
        if v.abs() < eps * d.length() { 0 } else { v.signum() as i8 }
    };
    let corners = [DVec2::ZERO, DVec2::X, DVec2::ONE, DVec2::Y].map(|c| (side(p, c), side(q, c)));
    let ends = [side(q, p[0]), side(q, p[1]), side(p, q[0]), side(p, q[1])];
    if corners.iter().any(|&(u, v)| u == 0 || v == 0) || ends.contains(&0) {
        return true;
    }
    let held = |pair: (i8, i8)| corners.contains(&pair);
    if ends[0] != ends[1] && ends[2] != ends[3] {
        // They cross inside: all four parts exist.
        return ![(1, 1), (1, -1), (-1, 1), (-1, -1)].into_iter().all(held);
    }
    // The parts either side of each chord at its ends.
    let parts = [(1, ends[0]), (-1, ends[0]), (1, ends[1]), (-1, ends[1])].into_iter().chain([
        (ends[2], 1),
        (ends[2], -1),
        (ends[3], 1),
        (ends[3], -1),
    ]);
    !parts.into_iter().all(held)
}

/// The part of a segment inside the unit square (Liang-Barsky), `None` when none of it is, or a hair.
fn chord([a, b]: [DVec2; 2]) -> Option<[DVec2; 2]> {
    let d = b - a;
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    for (v, dv) in [(a.x, d.x), (a.y, d.y)] {
        for (q, dq) in [(v, dv), (1.0 - v, -dv)] {
            // Keep q + t dq >= 0.
            if dq == 0.0 {
                if q < 0.0 {
                    return None;
                }
            } else if dq > 0.0 {
                t0 = t0.max(-q / dq);
            } else {
                t1 = t1.min(-q / dq);
            }
        }
    }
    (t1 - t0 > 1e-9).then(|| [a + d * t0, a + d * t1])
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec2;

    /// A 1:1 orthographic view: clip = world.
    fn straight_on() -> LightProjection {
        LightProjection {
            view_from_world: glam::Mat4::IDENTITY,
            clip_from_view: glam::Mat4::IDENTITY,
            clip_from_world: glam::Mat4::IDENTITY,
            clip_plane_from_world_plane: glam::Mat4::IDENTITY,
            near: 0.0,
            far: 1.0,
            orthographic: true,
        }
    }

    #[test]
    fn one_segment_or_a_clean_crossing_marks_no_cell_and_a_narrow_crossing_does() {
        let res = 16;
        let a = [Vec3::new(-0.7, -0.3, 0.25), Vec3::new(0.6, 0.45, 0.5)];
        let one = edge_cells(&[a], &straight_on(), res, None);
        assert_eq!(one.width(), res + 1);
        assert!(one.data().iter().all(|&d| d == 1.0), "a lone straight segment hides nowhere");
        // Crossing a's line at right angles: the four parts at the crossing each hold a texel centre,
        // unless the crossing lies within a hair of one (then the cell is marked; at most one is).
        let dir = (a[1] - a[0]).truncate().normalize().perp();
        let mid = (a[0] + a[1]) * 0.5;
        let across = [mid - (dir * 0.6).extend(0.0), mid + (dir * 0.6).extend(0.0)].map(|p| Vec3::new(p.x, p.y, 0.75));
        let square = edge_cells(&[a, across], &straight_on(), res, None);
        assert!(square.data().iter().filter(|&&d| d < 1.0).count() <= 1);
        // A line through a's crossing point at a tenth of a texel's angle: the thin wedges between them
        // miss every centre somewhere along the way.
        let narrow = [Vec3::new(-0.7, -0.3 - 0.02, 0.75), Vec3::new(0.6, 0.45 + 0.02, 0.75)];
        let cells = edge_cells(&[a, narrow], &straight_on(), res, None);
        let marked: Vec<f32> = cells.data().iter().copied().filter(|&d| d < 1.0).collect();
        assert!(marked.len() >= 2, "{} cells", marked.len());
        // The nearer segment's depth there: a's, between its ends' 0.25 and 0.5.
        assert!(marked.iter().all(|d| (0.25..0.5).contains(d)), "{marked:?}");
    }

    #[test]
    fn a_square_loop_turns_cleanly_and_a_sliver_marks_its_length() {
        let res = 32;
        let texel = 2.0 / res as f32;
        // A square loop many texels a side: each corner turns through two different sides of its cell.
        let corners = [Vec2::new(-0.51, -0.43), Vec2::new(0.47, -0.43), Vec2::new(0.47, 0.39), Vec2::new(-0.51, 0.39)];
        let seg = |k: usize| [corners[k].extend(0.5), corners[(k + 1) % 4].extend(0.5)];
        let square = edge_cells(&[seg(0), seg(1), seg(2), seg(3)], &straight_on(), res, None);
        assert!(square.data().iter().all(|&d| d == 1.0));
        // A triangle's tip a tenth of a texel wide: its two sides leave the tip's cell through one side.
        let tip = [Vec3::new(0.2, 0.13, 0.5), Vec3::new(-0.6, 0.13 + 0.1 * texel, 0.5)];
        let back = [Vec3::new(-0.6, 0.13 - 0.1 * texel, 0.5), Vec3::new(0.2, 0.13, 0.5)];
        let cells = edge_cells(&[tip, back], &straight_on(), res, None);
        let long = (0.8 / texel).ceil() as usize;
        let marked = cells.data().iter().filter(|&&d| d < 1.0).count();
        assert!((long..=long + 2).contains(&marked), "{marked} cells along a sliver {long} cells long");
    }

    /// Whether some part of the unit square that the segments cut off holds none of its corners: a
    /// flood fill over a fine grid with the segments as walls (an oracle for [`may_hide`]; parts thinner
    /// than a grid step, or of a dozen grid points, are lost, so it only ever under-reports).
    fn cornerless_part(segments: [[DVec2; 2]; 2]) -> bool {
        const N: usize = 160;
        let step = 1.0 / N as f64;
        let wall = |p: DVec2| {
            segments.iter().any(|&[a, b]| {
                let d = b - a;
                let t = ((p - a).dot(d) / d.length_squared()).clamp(0.0, 1.0);
                (a + d * t - p).length() < 0.75 * step
            })
        };
        let at = |i: usize, j: usize| DVec2::new(i as f64, j as f64) * step;
        let mut part = vec![usize::MAX; (N + 1) * (N + 1)];
        let mut parts_with_corner = Vec::new();
        for start in 0..part.len() {
            if part[start] != usize::MAX || wall(at(start % (N + 1), start / (N + 1))) {
                continue;
            }
            let id = parts_with_corner.len();
            let (mut stack, mut corner, mut size) = (vec![start], false, 0);
            part[start] = id;
            while let Some(k) = stack.pop() {
                size += 1;
                let (i, j) = (k % (N + 1), k / (N + 1));
                corner |= (i == 0 || i == N) && (j == 0 || j == N);
                for (di, dj) in [(-1i64, 0i64), (1, 0), (0, -1), (0, 1)] {
                    let (u, v) = (i as i64 + di, j as i64 + dj);
                    if u < 0 || v < 0 || u > N as i64 || v > N as i64 {
                        continue;
                    }
                    let q = v as usize * (N + 1) + u as usize;
                    if part[q] == usize::MAX && !wall(at(u as usize, v as usize)) {
                        part[q] = id;
                        stack.push(q);
                    }
                }
            }
            // A few grid points where walls meet at a sharp angle are the grid's, not a part.
            parts_with_corner.push(corner || size < 12);
        }
        parts_with_corner.iter().any(|&c| !c)
    }

    #[test]
    fn may_hide_clears_only_cells_whose_every_part_holds_a_corner() {
        // Random chords and turns, against the flood fill; configurations where a corner or an end
        // comes near a wall are left out, where the grid's walls, not the geometry, would cut a corner off.
        let mut seed = 0x2545_f491_u32;
        let mut unit = move || {
            seed ^= seed << 13;
            seed ^= seed >> 17;
            seed ^= seed << 5;
            f64::from(seed) / f64::from(u32::MAX)
        };
        let (mut cleared, mut hiding, mut tried) = (0, 0, 0);
        while tried < 400 {
            let mut outside = || loop {
                let p = DVec2::new(unit() * 3.0 - 1.0, unit() * 3.0 - 1.0);
                if !(p.cmpge(DVec2::splat(-0.01)).all() && p.cmple(DVec2::splat(1.01)).all()) {
                    break p;
                }
            };
            let ends = [outside(), outside(), outside(), outside()];
            let segments = if tried % 2 == 0 {
                [[ends[0], ends[1]], [ends[2], ends[3]]]
            } else {
                let v = DVec2::new(0.05 + 0.9 * ends[2].x.fract().abs(), 0.05 + 0.9 * ends[3].y.fract().abs());
                [[ends[0], v], [v, ends[1]]]
            };
            let clear_of = |p: DVec2| {
                segments.iter().all(|&[a, b]| {
                    let d = b - a;
                    let t = ((p - a).dot(d) / d.length_squared()).clamp(0.0, 1.0);
                    (a + d * t - p).length() > 0.04
                })
            };
            let corners = [DVec2::ZERO, DVec2::X, DVec2::ONE, DVec2::Y];
            let (Some(p), Some(q)) = (chord(segments[0]), chord(segments[1])) else { continue };
            // Nor where two chords come near each other at the square's side: a thin wedge there ends in
            // walls that cut its tip off as a part of its own.
            let off_line = |[a, b]: [DVec2; 2], c: DVec2| (b - a).normalize().perp_dot(c - a).abs() > 0.04;
            let apart = tried % 2 == 1 || p.iter().all(|&c| off_line(q, c)) && q.iter().all(|&c| off_line(p, c));
            if !corners.into_iter().all(clear_of) || !apart {
                continue;
            }
            tried += 1;
            let as_f32 = segments.map(|s| s.map(|p| Vec3::new(p.x as f32, p.y as f32, 0.5)));
            // Back through f32, as edge_cells has them.
            let segments = as_f32.map(|s| s.map(|p| DVec2::new(f64::from(p.x), f64::from(p.y))));
            let hides = cornerless_part(segments);
            let may = may_hide(0, 0, as_f32);
            assert!(may || !hides, "cleared a cell with a cornerless part: {segments:?}");
            cleared += usize::from(!may);
            hiding += usize::from(hides);
        }
        // Neither answer is vacuous.
        assert!(cleared > 100 && hiding > 20, "{cleared} cleared, {hiding} with a cornerless part");
    }

    #[test]
    fn a_cut_end_counts_twice() {
        // A perspective view: a segment from behind the near plane to the middle of the view ends, cut,
        // at the near plane; its cell holds two, the rest of it one.
        let clip = glam::camera::rh::proj::directx::perspective(std::f32::consts::FRAC_PI_2, 1.0, 0.5, 10.0);
        let proj = LightProjection {
            clip_from_view: clip,
            clip_from_world: clip,
            clip_plane_from_world_plane: clip.inverse().transpose(),
            near: 0.5,
            far: 10.0,
            orthographic: false,
            ..straight_on()
        };
        let seg = [Vec3::new(0.3, 0.1, 0.2), Vec3::new(0.0, 0.0, -5.0)];
        let cells = edge_cells(&[seg], &proj, 64, None);
        let marked: Vec<f32> = cells.data().iter().copied().filter(|&d| d < 1.0).collect();
        assert_eq!(marked.len(), 1, "the cut end's cell alone");
        assert!(marked[0] < 0.05, "at the near plane's depth: {}", marked[0]);
    }
}
