//! The passes every technique on the CPU backend builds from (DESIGN 5), named by what they do:
//!
//! - [`maps`]: render light depth maps (and object-ID maps), find a receiver's place in them, look them up
//!   with each filter;
//! - [`volumes`]: shadow volumes rasterized into the stencil with either counting, through a computation
//!   mask when given;
//! - [`rays`]: shadow-ray origins and the scene BVH, for the ray-traced references.
//!
//! [`per_receiver`] runs a technique's per-pixel answer over the G-buffer's receivers within the light's
//! reach ([`per_receiver_casting`] for one that casts rays, counting them).

pub mod maps;
pub mod rays;
pub mod volumes;

use rayon::prelude::*;
use shadow_core::Image;
use shadow_core::light::Reach;

#[cfg(doc)]
use crate::bvh::SceneBvh;
use crate::bvh::Walker;
use crate::gbuffer::GBuffer;

/// Fills `out` with `f(x, y, i)` at every receiver pixel within the light's `reach` (i the pixel index)
/// and 1 elsewhere.
pub fn per_receiver(g: &GBuffer, reach: &Reach, out: &mut Image<f32>, f: impl Fn(u32, u32, usize) -> f32 + Sync) {
    per_receiver_casting(g, reach, out, |_, x, y, i| (f(x, y, i), 0));
}

/// [`per_receiver`] for a pass that casts rays: `f` gives a receiver's visibility and the number of rays
/// it cast (none where the light is below its horizon), tracing them after the row's last blocker (see
/// [`SceneBvh::occluded_after`]). Returns the rays cast over the whole image.
pub fn per_receiver_casting(
    g: &GBuffer,
    reach: &Reach,
    out: &mut Image<f32>,
    f: impl Fn(&mut Walker, u32, u32, usize) -> (f32, u64) + Sync,
) -> u64 {
    let w = g.width() as usize;
    let (rows, columns) = (reach.rect.rows(), reach.rect.columns());
    let columns = columns.start as usize..columns.end as usize;
    out.data_mut()
        .par_chunks_mut(w)
        .enumerate()
        .map(|(y, row)| {
            row.fill(1.0);
            if !rows.contains(&(y as u32)) {
                return 0;
            }
            let (mut rays, mut walker) = (0, Walker::default());
            for (x, v) in row.iter_mut().enumerate().take(columns.end).skip(columns.start) {
                let i = y * w + x;
                if g.receiver.data()[i] && reach.holds(g.position.data()[i]) {
                    let (visibility, cast) = f(&mut walker, x as u32, y as u32, i);
                    rays += cast;
                    *v = visibility;
                }
            }
            rays
        })
        .sum()
}
