//! View-fitted maps on the CPU (twin: [`super::gpu`]).

use shadow_core::technique::maps::MapSampling;
use shadow_core::technique::settings::{DepthBias, Filter};
use shadow_core::technique::{DebugView, TechniqueError};
use shadow_core::{FrameInputs, Image, LightView};
use shadow_cpu::passes::maps::{depth_views, query_maps, render_depth_maps};
use shadow_cpu::{CpuError, GBuffer};

/// The projections of the last build and their maps.
#[derive(Default)]
pub struct ViewMaps {
    view: Option<LightView>,
    maps: Vec<Image<f32>>,
}

impl ViewMaps {
    /// Renders the casters' depth from every projection of `sampling`.
    ///
    /// # Errors
    /// Maps over the size limits, or casters a draw cannot number.
    pub fn build(&mut self, frame: &FrameInputs, sampling: MapSampling, bias: DepthBias) -> Result<(), CpuError> {
        self.view = None;
        render_depth_maps(frame, &sampling.view, sampling.resolution, bias, &mut self.maps)?;
        self.view = Some(sampling.view);
        Ok(())
    }

    /// Looks every receiver up in the maps of the last build (`technique` names it for the error when
    /// there is none).
    ///
    /// # Errors
    /// [`TechniqueError::NotBuilt`] before a build.
    pub fn query(
        &self,
        technique: &str,
        g: &GBuffer,
        out: &mut Image<f32>,
        filter: Filter,
        radius: f32,
        receiver_offset: f32,
    ) -> Result<(), CpuError> {
        let view = self.view.as_ref().ok_or_else(|| TechniqueError::NotBuilt(technique.into()))?;
        query_maps(&self.maps, view, g, out, filter, radius, receiver_offset);
        Ok(())
    }

    /// The maps in false colour, named `{prefix}{k}`.
    #[must_use]
    pub fn debug_views(&self, prefix: &str) -> Vec<DebugView> {
        depth_views(prefix, &self.maps)
    }
}
