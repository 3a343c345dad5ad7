//! `cascaded-shadow-map` on the CPU (twin: [`super::gpu`]): one depth map per cascade through the shared
//! map passes, looked up with the cascades' blending (`passes::maps::query_maps`).

use shadow_core::technique::maps::MapLayout;
use shadow_core::technique::{DebugView, LightPass, ShadowTechnique, TechniqueError};
use shadow_core::{Image, LightView};
use shadow_cpu::passes::maps::{depth_views, query_maps, render_depth_maps};
use shadow_cpu::{CpuBackend, CpuContext, CpuError, GBuffer};

use super::CascadedShadowMap;

/// The cascades of the last build and their maps.
#[derive(Default)]
pub struct State {
    view: Option<LightView>,
    maps: Vec<Image<f32>>,
}

impl ShadowTechnique<CpuBackend> for CascadedShadowMap {
    type State = State;

    fn name(&self) -> &'static str {
        Self::NAME
    }

    fn create_state(&self, _: &mut CpuContext) -> Result<State, CpuError> {
        Ok(State::default())
    }

    fn build(&self, _: &mut CpuContext, state: &mut State, pass: LightPass<'_>) -> Result<(), CpuError> {
        let sampling = self.sampling(pass.frame, pass.light, pass.aspect);
        state.view = None;
        render_depth_maps(pass.frame, &sampling.view, sampling.resolution, self.map.depth_bias(), &mut state.maps)?;
        state.view = Some(sampling.view);
        Ok(())
    }

    fn query(
        &self,
        _: &mut CpuContext,
        state: &mut State,
        _: LightPass<'_>,
        g: &GBuffer,
        out: &mut Image<f32>,
    ) -> Result<(), CpuError> {
        let view = state.view.as_ref().ok_or_else(|| TechniqueError::NotBuilt(Self::NAME.into()))?;
        query_maps(&state.maps, view, g, out, self.filter, self.filter_radius, self.map.receiver_offset());
        Ok(())
    }

    /// The cascades are fitted to the camera, which the build key does not hold.
    fn build_is_reusable(&self) -> bool {
        false
    }

    fn debug_views(&self, _: &mut CpuContext, state: &State) -> Result<Vec<DebugView>, CpuError> {
        Ok(depth_views("cascade", &state.maps))
    }
}
