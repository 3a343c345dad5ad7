//! Stencil shadow volumes on the GPU (twin: [`super::cpu`]): found, extruded and counted by
//! `passes::extrusion` with the technique's counting (or, with `extrusion=cpu`, the shared extrusion
//! uploaded and counted by `passes::volumes`), then resolved; with cut-out casters, resolved over their
//! map's visibility (`passes::maps::CutoutMaps`), which the query writes first.
//!
//! In instrumented frames the build reads back the extrusion's edge and triangle counts, and the other
//! counters come from occlusion queries: samples passing the volume pass, and, in a separate pass with
//! the depth test off, every rasterized volume fragment (inside the query phase, timed as its sub-phase
//! `count_fragments` so it can be taken out).

use shadow_core::FrameInputs;
use shadow_core::geometry::volume::{Caps, VolumeCounting};
use shadow_core::technique::LightPass;
use shadow_core::technique::{ShadowTechnique, TechniqueError};
use shadow_wgpu::passes::extrusion::GpuExtrusion;
use shadow_wgpu::passes::maps::CutoutMaps;
use shadow_wgpu::passes::volumes::{
    StencilResolve, VolumeDraw, VolumePass, build_draws, count_all_pipeline, counting_state, read_query,
    volume_pipeline,
};
use shadow_wgpu::{GpuGBuffer, GpuVisibility, WgpuBackend, WgpuContext, WgpuError, shaders};

use super::{Extrusion, ShadowVolume};
use crate::cascaded_shadow_map::cutout_view;

/// The resolve, the volumes as the `extrusion` setting makes them, and the cut-out casters' maps.
pub struct State {
    resolve: StencilResolve,
    volumes: Volumes,
    cutouts: CutoutMaps,
    /// Whether a light was built since the state was made.
    built: bool,
}

/// Where the volumes come from.
enum Volumes {
    /// Found and extruded on the GPU.
    Gpu(Box<GpuExtrusion>),
    /// shadow-core's extrusion, uploaded: the pipelines for either winding, the fragment counter's, and
    /// the last build's draws.
    Cpu { ccw: wgpu::RenderPipeline, cw: wgpu::RenderPipeline, count_all: wgpu::RenderPipeline, draws: Vec<VolumeDraw> },
}

impl ShadowVolume {
    fn caps(&self) -> Caps {
        if self.counting == VolumeCounting::ZFail { Caps::Both } else { Caps::None }
    }
}

impl ShadowTechnique<WgpuBackend> for ShadowVolume {
    type State = State;

    fn name(&self) -> &'static str {
        ShadowVolume::name(self)
    }

    /// The compute pass's lists outlast the frame; volumes extruded on the host are uploaded into the
    /// frame's transient buffer, which does not; cascades of the cut-out casters' map follow the camera.
    fn build_is_reusable(&self, frame: &FrameInputs) -> bool {
        self.gpu.extrusion == Extrusion::Gpu && !self.cutouts.follows_the_camera(frame)
    }

    fn create_state(&self, cx: &mut WgpuContext) -> Result<State, WgpuError> {
        let (counting, extrusion) = (self.counting, self.gpu.extrusion);
        cx.scoped("creating the shadow-volume pipelines", |cx| {
            let module = cx.pipelines.module("shadow_volume", shaders::shadow_volume());
            let resolve = StencilResolve::new(cx, &module, 0xff);
            let volumes = match extrusion {
                Extrusion::Gpu => Volumes::Gpu(Box::new(GpuExtrusion::new(cx, counting))),
                Extrusion::Cpu => {
                    let state = counting_state(cx.depth_stencil, counting, wgpu::CompareFunction::Always, 0xff, 0xff);
                    Volumes::Cpu {
                        ccw: volume_pipeline(cx, &module, "vs_volume", wgpu::FrontFace::Ccw, state.clone()),
                        cw: volume_pipeline(cx, &module, "vs_volume", wgpu::FrontFace::Cw, state),
                        count_all: count_all_pipeline(cx, &module),
                        draws: Vec::new(),
                    }
                }
            };
            State { resolve, volumes, cutouts: CutoutMaps::default(), built: false }
        })
    }

    fn build(&self, cx: &mut WgpuContext, state: &mut State, pass: LightPass<'_>) -> Result<(), WgpuError> {
        let LightPass { frame, light, slot, aspect, stats, .. } = pass;
        match &mut state.volumes {
            Volumes::Gpu(extrusion) => {
                extrusion.build(cx, frame, light, slot, self.caps())?;
                if cx.instrumented() {
                    let c = extrusion.counts(cx)?;
                    stats.counters.silhouette_edges = Some(c.silhouette_edges);
                    stats.counters.volume_triangles = Some(c.triangles);
                }
            }
            Volumes::Cpu { draws, .. } => *draws = build_draws(cx, frame, light, self.caps(), stats)?,
        }
        let view = cutout_view(&self.cutouts, frame, light, aspect);
        state.cutouts.render(cx, frame, &view, &self.cutouts)?;
        state.built = true;
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
        let LightPass { frame, slot, stats, .. } = pass;
        if !state.built {
            return Err(TechniqueError::NotBuilt(self.name().into()).into());
        }
        let depth = g.depth_view();
        let volumes = &state.volumes;
        let cutouts = state.cutouts.query(cx, g, out)?;
        let passed = cx.scoped("the shadow-volume pass", |cx| {
            let q = match volumes {
                Volumes::Gpu(extrusion) => extrusion.draw(cx, g, &depth, slot, false),
                Volumes::Cpu { ccw, cw, draws, .. } => {
                    let counting = VolumePass {
                        label: "shadow volumes",
                        ccw,
                        cw,
                        stencil: wgpu::LoadOp::Clear(0),
                        reference: 0,
                        scissors: None,
                    };
                    counting.run(cx, draws, frame, g, &depth)
                }
            };
            // Lit where no volume holds the receiver and the cut-out casters, when there are any, leave it light.
            if cutouts {
                state.resolve.run_onto(cx, g, out, &depth);
            } else {
                state.resolve.run(cx, g, out, &depth);
            }
            q
        })?;
        let Some(passed) = passed.filter(|_| cx.instrumented()) else { return Ok(()) };
        cx.end_of_work();
        let passed = read_query(cx, Some(&passed))?;
        // Every rasterized fragment, for Sen's overdraw: a second pass with the depth test off. It runs
        // after the resolve, so it does not disturb the result; its time lands in a separate sub-phase.
        let t = std::time::Instant::now();
        let all = cx.scoped("the volume fragment count", |cx| match volumes {
            Volumes::Gpu(extrusion) => extrusion.draw(cx, g, &depth, slot, true),
            Volumes::Cpu { count_all, draws, .. } => {
                VolumePass::count(count_all, "count volume fragments").run(cx, draws, frame, g, &depth)
            }
        })?;
        let all = match all {
            Some(q) => read_query(cx, Some(&q))?,
            None => 0,
        };
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
