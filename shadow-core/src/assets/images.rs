//! The images a model's materials name, decoded once each: their headers checked against the
//! [`TextureLimits`] in the order the model names them, before any texel is decoded, then the ones that
//! pass decoded in parallel.
//!
//! An image that cannot be used (missing, corrupt, too large, in a format not read) is not a reason to
//! refuse the model: the loaders leave its materials untextured and say so in one warning line. Only a
//! file the model may not read at all is refused, by the loader, before it gets here.

use std::path::Path;

use rayon::prelude::*;

use super::{AssetFault, IMAGE_FILE_LIMIT, LoadOptions, read_referenced};
use crate::material::texture::{ImageHeader, chain_bytes};
use crate::material::{MAX_TEXTURE_SIDE, Texture};

/// How much texture a model may bring.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TextureLimits {
    /// The largest side of an image, in texels (default [`MAX_TEXTURE_SIDE`], 16384).
    pub max_side: u32,
    /// The most bytes the decoded textures of one scene may hold, mip chains included (default 1 GiB).
    /// Images are counted in the order the model names them; the first that would pass the limit and
    /// every one after it that would too are left out.
    pub max_scene_bytes: u64,
}

impl Default for TextureLimits {
    fn default() -> Self {
        Self { max_side: MAX_TEXTURE_SIDE, max_scene_bytes: 1 << 30 }
    }
}

/// One image to decode: its names and its bytes, or why they could not be read.
pub(super) struct ImageSource {
    /// Where in the model the image is, for messages.
    pub label: String,
    /// The texture's name: the image's own name, or its file.
    pub name: String,
    /// Its bytes, or what went wrong reading them.
    pub bytes: Result<Vec<u8>, String>,
}

/// An image file a model names, `file` relative to its `folder`: its bytes, or why they cannot be used
/// (missing, unreadable, longer than [`IMAGE_FILE_LIMIT`]). A file the model may not read at all refuses
/// the model, as a buffer would.
pub(super) fn read_image_file(
    folder: &Path,
    file: &str,
    what: &str,
    options: &LoadOptions,
) -> Result<Result<Vec<u8>, String>, AssetFault> {
    match read_referenced(folder, file, what, Some(IMAGE_FILE_LIMIT), options) {
        Err(f @ (AssetFault::OutsideFolder(_) | AssetFault::Access(_))) => Err(f),
        Err(f) => Ok(Err(f.to_string())),
        Ok(b) if b.len() as u64 >= IMAGE_FILE_LIMIT => {
            Ok(Err(format!("larger than the {} MiB an image file may have", IMAGE_FILE_LIMIT >> 20)))
        }
        Ok(b) => Ok(Ok(b)),
    }
}

/// Decodes every source, in parallel, after checking all the headers against `limits` in order. The
/// result has one entry per source: the texture, or why it was left out (one line, without the label).
pub(super) fn decode_all(sources: Vec<ImageSource>, limits: &TextureLimits) -> Vec<Result<Texture, String>> {
    let mut budget = limits.max_scene_bytes;
    let checked: Vec<Result<ImageSource, String>> = sources
        .into_iter()
        .map(|source| {
            let bytes = source.bytes.as_ref().map_err(Clone::clone)?;
            let header = ImageHeader::read(bytes).map_err(|e| e.to_string())?;
            let (w, h) = (header.width, header.height);
            if w > limits.max_side || h > limits.max_side {
                let limit = limits.max_side;
                return Err(format!("{w} x {h} texels, beyond the limit of {limit} x {limit}"));
            }
            let needs = chain_bytes(w, h);
            if needs > budget {
                return Err(format!(
                    "its {w} x {h} texels need {} with their mips, past the scene's limit of {} of textures",
                    mib(needs),
                    mib(limits.max_scene_bytes)
                ));
            }
            budget -= needs;
            Ok(source)
        })
        .collect();
    checked
        .into_par_iter()
        .map(|source| {
            let source = source?;
            let bytes = source.bytes.as_deref().unwrap_or_default();
            Texture::decode_within(&source.name, bytes, limits.max_side).map_err(|e| e.to_string())
        })
        .collect()
}

fn mib(bytes: u64) -> String {
    if bytes < 1 << 20 { format!("{bytes} bytes") } else { format!("{:.1} MiB", bytes as f64 / f64::from(1 << 20)) }
}
