//! `penumbra-map` on the CPU backend, through its public rasterizer and depth-map API; the reference of
//! the passes build.wgsl and query.wgsl mirror.

use shadow_core::Image;
use shadow_core::glam::Vec2;
use shadow_core::light::LightProjection;
use shadow_core::lookup::{bilinear, on_map};
use shadow_core::stats::ms;
use shadow_core::technique::LightPass;
use shadow_core::technique::{DebugView, ShadowTechnique, TechniqueError};
use shadow_cpu::passes::maps::{map_position, render_depth_maps};
use shadow_cpu::passes::per_receiver;
use shadow_cpu::raster::{CullMode, DepthStencil, RasterState, Soup, draw};
use shadow_cpu::{CpuBackend, CpuContext, CpuError, GBuffer};
use std::time::Instant;

use super::geometry::{PenumbraTriangle, clip_space};
use super::{PenumbraMap, penumbra_value};

/// The depth map and the penumbra map of the last build, and the rasterizer's scratch target (kept so
/// frames reuse their memory).
#[derive(Default)]
pub struct State {
    maps: Vec<Image<f32>>,
    penumbra: Option<Image<f32>>,
    scratch: Option<DepthStencil>,
}

/// Renders `triangles` into `penumbra` (filled with 1 first; the size of `map`) over `map`, the surfaces'
/// NDC depths in projection `proj`, keeping the smallest value. `scratch` is the rasterizer's depth target
/// (no depth test is made; reused when the size fits). Returns the fragment count.
pub fn render_penumbra(
    triangles: &[PenumbraTriangle],
    map: &Image<f32>,
    proj: &LightProjection,
    penumbra: &mut Image<f32>,
    scratch: &mut Option<DepthStencil>,
) -> u64 {
    let res = map.width();
    penumbra.data_mut().fill(1.0);
    let ds = match scratch {
        Some(ds) if ds.width() == res => ds,
        _ => scratch.insert(DepthStencil::new(res, res, 1.0, 0)),
    };
    let clip = clip_space(triangles, proj);
    let state = RasterState { cull: CullMode::None, depth: None, ..RasterState::default() };
    let counters = draw(
        ds,
        penumbra,
        &Soup { triangles: &clip, prim_base: 0, flip: false },
        &state,
        |f| {
            let t = &triangles[f.prim as usize];
            let z_v = t.vertex_depth.iter().zip(f.bary()).map(|(z, b)| z * b).sum::<f32>();
            let z_f = proj.linear_depth(*map.get(f.x, f.y));
            penumbra_value(proj.linear_depth(f.depth), z_v, z_f)
        },
        |dst, src| *dst = dst.min(src),
    );
    counters.fragments
}

/// One texel (clamped to the map): behind the blocker 0, else the penumbra map's value.
fn texel_visibility(map: &Image<f32>, penumbra: &Image<f32>, x: i32, y: i32, depth: f32) -> f32 {
    if depth > *map.get_clamped(x, y) { 0.0 } else { *penumbra.get_clamped(x, y) }
}

/// Visibility at map point `uv`, NDC depth `depth`: the four nearest texels, bilinearly weighted; 1
/// outside the map.
#[must_use]
pub fn penumbra_lookup(map: &Image<f32>, penumbra: &Image<f32>, uv: Vec2, depth: f32) -> f32 {
    if !on_map(uv) {
        return 1.0;
    }
    bilinear(map.width(), uv, |x, y| texel_visibility(map, penumbra, x, y, depth))
}

impl ShadowTechnique<CpuBackend> for PenumbraMap {
    type State = State;

    fn name(&self) -> &'static str {
        Self::NAME
    }

    fn create_state(&self, _: &mut CpuContext) -> Result<State, CpuError> {
        Ok(State::default())
    }

    fn build(&self, _: &mut CpuContext, state: &mut State, pass: LightPass<'_>) -> Result<(), CpuError> {
        let LightPass { frame, light, stats, .. } = pass;
        // The sub-phase `penumbra_map`: the cones and sheets built and drawn (the depth map is shadow-map's).
        let t0 = Instant::now();
        let (proj, built) = Self::construct(frame, light, stats)?;
        let construct = t0.elapsed();
        render_depth_maps(frame, light, self.depth.resolution, self.depth.depth_bias(), &mut state.maps)?;
        let t0 = Instant::now();
        let res = self.depth.resolution;
        let penumbra = match &mut state.penumbra {
            Some(p) if p.width() == res => p,
            slot => slot.insert(Image::new(res, res, 1.0)),
        };
        let fragments = render_penumbra(&built.triangles, &state.maps[0], proj, penumbra, &mut state.scratch);
        stats.timings.extra.insert("penumbra_map".into(), ms(construct + t0.elapsed()));
        stats.counters.extra.insert("penumbra_fragments".into(), fragments as f64);
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
        let LightPass { light, reach, .. } = pass;
        let (Some(penumbra), Some(map)) = (&state.penumbra, state.maps.first()) else {
            return Err(TechniqueError::NotBuilt(Self::NAME.into()).into());
        };
        let offset = self.depth.receiver_offset();
        per_receiver(g, &reach, out, |_, _, i| {
            let m = map_position(light, g.position.data()[i], offset);
            penumbra_lookup(map, penumbra, m.uv, m.depth)
        });
        Ok(())
    }

    fn debug_views(&self, _: &mut CpuContext, state: &State) -> Result<Vec<DebugView>, CpuError> {
        Ok(state.penumbra.as_ref().map(super::debug_views).unwrap_or_default())
    }
}
