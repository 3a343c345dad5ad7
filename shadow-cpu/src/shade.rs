//! Shading and composition (DESIGN 5, step 4), with the shared formulas of `shadow_core::shading`.

use rayon::prelude::*;
use shadow_core::image::{Rgb8, linear_rgb_to_srgb8};
use shadow_core::scene::Light;
use shadow_core::{Image, shading};

use crate::gbuffer::{GBuffer, NO_INSTANCE};

/// The shaded sRGB image of a G-buffer lit by `lights` with one visibility image per light.
#[must_use]
pub fn shade(g: &GBuffer, lights: &[Light], visibility: &[&Image<f32>]) -> Image<Rgb8> {
    let n = g.depth.data().len();
    let terms: Vec<shading::LightTerms> = lights.iter().map(shading::LightTerms::new).collect();
    let data: Vec<Rgb8> = (0..n)
        .into_par_iter()
        .with_min_len(1024)
        .map(|i| {
            if g.instance.data()[i] == NO_INSTANCE {
                return linear_rgb_to_srgb8(shading::BACKGROUND);
            }
            let lit = terms.iter().zip(visibility.iter().map(|v| v.data()[i]));
            linear_rgb_to_srgb8(shading::shade(g.albedo.data()[i], g.position.data()[i], g.normal.data()[i], lit))
        })
        .collect();
    Image::from_vec(g.width(), g.height(), data).unwrap_or_else(|| unreachable!("one entry per pixel"))
}
