//! The passes every technique on the CPU backend builds from (DESIGN 5), named by what they do:
//!
//! - [`maps`]: render light depth maps (and object-ID maps), find a receiver's place in them, look them up
//!   with each filter;
//! - [`volumes`]: shadow volumes rasterized into the stencil with either counting, through a computation
//!   mask when given;
//! - [`rays`]: shadow-ray origins and the scene BVH, for the ray-traced references.
//!
//! [`per_receiver`] runs a technique's per-pixel answer over the G-buffer's receivers.

pub mod maps;
pub mod rays;
pub mod volumes;

use rayon::prelude::*;
use shadow_core::Image;

use crate::gbuffer::GBuffer;

/// Fills `out` with `f(x, y, i)` at every receiver pixel (i the pixel index) and 1 elsewhere.
pub fn per_receiver(g: &GBuffer, out: &mut Image<f32>, f: impl Fn(u32, u32, usize) -> f32 + Sync) {
    let w = g.width() as usize;
    out.data_mut().par_chunks_mut(w).enumerate().for_each(|(y, row)| {
        for (x, v) in row.iter_mut().enumerate() {
            let i = y * w + x;
            *v = if g.receiver.data()[i] { f(x as u32, y as u32, i) } else { 1.0 };
        }
    });
}
