//! Images: row-major, top-left origin, pixel (x, y) centred at (x + 0.5, y + 0.5) (DESIGN 4).
//!
//! Also the colour helpers every report uses: sRGB encoding, PNG output, visibility and error false-colour.

use std::path::Path;

/// An 8-bit sRGB colour.
pub type Rgb8 = [u8; 3];

/// A `width x height` grid of `T`, row-major from the top-left corner.
#[derive(Clone, Debug, PartialEq)]
pub struct Image<T> {
    width: u32,
    height: u32,
    data: Vec<T>,
}

impl<T> Default for Image<T> {
    /// The empty 0 x 0 image.
    fn default() -> Self {
        Self { width: 0, height: 0, data: Vec::new() }
    }
}

/// Why an image could not be written.
#[derive(Debug, thiserror::Error)]
#[error("cannot write {path}: {source}")]
pub struct ImageWriteError {
    /// The file.
    pub path: String,
    /// What went wrong.
    #[source]
    pub source: ::image::ImageError,
}

impl<T: Clone> Image<T> {
    /// An image filled with `value`.
    #[must_use]
    pub fn new(width: u32, height: u32, value: T) -> Self {
        Self { width, height, data: vec![value; width as usize * height as usize] }
    }
}

impl<T> Image<T> {
    /// An image over existing row-major data, or `None` when the length is not `width * height`.
    #[must_use]
    pub fn from_vec(width: u32, height: u32, data: Vec<T>) -> Option<Self> {
        (data.len() == width as usize * height as usize).then_some(Self { width, height, data })
    }

    /// An image whose pixel (x, y) is `f(x, y)`.
    #[must_use]
    pub fn from_fn(width: u32, height: u32, mut f: impl FnMut(u32, u32) -> T) -> Self {
        let mut data = Vec::with_capacity(width as usize * height as usize);
        for y in 0..height {
            for x in 0..width {
                data.push(f(x, y));
            }
        }
        Self { width, height, data }
    }

    /// Width in pixels.
    #[must_use]
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height in pixels.
    #[must_use]
    pub fn height(&self) -> u32 {
        self.height
    }

    /// Row-major pixels.
    #[must_use]
    pub fn data(&self) -> &[T] {
        &self.data
    }

    /// Row-major pixels, mutable.
    pub fn data_mut(&mut self) -> &mut [T] {
        &mut self.data
    }

    /// The pixel data, consuming the image.
    #[must_use]
    pub fn into_vec(self) -> Vec<T> {
        self.data
    }

    /// Index of pixel (x, y) in [`Image::data`].
    #[must_use]
    pub fn index(&self, x: u32, y: u32) -> usize {
        y as usize * self.width as usize + x as usize
    }

    /// Pixel (x, y).
    ///
    /// # Panics
    /// When (x, y) is outside the image.
    #[must_use]
    pub fn get(&self, x: u32, y: u32) -> &T {
        assert!(x < self.width && y < self.height, "pixel ({x}, {y}) outside {}x{}", self.width, self.height);
        &self.data[self.index(x, y)]
    }

    /// The pixel nearest (x, y): indices clamped to the image's edge, as a clamp-to-edge sampler reads a
    /// texture (map lookups whose 2x2 footprint reaches one texel past the border).
    ///
    /// # Panics
    /// When the image is empty.
    #[must_use]
    #[inline]
    pub fn get_clamped(&self, x: i32, y: i32) -> &T {
        let clamp = |v: i32, n: u32| v.clamp(0, n as i32 - 1) as u32;
        self.get(clamp(x, self.width), clamp(y, self.height))
    }

    /// Pixel (x, y), mutable.
    ///
    /// # Panics
    /// When (x, y) is outside the image.
    pub fn get_mut(&mut self, x: u32, y: u32) -> &mut T {
        assert!(x < self.width && y < self.height, "pixel ({x}, {y}) outside {}x{}", self.width, self.height);
        let i = self.index(x, y);
        &mut self.data[i]
    }

    /// Row `y`.
    #[must_use]
    pub fn row(&self, y: u32) -> &[T] {
        let w = self.width as usize;
        &self.data[y as usize * w..(y as usize + 1) * w]
    }

    /// A new image of `f` applied to every pixel.
    #[must_use]
    pub fn map<U>(&self, f: impl FnMut(&T) -> U) -> Image<U> {
        Image { width: self.width, height: self.height, data: self.data.iter().map(f).collect() }
    }

    /// True when both images have the same size.
    #[must_use]
    pub fn same_size<U>(&self, other: &Image<U>) -> bool {
        self.width == other.width && self.height == other.height
    }
}

impl Image<Rgb8> {
    /// Writes the image as an 8-bit RGB PNG.
    ///
    /// # Errors
    /// When the file cannot be created or encoded.
    pub fn save_png(&self, path: impl AsRef<Path>) -> Result<(), ImageWriteError> {
        let path = path.as_ref();
        let bytes: Vec<u8> = self.data.iter().flatten().copied().collect();
        ::image::save_buffer(path, &bytes, self.width, self.height, ::image::ExtendedColorType::Rgb8)
            .map_err(|source| ImageWriteError { path: path.display().to_string(), source })
    }

    /// Reads an 8-bit RGB PNG (any PNG is converted to RGB8).
    ///
    /// # Errors
    /// When the file cannot be read or decoded.
    pub fn load_png(path: impl AsRef<Path>) -> Result<Self, ImageWriteError> {
        let path = path.as_ref();
        let img = ::image::open(path)
            .map_err(|source| ImageWriteError { path: path.display().to_string(), source })?
            .into_rgb8();
        let (w, h) = img.dimensions();
        let data = img.into_raw().chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
        Ok(Self { width: w, height: h, data })
    }
}

/// Linear [0, 1] to the sRGB transfer curve, 8 bits, rounded to nearest (NaN to 0).
///
/// By table, not by `powf` per channel (a shaded frame encodes three channels per pixel): the code is the
/// number of code boundaries at or below `v`, each boundary the linear value where the curve crosses the
/// midpoint between two codes, computed once in f64. A table of codes at the starts of bins finer than
/// the closest two boundaries gives the code at `v`'s bin start, and one comparison with the next
/// boundary finds it.
#[must_use]
#[inline]
pub fn linear_to_srgb8(v: f32) -> u8 {
    srgb8_table().encode(v)
}

/// A linear colour to sRGB8, each channel as [`linear_to_srgb8`] encodes it (the table fetched once).
#[must_use]
#[inline]
pub fn linear_rgb_to_srgb8(c: glam::Vec3) -> Rgb8 {
    let t = srgb8_table();
    [t.encode(c.x), t.encode(c.y), t.encode(c.z)]
}

/// Bins of [`Srgb8Table::lower_bound`] over [0, 1]: finer than the curve's steepest part (12.92 x 255, some
/// 3300 codes per unit near black), so no bin holds two code boundaries.
const SRGB8_BINS: usize = 4096;

struct Srgb8Table {
    /// `boundaries[k]`: the least f32 encoded as code `k + 1`; infinity past code 255.
    boundaries: [f32; 256],
    /// The code of each bin's start (and one past the end for 1.0).
    lower_bound: [u8; SRGB8_BINS + 1],
}

impl Srgb8Table {
    /// [`linear_to_srgb8`].
    #[inline(always)]
    fn encode(&self, v: f32) -> u8 {
        let v = v.clamp(0.0, 1.0);
        // NaN survives the clamp, indexes 0 and passes no boundary. Scaling by a power of two is exact, so
        // `v` lies in the bin it indexes, at or past its start's code and short of the boundary after next.
        let code = self.lower_bound[(v * SRGB8_BINS as f32) as usize];
        code + u8::from(v >= self.boundaries[usize::from(code)])
    }
}

#[inline]
fn srgb8_table() -> &'static Srgb8Table {
    static TABLE: std::sync::LazyLock<Srgb8Table> = std::sync::LazyLock::new(|| {
        let decode = |s: f64| if s <= 0.040_45 { s / 12.92 } else { ((s + 0.055) / 1.055).powf(2.4) };
        let boundaries: [f32; 256] = std::array::from_fn(|k| {
            if k == 255 {
                return f32::INFINITY;
            }
            let exact = decode((k as f64 + 0.5) / 255.0);
            // The least f32 at or above the exact crossing.
            let f = exact as f32;
            if f64::from(f) < exact { f.next_up() } else { f }
        });
        let mut lower_bound = [0u8; SRGB8_BINS + 1];
        for (i, code) in lower_bound.iter_mut().enumerate() {
            let v = i as f32 / SRGB8_BINS as f32;
            *code = boundaries.partition_point(|&b| b <= v) as u8;
        }
        Srgb8Table { boundaries, lower_bound }
    });
    &TABLE
}

/// sRGB 8-bit to linear [0, 1].
#[must_use]
pub fn srgb8_to_linear(v: u8) -> f32 {
    let s = f32::from(v) / 255.0;
    if s <= 0.040_45 { s / 12.92 } else { ((s + 0.055) / 1.055).powf(2.4) }
}

/// Visibility as grey: lit white, shadow black; pixels outside `mask` dark blue so they read as "no receiver".
#[must_use]
pub fn visibility_to_rgb(vis: &Image<f32>, mask: &Image<bool>) -> Image<Rgb8> {
    Image::from_fn(vis.width(), vis.height(), |x, y| {
        if *mask.get(x, y) {
            let g = (vis.get(x, y).clamp(0.0, 1.0) * 255.0 + 0.5) as u8;
            [g, g, g]
        } else {
            [24, 28, 48]
        }
    })
}

/// The colour of false shadow (shadowed here, lit in the reference) in error maps.
const FALSE_SHADOW: Rgb8 = [230, 40, 40];
/// The colour of false light (lit here, shadowed in the reference) in error maps.
const FALSE_LIGHT: Rgb8 = [40, 90, 240];

/// The error colour of a pixel whose visibility is `test` where the reference has `reference`, or `None`
/// where the two agree on lit or shadowed.
fn disagreement(test: f32, reference: f32) -> Option<Rgb8> {
    match (test >= 0.5, reference >= 0.5) {
        (false, true) => Some(FALSE_SHADOW),
        (true, false) => Some(FALSE_LIGHT),
        _ => None,
    }
}

/// The error heat map of DESIGN 11: false shadow red, false light blue, agreement grey (lit light, shadowed
/// dark) over the measured pixels; over `shown` pixels that are not measured (receivers turned away from
/// the light) the same colours, dimmed; everything else black.
#[must_use]
pub fn error_map(
    test: &Image<f32>,
    reference: &Image<f32>,
    measured: &Image<bool>,
    shown: &Image<bool>,
) -> Image<Rgb8> {
    Image::from_fn(test.width(), test.height(), |x, y| {
        let (m, s) = (*measured.get(x, y), *shown.get(x, y));
        if !m && !s {
            return [0, 0, 0];
        }
        let (t, r) = (*test.get(x, y), *reference.get(x, y));
        let agreement = if r >= 0.5 { [150, 150, 150] } else { [70, 70, 70] };
        let c = disagreement(t, r).unwrap_or(agreement);
        if m { c } else { c.map(|v| v / 3 + 20) }
    })
}

/// The error map over the shaded picture, as the contact sheet and `compare` show it: agreement is the
/// picture in grey (so the model stays visible against the ground), false shadow red, false light blue,
/// unmeasured receivers dimmed; a legend in the top-left corner says which colour is which.
#[must_use]
pub fn error_map_over(
    test: &Image<f32>,
    reference: &Image<f32>,
    measured: &Image<bool>,
    shown: &Image<bool>,
    picture: &Image<Rgb8>,
) -> Image<Rgb8> {
    let mut out = Image::from_fn(test.width(), test.height(), |x, y| {
        let p = picture.get(x, y);
        let grey = ((u16::from(p[0]) * 3 + u16::from(p[1]) * 6 + u16::from(p[2])) / 10) as u8;
        let (m, s) = (*measured.get(x, y), *shown.get(x, y));
        match disagreement(*test.get(x, y), *reference.get(x, y)) {
            Some(c) if m => c,
            Some(c) if s => c.map(|v| v / 2 + grey / 2),
            // Agreement, and everything not measured: the picture at lower contrast, so colours stand out.
            _ => [(u16::from(grey) * 3 / 5 + 40) as u8; 3],
        }
    });
    // The legend: two swatches with their meaning, on a dark band.
    let scale = (out.width() / 256).max(1);
    let (line, cell) = (crate::text::LINE_HEIGHT * scale, crate::text::CELL_WIDTH * scale);
    let band_w = cell * 30;
    let y0 = 0;
    crate::text::fill_rect(&mut out, 0, y0, band_w, line + 4, [30, 30, 36]);
    let mut x = 4i32;
    for (colour, words) in [(FALSE_SHADOW, "false shadow"), (FALSE_LIGHT, "false light")] {
        crate::text::fill_rect(&mut out, x, y0 + 2 + (line / 4) as i32, cell, line / 2, colour);
        x += (cell + cell / 2) as i32;
        crate::text::draw_text(&mut out, x, y0 + 2, words, [235, 235, 235], scale);
        x += (crate::text::text_width(words, scale) + cell * 2) as i32;
    }
    out
}

/// A scalar field as a blue-to-yellow ramp between `lo` and `hi` (debug views of depth maps); NaN is black.
#[must_use]
pub fn false_colour(values: &Image<f32>, lo: f32, hi: f32) -> Image<Rgb8> {
    let span = (hi - lo).max(f32::MIN_POSITIVE);
    values.map(|&v| {
        if v.is_nan() {
            return [0, 0, 0];
        }
        let t = ((v - lo) / span).clamp(0.0, 1.0);
        // A perceptually ordered ramp: dark blue, teal, yellow.
        let r = (255.0 * (1.5 * t - 0.5).clamp(0.0, 1.0)) as u8;
        let g = (255.0 * (0.15 + 0.85 * t)) as u8;
        let b = (255.0 * (0.55 - 0.5 * t).clamp(0.0, 1.0)) as u8;
        [r, g, b]
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clamped_reads_take_the_nearest_edge_pixel() {
        let img = Image::from_fn(3, 2, |x, y| (x, y));
        assert_eq!(*img.get_clamped(1, 1), (1, 1));
        assert_eq!(*img.get_clamped(-1, -5), (0, 0));
        assert_eq!(*img.get_clamped(3, 1), (2, 1));
        assert_eq!(*img.get_clamped(7, 2), (2, 1));
    }

    #[test]
    fn srgb_round_trip() {
        for v in 0..=255u8 {
            assert_eq!(linear_to_srgb8(srgb8_to_linear(v)), v);
        }
        assert_eq!(linear_to_srgb8(0.5), 188);
    }

    #[test]
    fn srgb_encoding_rounds_the_exact_curve_to_nearest() {
        let encode = |v: f64| {
            let s = if v <= 0.003_130_8 { 12.92 * v } else { 1.055 * v.powf(1.0 / 2.4) - 0.055 };
            s * 255.0
        };
        // Every 97th f32 in [0, 1] (some 11 million), and the ends.
        let one = 1.0f32.to_bits();
        for bits in (0..=one).step_by(97).chain([one]) {
            let v = f32::from_bits(bits);
            let code = linear_to_srgb8(v);
            let exact = encode(f64::from(v));
            assert!((f64::from(code) - exact).abs() <= 0.5 + 1e-9, "{v}: code {code}, exact {exact}");
        }
        for (v, code) in [(-1.0, 0), (0.0, 0), (2.0, 255), (f32::NAN, 0), (f32::INFINITY, 255)] {
            assert_eq!(linear_to_srgb8(v), code, "{v}");
        }
    }

    #[test]
    fn srgb_encoding_steps_at_each_boundary_and_no_bin_holds_two() {
        let t = srgb8_table();
        for (k, &b) in t.boundaries[..255].iter().enumerate() {
            assert_eq!(usize::from(linear_to_srgb8(b)), k + 1, "at boundary {b}");
            assert_eq!(usize::from(linear_to_srgb8(b.next_down())), k, "just below boundary {b}");
        }
        for (i, pair) in t.lower_bound.windows(2).enumerate() {
            assert!(pair[1] - pair[0] <= 1, "bin {i} holds {} boundaries", pair[1] - pair[0]);
        }
    }

    #[test]
    fn layout_is_row_major_top_left() {
        let img = Image::from_fn(3, 2, |x, y| (x, y));
        assert_eq!(img.data()[4], (1, 1));
        assert_eq!(img.row(1)[2], (2, 1));
        assert!(Image::from_vec(2, 2, vec![0; 3]).is_none());
    }
}
