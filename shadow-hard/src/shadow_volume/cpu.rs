//! Stencil shadow volumes on the CPU (twin: [`super::gpu`]): the shared extrusion, counted by
//! `passes::volumes` with the technique's counting; the cut-out casters through their map
//! (`passes::maps::CutoutMaps`).

use shadow_core::frame::InstanceVolume;
use shadow_core::geometry::volume::{Caps, VolumeCounting};
use shadow_core::technique::LightPass;
use shadow_core::technique::{DebugView, ShadowTechnique, TechniqueError};
use shadow_core::{FrameInputs, Image};
use shadow_cpu::passes::maps::CutoutMaps;
use shadow_cpu::passes::per_receiver;
use shadow_cpu::passes::volumes::{build_volumes, rasterize_volumes};
use shadow_cpu::raster::DepthStencil;
use shadow_cpu::{CpuBackend, CpuContext, CpuError, GBuffer};

use super::ShadowVolume;
use crate::cascaded_shadow_map::cutout_view;

/// The volumes and the cut-out casters' maps of the last build.
#[derive(Default)]
pub struct State {
    volumes: Option<Vec<InstanceVolume>>,
    cutouts: CutoutMaps,
}

impl ShadowTechnique<CpuBackend> for ShadowVolume {
    type State = State;

    fn name(&self) -> &'static str {
        ShadowVolume::name(self)
    }

    /// Cascades of the cut-out casters' map follow the camera.
    fn build_is_reusable(&self, frame: &FrameInputs) -> bool {
        !self.cutouts.follows_the_camera(frame)
    }

    fn create_state(&self, _: &mut CpuContext) -> Result<State, CpuError> {
        Ok(State::default())
    }

    fn build(&self, _: &mut CpuContext, state: &mut State, pass: LightPass<'_>) -> Result<(), CpuError> {
        let LightPass { frame, light, aspect, stats, .. } = pass;
        let caps = if self.counting == VolumeCounting::ZFail { Caps::Both } else { Caps::None };
        state.volumes = Some(build_volumes(frame, light, caps, stats));
        let view = cutout_view(&self.cutouts, frame, light, aspect);
        state.cutouts.render(frame, &view, &self.cutouts)
    }

    fn query(
        &self,
        _: &mut CpuContext,
        state: &mut State,
        pass: LightPass<'_>,
        g: &GBuffer,
        out: &mut Image<f32>,
    ) -> Result<(), CpuError> {
        let LightPass { frame, stats, reach, .. } = pass;
        let volumes = state.volumes.as_ref().ok_or_else(|| TechniqueError::NotBuilt(self.name().into()))?;
        let mut ds = DepthStencil::from_depth(&g.depth, 0);
        let c = rasterize_volumes(frame, g, volumes, self.counting, &mut ds, None);
        // Lit where no volume holds the receiver and the cut-out casters leave it light.
        let cutouts = &state.cutouts;
        per_receiver(g, &reach, out, |x, y, i| {
            if ds.stencil[i] == 0 { cutouts.visibility(g.position.data()[i], (x, y)) } else { 0.0 }
        });
        let counters = &mut stats.counters;
        counters.volume_fragments = Some(c.fragments);
        counters.stencil_updates = Some(c.stencil_updates);
        Ok(())
    }

    fn debug_views(&self, _: &mut CpuContext, state: &State) -> Result<Vec<DebugView>, CpuError> {
        Ok(state.cutouts.views("cutout-depth"))
    }
}
