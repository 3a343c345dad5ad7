//! Stencil shadow volumes on the GPU (twin: [`super::cpu`]): the shared extrusion, uploaded and counted by
//! `passes::volumes` with the technique's counting, then resolved.
//!
//! Counters come from occlusion queries: samples passing the volume pass, and, in a separate pass with
//! the depth test off, every rasterized volume fragment (inside the query phase, timed as its sub-phase
//! `count_fragments` so it can be taken out).

use shadow_core::geometry::volume::{Caps, VolumeCounting};
use shadow_core::technique::LightPass;
use shadow_core::technique::{ShadowTechnique, TechniqueError};
use shadow_wgpu::passes::volumes::{
    StencilResolve, VolumeDraw, VolumePass, build_draws, count_all_pipeline, counting_state, read_query,
    volume_pipeline,
};
use shadow_wgpu::{GpuGBuffer, GpuVisibility, WgpuBackend, WgpuContext, WgpuError, shaders};

use super::ShadowVolume;

/// Pipelines and the uploaded volumes of the last build.
pub struct State {
    ccw: wgpu::RenderPipeline,
    cw: wgpu::RenderPipeline,
    count_all: wgpu::RenderPipeline,
    resolve: StencilResolve,
    draws: Vec<VolumeDraw>,
}

impl ShadowTechnique<WgpuBackend> for ShadowVolume {
    type State = State;

    fn name(&self) -> &'static str {
        ShadowVolume::name(self)
    }

    fn create_state(&self, cx: &mut WgpuContext) -> Result<State, WgpuError> {
        let counting = self.counting;
        cx.scoped("creating the shadow-volume pipelines", |cx| {
            let module = shaders::module(&cx.device, "shadow_volume", shaders::shadow_volume());
            let state = counting_state(counting, wgpu::CompareFunction::Always, 0xff, 0xff);
            let ccw = volume_pipeline(cx, &module, "vs_volume", wgpu::FrontFace::Ccw, state.clone());
            let cw = volume_pipeline(cx, &module, "vs_volume", wgpu::FrontFace::Cw, state);
            let count_all = count_all_pipeline(cx, &module);
            let resolve = StencilResolve::new(cx, &module, 0xff);
            State { ccw, cw, count_all, resolve, draws: Vec::new() }
        })
    }

    fn build(&self, cx: &mut WgpuContext, state: &mut State, pass: LightPass<'_>) -> Result<(), WgpuError> {
        let LightPass { frame, light, stats } = pass;
        let caps = if self.counting == VolumeCounting::ZFail { Caps::Both } else { Caps::None };
        state.draws = build_draws(cx, frame, light, caps, stats)?;
        Ok(())
    }

    fn query(
        &self,
        cx: &mut WgpuContext,
        state: &mut State,
        pass: LightPass<'_>,
        g: &GpuGBuffer,
        out: &mut GpuVisibility,
    ) -> Result<(), WgpuError> {
        let LightPass { frame, stats, .. } = pass;
        if state.draws.is_empty() && stats.counters.volume_triangles.is_none() {
            return Err(TechniqueError::NotBuilt(self.name().into()).into());
        }
        let depth = g.depth_view();
        let counting = VolumePass {
            label: "shadow volumes",
            ccw: &state.ccw,
            cw: &state.cw,
            stencil: wgpu::LoadOp::Clear(0),
            reference: 0,
            scissors: None,
        };
        let passed = cx.scoped("the shadow-volume pass", |cx| {
            let q = counting.run(cx, &state.draws, frame, g, &depth);
            state.resolve.run(cx, g, out, &depth);
            q
        })?;
        if !cx.instrumented() {
            return Ok(());
        }
        cx.end_of_work();
        let passed = read_query(cx, &passed)?;
        // Every rasterized fragment, for Sen's overdraw: a second pass with the depth test off. It runs
        // after the resolve, so it does not disturb the result; its time lands in a separate sub-phase.
        let t = std::time::Instant::now();
        let every = VolumePass::count(&state.count_all, "count volume fragments");
        let all = cx.scoped("the volume fragment count", |cx| every.run(cx, &state.draws, frame, g, &depth))?;
        let all = read_query(cx, &all)?;
        stats.timings.extra.insert("count_fragments".into(), shadow_core::stats::ms(t.elapsed()));
        let c = &mut stats.counters;
        c.volume_fragments = Some(all);
        // Z-pass applies an op where the depth test passes, z-fail where it fails.
        c.stencil_updates = Some(match self.counting {
            VolumeCounting::ZPass => passed,
            VolumeCounting::ZFail => all - passed.min(all),
        });
        Ok(())
    }
}
