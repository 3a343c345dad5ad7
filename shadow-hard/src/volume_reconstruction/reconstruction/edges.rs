//! `depth_edges`: discontinuities of a light depth map (McCool sections 3.1 to 3.3).
//!
//! Flags sit between neighbouring samples (Fig. 2): `u(x, y)` between `(x, y)` and `(x + 1, y)`, `v(x, y)`
//! between `(x, y)` and `(x, y + 1)`. With first differences `d`, a flag is set when `|d| > high` (a sure
//! edge), or when `|d| > low` and `d` is a local extremum of the differences along its direction by more
//! than `second` on both sides: the second-derivative test, a strong zero crossing of the right sign, which
//! clears the blocks of candidates over steep surfaces seen nearly edge-on. Missing differences past the
//! map's border count as 0.
//!
//! A cell whose code has one bit has a dangling edge: a contour that ends inside it, typically where an
//! object meets another and the depth contrast fades (section 3.2). With `dangling_steps > 0` the contour
//! is followed with the thresholds lowered (section 3.2): of the dangling cell's unflagged sides whose
//! difference is over the much lower `dangling` threshold and is still a local extremum of the
//! differences, the strongest (on a tie, the side straight on) is flagged, and so on from the next cell,
//! up to that many steps. The extremum test keeps the contour from wandering off along a steep surface,
//! whose differences are large but even.
//!
//! An object-ID channel of the light pass (section 3.2, "as a last resort") adds flags wherever adjacent
//! samples belong to different objects: everywhere ([`ObjectIds::All`], ORed with the depth flags), or only
//! where a dangling contour is followed ([`ObjectIds::Dangling`]: a side between two objects is taken
//! before any side the lowered depth test would pick), which is where the paper says it is needed: depth
//! contrast fades where one object meets another, and objects' own concavities still need the depth test.
//!
//! Depths here are linear (distances along the light's axis), so the thresholds are scene distances: the
//! quantization of NDC depth is not constant in world space (section 3.1), but a threshold on an object's
//! separation from what is behind it should be.

use crate::volume_reconstruction::ObjectIds;

/// Thresholds, in the depth map's units.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EdgeSettings {
    /// Candidate threshold, theta_L.
    pub low: f32,
    /// Sure-edge threshold, theta_H (above `low`).
    pub high: f32,
    /// Strength of the second-derivative zero crossing, theta_S; `None` turns the test off (every
    /// candidate is an edge: the plain first-difference detector of section 3.1).
    pub second: Option<f32>,
    /// The lowered threshold along dangling edges.
    pub dangling: f32,
    /// How many cells a dangling edge may be followed (0: not at all).
    pub dangling_steps: u32,
}

/// Edge flags of a `w x h` depth map.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct EdgeMap {
    w: u32,
    h: u32,
    /// `(w - 1) x h`, row-major.
    u: Vec<bool>,
    /// `w x (h - 1)`, row-major.
    v: Vec<bool>,
}

impl EdgeMap {
    /// No flags over a `w x h` map.
    #[must_use]
    pub fn empty(w: u32, h: u32) -> Self {
        let (w1, h1) = (w.saturating_sub(1) as usize, h.saturating_sub(1) as usize);
        Self { w, h, u: vec![false; w1 * h as usize], v: vec![false; w as usize * h1] }
    }

    /// Samples across and down.
    #[must_use]
    pub fn size(&self) -> (u32, u32) {
        (self.w, self.h)
    }

    /// The flag between samples `(x, y)` and `(x + 1, y)`.
    #[must_use]
    pub fn u(&self, x: u32, y: u32) -> bool {
        self.u[(y * (self.w - 1) + x) as usize]
    }

    /// The flag between samples `(x, y)` and `(x, y + 1)`.
    #[must_use]
    pub fn v(&self, x: u32, y: u32) -> bool {
        self.v[(y * self.w + x) as usize]
    }

    /// Sets the flag between `(x, y)` and `(x + 1, y)`.
    pub fn set_u(&mut self, x: u32, y: u32) {
        let i = (y * (self.w - 1) + x) as usize;
        self.u[i] = true;
    }

    /// Sets the flag between `(x, y)` and `(x, y + 1)`.
    pub fn set_v(&mut self, x: u32, y: u32) {
        let i = (y * self.w + x) as usize;
        self.v[i] = true;
    }

    /// The 4-bit code of cell `(x, y)` (section 3.2): bit 0 its top side (`u(x, y)`), bit 1 its right side
    /// (`v(x + 1, y)`), bit 2 its bottom side (`u(x, y + 1)`), bit 3 its left side (`v(x, y)`).
    #[must_use]
    pub fn code(&self, x: u32, y: u32) -> u8 {
        u8::from(self.u(x, y))
            | u8::from(self.v(x + 1, y)) << 1
            | u8::from(self.u(x, y + 1)) << 2
            | u8::from(self.v(x, y)) << 3
    }

    /// How many flags are set.
    #[must_use]
    pub fn flag_count(&self) -> usize {
        self.u.iter().chain(&self.v).filter(|&&f| f).count()
    }

    /// The fraction of potential flags that are set: a measure of scene complexity (section 3.2), O(1/n)
    /// for a well-chosen threshold.
    #[must_use]
    pub fn flag_fraction(&self) -> f64 {
        let total = self.u.len() + self.v.len();
        if total == 0 { 0.0 } else { self.flag_count() as f64 / total as f64 }
    }

    /// Every cell with at least one flagged side, as `y * (w - 1) + x`, ascending.
    #[must_use]
    pub fn marked_cells(&self) -> Vec<u32> {
        let (cw, ch) = (self.w.saturating_sub(1), self.h.saturating_sub(1));
        let mut cells = Vec::new();
        let mut add = |x: u32, y: u32| {
            if x < cw && y < ch {
                cells.push(y * cw + x);
            }
        };
        for y in 0..self.h {
            for x in 0..cw {
                if self.u(x, y) {
                    add(x, y);
                    if y > 0 {
                        add(x, y - 1);
                    }
                }
            }
        }
        for y in 0..ch {
            for x in 0..self.w {
                if self.v(x, y) {
                    add(x, y);
                    if x > 0 {
                        add(x - 1, y);
                    }
                }
            }
        }
        cells.sort_unstable();
        cells.dedup();
        cells
    }

    /// Sets every flag `other` has (the same size).
    ///
    /// # Panics
    /// When the sizes differ: a caller bug.
    pub fn union_with(&mut self, other: &EdgeMap) {
        assert_eq!(self.size(), other.size(), "edge maps of different sizes");
        for (a, b) in self.u.iter_mut().zip(&other.u).chain(self.v.iter_mut().zip(&other.v)) {
            *a |= *b;
        }
    }
}

/// Flags between every pair of adjacent samples of a `w x h` ID map whose IDs differ.
#[must_use]
pub fn id_edges(ids: &[u32], w: u32, h: u32) -> EdgeMap {
    let mut map = EdgeMap::empty(w, h);
    let id = |x: u32, y: u32| ids[(y * w + x) as usize];
    for y in 0..h {
        for x in 0..w.saturating_sub(1) {
            if id(x, y) != id(x + 1, y) {
                map.set_u(x, y);
            }
        }
    }
    for y in 0..h.saturating_sub(1) {
        for x in 0..w {
            if id(x, y) != id(x, y + 1) {
                map.set_v(x, y);
            }
        }
    }
    map
}

/// Whether the difference `d`, with `before` and `after` its neighbours along the same direction, is an
/// edge under `s`.
fn is_edge(d: f32, before: f32, after: f32, s: &EdgeSettings) -> bool {
    let a = d.abs();
    if a > s.high {
        return true;
    }
    if a <= s.low {
        return false;
    }
    match s.second {
        None => true,
        // A local extremum of the first difference, by more than theta_S on both sides: the second
        // difference changes sign across the flag, from + to - for a rising step, - to + for a falling one.
        Some(theta) => {
            let sign = d.signum();
            a - sign * before > theta && a - sign * after > theta
        }
    }
}

/// The edge map of a `w x h` linear depth map (row-major).
#[must_use]
pub fn depth_edges(depth: &[f32], w: u32, h: u32, s: &EdgeSettings) -> EdgeMap {
    detect(depth, None, w, h, s)
}

/// The edge map of a `w x h` linear depth map and the object IDs of the same samples, combined as `mode`
/// says (see the module's documentation).
///
/// # Panics
/// When `ids` is not the size of `depth`: a caller bug.
#[must_use]
pub fn depth_and_id_edges(depth: &[f32], ids: &[u32], w: u32, h: u32, s: &EdgeSettings, mode: ObjectIds) -> EdgeMap {
    assert_eq!(ids.len(), depth.len(), "an ID map the size of the depth map");
    match mode {
        ObjectIds::Off => depth_edges(depth, w, h, s),
        ObjectIds::Dangling => detect(depth, Some(ids), w, h, s),
        ObjectIds::All => {
            // Every ID flag before the dangling ends are looked for: a contour that fades where two objects
            // meet is then already closed by the ID boundary.
            let mut map = EdgeMap::empty(w, h);
            if w >= 2 && h >= 2 {
                threshold_flags(&mut map, depth, s);
                map.union_with(&id_edges(ids, w, h));
                follow_dangling(&mut map, depth, None, s);
            }
            map
        }
    }
}

/// Depth flags, dangling contours followed preferring ID boundaries when `ids` are given.
fn detect(depth: &[f32], ids: Option<&[u32]>, w: u32, h: u32, s: &EdgeSettings) -> EdgeMap {
    let mut map = EdgeMap::empty(w, h);
    if w >= 2 && h >= 2 {
        threshold_flags(&mut map, depth, s);
        follow_dangling(&mut map, depth, ids, s);
    }
    map
}

/// The first-difference flags, thinned by the second-derivative test when `s` has it.
fn threshold_flags(map: &mut EdgeMap, depth: &[f32], s: &EdgeSettings) {
    let (w, h) = map.size();
    let z = |x: u32, y: u32| depth[(y * w + x) as usize];
    // First differences along x at (x, y) for x in -1..=w-1, 0 outside.
    let dx = |x: i64, y: u32| if x < 0 || x >= i64::from(w) - 1 { 0.0 } else { z(x as u32 + 1, y) - z(x as u32, y) };
    let dy = |x: u32, y: i64| if y < 0 || y >= i64::from(h) - 1 { 0.0 } else { z(x, y as u32 + 1) - z(x, y as u32) };
    for y in 0..h {
        for x in 0..w - 1 {
            let xi = i64::from(x);
            if is_edge(dx(xi, y), dx(xi - 1, y), dx(xi + 1, y), s) {
                map.set_u(x, y);
            }
        }
    }
    for y in 0..h - 1 {
        for x in 0..w {
            let yi = i64::from(y);
            if is_edge(dy(x, yi), dy(x, yi - 1), dy(x, yi + 1), s) {
                map.set_v(x, y);
            }
        }
    }
}

/// How strongly the flag at `(x, y)` (a `u` flag when `is_u`) stands out under the lowered thresholds:
/// the amount by which its difference exceeds both neighbours' along its direction, when it is over
/// `floor`; 0 otherwise.
fn lowered_strength(depth: &[f32], w: u32, h: u32, is_u: bool, x: u32, y: u32, floor: f32) -> f32 {
    let z = |x: i64, y: i64| depth[(y * i64::from(w) + x) as usize];
    let (x, y) = (i64::from(x), i64::from(y));
    let (step, len, pos) = if is_u { ((1, 0), i64::from(w), x) } else { ((0, 1), i64::from(h), y) };
    let diff = |k: i64| {
        if k < 0 || k >= len - 1 {
            return 0.0;
        }
        let (ax, ay) = if is_u { (k, y) } else { (x, k) };
        z(ax + step.0, ay + step.1) - z(ax, ay)
    };
    let d = diff(pos);
    let sign = d.signum();
    if d.abs() <= floor {
        return 0.0;
    }
    (d.abs() - sign * diff(pos - 1)).min(d.abs() - sign * diff(pos + 1)).max(0.0)
}

/// Whether the samples on the two sides of the flag at `(x, y)` (a `u` flag when `is_u`) are of different
/// objects.
fn ids_differ(ids: &[u32], w: u32, is_u: bool, x: u32, y: u32) -> bool {
    let (x2, y2) = if is_u { (x + 1, y) } else { (x, y + 1) };
    ids[(y * w + x) as usize] != ids[(y2 * w + x2) as usize]
}

/// Whether a code has exactly one bit: a dangling edge ends in that cell.
#[must_use]
pub fn dangling(code: u8) -> bool {
    code.count_ones() == 1
}

/// Extends dangling edges under the lowered threshold, one cell per step, all dangling cells of a step at
/// once (so the result does not depend on the order cells are visited in). With `ids`, a side between two
/// objects outranks any the depth test picks.
fn follow_dangling(map: &mut EdgeMap, depth: &[f32], ids: Option<&[u32]>, s: &EdgeSettings) {
    let (w, h) = map.size();
    let mut frontier = map.marked_cells();
    for _ in 0..s.dangling_steps {
        let mut new_flags: Vec<(bool, u32, u32)> = Vec::new();
        for &cell in &frontier {
            let (x, y) = (cell % (w - 1), cell / (w - 1));
            let code = map.code(x, y);
            if !dangling(code) {
                continue;
            }
            // The cell's sides as (bit, is u, flag position, strength), tested again with the thresholds
            // lowered: over theta_D, and a local extremum of the differences (theta_S lowered to 0).
            let sides =
                [(0b0001, true, x, y), (0b0010, false, x + 1, y), (0b0100, true, x, y + 1), (0b1000, false, x, y)];
            // The largest strength; on a tie, straight on (the side opposite the flagged one).
            let opposite = ((code << 2) | (code >> 2)) & 0b1111;
            let best = sides
                .iter()
                .filter(|side| side.0 & code == 0)
                .map(|&(bit, is_u, fx, fy)| {
                    let strength = if ids.is_some_and(|ids| ids_differ(ids, w, is_u, fx, fy)) {
                        f32::INFINITY
                    } else {
                        lowered_strength(depth, w, h, is_u, fx, fy, s.dangling)
                    };
                    (bit, is_u, fx, fy, strength)
                })
                .filter(|side| side.4 > 0.0)
                .max_by(|a, b| a.4.total_cmp(&b.4).then((a.0 == opposite).cmp(&(b.0 == opposite))));
            if let Some((_, is_u, fx, fy, _)) = best {
                new_flags.push((is_u, fx, fy));
            }
        }
        if new_flags.is_empty() {
            break;
        }
        let mut next = Vec::new();
        for (is_u, fx, fy) in new_flags {
            // The cells on both sides of the new flag are where the contour may dangle next.
            if is_u {
                map.set_u(fx, fy);
                next.push(fy * (w - 1) + fx);
                if fy > 0 {
                    next.push((fy - 1) * (w - 1) + fx);
                }
            } else {
                map.set_v(fx, fy);
                if fx < w - 1 {
                    next.push(fy * (w - 1) + fx);
                }
                if fx > 0 {
                    next.push(fy * (w - 1) + fx - 1);
                }
            }
        }
        next.retain(|&c| c / (w - 1) < h - 1);
        next.sort_unstable();
        next.dedup();
        frontier = next;
    }
}
