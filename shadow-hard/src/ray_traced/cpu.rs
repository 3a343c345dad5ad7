//! `ray-traced` on the CPU: one ray per receiver through the scene BVH (`passes::rays`).

use shadow_core::light::LightView;
use shadow_core::scene::LightKind;
use shadow_core::technique::{FrameStats, ShadowTechnique};
use shadow_core::{FrameInputs, Image};
use shadow_cpu::passes::per_receiver;
use shadow_cpu::passes::rays::{RayOrigins, State};
use shadow_cpu::{CpuBackend, CpuContext, CpuError, GBuffer};

use super::RayTraced;

impl ShadowTechnique<CpuBackend> for RayTraced {
    type State = State;

    fn name(&self) -> &'static str {
        Self::NAME
    }

    fn create_state(&self, _: &mut CpuContext) -> Result<State, CpuError> {
        Ok(State::default())
    }

    fn build(
        &self,
        cx: &mut CpuContext,
        state: &mut State,
        frame: &FrameInputs,
        _: &LightView,
        _: &mut FrameStats,
    ) -> Result<(), CpuError> {
        state.build(cx, frame);
        Ok(())
    }

    fn query(
        &self,
        _: &mut CpuContext,
        state: &mut State,
        frame: &FrameInputs,
        light: &LightView,
        g: &GBuffer,
        out: &mut Image<f32>,
        stats: &mut FrameStats,
    ) -> Result<(), CpuError> {
        let bvh = state.bvh(Self::NAME)?;
        let origins = RayOrigins::new(g, frame, self.epsilon);
        per_receiver(g, out, |_, _, i| {
            let (origin, n) = origins.at(i);
            let (dir, tmax) = match light.light.kind {
                LightKind::Spot { position, .. } | LightKind::Point { position } => {
                    let d = position - origin;
                    let len = d.length();
                    (d / len, len)
                }
                LightKind::Directional { direction } => (-direction.normalize(), f32::INFINITY),
            };
            if n.dot(dir) <= 0.0 || bvh.occluded(origin, dir, tmax) { 0.0 } else { 1.0 }
        });
        stats.counters.extra.insert("shadow_rays".into(), g.covered_pixels() as f64);
        Ok(())
    }
}
