//! Stencil shadow volumes on the CPU (twin: [`super::gpu`]): the shared extrusion, counted by
//! `passes::volumes` with the technique's counting.

use shadow_core::Image;
use shadow_core::frame::InstanceVolume;
use shadow_core::geometry::volume::{Caps, VolumeCounting};
use shadow_core::technique::LightPass;
use shadow_core::technique::{ShadowTechnique, TechniqueError};
use shadow_cpu::passes::per_receiver;
use shadow_cpu::passes::volumes::{build_volumes, rasterize_volumes};
use shadow_cpu::raster::DepthStencil;
use shadow_cpu::{CpuBackend, CpuContext, CpuError, GBuffer};

use super::ShadowVolume;

/// The volumes of the last build.
#[derive(Default)]
pub struct State {
    volumes: Option<Vec<InstanceVolume>>,
}

impl ShadowTechnique<CpuBackend> for ShadowVolume {
    type State = State;

    fn name(&self) -> &'static str {
        ShadowVolume::name(self)
    }

    fn create_state(&self, _: &mut CpuContext) -> Result<State, CpuError> {
        Ok(State::default())
    }

    fn build(&self, _: &mut CpuContext, state: &mut State, pass: LightPass<'_>) -> Result<(), CpuError> {
        let LightPass { frame, light, stats, .. } = pass;
        let caps = if self.counting == VolumeCounting::ZFail { Caps::Both } else { Caps::None };
        state.volumes = Some(build_volumes(frame, light, caps, stats));
        Ok(())
    }

    fn query(
        &self,
        _: &mut CpuContext,
        state: &mut State,
        pass: LightPass<'_>,
        g: &GBuffer,
        out: &mut Image<f32>,
    ) -> Result<(), CpuError> {
        let LightPass { frame, stats, .. } = pass;
        let volumes = state.volumes.as_ref().ok_or_else(|| TechniqueError::NotBuilt(self.name().into()))?;
        let mut ds = DepthStencil::from_depth(&g.depth, 0);
        let c = rasterize_volumes(frame, g, volumes, self.counting, &mut ds, None);
        per_receiver(g, out, |_, _, i| if ds.stencil[i] == 0 { 1.0 } else { 0.0 });
        let counters = &mut stats.counters;
        counters.volume_fragments = Some(c.fragments);
        counters.stencil_updates = Some(c.stencil_updates);
        Ok(())
    }
}
