//! Shadow silhouette maps (Sen, Cammarano, Hanrahan 2003): the parts both backends share, written once and
//! mirrored in WGSL (build.wgsl and query.wgsl; each function names
//! its twin).
//!
//! **Texel space.** For a light projection with an `N x N` depth map, a point's map position is
//! `s = uv * N - 0.5`: depth sample `(i, j)` (the texel centre of DESIGN 4) sits at the integer point
//! `(i, j)`. The silhouette map is the depth map shifted by half a texel (section 2): its texel `(i, j)`
//! spans `[i, i + 1] x [j, j + 1]`, so its four corners are depth samples. It has `N - 1` texels a side; the
//! outermost half texel of the depth map has no four corners around it, and there the lookup is the plain
//! shadow map's.
//!
//! **Build** ([`PointMap::store`]): every silhouette edge, projected into texel space ([`project_segments`]), is
//! offered to every texel whose slightly enlarged square it may touch; [`choose_point`] picks the stored
//! point as Fig. 4 does (an endpoint inside the texel; else the diagonal intersections, one or the midpoint
//! of two; else nothing), with the corner rule of section 3.1; a point farther from the light than all four
//! corner depths is hidden and dropped. Where silhouettes share a texel it keeps the point nearest the
//! light ([`Keep::Nearest`]) or, as the paper's does, the last one drawn ([`Keep::Last`]).
//!
//! **Query** ([`silhouette_lookup`]): the four corner depth tests; when they disagree, the texel's point
//! and its four neighbours' points split the texel into four skewed quadrants (Fig. 5), found with eight
//! pie-shaped regions ([`quadrant`]), and the quadrant's corner decides. An empty texel stands for its
//! centre, so an empty map is exactly a nearest-sample shadow map. Each corner is compared with the
//! receiver plane's depth there ([`CornerDepth::ReceiverPlane`]) or with the fragment's, as the paper
//! does ([`CornerDepth::Fragment`]).
//!
//! Both defaults depart from the paper, for reasons measured and given where they are defined; the
//! paper's rules stay one setting away.

use bytemuck::{Pod, Zeroable};
use glam::{Vec2, Vec3, Vec4Swizzles};

use shadow_core::image::{Image, Rgb8};
use shadow_core::light::{LightProjection, ndc_to_uv};
use shadow_core::lookup::{compare_nearest, on_map};

/// The value of a texel holding no point (stored points lie in `[0, 1]^2`).
pub const EMPTY: [f32; 2] = [-1.0, -1.0];

/// A silhouette edge projected into one light projection, in texel space (see the module notes), with
/// the light's NDC depth at both ends. NDC depth is affine in screen space along a projected segment
/// (1 / w is), so the depth at any point of it is the linear blend of the two. GPU twin: `Segment` in
/// build.wgsl (hence `repr(C)` and the padding).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct MapSegment {
    /// First end.
    pub a: Vec2,
    /// Second end.
    pub b: Vec2,
    /// NDC depth at `a` and at `b`.
    pub depth: Vec2,
    /// Padding to 32 bytes.
    pub pad: Vec2,
}

impl MapSegment {
    /// A segment from its ends and their depths.
    #[must_use]
    pub fn new(a: Vec2, b: Vec2, depth_a: f32, depth_b: f32) -> Self {
        Self { a, b, depth: Vec2::new(depth_a, depth_b), pad: Vec2::ZERO }
    }

    /// Depth at parameter `t` along the segment.
    #[must_use]
    pub fn depth_at(&self, t: f32) -> f32 {
        self.depth.x + (self.depth.y - self.depth.x) * t
    }
}

/// Clips the homogeneous segment `p + t (q - p)`, `t in [t0, t1]`, to the half-space `f >= 0` where `f` is
/// linear along it with values `fp`, `fq` at the ends. Returns the clipped range or `None`.
fn clip_range(t0: f32, t1: f32, fp: f32, fq: f32) -> Option<(f32, f32)> {
    let (f0, f1) = (fp + (fq - fp) * t0, fp + (fq - fp) * t1);
    match (f0 >= 0.0, f1 >= 0.0) {
        (true, true) => Some((t0, t1)),
        (false, false) => None,
        (inside0, _) => {
            let t = t0 + (t1 - t0) * (f0 / (f0 - f1));
            Some(if inside0 { (t0, t) } else { (t, t1) })
        }
    }
}

/// World-space silhouette edges projected into a projection's `res x res` map, in texel space.
///
/// Each edge is clipped to the near plane in clip space (so edges reaching behind a spot or point light
/// keep their visible part), then to the map's texel range plus a margin of two texels (parts farther out
/// cannot reach a silhouette texel or its neighbours).
#[must_use]
pub fn project_segments(edges: &[[Vec3; 2]], proj: &LightProjection, res: u32) -> Vec<MapSegment> {
    let n = res as f32;
    let (lo, hi) = (-2.0, n + 1.0);
    let mut out = Vec::with_capacity(edges.len());
    for &[p, q] in edges {
        let (cp, cq) = (proj.clip_from_world * p.extend(1.0), proj.clip_from_world * q.extend(1.0));
        // Near plane: z >= 0 (depth 0..1 clip space); it also keeps w > 0 for perspective views.
        let Some((t0, t1)) = clip_range(0.0, 1.0, cp.z, cq.z) else { continue };
        let at = |t: f32| {
            let c = cp + (cq - cp) * t;
            let uv = ndc_to_uv(c.xy() / c.w);
            (uv * n - Vec2::splat(0.5), c.z / c.w)
        };
        let ((a, za), (b, zb)) = (at(t0), at(t1));
        // Now in texel space, where depth is affine: clip to [lo, hi]^2 (Liang-Barsky).
        let mut range = Some((0.0f32, 1.0f32));
        for (fa, fb) in [(a.x - lo, b.x - lo), (hi - a.x, hi - b.x), (a.y - lo, b.y - lo), (hi - a.y, hi - b.y)] {
            range = range.and_then(|(s0, s1)| clip_range(s0, s1, fa, fb));
        }
        let Some((s0, s1)) = range else { continue };
        let seg = MapSegment::new(a, b, za, zb);
        let end = |s: f32| (a + (b - a) * s, seg.depth_at(s));
        let ((a, za), (b, zb)) = (end(s0), end(s1));
        if a.is_finite() && b.is_finite() {
            out.push(MapSegment::new(a, b, za, zb));
        }
    }
    out
}

/// The point texel `texel` stores for `seg` (Fig. 4), in the texel's own frame (`[0, 1]^2`, origin at its
/// corner nearest the map origin), with the segment's depth there; `None` when the segment misses the
/// texel. WGSL twin: `choose_point`.
///
/// The clip square is enlarged by `margin` texels on every side and the result clamped back into the
/// texel: the corner rule of section 3.1, so a segment passing through (or within rounding of) a texel
/// corner is stored in all four texels around it and the stored points stay 4-connected. When both ends
/// lie in the texel the paper does not say which to keep; this keeps the first.
#[must_use]
pub fn choose_point(seg: &MapSegment, texel: Vec2, margin: f32) -> Option<(Vec2, f32)> {
    let (a, b) = (seg.a - texel, seg.b - texel);
    let inside = |p: Vec2| p.x >= -margin && p.y >= -margin && p.x <= 1.0 + margin && p.y <= 1.0 + margin;
    let t = if inside(a) {
        0.0
    } else if inside(b) {
        1.0
    } else {
        // Fig. 4 (B)-(D): where the segment crosses the diagonals x - y = 0 and x + y - 1 = 0, if inside.
        let cross = |fa: f32, fb: f32| -> Option<f32> {
            if fa == fb {
                return None;
            }
            let t = fa / (fa - fb);
            ((0.0..=1.0).contains(&t) && inside(a + (b - a) * t)).then_some(t)
        };
        match (cross(a.x - a.y, b.x - b.y), cross(a.x + a.y - 1.0, b.x + b.y - 1.0)) {
            (Some(t0), Some(t1)) => 0.5 * (t0 + t1),
            (Some(t), None) | (None, Some(t)) => t,
            (None, None) => return None,
        }
    };
    Some(((a + (b - a) * t).clamp(Vec2::ZERO, Vec2::ONE), seg.depth_at(t)))
}

/// The silhouette texels `(i, j)` whose square, enlarged by `margin`, the segment may touch: a superset
/// of those [`choose_point`] accepts, walked row by row. `side` is the silhouette map's side.
fn candidate_texels(seg: &MapSegment, margin: f32, side: u32) -> impl Iterator<Item = (u32, u32)> {
    let (a, b) = (seg.a, seg.b);
    let last = side as i64 - 1;
    let cell = move |v: f32| (v.floor() as i64).clamp(-1, last + 1);
    let rows = cell(a.y.min(b.y) - margin).max(0)..=cell(a.y.max(b.y) + margin).min(last);
    rows.flat_map(move |j| {
        // The segment's x-extent over rows y in [j - margin, j + 1 + margin].
        let (y0, y1) = (j as f32 - margin, j as f32 + 1.0 + margin);
        let (t0, t1) = if a.y == b.y {
            (0.0, 1.0)
        } else {
            let (u, v) = ((y0 - a.y) / (b.y - a.y), (y1 - a.y) / (b.y - a.y));
            (u.min(v).max(0.0), u.max(v).min(1.0))
        };
        // An empty range when the segment misses the row band.
        let (first, end) = if t0 > t1 {
            (0, -1)
        } else {
            let (x0, x1) = (a.x + (b.x - a.x) * t0, a.x + (b.x - a.x) * t1);
            (cell(x0.min(x1) - margin).max(0), cell(x0.max(x1) + margin).min(last))
        };
        (first..=end).map(move |i| (i as u32, j as u32))
    })
}

shadow_core::named_enum! {
    /// Which point a texel keeps when several silhouettes cross it (Fig. 7, left and centre).
    pub enum Keep {
        /// The one nearest the light (ties: the last drawn). The silhouette in front is the one whose
        /// shadow edge a receiver behind it sees; the paper's rule keeps whichever edge happens to come
        /// last, and at 256 texels that cost strike 0.119% edge-band mismatch against 0.074%, crowd
        /// 0.407% against 0.256%.
        Nearest = "nearest",
        /// The last drawn, in edge order: the paper's rule.
        Last = "last",
    }
}

shadow_core::named_enum! {
    /// What a silhouette map's four corner samples are compared with.
    pub enum CornerDepth {
        /// The receiver plane's depth at each corner (see [`silhouette_lookup`] for why).
        ReceiverPlane = "receiver-plane",
        /// The fragment's own depth at all four: the paper's test.
        Fragment = "fragment",
    }
}

/// A silhouette map on the CPU, kept from frame to frame: only the texels the last build wrote are reset,
/// so a build costs its silhouette texels, not the map's area (a 2047^2 map is 33 MB to clear).
#[derive(Clone, Debug, Default)]
pub struct PointMap {
    points: Image<[f32; 2]>,
    /// The depth of each stored point, for [`Keep::Nearest`] (a less-or-equal depth test).
    depth: Image<f32>,
    /// Indices of the non-empty texels, each once.
    written: Vec<u32>,
}

impl PointMap {
    /// The points, [`EMPTY`] where none was stored.
    #[must_use]
    pub fn points(&self) -> &Image<[f32; 2]> {
        &self.points
    }

    /// How many texels hold a point.
    #[must_use]
    pub fn texels(&self) -> u64 {
        self.written.len() as u64
    }

    /// Pass 2 on the CPU: the silhouette map of `depth` (an `N x N` depth map) for `segments` in texel space,
    /// `N - 1` texels a side. GPU twin: `fs_silhouette_point`, drawn with a depth test for
    /// [`Keep::Nearest`].
    pub fn store(&mut self, segments: &[MapSegment], depth: &Image<f32>, margin: f32, keep: Keep) {
        let side = depth.width().saturating_sub(1);
        if self.points.width() == side {
            for &i in &self.written {
                self.points.data_mut()[i as usize] = EMPTY;
                self.depth.data_mut()[i as usize] = f32::INFINITY;
            }
        } else {
            self.points = Image::new(side, side, EMPTY);
            self.depth = Image::new(side, side, f32::INFINITY);
        }
        self.written.clear();
        for seg in segments {
            for (i, j) in candidate_texels(seg, margin, side) {
                let Some((p, z)) = choose_point(seg, Vec2::new(i as f32, j as f32), margin) else { continue };
                // Section 3.1: a point farther from the light than all four corner samples is hidden.
                let corners = [(i, j), (i + 1, j), (i, j + 1), (i + 1, j + 1)].map(|(x, y)| *depth.get(x, y));
                if z > corners.into_iter().fold(f32::MIN, f32::max) {
                    continue;
                }
                let at = self.points.index(i, j);
                if keep == Keep::Nearest {
                    if z > self.depth.data()[at] {
                        continue;
                    }
                    self.depth.data_mut()[at] = z;
                }
                if self.points.data()[at][0] < 0.0 {
                    self.written.push(at as u32);
                }
                self.points.data_mut()[at] = p.to_array();
            }
        }
    }
}

/// [`PointMap::store`] into a new map: the points and the number of non-empty texels.
#[must_use]
pub fn store_points(segments: &[MapSegment], depth: &Image<f32>, margin: f32, keep: Keep) -> (Image<[f32; 2]>, u64) {
    let mut map = PointMap::default();
    map.store(segments, depth, margin, keep);
    let texels = map.texels();
    (map.points, texels)
}

/// Corners of a texel in its own frame, in the cyclic order the quadrants use: (0, 0), (1, 0), (1, 1),
/// (0, 1). The neighbour between corners `k` and `k + 1` is [`NEIGHBOURS`]`[k]`.
pub const CORNERS: [Vec2; 4] = [Vec2::ZERO, Vec2::X, Vec2::ONE, Vec2::Y];

/// Offsets of the four neighbour texels, each between two consecutive [`CORNERS`]: the texel before in y,
/// after in x, after in y, before in x.
pub const NEIGHBOURS: [[i32; 2]; 4] = [[0, -1], [1, 0], [0, 1], [-1, 0]];

fn cross(a: Vec2, b: Vec2) -> f32 {
    a.x * b.y - a.y * b.x
}

/// The skewed quadrant (Fig. 5) holding `f`, as an index into [`CORNERS`]: `o` is the texel's point and
/// `neighbours` its neighbours' points, all in the texel's frame. WGSL twin: `quadrant`.
///
/// The rays from `o` to the four corners cut the texel into four triangles; each holds the ray to one
/// neighbour, which splits it into two pie-shaped regions, one per quadrant: eight regions in all. A point
/// is placed by two half-plane tests for its triangle and one for its side of the neighbour ray. Where `o`
/// lies on the texel's border some triangles are empty, and a point exactly on `o` falls in none: those
/// take the nearest corner (the shadow map's answer).
#[must_use]
pub fn quadrant(o: Vec2, neighbours: [Vec2; 4], f: Vec2) -> usize {
    let d = f - o;
    for k in 0..4 {
        let (c0, c1) = (CORNERS[k] - o, CORNERS[(k + 1) % 4] - o);
        if cross(c0, d) >= 0.0 && cross(d, c1) > 0.0 {
            return if cross(neighbours[k] - o, d) <= 0.0 { k } else { (k + 1) % 4 };
        }
    }
    nearest_corner(f)
}

/// The corner of the texel nearest `f` (ties to the lower index).
#[must_use]
pub fn nearest_corner(f: Vec2) -> usize {
    match (f.x > 0.5, f.y > 0.5) {
        (false, false) => 0,
        (true, false) => 1,
        (true, true) => 2,
        (false, true) => 3,
    }
}

/// A stored point in texel `(x, y)`'s frame, the centre for an empty texel or one off the map.
fn point_or_centre(points: &Image<[f32; 2]>, x: i64, y: i64) -> Vec2 {
    let side = i64::from(points.width());
    if x < 0 || y < 0 || x >= side || y >= side {
        return Vec2::splat(0.5);
    }
    let p = *points.get(x as u32, y as u32);
    if p[0] < 0.0 { Vec2::splat(0.5) } else { Vec2::from_array(p) }
}

/// What a silhouette-map lookup found.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SilhouetteLookup {
    /// 1 lit, 0 shadowed.
    pub visibility: f32,
    /// The corner tests disagreed, so the silhouette map decided (Sen's P counts these pixels).
    pub silhouette: bool,
}

/// Visibility of a point at map position `uv` and NDC depth `depth` from a depth map and its silhouette
/// map (section 3.2). WGSL twin: `silhouette_lookup`.
///
/// `gradient` is the receiver plane's depth gradient over uv ([`LightProjection::depth_gradient`]): each
/// corner sample is compared with the receiver plane's depth at that corner rather than the fragment's
/// own depth. Zero gives the paper's test ([`CornerDepth::Fragment`]).
///
/// Why not the paper's test: a corner can lie 1.4 texels from the fragment, where a nearest-sample
/// shadow map looks at most 0.7 away, and the skewed quadrants hand a receiver on a curved occluder,
/// just inside its own silhouette, to a corner on that occluder. The occluder's slope bias there is
/// its own triangle's; near the terminator the receiver's triangle is steeper, so the surface shadows
/// itself in stripes a texel apart (crowd at 512: 0.24% interior mismatch against the shadow map's
/// 0.09%). On the receiver's plane a convex surface lies behind the plane's depth at every corner, and
/// the stripes go (0.001%).
#[must_use]
pub fn silhouette_lookup(
    depth_map: &Image<f32>,
    points: &Image<[f32; 2]>,
    uv: Vec2,
    depth: f32,
    gradient: Vec2,
) -> SilhouetteLookup {
    let plain = |v: f32| SilhouetteLookup { visibility: v, silhouette: false };
    if !on_map(uv) {
        return plain(1.0);
    }
    let s = uv * depth_map.width() as f32 - Vec2::splat(0.5);
    let side = points.width() as f32;
    if !(s.x >= 0.0 && s.y >= 0.0 && s.x < side && s.y < side) {
        return plain(compare_nearest(depth_map, uv, depth));
    }
    let t = s.floor();
    let f = s - t;
    let (i, j) = (t.x as u32, t.y as u32);
    let n = depth_map.width() as f32;
    let lit = CORNERS.map(|c| depth + gradient.dot((c - f) / n) <= *depth_map.get(i + c.x as u32, j + c.y as u32));
    if lit.iter().all(|&l| l == lit[0]) {
        return plain(if lit[0] { 1.0 } else { 0.0 });
    }
    let (x, y) = (i64::from(i), i64::from(j));
    let o = point_or_centre(points, x, y);
    let neighbours = NEIGHBOURS.map(|[dx, dy]| {
        point_or_centre(points, x + i64::from(dx), y + i64::from(dy)) + Vec2::new(dx as f32, dy as f32)
    });
    let k = quadrant(o, neighbours, f);
    SilhouetteLookup { visibility: if lit[k] { 1.0 } else { 0.0 }, silhouette: true }
}

/// The debug view of Fig. 9 (middle), in light space: the depth map in false colour, magnified so a texel
/// is at least four pixels wide (up to 2048 pixels a side), with every stored point as a red dot.
#[must_use]
pub fn overlay(depth_map: &Image<f32>, points: &Image<[f32; 2]>) -> Image<Rgb8> {
    let n = depth_map.width().max(1);
    let scale = (2048 / n).clamp(1, 4);
    let lo = depth_map.data().iter().copied().fold(1.0f32, f32::min);
    let base = shadow_core::image::false_colour(depth_map, lo, 1.0);
    let mut img = Image::from_fn(n * scale, n * scale, |x, y| *base.get(x / scale, y / scale));
    let size = img.width() as i64;
    for j in 0..points.height() {
        for i in 0..points.width() {
            let p = *points.get(i, j);
            if p[0] < 0.0 {
                continue;
            }
            // Silhouette texel (i, j) starts at depth sample (i, j), whose texel centre is half a texel in.
            let at = (Vec2::new(i as f32, j as f32) + Vec2::from_array(p) + Vec2::splat(0.5)) * scale as f32;
            let (cx, cy) = (at.x as i64, at.y as i64);
            let r = i64::from(scale > 2);
            for y in cy - r..=cy + r {
                for x in cx - r..=cx + r {
                    if x >= 0 && y >= 0 && x < size && y < size {
                        *img.get_mut(x as u32, y as u32) = [235, 30, 30];
                    }
                }
            }
        }
    }
    img
}

#[cfg(test)]
mod tests;
