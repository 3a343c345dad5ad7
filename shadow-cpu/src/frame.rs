//! One frame on the CPU: the frame script of shadow-core ([`shadow_core::script`]) with the CPU's steps.
//! The CPU runs each step to the end before returning, so every phase's time is its own.

use shadow_core::image::Rgb8;
use shadow_core::light::{AtlasPlan, LightView, Reach};
use shadow_core::script::{FrameRun, FrameSteps, LightTechniques, run_frame};
use shadow_core::technique::FrameStats;
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
    /// The shadow atlas: each light's tiles and their side.
    pub atlas: Option<AtlasPlan>,
    /// Visibility per light, 1 lit, 0 shadowed (1 outside the receiver mask).
    pub visibility: Vec<Image<f32>>,
    /// The shaded image.
    pub color: Image<Rgb8>,
    /// Counters (summed over lights) and phase times.
    pub stats: FrameStats,
}

impl CpuFrame {
    /// Each receiver pixel's world position and its visibility under light `light`, in pixel order.
    ///
    /// # Panics
    /// For a light the frame does not have.
    pub fn receiver_points(&self, light: usize) -> impl Iterator<Item = (shadow_core::glam::Vec3, f32)> + '_ {
        let g = &self.gbuffer;
        (g.position.data().iter().zip(g.receiver.data()).zip(self.visibility[light].data()))
            .filter(|((_, receiver), _)| **receiver)
            .map(|((&p, _), &v)| (p, v))
    }
}

/// Renders a frame, each light shadowed by the frame's technique or its own (`techniques`; a single
/// technique converts into them).
///
/// # Errors
/// A bad view size, a light its technique does not support, or a technique failure.
pub fn render_frame<'t, 'o: 't>(
    cx: &mut CpuContext,
    frame: &FrameInputs,
    width: u32,
    height: u32,
    techniques: impl Into<LightTechniques<'t, 'o, CpuBackend>>,
) -> Result<CpuFrame, CpuError> {
    let steps = CpuSteps { width, height, given: None, visibility: Vec::with_capacity(frame.lights.len()) };
    let FrameRun { output: (gbuffer, visibility, color), light_views, atlas, stats } =
        run_frame(cx, frame, steps, techniques)?;
    Ok(CpuFrame { gbuffer, light_views, atlas, visibility, color, stats })
}

/// Renders a frame over receivers given as another view's G-buffer: the techniques build for `frame`
/// (its camera, which maps fitted to the view follow) and are queried at the points of `gbuffer`. Held
/// still while the camera moves, those points show what the maps' changes alone do to the shadows (the
/// shimmer that stabilised cascades remove).
///
/// # Errors
/// As [`render_frame`].
pub fn render_frame_over<'t, 'o: 't>(
    cx: &mut CpuContext,
    frame: &FrameInputs,
    gbuffer: &GBuffer,
    techniques: impl Into<LightTechniques<'t, 'o, CpuBackend>>,
) -> Result<CpuFrame, CpuError> {
    let (width, height) = (gbuffer.depth.width(), gbuffer.depth.height());
    let visibility = Vec::with_capacity(frame.lights.len());
    let steps = CpuSteps { width, height, given: Some(gbuffer.clone()), visibility };
    let FrameRun { output: (gbuffer, visibility, color), light_views, atlas, stats } =
        run_frame(cx, frame, steps, techniques)?;
    Ok(CpuFrame { gbuffer, light_views, atlas, visibility, color, stats })
}

/// The CPU's steps: images in memory, one per light's visibility.
struct CpuSteps {
    width: u32,
    height: u32,
    /// Receivers given instead of the frame camera's view.
    given: Option<GBuffer>,
    visibility: Vec<Image<f32>>,
}

impl FrameSteps<CpuBackend> for CpuSteps {
    type Shaded = Image<Rgb8>;
    type Output = (GBuffer, Vec<Image<f32>>, Image<Rgb8>);

    fn gbuffer(&mut self, cx: &mut CpuContext, frame: &FrameInputs) -> Result<GBuffer, CpuError> {
        match self.given.take() {
            Some(g) => Ok(g),
            None => gbuffer::render_reusing(frame, self.width, self.height, cx.take_spare()),
        }
    }

    fn visibility(&mut self, _cx: &mut CpuContext, _k: usize, _reach: &Reach) -> Result<Image<f32>, CpuError> {
        Ok(Image::new(self.width, self.height, 1.0))
    }

    fn keep(&mut self, _k: usize, visibility: Image<f32>) {
        self.visibility.push(visibility);
    }

    fn lit(&mut self, _cx: &mut CpuContext, visibility: &mut Image<f32>) -> Result<(), CpuError> {
        visibility.data_mut().fill(1.0);
        Ok(())
    }

    fn shade(
        &mut self,
        _cx: &mut CpuContext,
        (frame, reaches): (&FrameInputs, &[Reach]),
        gbuffer: &GBuffer,
    ) -> Result<Image<Rgb8>, CpuError> {
        let refs: Vec<&Image<f32>> = self.visibility.iter().collect();
        Ok(shade(gbuffer, (&frame.lights, reaches), &refs))
    }

    fn finish(
        self,
        _cx: &mut CpuContext,
        gbuffer: GBuffer,
        color: Image<Rgb8>,
        stats: &mut FrameStats,
    ) -> Result<Self::Output, CpuError> {
        stats.counters.covered_pixels = Some(gbuffer.covered_pixels());
        Ok((gbuffer, self.visibility, color))
    }
}
