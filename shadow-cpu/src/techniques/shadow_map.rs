//! `shadow-map` (Williams 1978; the survey of Nealen, section 3; Weiskopf-Ertl section 5): depth from
//! the light, rendered with Vulkan's depth bias, compared at each receiver with a percentage-closer
//! filter. Spot and directional lights use one map, point lights six cube faces.

use shadow_core::light::LightView;
use shadow_core::lookup::shadow_lookup;
use shadow_core::technique::hard::ShadowMap;
use shadow_core::technique::{DebugView, FrameStats, ShadowTechnique, TechniqueError};
use shadow_core::{FrameInputs, Image};

use super::{check_maps, per_receiver, render_depth_map};
use crate::context::{CpuBackend, CpuContext, CpuError};
use crate::gbuffer::GBuffer;
use crate::raster::CullMode;

/// The maps of the last build, one per light projection.
#[derive(Default)]
pub struct State {
    maps: Vec<Image<f32>>,
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
        check_maps(self.resolution, light.projections.len())?;
        let mut old = std::mem::take(&mut state.maps).into_iter();
        state.maps = light
            .projections
            .iter()
            .map(|p| render_depth_map(frame, p, self.resolution, self.depth_bias(), CullMode::None, old.next()).0)
            .collect();
        Ok(())
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
        per_receiver(g, out, |x, y, i| {
            let p = g.position.data()[i];
            let k = light.projection_index(p);
            let (uv, depth) = light.projections[k].uv_depth(p);
            shadow_lookup(&state.maps[k], uv, depth, self.filter, self.filter_radius, (x, y))
        });
        Ok(())
    }

    fn debug_views(&self, _: &mut CpuContext, state: &State) -> Result<Vec<DebugView>, CpuError> {
        Ok(state
            .maps
            .iter()
            .enumerate()
            .map(|(k, m)| {
                let lo = m.data().iter().copied().fold(1.0f32, f32::min);
                DebugView { name: format!("depth{k}"), image: shadow_core::image::false_colour(m, lo, 1.0) }
            })
            .collect())
    }
}
