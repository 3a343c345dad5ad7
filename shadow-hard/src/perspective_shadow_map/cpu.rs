//! `perspective-shadow-map` on the CPU (twin: [`super::gpu`]): the post-perspective map, rendered and looked
//! up through the shared map passes (the camera's and the light's projections in one matrix).

use shadow_core::Image;
use shadow_core::technique::maps::MapLayout;
use shadow_core::technique::{DebugView, LightPass, ShadowTechnique};
use shadow_cpu::{CpuBackend, CpuContext, CpuError, GBuffer};

use super::PerspectiveShadowMap;
use crate::view_maps::cpu::ViewMaps;

impl ShadowTechnique<CpuBackend> for PerspectiveShadowMap {
    type State = ViewMaps;

    fn name(&self) -> &'static str {
        Self::NAME
    }

    fn create_state(&self, _: &mut CpuContext) -> Result<ViewMaps, CpuError> {
        Ok(ViewMaps::default())
    }

    fn build(&self, _: &mut CpuContext, state: &mut ViewMaps, pass: LightPass<'_>) -> Result<(), CpuError> {
        state.build(pass.frame, self.sampling(pass.frame, pass.light, pass.aspect), self.map.depth_bias())
    }

    fn query(
        &self,
        _: &mut CpuContext,
        state: &mut ViewMaps,
        _: LightPass<'_>,
        g: &GBuffer,
        out: &mut Image<f32>,
    ) -> Result<(), CpuError> {
        state.query(Self::NAME, g, out, self.filter, self.filter_radius, self.map.receiver_offset())
    }

    /// The map is fitted to the camera, which the build key does not hold.
    fn build_is_reusable(&self) -> bool {
        false
    }

    fn debug_views(&self, _: &mut CpuContext, state: &ViewMaps) -> Result<Vec<DebugView>, CpuError> {
        Ok(state.debug_views("depth"))
    }
}
