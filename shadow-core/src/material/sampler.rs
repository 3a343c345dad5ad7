//! How a texture is read: wrap modes, filters and the mip level of a pixel's footprint.
//!
//! This is the one rule by which textures are read. A GPU backend mirrors it over the same texels and
//! mip chain ([`super::texture`]) rather than through a hardware sampler, whose level selection and
//! filter weights vary between drivers. The rule is the one the Vulkan specification gives for a
//! sampler (16.6 to 16.9), with the choices it leaves open fixed:
//!
//! - The footprint's scale factor is `rho = max(|d(uv)/dx|, |d(uv)/dy|)` in level-0 texels, and the
//!   level of detail `lambda = log2(rho)`.
//! - `lambda <= 0` magnifies (the `mag` filter on level 0), anything above minifies.
//! - Nearest mip selection takes level `k` for `lambda` in `[k - 1/2, k + 1/2)`, decided by comparing
//!   `rho^2` with `2^(2k+1)`, exact powers of two, so no logarithm can round the level differently on the
//!   two backends. Linear mip selection blends `floor(lambda)` and the level above by `fract(lambda)`.
//! - A linear filter reads the 2 x 2 texels around `uv * size - 1/2`, each index wrapped on its own.

use glam::{Vec2, Vec4};

use super::texture::{Texture, TextureLevel};
use crate::image::srgb8_to_linear;

/// What a coordinate outside [0, 1] reads.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Wrap {
    /// The image tiles (glTF's default).
    #[default]
    Repeat,
    /// The edge texel extends.
    ClampToEdge,
    /// The image tiles, every other copy mirrored.
    MirroredRepeat,
}

impl Wrap {
    /// Wraps texel index `i` into `0..size`.
    #[must_use]
    #[inline]
    pub fn index(self, i: i32, size: u32) -> u32 {
        let n = size as i32;
        match self {
            Self::Repeat => i.rem_euclid(n) as u32,
            Self::ClampToEdge => i.clamp(0, n - 1) as u32,
            Self::MirroredRepeat => {
                let m = i.rem_euclid(2 * n);
                (if m >= n { 2 * n - 1 - m } else { m }) as u32
            }
        }
    }
}

/// How texels are combined within a level, or levels with each other.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Filter {
    /// The one nearest texel (level).
    Nearest,
    /// The weighted 2 x 2 texels (two levels).
    #[default]
    Linear,
}

/// A texture sampler. The default is glTF's for a texture without one: repeat, trilinear.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Sampler {
    /// Filter when a texel covers more than a pixel.
    pub mag: Filter,
    /// Filter within a level when a pixel covers more than a texel.
    pub min: Filter,
    /// Filter between levels; `None` reads level 0 only.
    pub mipmap: Option<Filter>,
    /// Wrap along u.
    pub wrap_u: Wrap,
    /// Wrap along v.
    pub wrap_v: Wrap,
}

impl Default for Sampler {
    fn default() -> Self {
        Self {
            mag: Filter::Linear,
            min: Filter::Linear,
            mipmap: Some(Filter::Linear),
            wrap_u: Wrap::Repeat,
            wrap_v: Wrap::Repeat,
        }
    }
}

/// A pixel's footprint in texture coordinates: how `uv` changes a pixel to the right and a pixel down.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Footprint {
    /// `d(uv)/dx`.
    pub dx: Vec2,
    /// `d(uv)/dy`.
    pub dy: Vec2,
}

impl Footprint {
    /// A footprint of no extent: level 0, magnified.
    pub const POINT: Self = Self { dx: Vec2::ZERO, dy: Vec2::ZERO };

    /// `rho^2`: the squared scale factor in texels of a `width` x `height` level 0.
    #[must_use]
    #[inline]
    pub fn rho_squared(&self, width: u32, height: u32) -> f32 {
        let size = Vec2::new(width as f32, height as f32);
        (self.dx * size).length_squared().max((self.dy * size).length_squared())
    }
}

/// The levels and weights a sample reads: `(level, weight)` pairs, one or two.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LevelChoice {
    /// The first level and its weight.
    pub first: (usize, f32),
    /// The level above and its weight, when two are blended.
    pub second: Option<(usize, f32)>,
    /// True when the sample magnifies (reads level 0 with the `mag` filter).
    pub magnified: bool,
}

impl Sampler {
    /// The levels a footprint of `rho_squared` reads in a chain of `levels` levels.
    #[must_use]
    pub fn levels(&self, rho_squared: f32, levels: usize) -> LevelChoice {
        let top = levels.saturating_sub(1);
        // lambda <= 0 exactly when rho^2 <= 1; NaN footprints magnify.
        let magnified = rho_squared <= 1.0 || rho_squared.is_nan();
        let level0 = LevelChoice { first: (0, 1.0), second: None, magnified };
        if magnified {
            return level0;
        }
        match self.mipmap {
            None => level0,
            Some(Filter::Nearest) => {
                let mut k = 0;
                // 2^(2k+1) for k = 0, 1, ...: 2, 8, 32, ... (exact in f32 up to any level a chain has).
                let mut bound = 2.0f32;
                while k < top && rho_squared >= bound {
                    k += 1;
                    bound *= 4.0;
                }
                LevelChoice { first: (k, 1.0), second: None, magnified: false }
            }
            Some(Filter::Linear) => {
                let lambda = (0.5 * rho_squared.log2()).min(top as f32);
                let k = lambda.floor() as usize;
                let t = lambda - k as f32;
                if k >= top || t == 0.0 {
                    LevelChoice { first: (k.min(top), 1.0), second: None, magnified: false }
                } else {
                    LevelChoice { first: (k, 1.0 - t), second: Some((k + 1, t)), magnified: false }
                }
            }
        }
    }

    /// The texture's colour at `uv` over `footprint`: linear RGB and alpha.
    #[must_use]
    pub fn sample(&self, texture: &Texture, uv: Vec2, footprint: Footprint) -> Vec4 {
        self.filtered(texture, uv, footprint, decode)
    }

    /// The alpha of [`Self::sample`], to the bit, without decoding the colour: what an alpha test reads.
    #[must_use]
    pub fn sample_alpha(&self, texture: &Texture, uv: Vec2, footprint: Footprint) -> f32 {
        self.filtered(texture, uv, footprint, |t| f32::from(t[3]) / 255.0)
    }

    /// The texels' values `read` gives, filtered at `uv` over `footprint`.
    fn filtered<T: Filtered>(&self, texture: &Texture, uv: Vec2, footprint: Footprint, read: fn([u8; 4]) -> T) -> T {
        let chain = texture.levels();
        let choice = self.levels(footprint.rho_squared(texture.width(), texture.height()), chain.len());
        let filter = if choice.magnified { self.mag } else { self.min };
        let level = |k: usize| {
            let level = &chain[k];
            let texels = self.texels(level, uv, filter);
            texels.iter().filter(|(_, w)| *w > 0.0).fold(T::ZERO, |sum, &((x, y), w)| sum + read(*level.get(x, y)) * w)
        };
        let mut out = level(choice.first.0) * choice.first.1;
        if let Some((k, w)) = choice.second {
            out = out + level(k) * w;
        }
        out
    }

    /// The texels a filter reads in one level at `uv`, each with its weight (up to four).
    #[must_use]
    pub fn texels(&self, level: &TextureLevel, uv: Vec2, filter: Filter) -> [((u32, u32), f32); 4] {
        let (w, h) = (level.width(), level.height());
        let p = uv * Vec2::new(w as f32, h as f32);
        match filter {
            Filter::Nearest => {
                let at = (self.wrap_u.index(p.x.floor() as i32, w), self.wrap_v.index(p.y.floor() as i32, h));
                [(at, 1.0), (at, 0.0), (at, 0.0), (at, 0.0)]
            }
            Filter::Linear => {
                let q = p - 0.5;
                let base = q.floor();
                let f = q - base;
                let (i, j) = (base.x as i32, base.y as i32);
                let (u0, u1) = (self.wrap_u.index(i, w), self.wrap_u.index(i + 1, w));
                let (v0, v1) = (self.wrap_v.index(j, h), self.wrap_v.index(j + 1, h));
                [
                    ((u0, v0), (1.0 - f.x) * (1.0 - f.y)),
                    ((u1, v0), f.x * (1.0 - f.y)),
                    ((u0, v1), (1.0 - f.x) * f.y),
                    ((u1, v1), f.x * f.y),
                ]
            }
        }
    }
}

/// What a sampler filters: weighted sums of texel values, lane by lane in the same operations whether
/// it is a colour or its alpha alone.
trait Filtered: Copy + std::ops::Add<Output = Self> + std::ops::Mul<f32, Output = Self> {
    const ZERO: Self;
}

impl Filtered for f32 {
    const ZERO: Self = 0.0;
}

impl Filtered for Vec4 {
    const ZERO: Self = Vec4::ZERO;
}

/// An RGBA8 texel as linear colour and alpha.
#[must_use]
pub fn decode(t: [u8; 4]) -> Vec4 {
    Vec4::new(srgb8_to_linear(t[0]), srgb8_to_linear(t[1]), srgb8_to_linear(t[2]), f32::from(t[3]) / 255.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wraps_repeat_clamp_and_mirror() {
        let at = |w: Wrap| (-3..7).map(|i| w.index(i, 3)).collect::<Vec<_>>();
        assert_eq!(at(Wrap::Repeat), vec![0, 1, 2, 0, 1, 2, 0, 1, 2, 0]);
        assert_eq!(at(Wrap::ClampToEdge), vec![0, 0, 0, 0, 1, 2, 2, 2, 2, 2]);
        assert_eq!(at(Wrap::MirroredRepeat), vec![2, 1, 0, 0, 1, 2, 2, 1, 0, 0]);
    }

    #[test]
    fn nearest_levels_change_at_half_steps_of_lambda() {
        let s = Sampler { mipmap: Some(Filter::Nearest), ..Sampler::default() };
        let level = |rho: f32| s.levels(rho * rho, 6).first.0;
        assert_eq!(level(1.0), 0);
        assert!(s.levels(1.0, 6).magnified && !s.levels(1.01, 6).magnified);
        assert_eq!(level(1.41), 0);
        assert_eq!(level(1.42), 1);
        assert_eq!(level(2.82), 1);
        assert_eq!(level(2.83), 2);
        assert_eq!(level(1e6), 5, "the chain's last level");
    }

    #[test]
    fn linear_levels_blend_by_the_fraction_of_lambda() {
        let c = Sampler::default().levels(8.0, 6); // lambda 1.5
        assert_eq!(c.first.0, 1);
        assert!((c.first.1 - 0.5).abs() < 1e-6);
        assert_eq!(c.second.map(|s| s.0), Some(2));
        assert_eq!(Sampler::default().levels(1e9, 3), LevelChoice { first: (2, 1.0), second: None, magnified: false });
    }

    #[test]
    fn bilinear_reads_the_texels_around_the_shifted_point() {
        let texels = vec![[0, 0, 0, 0], [0, 0, 0, 255], [0, 0, 0, 255], [0, 0, 0, 0]];
        let t = Texture::from_rgba8("2x2", 2, 2, texels).unwrap();
        let s = Sampler { wrap_u: Wrap::ClampToEdge, wrap_v: Wrap::ClampToEdge, ..Sampler::default() };
        // Texel centres read their own texel; the middle reads all four equally.
        assert_eq!(s.sample(&t, Vec2::new(0.75, 0.25), Footprint::POINT).w, 1.0);
        assert_eq!(s.sample(&t, Vec2::new(0.25, 0.25), Footprint::POINT).w, 0.0);
        assert!((s.sample(&t, Vec2::new(0.5, 0.5), Footprint::POINT).w - 0.5).abs() < 1e-6);
        // Repeat wraps the left edge onto the right column.
        let r = Sampler::default();
        assert!((r.sample(&t, Vec2::new(0.0, 0.25), Footprint::POINT).w - 0.5).abs() < 1e-6);
    }

    /// Footprints from 1/8 to 64 texels in quarter steps of lambda, with the level each mip mode reads by
    /// the closed form: magnified at and below one texel; nearest mips at `floor(lambda + 1/2)`; linear
    /// mips between `floor(lambda)` and the next by `fract(lambda)`; the chain's last level beyond it.
    #[test]
    fn levels_over_footprints_from_an_eighth_to_sixty_four_texels() {
        let levels = 6; // a 32 x 32 chain: lambda beyond 5 stays on its last level
        for step in -12..=24 {
            let lambda = f64::from(step) / 4.0;
            let rho = 2f64.powf(lambda);
            let rho_squared = (rho * rho) as f32;
            let top = (levels - 1) as f64;
            for mipmap in [None, Some(Filter::Nearest), Some(Filter::Linear)] {
                let c = Sampler { mipmap, ..Sampler::default() }.levels(rho_squared, levels);
                assert_eq!(c.magnified, lambda <= 0.0, "lambda {lambda}");
                let expected = match mipmap {
                    _ if lambda <= 0.0 => ((0, 1.0), None),
                    None => ((0, 1.0), None),
                    Some(Filter::Nearest) => (((lambda + 0.5).floor().min(top) as usize, 1.0), None),
                    Some(Filter::Linear) => {
                        let l = lambda.min(top);
                        let (k, t) = (l.floor(), l - l.floor());
                        if t == 0.0 {
                            ((k as usize, 1.0), None)
                        } else {
                            ((k as usize, 1.0 - t), Some((k as usize + 1, t)))
                        }
                    }
                };
                assert_eq!(c.first.0, expected.0.0, "{mipmap:?} lambda {lambda}");
                assert!((f64::from(c.first.1) - expected.0.1).abs() < 1e-5, "{mipmap:?} lambda {lambda}: {c:?}");
                assert_eq!(c.second.map(|s| s.0), expected.1.map(|s| s.0), "{mipmap:?} lambda {lambda}");
                if let (Some(got), Some(want)) = (c.second, expected.1) {
                    assert!((f64::from(got.1) - want.1).abs() < 1e-5, "{mipmap:?} lambda {lambda}: {c:?}");
                }
            }
        }
    }

    #[test]
    fn the_filter_is_mag_below_a_texel_and_min_above() {
        // Columns of one texel, black and white: nearest reads one, linear blends two at a column edge.
        let texels = (0..16).map(|i| if i % 2 == 0 { [0, 0, 0, 0] } else { [255, 255, 255, 255] }).collect();
        let t = Texture::from_rgba8("columns", 4, 4, texels).unwrap();
        let s = Sampler { mag: Filter::Nearest, min: Filter::Linear, mipmap: None, ..Sampler::default() };
        let edge = Vec2::new(0.5, 0.375); // between columns 1 and 2, on a row's centre
        let small = Footprint { dx: Vec2::new(0.125 / 4.0, 0.0), dy: Vec2::ZERO };
        let large = Footprint { dx: Vec2::new(2.0 / 4.0, 0.0), dy: Vec2::ZERO };
        assert_eq!(s.sample(&t, edge, small).w, 0.0, "nearest: column 2");
        assert!((s.sample(&t, edge, large).w - 0.5).abs() < 1e-6, "linear: columns 1 and 2");
        let flipped = Sampler { mag: Filter::Linear, min: Filter::Nearest, ..s };
        assert!((flipped.sample(&t, edge, small).w - 0.5).abs() < 1e-6);
        assert_eq!(flipped.sample(&t, edge, large).w, 0.0);
    }

    #[test]
    fn bilinear_weights_are_the_distances_to_the_texel_centres() {
        let s = Sampler::default();
        let level = TextureLevel::from_fn(8, 4, |_, _| [0; 4]);
        for &(u, v) in &[(0.3f32, 0.7f32), (0.01, 0.99), (0.5, 0.5), (-0.2, 1.3)] {
            let taps = s.texels(&level, Vec2::new(u, v), Filter::Linear);
            let total: f32 = taps.iter().map(|t| t.1).sum();
            assert!((total - 1.0).abs() < 1e-6);
            let (x, y) = (u * 8.0 - 0.5, v * 4.0 - 0.5);
            let (fx, fy) = (x - x.floor(), y - y.floor());
            assert!((taps[0].1 - (1.0 - fx) * (1.0 - fy)).abs() < 1e-6 && (taps[3].1 - fx * fy).abs() < 1e-6);
            assert_eq!(taps[0].0, (Wrap::Repeat.index(x.floor() as i32, 8), Wrap::Repeat.index(y.floor() as i32, 4)));
        }
    }
}
