//! `midpoint-shadow-map` (Woo), `second-depth-shadow-map` (Wang-Molnar) and `dual-shadow-map`
//! (Weiskopf-Ertl 2003): the two layers nearest the light, found by depth peeling, combined into one map
//! that the ordinary shadow-map lookup then reads (Weiskopf-Ertl section 5: "the rendering of the scene
//! from the eye point in phase two is not modified").
//!
//! Pass 1 renders the nearest depth z1. Pass 2 renders the scene again, discarding every fragment within
//! `peel_epsilon` of z1 at its texel, which leaves the second-nearest depth z2. Where a layer is missing
//! the far plane stands in, as in the paper. Back faces of closed meshes are culled in both passes under
//! `culling=auto`, open meshes are never culled: the paper's mix of solid and thin objects in one scene.
//! The combination is taken on linear depths (see `DepthLayers::combine`).

use rayon::prelude::*;

use super::{DepthLayers, LayerCulling};
use shadow_core::light::LightProjection;
use shadow_core::technique::{BuildReads, LightPass};
use shadow_core::technique::{DebugView, ShadowTechnique, TechniqueError};
use shadow_core::{FrameInputs, Image};

use shadow_core::frame::Coverage;
use shadow_cpu::alpha_test::{Cutout, draw_alpha_tested};
use shadow_cpu::gbuffer::{GBuffer, clip_vertices};
use shadow_cpu::passes::maps::check_maps;
use shadow_cpu::passes::maps::{MapLookup, depth_views};
use shadow_cpu::raster::{
    Batch, CullMode, DepthState, DepthStencil, Fragment, Indexed, RasterState, draw_depth, draw_depth_peeled,
};
use shadow_cpu::{CpuBackend, CpuContext, CpuError};

/// The layers and the combined map of the last build, one of each per light projection.
#[derive(Default)]
pub struct State {
    z1: Vec<Image<f32>>,
    z2: Vec<Image<f32>>,
    maps: Vec<Image<f32>>,
}

/// One light pass: the nearest depth, or with `first` the nearest depth behind it (depth peeling). A
/// caster cut out by its texture leaves no depth where its texel is clear, in either pass.
///
/// # Errors
/// [`FrameError::TooManyTriangles`](shadow_core::frame::FrameError) for a caster a draw cannot number.
fn layer_pass(
    frame: &FrameInputs,
    proj: &LightProjection,
    res: u32,
    culling: LayerCulling,
    first: Option<(&Image<f32>, f32)>,
) -> Result<Image<f32>, CpuError> {
    let mut ds = DepthStencil::new(res, res, 1.0, 0);
    for inst in frame.instances.iter().filter(|i| i.casts_shadow && i.coverage() != Coverage::Absent) {
        let cull =
            if culling == LayerCulling::Auto && inst.adjacency.closed() { CullMode::Back } else { CullMode::None };
        let clip = clip_vertices(inst.mesh.positions(), proj.clip_from_world * inst.world_from_local);
        let src = Indexed {
            positions: &clip,
            triangles: inst.mesh.triangles(),
            prim_base: 0,
            flip: inst.mirrored,
            cull_back: false,
        };
        let state = RasterState { cull, depth: Some(DepthState::LESS_WRITE), ..RasterState::default() };
        match (Cutout::of(inst), first) {
            (None, None) => {
                draw_depth(&mut ds, &src, &state);
            }
            (None, Some((z1, eps))) => {
                draw_depth_peeled(&mut ds, &src, &state, z1, eps);
            }
            (Some(test), first) => {
                // The peel's discard (see `draw_depth_peeled`) after the alpha test's.
                let behind = |f: &Fragment| first.is_none_or(|(z1, eps)| f.depth > *z1.get(f.x, f.y) + eps);
                let mut none = Image::new(res, res, ());
                let batch = Batch::new(vec![src])?;
                draw_alpha_tested(&mut ds, &mut none, (&batch, &[test]), &state, |f| behind(f).then_some(()));
            }
        }
    }
    Ok(ds.into_depth_image())
}

impl ShadowTechnique<CpuBackend> for DepthLayers {
    type State = State;

    fn name(&self) -> &'static str {
        self.kind.name()
    }

    fn create_state(&self, _: &mut CpuContext) -> Result<State, CpuError> {
        Ok(State::default())
    }

    fn build(&self, _: &mut CpuContext, state: &mut State, pass: LightPass<'_>) -> Result<(), CpuError> {
        let LightPass { frame, light, aspect, .. } = pass;
        let view = self.view(frame, light, aspect);
        let light = &*view;
        check_maps(self.resolution, 3 * light.projections.len())?;
        state.z1.clear();
        state.z2.clear();
        state.maps.clear();
        for proj in &light.projections {
            let z1 = layer_pass(frame, proj, self.resolution, self.culling, None)?;
            let z2 = layer_pass(frame, proj, self.resolution, self.culling, Some((&z1, self.peel_epsilon)))?;
            // Where the first layer is missing (the far plane) no caster is: the map stays at the far plane.
            let mut combined = Image::new(self.resolution, self.resolution, 1.0f32);
            combined.data_mut().par_iter_mut().zip(z1.data()).zip(z2.data()).with_min_len(4096).for_each(
                |((m, &a), &b)| {
                    if a < 1.0 {
                        *m = proj.ndc_depth(self.combine(proj.linear_depth(a), proj.linear_depth(b)));
                    }
                },
            );
            state.z1.push(z1);
            state.z2.push(z2);
            state.maps.push(combined);
        }
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
        let LightPass { frame, light, reach, aspect, .. } = pass;
        let view = self.view(frame, light, aspect);
        let light = &*view;
        if state.maps.len() != light.projections.len() {
            return Err(TechniqueError::NotBuilt(self.kind.name().into()).into());
        }
        MapLookup { filter: self.filter, radius: self.filter_radius, receiver_offset: 0.0 }.query(
            &state.maps,
            light,
            &reach,
            g,
            out,
        );
        Ok(())
    }

    /// With cascades the maps follow the camera, which the build key does not hold.
    fn build_is_reusable(&self, _: &FrameInputs) -> bool {
        self.cascades == 0
    }

    /// Its build peels casters' layers in the light's maps and reads nothing else of the frame.
    fn build_reads(&self) -> BuildReads {
        BuildReads::LightViews
    }

    fn debug_views(&self, _: &mut CpuContext, state: &State) -> Result<Vec<DebugView>, CpuError> {
        let mut v = depth_views("z1-", &state.z1);
        v.extend(depth_views("z2-", &state.z2));
        v.extend(depth_views("map", &state.maps));
        Ok(v)
    }
}
