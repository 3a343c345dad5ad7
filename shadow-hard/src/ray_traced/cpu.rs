//! `ray-traced` on the CPU: one ray per receiver through the scene BVH (`passes::rays`).

use shadow_core::Image;
use shadow_core::technique::LightPass;
use shadow_core::technique::ShadowTechnique;
use shadow_cpu::passes::per_receiver_casting;
use shadow_cpu::passes::rays::{RayOrigins, State, towards};
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

    fn build(&self, cx: &mut CpuContext, state: &mut State, pass: LightPass<'_>) -> Result<(), CpuError> {
        let LightPass { frame, .. } = pass;
        state.build(cx, frame);
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
        let LightPass { frame, light, stats, reach, .. } = pass;
        let bvh = state.bvh(Self::NAME)?;
        let origins = RayOrigins::new(g, frame, self.epsilon);
        let rays = per_receiver_casting(g, &reach, out, |walker, _, _, i| {
            let (origin, n) = origins.at(i);
            let (dir, tmax) = towards(&light.light.kind, origin);
            // The light below the receiver's horizon: shadowed, and no ray to cast.
            if n.dot(dir) <= 0.0 {
                (0.0, 0)
            } else {
                (if bvh.occluded_after(walker, origin, dir, tmax) { 0.0 } else { 1.0 }, 1)
            }
        });
        stats.counters.extra.insert("rays_cast".into(), rays as f64);
        Ok(())
    }
}
