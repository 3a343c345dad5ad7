//! `shadow-map` (Williams 1978; the survey of Nealen, section 3; Weiskopf-Ertl section 5): depth from
//! the light, rendered with Vulkan's depth bias, compared at each receiver with a percentage-closer
//! filter. Spot and directional lights use one map, point lights six cube faces.

use shadow_core::light::LightView;
use shadow_core::lookup::shadow_lookup;
use shadow_core::technique::hard::ShadowMap;
use shadow_core::technique::settings::Filter;
use shadow_core::technique::{DebugView, FrameStats, ShadowTechnique, TechniqueError};
use shadow_core::{FrameInputs, Image};

use super::{map_position, per_receiver, render_depth_maps};
use crate::context::{CpuBackend, CpuContext, CpuError};
use crate::gbuffer::GBuffer;

/// The maps of the last build, one per light projection.
#[derive(Default)]
pub struct State {
    maps: Vec<Image<f32>>,
}

/// The lookup every map-based technique shares: each receiver (moved `receiver_offset` towards the light)
/// projected into its map and compared through `filter`.
pub fn query_maps(
    maps: &[Image<f32>],
    light: &LightView,
    g: &GBuffer,
    out: &mut Image<f32>,
    filter: Filter,
    radius: f32,
    receiver_offset: f32,
) {
    per_receiver(g, out, |x, y, i| {
        let m = map_position(light, g.position.data()[i], receiver_offset);
        shadow_lookup(&maps[m.projection], m.uv, m.depth, filter, radius, (x, y))
    });
}

/// False-colour pictures of depth maps, named `{prefix}{k}`.
#[must_use]
pub fn depth_views(prefix: &str, maps: &[Image<f32>]) -> Vec<DebugView> {
    maps.iter()
        .enumerate()
        .map(|(k, m)| {
            let lo = m.data().iter().copied().fold(1.0f32, f32::min);
            DebugView { name: format!("{prefix}{k}"), image: shadow_core::image::false_colour(m, lo, 1.0) }
        })
        .collect()
}

impl ShadowTechnique<CpuBackend> for ShadowMap {
    type State = State;

    fn name(&self) -> &'static str {
        "shadow-map"
    }

    fn create_state(&self, _: &mut CpuContext) -> Result<State, CpuError> {
        Ok(State::default())
    }

    fn build(
        &self,
        _: &mut CpuContext,
        state: &mut State,
        frame: &FrameInputs,
        light: &LightView,
        _: &mut FrameStats,
    ) -> Result<(), CpuError> {
        render_depth_maps(frame, light, self.resolution, self.depth_bias(), &mut state.maps)
    }

    fn query(
        &self,
        _: &mut CpuContext,
        state: &mut State,
        _: &FrameInputs,
        light: &LightView,
        g: &GBuffer,
        out: &mut Image<f32>,
        _: &mut FrameStats,
    ) -> Result<(), CpuError> {
        if state.maps.len() != light.projections.len() {
            return Err(TechniqueError::NotBuilt(self.name().into()).into());
        }
        query_maps(&state.maps, light, g, out, self.filter, self.filter_radius, self.receiver_offset());
        Ok(())
    }

    fn debug_views(&self, _: &mut CpuContext, state: &State) -> Result<Vec<DebugView>, CpuError> {
        Ok(depth_views("depth", &state.maps))
    }
}
