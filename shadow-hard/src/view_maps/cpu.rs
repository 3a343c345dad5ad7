//! View-fitted maps on the CPU (twin: [`super::gpu`]).

use shadow_core::light::Reach;
use shadow_core::technique::maps::MapSampling;
use shadow_core::technique::settings::DepthBias;
use shadow_core::technique::{DebugView, TechniqueError};
use shadow_core::{FrameInputs, Image, LightView};
use shadow_cpu::passes::maps::{MapLookup, depth_views, render_depth_maps};
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
        lookup: MapLookup,
        reach: &Reach,
        g: &GBuffer,
        out: &mut Image<f32>,
    ) -> Result<(), CpuError> {
        let view = self.view.as_ref().ok_or_else(|| TechniqueError::NotBuilt(technique.into()))?;
        lookup.query(&self.maps, view, reach, g, out);
        Ok(())
    }

    /// The maps in false colour, named `{prefix}{k}`.
    #[must_use]
    pub fn debug_views(&self, prefix: &str) -> Vec<DebugView> {
        depth_views(prefix, &self.maps)
    }
}

/// The CPU backend of a technique whose maps are [`ViewMaps`]: a settings type with `NAME`, `map` (a
/// `DepthMap`), `filter`, `filter_radius` and a `MapLayout`, its debug views named `$views{k}`. Its build
/// reads the camera, which the build key does not hold, so it is made every frame.
macro_rules! view_fitted_on_cpu {
    ($technique:ty, $views:literal) => {
        impl shadow_core::technique::ShadowTechnique<shadow_cpu::CpuBackend> for $technique {
            type State = $crate::view_maps::cpu::ViewMaps;

            fn name(&self) -> &'static str {
                Self::NAME
            }

            fn create_state(&self, _: &mut shadow_cpu::CpuContext) -> Result<Self::State, shadow_cpu::CpuError> {
                Ok(Self::State::default())
            }

            fn build(
                &self,
                _: &mut shadow_cpu::CpuContext,
                state: &mut Self::State,
                pass: shadow_core::technique::LightPass<'_>,
            ) -> Result<(), shadow_cpu::CpuError> {
                use shadow_core::technique::maps::MapLayout;
                state.build(pass.frame, self.sampling(pass.frame, pass.light, pass.aspect), self.map.depth_bias())
            }

            fn query(
                &self,
                _: &mut shadow_cpu::CpuContext,
                state: &mut Self::State,
                pass: shadow_core::technique::LightPass<'_>,
                g: &shadow_cpu::GBuffer,
                out: &mut shadow_core::Image<f32>,
            ) -> Result<(), shadow_cpu::CpuError> {
                let lookup = shadow_cpu::passes::maps::MapLookup {
                    filter: self.filter,
                    radius: self.filter_radius,
                    receiver_offset: self.map.receiver_offset(),
                };
                state.query(Self::NAME, lookup, &pass.reach, g, out)
            }

            fn build_is_reusable(&self, _: &shadow_core::FrameInputs) -> bool {
                false
            }

            fn debug_views(
                &self,
                _: &mut shadow_cpu::CpuContext,
                state: &Self::State,
            ) -> Result<Vec<shadow_core::technique::DebugView>, shadow_cpu::CpuError> {
                Ok(state.debug_views($views))
            }
        }
    };
}
pub(crate) use view_fitted_on_cpu;
