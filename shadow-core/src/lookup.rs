//! Shadow-map lookups and percentage-closer filters (DESIGN 4 and 6), written once and mirrored in WGSL
//! (`shadow_lookup` in shadow-wgpu's common shader; each function below names its twin).
//!
//! A map is `N x N` depths, row-major from the top-left; texel `i` is centred at `(i + 0.5) / N`. A
//! sample is lit when its depth is at most the stored depth. Samples outside the map are lit: the map has
//! nothing to say there, and for a spot light the metrics leave those pixels out anyway. Filter taps
//! clamp to the map's edge, as a clamp-to-edge sampler does.

use glam::Vec2;

use crate::image::Image;
use crate::technique::settings::Filter;

/// 16 points in the unit disk, spread by best-candidate sampling (minimum distance 0.41), centred.
pub const POISSON16: [Vec2; 16] = [
    Vec2::new(0.9306, 0.0506),
    Vec2::new(-0.9488, 0.0122),
    Vec2::new(-0.0356, 0.9994),
    Vec2::new(-0.0246, -0.9163),
    Vec2::new(0.0220, 0.0607),
    Vec2::new(0.6663, -0.6365),
    Vec2::new(0.6533, 0.7137),
    Vec2::new(-0.6883, 0.6873),
    Vec2::new(-0.6823, -0.6171),
    Vec2::new(-0.1826, -0.4239),
    Vec2::new(-0.4766, 0.2110),
    Vec2::new(0.4581, -0.1665),
    Vec2::new(0.1390, 0.5459),
    Vec2::new(0.5258, 0.2807),
    Vec2::new(-0.5932, -0.2138),
    Vec2::new(0.2370, -0.5874),
];

/// An integer hash of a pixel, the same on both backends (WGSL twin: `pixel_hash`).
#[must_use]
pub fn pixel_hash(x: u32, y: u32) -> u32 {
    let mut h = x.wrapping_mul(0x8da6_b343) ^ y.wrapping_mul(0xd816_3841);
    h ^= h >> 16;
    h = h.wrapping_mul(0x7feb_352d);
    h ^= h >> 15;
    h = h.wrapping_mul(0x846c_a68b);
    h ^ (h >> 16)
}

/// A hash turned into [0, 1) (24 bits).
#[must_use]
pub fn hash_unit(h: u32) -> f32 {
    (h >> 8) as f32 * (1.0 / 16_777_216.0)
}

/// One comparison against texel (x, y), clamped to the edge (WGSL twin: `compare_texel`).
#[inline]
fn compare_texel(map: &Image<f32>, x: i32, y: i32, depth: f32) -> f32 {
    if depth <= *map.get_clamped(x, y) { 1.0 } else { 0.0 }
}

/// Texels `(x, y)`, `(x + 1, y)`, `(x, y + 1)` and `(x + 1, y + 1)`, clamped to the edge: read straight
/// from the rows inside the map (nearly every lookup), through [`Image::get_clamped`] at its border.
#[inline]
fn texels_2x2(map: &Image<f32>, x: i32, y: i32) -> [f32; 4] {
    let (w, h) = (map.width() as i32, map.height() as i32);
    if x >= 0 && y >= 0 && x + 1 < w && y + 1 < h {
        let at = (y * w + x) as usize;
        let (top, bottom) = (&map.data()[at..at + 2], &map.data()[at + w as usize..at + w as usize + 2]);
        [top[0], top[1], bottom[0], bottom[1]]
    } else {
        [(x, y), (x + 1, y), (x, y + 1), (x + 1, y + 1)].map(|(x, y)| *map.get_clamped(x, y))
    }
}

/// `v.floor()` bit for bit (signed zeros, NaN and the integers from 2^23 up included), without the libm
/// call `floor` makes on a plain x86-64 target: a bilinear lookup floors twice.
#[inline]
#[must_use]
pub fn floor_f32(v: f32) -> f32 {
    if v.abs() < 8_388_608.0 {
        let t = v as i32 as f32;
        (if t > v { t - 1.0 } else { t }).copysign(v)
    } else {
        v
    }
}

/// [`floor_f32`] of both components.
#[inline]
#[must_use]
pub fn floor_vec2(v: Vec2) -> Vec2 {
    Vec2::new(floor_f32(v.x), floor_f32(v.y))
}

/// `v.floor() as i64`, saturating and NaN to 0 as that is, without the libm call `floor` makes on a plain
/// x86-64 target, which cost a fifth of `hybrid`'s classification of every receiver and is in the edge
/// cells' walk. (Converting [`floor_f32`] gives the same, with a branch this measured slower for.)
#[inline]
#[must_use]
pub fn floor(v: f32) -> i64 {
    let i = v as i64;
    // Below -2^63 the conversion saturates to i64::MIN, which the comparison then finds above `v`.
    i.saturating_sub(i64::from(i as f32 > v))
}

/// Comparison against the texel holding `uv` (WGSL twin: `compare_nearest`).
#[must_use]
#[inline]
pub fn compare_nearest(map: &Image<f32>, uv: Vec2, depth: f32) -> f32 {
    let n = map.width() as f32;
    let t = floor_vec2(uv * n);
    compare_texel(map, t.x as i32, t.y as i32, depth)
}

/// Bilinearly weighted comparisons of the 2x2 texels around `uv - half a texel`: what a hardware
/// comparison sampler with linear filtering returns (WGSL: `textureSampleCompareLevel`).
#[must_use]
#[inline]
pub fn compare_bilinear(map: &Image<f32>, uv: Vec2, depth: f32) -> f32 {
    bilinear(map.width(), uv, |x, y| compare_texel(map, x, y, depth))
}

/// Whether map coordinates `uv` lie on the map (`[0, 1]` on both axes, edges included): what every lookup
/// asks first, outside being lit (or no edge) by convention.
#[inline]
#[must_use]
pub fn on_map(uv: Vec2) -> bool {
    (0.0..=1.0).contains(&uv.x) && (0.0..=1.0).contains(&uv.y)
}

/// A per-texel value `texel(x, y)` of an `n x n` map, bilinearly weighted over the 2x2 texels around
/// `uv - half a texel` (indices may fall one outside the map: `texel` clamps them).
#[inline]
#[must_use]
pub fn bilinear(n: u32, uv: Vec2, texel: impl Fn(i32, i32) -> f32) -> f32 {
    let st = uv * n as f32 - Vec2::splat(0.5);
    let i = floor_vec2(st);
    let f = st - i;
    let (x, y) = (i.x as i32, i.y as i32);
    let top = texel(x, y) * (1.0 - f.x) + texel(x + 1, y) * f.x;
    let bottom = texel(x, y + 1) * (1.0 - f.x) + texel(x + 1, y + 1) * f.x;
    top * (1.0 - f.y) + bottom * f.y
}

/// How a receiver stands against the four texels nearest its map position.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MapClass {
    /// All four depth tests say lit.
    Lit,
    /// All four say shadowed, or they disagree on a surface facing away from the light (always shadowed).
    Shadowed,
    /// They disagree on a surface facing the light: a shadow silhouette pixel (Chan, thesis 3.1 step 2).
    Silhouette,
}

/// What decided a pixel of `hybrid`, as its debug view shows it (Chan, thesis Fig. 3-5). The GPU writes
/// the discriminants as codes (`from_code`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum PixelClass {
    /// Not a receiver.
    #[default]
    None = 0,
    /// The map: shadowed (red).
    MapShadowed = 1,
    /// The map: lit (blue).
    MapLit = 2,
    /// The volumes, at a silhouette pixel: shadowed (black).
    VolumeShadowed = 3,
    /// The volumes, at a silhouette pixel: lit (green).
    VolumeLit = 4,
}

impl PixelClass {
    /// The class of a code the GPU wrote (its discriminant); `None` for anything else.
    #[must_use]
    pub fn from_code(code: u32) -> Self {
        match code {
            1 => Self::MapShadowed,
            2 => Self::MapLit,
            3 => Self::VolumeShadowed,
            4 => Self::VolumeLit,
            _ => Self::None,
        }
    }

    /// The class of a receiver from the map's class and, at a silhouette pixel, the volumes' answer.
    #[must_use]
    pub fn of(map: MapClass, volume_shadowed: bool) -> Self {
        match (map, volume_shadowed) {
            (MapClass::Lit, _) => Self::MapLit,
            (MapClass::Shadowed, _) => Self::MapShadowed,
            (MapClass::Silhouette, true) => Self::VolumeShadowed,
            (MapClass::Silhouette, false) => Self::VolumeLit,
        }
    }

    /// The thesis's colours; grey where nothing was decided.
    #[must_use]
    pub fn colour(self) -> crate::image::Rgb8 {
        match self {
            Self::None => [96, 96, 96],
            Self::MapShadowed => [200, 30, 30],
            Self::MapLit => [40, 70, 210],
            Self::VolumeShadowed => [0, 0, 0],
            Self::VolumeLit => [40, 200, 60],
        }
    }
}

/// Chan's classification (thesis Fig. 3-3) through the 2x2 texels a bilinear comparison would read
/// (WGSL twin: `classify`). The thesis reads them through the hardware's filter and tests 0 < v < 1; the
/// four texels are compared one by one here, so a receiver exactly on a texel row, whose filter weight
/// for the far row is 0, is still a silhouette pixel when that row disagrees, on both backends alike.
/// Outside the map a receiver is lit, as in [`shadow_lookup`].
#[must_use]
#[inline]
pub fn classify(map: &Image<f32>, uv: Vec2, depth: f32, faces_light: bool) -> MapClass {
    if uv.x < 0.0 || uv.x > 1.0 || uv.y < 0.0 || uv.y > 1.0 {
        return MapClass::Lit;
    }
    let st = uv * map.width() as f32 - Vec2::splat(0.5);
    let (x, y) = (floor(st.x) as i32, floor(st.y) as i32);
    let lit = texels_2x2(map, x, y).iter().filter(|&&texel| depth <= texel).count();
    match lit {
        4 => MapClass::Lit,
        0 => MapClass::Shadowed,
        _ if faces_light => MapClass::Silhouette,
        _ => MapClass::Shadowed,
    }
}

/// The cell of an `edge_cells` (shadow-hard's `hybrid::edge_map`) map of a map of side `res` that
/// holds `uv`: the square between the four texels a lookup at `uv` reads, `(0, 0)` to `(res, res)` for
/// `uv` on the map.
#[inline]
#[must_use]
pub fn cell_of(res: u32, uv: Vec2) -> (u32, u32) {
    let st = uv * res as f32 + Vec2::splat(0.5);
    let cell = |v: f32| floor(v).clamp(0, i64::from(res)) as u32;
    (cell(st.x), cell(st.y))
}

/// Whether two silhouette edges or more nearer the light than `depth` (by [`EDGE_MARGIN`]) enter the
/// square between the four texels of `map` nearest `uv`, where Chan's rule may miss a sliver, a gap or a
/// corner between them (`hybrid`'s `edge_texels=paired`; `cells` from
/// `edge_cells` (shadow-hard's `hybrid::edge_map`), side one more than `map`'s; WGSL twin:
/// `near_edge` in edges_paired.wgsl). Outside the map, no.
///
/// Not where the edges are hidden ([`hidden`]): when all four texels hold a surface nearer the light than
/// the nearest of the edges (by [`EDGE_MARGIN`]), those surfaces cover the whole square in front of the
/// edges, since nothing nearer has an edge inside it that could end them. This leaves out most of a cloud
/// of casters' crossings, those behind other casters (cubes: 14 126 of 23 503 pair cells). It assumes a
/// surface's depth changes across the square by no more than the map's bias adds at the texels, which the
/// slope-scaled bias sees to for a surface as tilted at the texels as between them (twice the depth
/// change per texel by default, against at most 0.71 texels from a corner to any point of the square).
/// A surface that turns steep between the texel centres without a silhouette edge breaks it: light
/// through a sub-texel countersunk hole, whose silhouette is its far rim, deeper than the face the four
/// texels see around it, would be missed.
#[must_use]
#[inline]
pub fn near_edge_pair(cells: &Image<f32>, map: &Image<f32>, uv: Vec2, depth: f32) -> bool {
    if !on_map(uv) {
        return false;
    }
    let (x, y) = cell_of(map.width(), uv);
    let nearest = *cells.get(x, y);
    nearest < depth - EDGE_MARGIN && !hidden(map, x, y, nearest)
}

/// Whether all four texels of `map` at the corners of cell `(x, y)` ([`cell_of`]) hold a surface nearer the
/// light than `nearest` by [`EDGE_MARGIN`], hiding every edge of that depth or more in the cell
/// ([`near_edge_pair`] says why).
#[must_use]
#[inline]
pub fn hidden(map: &Image<f32>, x: u32, y: u32, nearest: f32) -> bool {
    texels_2x2(map, x as i32 - 1, y as i32 - 1).iter().all(|&t| t < nearest - EDGE_MARGIN)
}

/// How much nearer the light than a receiver (NDC depth) an edge must be to count in [`near_edge_pair`]: a
/// surface's own rim lies at the depth of its silhouette edge, where which of the two rounds nearer differs
/// between backends by a few ulps; a caster that shadows the receiver is orders of magnitude nearer.
pub const EDGE_MARGIN: f32 = 1e-5;

/// Visibility from a shadow map with a filter (WGSL twin: `shadow_lookup`). `radius` is the kernel radius
/// in texels for the jittered and Poisson filters; `pixel` seeds their per-pixel rotation or jitter.
#[must_use]
#[inline]
pub fn shadow_lookup(map: &Image<f32>, uv: Vec2, depth: f32, filter: Filter, radius: f32, pixel: (u32, u32)) -> f32 {
    if !on_map(uv) {
        return 1.0;
    }
    let texel = 1.0 / map.width() as f32;
    match filter {
        Filter::None => compare_nearest(map, uv, depth),
        Filter::Bilinear => compare_bilinear(map, uv, depth),
        Filter::Pcf3x3 => {
            let mut sum = 0.0;
            for dy in -1..=1 {
                for dx in -1..=1 {
                    sum += compare_bilinear(map, uv + Vec2::new(dx as f32, dy as f32) * texel, depth);
                }
            }
            sum / 9.0
        }
        Filter::Pcf4x4Jitter => {
            let mut h = pixel_hash(pixel.0, pixel.1);
            let mut sum = 0.0;
            for j in 0..4 {
                for i in 0..4 {
                    h = pixel_hash(h, (j * 4 + i) as u32);
                    let jx = hash_unit(h);
                    let jy = hash_unit(h.rotate_left(12));
                    // Cell (i, j) of a 4x4 grid over [-radius, radius]^2, jittered inside the cell.
                    let o = (Vec2::new(i as f32 + jx, j as f32 + jy) * 0.5 - Vec2::splat(1.0)) * radius;
                    sum += compare_bilinear(map, uv + o * texel, depth);
                }
            }
            sum / 16.0
        }
        Filter::Poisson16 => {
            let angle = hash_unit(pixel_hash(pixel.0, pixel.1)) * std::f32::consts::TAU;
            let (s, c) = angle.sin_cos();
            let mut sum = 0.0;
            for p in POISSON16 {
                let o = Vec2::new(c * p.x - s * p.y, s * p.x + c * p.y) * radius;
                sum += compare_bilinear(map, uv + o * texel, depth);
            }
            sum / 16.0
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 4x4 map: the left half at depth 0.2 (an occluder), the right half at 1.0.
    #[test]
    fn the_floors_are_floor_bit_for_bit() {
        // `floor_f32` and `floor` against `f32::floor`, at every 65537th bit pattern (all exponents, both
        // signs, NaNs and infinities among them) and at the values around the integers near zero and near
        // 2^23, where the conversion's shortcut ends.
        let strided = (0..=u32::MAX / 65_537).map(|k| f32::from_bits(k * 65_537));
        let near = [0.0f32, 1.0, 2.0, 8_388_607.0, 8_388_608.0, 16_777_216.0, 2_147_483_648.0]
            .into_iter()
            .flat_map(|v| [v, v.next_up(), v.next_down(), v + 0.5, -v, -v.next_up(), -v.next_down(), -v - 0.5]);
        for v in strided.chain(near).chain([f32::MIN_POSITIVE, -f32::MIN_POSITIVE, f32::INFINITY, f32::NEG_INFINITY]) {
            let (want, got) = (v.floor(), floor_f32(v));
            assert!(want.to_bits() == got.to_bits() || want.is_nan() && got.is_nan(), "{v:e}: {got:e} for {want:e}");
            assert_eq!(floor(v), want as i64, "{v:e} as an integer");
        }
    }

    fn half_map() -> Image<f32> {
        Image::from_fn(4, 4, |x, _| if x < 2 { 0.2 } else { 1.0 })
    }

    #[test]
    fn classification_and_edges_read_the_four_texels_clamped_to_the_edge() {
        // Against the four clamped comparisons written out, over a map with a texel of its own everywhere,
        // at positions across the whole map, its border and just outside it.
        let map = Image::from_fn(7, 7, |x, y| ((x * 5 + y * 3) % 7) as f32 / 7.0);
        for i in 0..=160 {
            for j in 0..=160 {
                let uv = Vec2::new(i as f32, j as f32) / 160.0 * 1.02 - Vec2::splat(0.01);
                for depth in [0.1, 0.45, 0.8] {
                    let st = uv * 7.0 - Vec2::splat(0.5);
                    let (x, y) = (st.x.floor() as i32, st.y.floor() as i32);
                    let lit: f32 = [(x, y), (x + 1, y), (x, y + 1), (x + 1, y + 1)]
                        .map(|(x, y)| compare_texel(&map, x, y, depth))
                        .iter()
                        .sum();
                    let want = match lit {
                        _ if uv.x < 0.0 || uv.x > 1.0 || uv.y < 0.0 || uv.y > 1.0 => MapClass::Lit,
                        4.0 => MapClass::Lit,
                        0.0 => MapClass::Shadowed,
                        _ => MapClass::Silhouette,
                    };
                    assert_eq!(classify(&map, uv, depth, true), want, "uv {uv}, depth {depth}");
                }
            }
        }
    }

    #[test]
    fn nearest_uses_the_texel_under_uv() {
        let m = half_map();
        assert_eq!(compare_nearest(&m, Vec2::new(0.49, 0.5), 0.5), 0.0);
        assert_eq!(compare_nearest(&m, Vec2::new(0.51, 0.5), 0.5), 1.0);
        assert_eq!(compare_nearest(&m, Vec2::new(0.1, 0.5), 0.2), 1.0, "equal depth is lit");
        assert_eq!(shadow_lookup(&m, Vec2::new(-0.1, 0.5), 0.9, Filter::None, 1.0, (0, 0)), 1.0, "outside is lit");
    }

    #[test]
    fn bilinear_weights_across_the_boundary() {
        let m = half_map();
        // Texel centres 1 and 2 are at u = 0.375 and 0.625; halfway between, half the weight is lit.
        assert!((compare_bilinear(&m, Vec2::new(0.5, 0.5), 0.5) - 0.5).abs() < 1e-6);
        assert!((compare_bilinear(&m, Vec2::new(0.4375, 0.5), 0.5) - 0.25).abs() < 1e-6);
        assert_eq!(compare_bilinear(&m, Vec2::new(0.625, 0.5), 0.5), 1.0);
    }

    #[test]
    fn wide_filters_are_averages_in_range() {
        let m = half_map();
        for f in [Filter::Pcf3x3, Filter::Pcf4x4Jitter, Filter::Poisson16] {
            let edge = shadow_lookup(&m, Vec2::new(0.5, 0.5), 0.5, f, 1.5, (3, 7));
            assert!(edge > 0.1 && edge < 0.9, "{f}: {edge}");
            assert_eq!(shadow_lookup(&m, Vec2::new(0.5, 0.5), 0.1, f, 1.5, (3, 7)), 1.0, "{f}");
        }
        assert!(POISSON16.iter().all(|p| p.length() <= 1.0 + 1e-4));
    }
}
