//! `shadow-map` on the CPU (twin: [`super::gpu`]): depth from the light, rendered with Vulkan's depth bias,
//! compared at each receiver through the map filter (`passes::maps`).

use shadow_core::Image;
use shadow_core::technique::{BuildReads, LightPass};
use shadow_core::technique::{DebugView, ShadowTechnique, TechniqueError};
use shadow_cpu::passes::maps::{MapLookup, depth_views, render_depth_maps};
use shadow_cpu::{CpuBackend, CpuContext, CpuError, GBuffer};

use super::ShadowMap;

/// The maps of the last build, one per light projection.
#[derive(Default)]
pub struct State {
    maps: Vec<Image<f32>>,
}

impl ShadowTechnique<CpuBackend> for ShadowMap {
    type State = State;

    fn name(&self) -> &'static str {
        Self::NAME
    }

    /// Its build draws casters into the light's map and reads nothing else of the frame.
    fn build_reads(&self) -> BuildReads {
        BuildReads::LightViews
    }

    /// A map of its resolution, or the side the frame's atlas grants.
    fn atlas_side(&self) -> Option<u32> {
        Some(self.map().resolution)
    }

    fn create_state(&self, _: &mut CpuContext) -> Result<State, CpuError> {
        Ok(State::default())
    }

    fn build(&self, _: &mut CpuContext, state: &mut State, pass: LightPass<'_>) -> Result<(), CpuError> {
        let LightPass { frame, light, tiles, .. } = pass;
        let map = self.map();
        let resolution = tiles.map_or(map.resolution, |t| t.side);
        render_depth_maps(frame, light, resolution, map.depth_bias(), &mut state.maps)
    }

    fn query(
        &self,
        _: &mut CpuContext,
        state: &mut State,
        pass: LightPass<'_>,
        g: &GBuffer,
        out: &mut Image<f32>,
    ) -> Result<(), CpuError> {
        let LightPass { light, reach, .. } = pass;
        if state.maps.len() != light.projections.len() {
            return Err(TechniqueError::NotBuilt(Self::NAME.into()).into());
        }
        let lookup = MapLookup {
            filter: self.filter,
            radius: self.filter_radius,
            receiver_offset: self.map().receiver_offset(),
        };
        lookup.query(&state.maps, light, &reach, g, out);
        Ok(())
    }

    fn debug_views(&self, _: &mut CpuContext, state: &State) -> Result<Vec<DebugView>, CpuError> {
        Ok(depth_views("depth", &state.maps))
    }
}
