//! One frame on the CPU (DESIGN 5): G-buffer, then per light a build and a query, then shading. Every
//! phase is timed.

use std::time::Instant;

use shadow_core::image::Rgb8;
use shadow_core::light::LightView;
use shadow_core::stats::{Phase, ms};
use shadow_core::technique::{DynShadowTechnique, FrameStats, LightPass};
use shadow_core::{FrameInputs, Image};

use crate::context::{CpuBackend, CpuContext, CpuError};
use crate::gbuffer::{self, GBuffer};
use crate::shade::shade;

/// Everything a CPU frame produced.
pub struct CpuFrame {
    /// The camera view.
    pub gbuffer: GBuffer,
    /// The fitted view of each light.
    pub light_views: Vec<LightView>,
    /// Visibility per light, 1 lit, 0 shadowed (1 outside the receiver mask).
    pub visibility: Vec<Image<f32>>,
    /// The shaded image.
    pub color: Image<Rgb8>,
    /// Counters (summed over lights) and phase times.
    pub stats: FrameStats,
}

/// Renders a frame with one technique for every light of the frame.
///
/// # Errors
/// A bad view size, a light the technique does not support, or a technique failure.
pub fn render_frame(
    cx: &mut CpuContext,
    frame: &FrameInputs,
    width: u32,
    height: u32,
    technique: &mut dyn DynShadowTechnique<CpuBackend>,
) -> Result<CpuFrame, CpuError> {
    let start = Instant::now();
    let mut stats = FrameStats::default();

    let t = Instant::now();
    let gbuffer = gbuffer::render_reusing(frame, width, height, cx.take_spare())?;
    stats.timings.add(Phase::GBuffer, ms(t.elapsed()));

    let mut visibility = Vec::with_capacity(frame.lights.len());
    let mut light_views = Vec::with_capacity(frame.lights.len());
    for light in &frame.lights {
        let view = frame.light_view(light)?;
        let mut light_stats = FrameStats::default();
        let t = Instant::now();
        technique.build(cx, LightPass { frame, light: &view, stats: &mut light_stats })?;
        stats.timings.add(Phase::Build, ms(t.elapsed()));
        let mut vis = Image::new(width, height, 1.0f32);
        let t = Instant::now();
        technique.query(cx, LightPass { frame, light: &view, stats: &mut light_stats }, &gbuffer, &mut vis)?;
        stats.timings.add(Phase::Query, ms(t.elapsed()));
        stats.counters.merge(&light_stats.counters);
        for (k, v) in light_stats.timings.extra {
            *stats.timings.extra.entry(k).or_insert(0.0) += v;
        }
        visibility.push(vis);
        light_views.push(view);
    }

    let t = Instant::now();
    let refs: Vec<&Image<f32>> = visibility.iter().collect();
    let color = shade(&gbuffer, &frame.lights, &refs);
    stats.timings.add(Phase::Shade, ms(t.elapsed()));
    stats.timings.total = ms(start.elapsed());
    stats.counters.covered_pixels = Some(gbuffer.covered_pixels());
    Ok(CpuFrame { gbuffer, light_views, visibility, color, stats })
}
