//! Shading and composition (DESIGN 5, step 4), with the shared formulas of `shadow_core::shading`.

use rayon::prelude::*;
use shadow_core::image::{Rgb8, linear_rgb_to_srgb8};
use shadow_core::light::{PixelRect, Reach};
use shadow_core::scene::Light;
use shadow_core::{Image, shading};

use crate::gbuffer::{GBuffer, NO_INSTANCE};

/// The shaded sRGB image of a G-buffer lit by `lights` with their reaches in its view, and one visibility
/// image per light. A light adds nothing to a pixel outside its reach's rectangle (its direct term there
/// is 0), so the pixel does not evaluate it: the same sum, to the bit.
#[must_use]
pub fn shade(g: &GBuffer, (lights, reaches): (&[Light], &[Reach]), visibility: &[&Image<f32>]) -> Image<Rgb8> {
    let (width, height) = (g.width(), g.height());
    let lights: Vec<(shading::LightTerms, PixelRect)> =
        lights.iter().zip(reaches).map(|(l, r)| (shading::LightTerms::new(l), r.rect)).collect();
    let data: Vec<Rgb8> = (0..g.depth.data().len())
        .into_par_iter()
        .with_min_len(1024)
        .map(|i| {
            if g.instance.data()[i] == NO_INSTANCE {
                return linear_rgb_to_srgb8(shading::BACKGROUND);
            }
            let (x, y) = ((i % width as usize) as u32, (i / width as usize) as u32);
            let lit = lights
                .iter()
                .zip(visibility.iter().map(|v| v.data()[i]))
                .filter(|((_, rect), _)| rect.contains(x, y))
                .map(|((terms, _), v)| (terms, v));
            linear_rgb_to_srgb8(shading::shade(g.albedo.data()[i], g.position.data()[i], g.normal.data()[i], lit))
        })
        .collect();
    Image::from_vec(width, height, data).unwrap_or_else(|| unreachable!("one entry per pixel"))
}
