//! Decoded images with their mip chains.
//!
//! A texture is decoded once, where the model names it, and shared by every material that names the same
//! image. Its texels are kept as the file gives them, RGBA8 with sRGB-encoded colour and linear alpha
//! (glTF 2.0 3.9.2 and 5.19: base colour textures are sRGB), so the GPU reads the same bytes the CPU
//! samples. The mip chain is built here, once, for both backends, so neither a driver's nor a shader's
//! downsampling can make the two pick different texels. Its filter is a 2 x 2 box: each texel of a level
//! is the mean of the texels it covers in the level above (the last row or column of an odd side folded
//! into its neighbour's), colour averaged in linear light and encoded back to sRGB, alpha averaged as it
//! is, each rounded to the nearest code; the chain ends at 1 x 1.

use std::io::Cursor;

use crate::image::{Image, linear_to_srgb8, srgb8_to_linear};

/// The largest side of an image a model may name, in texels: 16384, the largest 2D texture every
/// desktop GPU takes (`maxImageDimension2D`). A larger one is refused before it is decoded, so an image
/// whose header claims more than the file holds never reaches an allocation.
pub const MAX_TEXTURE_SIDE: u32 = 16_384;

/// Why an image was refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum TextureError {
    /// Neither a PNG nor a JPEG (by its first bytes).
    #[error("not a PNG or JPEG image")]
    UnknownFormat,
    /// A format recognised by its first bytes that this crate does not decode.
    #[error("a {0} image; only PNG and JPEG are read")]
    UnsupportedFormat(&'static str),
    /// A side beyond the limit.
    #[error("{width} x {height} texels, beyond the limit of {limit} x {limit}")]
    TooLarge {
        /// Width the image claims.
        width: u32,
        /// Height the image claims.
        height: u32,
        /// The largest side allowed.
        limit: u32,
    },
    /// An image with no texels.
    #[error("an image of {width} x {height} texels is empty")]
    Empty {
        /// Width the image claims.
        width: u32,
        /// Height the image claims.
        height: u32,
    },
    /// The decoder failed: a truncated or corrupt file.
    #[error("cannot decode: {0}")]
    Decode(String),
    /// Texels given directly, not one per texel of the stated size.
    #[error("{texels} texels for {width} x {height}")]
    TexelCount {
        /// Texels given.
        texels: usize,
        /// Width stated.
        width: u32,
        /// Height stated.
        height: u32,
    },
}

/// One level of a mip chain: RGBA8 texels, rows from the image's top (glTF's UV origin), sRGB colour.
pub type TextureLevel = Image<[u8; 4]>;

/// The next level down from `level`: each texel the mean of the 2 x 2 texels it covers, colour averaged in
/// linear light and alpha as it is. An odd side's last row or column is folded into the one before it.
fn halved(level: &TextureLevel, to_linear: &[f32; 256]) -> TextureLevel {
    let (width, height) = (level.width(), level.height());
    let (w, h) = ((width / 2).max(1), (height / 2).max(1));
    // The texels of `level` that texel `i` of the halved side covers, first and last.
    let span = |i: u32, half: u32, side: u32| {
        let last = if i == half - 1 && side > 2 && side % 2 == 1 { side - 1 } else { (2 * i + 1).min(side - 1) };
        (2 * i, last)
    };
    Image::from_fn(w, h, |x, y| {
        let ((x0, x1), (y0, y1)) = (span(x, w, width), span(y, h, height));
        let mut sum = [0.0f32; 4];
        for sy in y0..=y1 {
            for sx in x0..=x1 {
                let t = level.get(sx, sy);
                for c in 0..3 {
                    sum[c] += to_linear[usize::from(t[c])];
                }
                sum[3] += f32::from(t[3]) / 255.0;
            }
        }
        let n = ((x1 - x0 + 1) * (y1 - y0 + 1)) as f32;
        let alpha = ((sum[3] / n) * 255.0 + 0.5) as u8;
        [linear_to_srgb8(sum[0] / n), linear_to_srgb8(sum[1] / n), linear_to_srgb8(sum[2] / n), alpha]
    })
}

/// A decoded image and its full mip chain, down to 1 x 1.
#[derive(Clone, Debug, PartialEq)]
pub struct Texture {
    name: String,
    levels: Vec<TextureLevel>,
}

impl Texture {
    /// A texture from RGBA8 texels (sRGB colour, linear alpha), rows from the top.
    ///
    /// # Errors
    /// An empty or oversized image, or a texel count that is not `width * height`.
    pub fn from_rgba8(name: &str, width: u32, height: u32, texels: Vec<[u8; 4]>) -> Result<Self, TextureError> {
        Self::from_rgba8_within(name, width, height, texels, MAX_TEXTURE_SIDE)
    }

    fn from_rgba8_within(
        name: &str,
        width: u32,
        height: u32,
        texels: Vec<[u8; 4]>,
        max_side: u32,
    ) -> Result<Self, TextureError> {
        check_size(width, height, max_side)?;
        let count = texels.len();
        let top =
            Image::from_vec(width, height, texels).ok_or(TextureError::TexelCount { texels: count, width, height })?;
        let to_linear: [f32; 256] = std::array::from_fn(|v| srgb8_to_linear(v as u8));
        let mut levels = vec![top];
        while let Some(last) = levels.last()
            && (last.width() > 1 || last.height() > 1)
        {
            let next = halved(last, &to_linear);
            levels.push(next);
        }
        Ok(Self { name: name.to_string(), levels })
    }

    /// Decodes a PNG or a JPEG of at most [`MAX_TEXTURE_SIDE`] texels a side; see [`Self::decode_within`].
    ///
    /// # Errors
    /// A [`TextureError`] saying what is wrong with the bytes.
    pub fn decode(name: &str, bytes: &[u8]) -> Result<Self, TextureError> {
        Self::decode_within(name, bytes, MAX_TEXTURE_SIDE)
    }

    /// Decodes a PNG or a JPEG whose sides are at most `max_side` texels. The size is read from the
    /// header and checked before any texel is decoded, so a header that claims more than the file holds
    /// never reaches an allocation.
    ///
    /// # Errors
    /// A [`TextureError`] saying what is wrong with the bytes.
    pub fn decode_within(name: &str, bytes: &[u8], max_side: u32) -> Result<Self, TextureError> {
        use image::ImageDecoder;
        let header = ImageHeader::read(bytes)?;
        check_size(header.width, header.height, max_side)?;
        let reader = image::ImageReader::new(Cursor::new(bytes))
            .with_guessed_format()
            .map_err(|e| TextureError::Decode(e.to_string()))?;
        let mut decoder = reader.into_decoder().map_err(|e| TextureError::Decode(e.to_string()))?;
        let mut limits = image::Limits::default();
        limits.max_image_width = Some(max_side);
        limits.max_image_height = Some(max_side);
        // The sides are checked, so the decoder may allocate what they need (its default stops at 512 MiB,
        // less than one 16384 x 16384 image).
        limits.max_alloc = None;
        decoder.set_limits(limits).map_err(|e| TextureError::Decode(e.to_string()))?;
        let image = image::DynamicImage::from_decoder(decoder).map_err(|e| TextureError::Decode(e.to_string()))?;
        let bytes = image.into_rgba8().into_raw();
        // The decoder's buffer becomes the texels without a copy where its capacity is whole texels.
        let texels = bytemuck::allocation::try_cast_vec(bytes)
            .unwrap_or_else(|(_, bytes)| bytes.chunks_exact(4).map(|c| [c[0], c[1], c[2], c[3]]).collect());
        Self::from_rgba8_within(name, header.width, header.height, texels, max_side)
    }

    /// The image's name, for reports: the file it came from, or where in the model it was.
    #[must_use]
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Width of level 0.
    #[must_use]
    pub fn width(&self) -> u32 {
        self.levels[0].width()
    }

    /// Height of level 0.
    #[must_use]
    pub fn height(&self) -> u32 {
        self.levels[0].height()
    }

    /// The mip chain, level 0 first, down to 1 x 1.
    #[must_use]
    pub fn levels(&self) -> &[TextureLevel] {
        &self.levels
    }

    /// Bytes the chain holds (four per texel over every level).
    #[must_use]
    pub fn memory_bytes(&self) -> usize {
        self.levels.iter().map(|l| l.data().len() * 4).sum()
    }

    /// True when some texel of level 0 is not fully opaque.
    #[must_use]
    pub fn has_alpha(&self) -> bool {
        self.levels[0].data().iter().any(|t| t[3] < 255)
    }
}

fn check_size(width: u32, height: u32, limit: u32) -> Result<(), TextureError> {
    if width == 0 || height == 0 {
        return Err(TextureError::Empty { width, height });
    }
    if width > limit || height > limit {
        return Err(TextureError::TooLarge { width, height, limit });
    }
    Ok(())
}

/// Bytes a `width` x `height` texture holds with its full mip chain, four per texel.
#[must_use]
pub fn chain_bytes(width: u32, height: u32) -> u64 {
    let (mut w, mut h, mut sum) = (u64::from(width), u64::from(height), 0);
    loop {
        sum += w * h * 4;
        if w <= 1 && h <= 1 {
            return sum;
        }
        (w, h) = ((w / 2).max(1), (h / 2).max(1));
    }
}

/// What an image file's first bytes say: its format and size, read without decoding a texel.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ImageHeader {
    /// Width in texels.
    pub width: u32,
    /// Height in texels.
    pub height: u32,
}

impl ImageHeader {
    /// Reads a PNG's or a JPEG's header.
    ///
    /// # Errors
    /// [`TextureError::UnsupportedFormat`] for KTX2, WebP and the other formats recognised by their
    /// signature, [`TextureError::UnknownFormat`] for anything else that is not a PNG or JPEG, and
    /// [`TextureError::Decode`] for a header that cannot be read.
    pub fn read(bytes: &[u8]) -> Result<Self, TextureError> {
        use image::ImageDecoder;
        const KTX2: &[u8] = b"\xABKTX 20\xBB\r\n\x1A\n";
        if bytes.starts_with(KTX2) {
            return Err(TextureError::UnsupportedFormat("KTX2"));
        }
        let format = image::guess_format(bytes).map_err(|_| TextureError::UnknownFormat)?;
        match format {
            image::ImageFormat::Png | image::ImageFormat::Jpeg => {}
            other => {
                return Err(TextureError::UnsupportedFormat(
                    other.extensions_str().first().map_or("other", |e| format_name(e)),
                ));
            }
        }
        if format == image::ImageFormat::Jpeg && !ends_its_scan(bytes) {
            return Err(TextureError::Decode("a JPEG that ends before its end-of-image marker".into()));
        }
        let reader = image::ImageReader::with_format(Cursor::new(bytes), format);
        let decoder = reader.into_decoder().map_err(|e| TextureError::Decode(e.to_string()))?;
        let (width, height) = decoder.dimensions();
        Ok(Self { width, height })
    }
}

/// True when a JPEG's end-of-image marker follows its last scan. The decoder fills a scan cut short with
/// grey rather than fail, so a truncated file would load as a wrong picture; inside a scan's coded data
/// a 0xFF byte is always followed by 0x00 or a restart marker, so the pair `FF D9` there is the end.
fn ends_its_scan(bytes: &[u8]) -> bool {
    let marker = |m: u8| move |w: &[u8]| w == [0xFF, m];
    let last_scan = bytes.windows(2).rposition(marker(0xDA)).unwrap_or(0);
    bytes[last_scan..].windows(2).any(marker(0xD9))
}

/// A format's name from its usual extension, for messages.
fn format_name(extension: &str) -> &'static str {
    match extension {
        "webp" => "WebP",
        "gif" => "GIF",
        "bmp" => "BMP",
        "tiff" | "tif" => "TIFF",
        "dds" => "DDS",
        "exr" => "OpenEXR",
        "hdr" => "Radiance HDR",
        "avif" => "AVIF",
        "qoi" => "QOI",
        "ico" => "ICO",
        "tga" => "TGA",
        _ => "other",
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::tests::png;

    #[test]
    fn the_chain_halves_to_one_texel_and_averages_colour_in_linear_light() {
        // Black and white columns: their mean is half the light, sRGB code 188, not 128.
        let texels: Vec<[u8; 4]> =
            (0..8 * 4).map(|i| if i % 2 == 0 { [0, 0, 0, 0] } else { [255, 255, 255, 255] }).collect();
        let t = Texture::from_rgba8("stripes", 8, 4, texels).unwrap();
        let sides: Vec<(u32, u32)> = t.levels().iter().map(|l| (l.width(), l.height())).collect();
        assert_eq!(sides, vec![(8, 4), (4, 2), (2, 1), (1, 1)]);
        assert_eq!(*t.levels()[1].get(0, 0), [188, 188, 188, 128]);
        assert_eq!(t.memory_bytes(), (32 + 8 + 2 + 1) * 4);
        assert!(t.has_alpha());
    }

    #[test]
    fn an_odd_side_folds_its_last_texel_into_the_level_below() {
        let texels = vec![[255, 255, 255, 255], [255, 255, 255, 255], [255, 255, 255, 0]];
        let t = Texture::from_rgba8("row", 3, 1, texels).unwrap();
        // The single texel of level 1 covers all three: alpha (1 + 1 + 0) / 3.
        assert_eq!(t.levels()[1].get(0, 0)[3], 170);
    }

    #[test]
    fn decodes_png_and_refuses_what_is_not_an_image() {
        let bytes = png(2, 1, &[[10, 20, 30, 40], [50, 60, 70, 80]]);
        let t = Texture::decode("two", &bytes).unwrap();
        assert_eq!(t.levels()[0].data(), &[[10, 20, 30, 40], [50, 60, 70, 80]]);
        assert_eq!(Texture::decode("text", b"hello, world"), Err(TextureError::UnknownFormat));
        let cut = &bytes[..bytes.len() - 20];
        assert!(matches!(Texture::decode("cut", cut), Err(TextureError::Decode(_))));
    }

    #[test]
    fn a_header_claiming_a_huge_image_is_refused_before_decoding() {
        let bytes = crate::material::tests::png_claiming(1, 1, 100_000, 100_000);
        let too_large = TextureError::TooLarge { width: 100_000, height: 100_000, limit: MAX_TEXTURE_SIDE };
        assert_eq!(Texture::decode("huge", &bytes), Err(too_large));
        assert_eq!(ImageHeader::read(&bytes), Ok(ImageHeader { width: 100_000, height: 100_000 }));
    }

    #[test]
    fn a_chain_holds_a_third_more_than_its_top_level() {
        assert_eq!(chain_bytes(1, 1), 4);
        assert_eq!(chain_bytes(8, 4), (32 + 8 + 2 + 1) * 4);
        let t = Texture::from_rgba8("odd", 5, 3, vec![[0; 4]; 15]).unwrap();
        assert_eq!(chain_bytes(5, 3), t.memory_bytes() as u64);
    }
}
