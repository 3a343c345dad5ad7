//! `smoothies` on the CPU backend, through its public rasterizer and depth-map API.

use shadow_core::Image;
use shadow_core::glam::{Vec2, Vec4};
use shadow_core::lookup::{bilinear, on_map};
use shadow_core::stats::ms;
use shadow_core::technique::LightPass;
use shadow_core::technique::{DebugView, ShadowTechnique, TechniqueError};
use shadow_cpu::passes::maps::{map_position, render_depth_maps};
use shadow_cpu::passes::per_receiver;
use shadow_cpu::raster::{CullMode, DepthStencil, RasterState, Soup, draw};
use shadow_cpu::{CpuBackend, CpuContext, CpuError, GBuffer};
use std::time::Instant;

use super::geometry::SmoothieTriangle;
use super::{FalloffTable, Smoothies};

/// The depth map and the smoothie buffer of the last build, and the rasterizer's scratch target (kept so
/// frames reuse their memory).
#[derive(Default)]
pub struct State {
    maps: Vec<Image<f32>>,
    buffer: Option<SmoothieBuffer>,
    scratch: Option<DepthStencil>,
}

/// A smoothie buffer: per texel the nearest smoothie's NDC depth (1 where none) and the minimum alpha
/// (1 where none), side by side so a lookup reads them together.
#[derive(Clone, Debug, PartialEq)]
pub struct SmoothieBuffer {
    /// `[depth, alpha]` per texel.
    pub texels: Image<[f32; 2]>,
}

impl SmoothieBuffer {
    /// An empty buffer of side `res`: no smoothie anywhere.
    #[must_use]
    pub fn new(res: u32) -> Self {
        Self { texels: Image::new(res, res, [1.0, 1.0]) }
    }

    /// One channel as an image (0: depth, 1: alpha).
    #[must_use]
    pub fn channel(&self, k: usize) -> Image<f32> {
        Image::from_fn(self.texels.width(), self.texels.height(), |x, y| self.texels.get(x, y)[k])
    }
}

/// Renders `triangles` into `buffer` (cleared first; the size of `map`) over `map`, the blockers' NDC
/// depths in projection `proj`: alpha from each triangle's ramp at the texel centre, remapped when
/// `remap`, discarded behind the map's surface, minimum-blended. `scratch` is the rasterizer's depth
/// target (no depth test is made; reused when the size fits). Returns the fragment count.
pub fn render_buffer(
    triangles: &[SmoothieTriangle],
    map: &Image<f32>,
    proj: &shadow_core::light::LightProjection,
    (t, remap): (f32, bool),
    buffer: &mut SmoothieBuffer,
    scratch: &mut Option<DepthStencil>,
) -> u64 {
    let res = map.width();
    let clip: Vec<[Vec4; 3]> = triangles
        .iter()
        .map(|tri| tri.corners.map(|c| Vec4::new(2.0 * c.x - 1.0, 1.0 - 2.0 * c.y, c.z, 1.0)))
        .collect();
    if buffer.texels.width() == res {
        buffer.texels.data_mut().fill([1.0, 1.0]);
    } else {
        *buffer = SmoothieBuffer::new(res);
    }
    let ds = match scratch {
        Some(ds) if ds.width() == res => ds,
        _ => scratch.insert(DepthStencil::new(res, res, 1.0, 0)),
    };
    let state = RasterState { cull: CullMode::None, depth: None, ..RasterState::default() };
    let counters = draw(
        ds,
        &mut buffer.texels,
        &Soup { triangles: &clip, prim_base: 0, flip: false },
        &state,
        |f| {
            let p = Vec2::new(f.x as f32 + 0.5, f.y as f32 + 0.5) / res as f32;
            let a = triangles[f.prim as usize].ramp.alpha(p, t);
            // Eq. 4.1 on linear depths: b the smoothie's, r the surface the map sees behind it.
            let ratio = proj.linear_depth(f.depth) / proj.linear_depth(*map.get(f.x, f.y));
            if ratio >= 1.0 {
                return None;
            }
            let a = if remap { (a / (1.0 - ratio)).clamp(0.0, 1.0) } else { a };
            Some([f.depth, a])
        },
        |dst, src| *dst = [dst[0].min(src[0]), dst[1].min(src[1])],
    );
    counters.fragments
}

/// The thesis's three cases at one texel (clamped to the map): behind the blocker 0, behind a smoothie
/// its alpha, else 1.
fn texel_visibility(map: &Image<f32>, buffer: &SmoothieBuffer, x: i32, y: i32, depth: f32) -> f32 {
    let [smoothie, alpha] = *buffer.texels.get_clamped(x, y);
    let penumbra = if depth > smoothie { alpha } else { 1.0 };
    if depth > *map.get_clamped(x, y) { 0.0 } else { penumbra }
}

/// Visibility at map point `uv`, NDC depth `depth`: the three cases at the four nearest texels, bilinearly
/// weighted (the thesis's 2x2 filtering); 1 outside the map. Before the falloff.
#[must_use]
pub fn smoothie_lookup(map: &Image<f32>, buffer: &SmoothieBuffer, uv: Vec2, depth: f32) -> f32 {
    if !on_map(uv) {
        return 1.0;
    }
    bilinear(map.width(), uv, |x, y| texel_visibility(map, buffer, x, y, depth))
}

impl ShadowTechnique<CpuBackend> for Smoothies {
    type State = State;

    fn name(&self) -> &'static str {
        Self::NAME
    }

    fn create_state(&self, _: &mut CpuContext) -> Result<State, CpuError> {
        Ok(State::default())
    }

    fn build(&self, _: &mut CpuContext, state: &mut State, pass: LightPass<'_>) -> Result<(), CpuError> {
        let LightPass { frame, light, stats, .. } = pass;
        let proj = Self::projection(light)?;
        render_depth_maps(frame, light, self.depth.resolution, self.depth.depth_bias(), &mut state.maps)?;
        let t0 = Instant::now();
        let (t, smoothies) = self.construct(frame, light, proj, stats);
        let buffer = state.buffer.get_or_insert_with(|| SmoothieBuffer::new(self.depth.resolution));
        let settings = (t, self.remap.is_on());
        let fragments = render_buffer(&smoothies.triangles, &state.maps[0], proj, settings, buffer, &mut state.scratch);
        stats.timings.extra.insert("smoothies".into(), ms(t0.elapsed()));
        stats.counters.extra.insert("smoothie_fragments".into(), fragments as f64);
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
        let not_built = || TechniqueError::NotBuilt(Self::NAME.into());
        let (Some(buffer), Some(map)) = (&state.buffer, state.maps.first()) else { return Err(not_built().into()) };
        let offset = self.depth.receiver_offset();
        let falloff = FalloffTable::new(self.falloff);
        per_receiver(g, &reach, out, |_, _, i| {
            let m = map_position(light, g.position.data()[i], offset);
            falloff.apply(smoothie_lookup(map, buffer, m.uv, m.depth))
        });
        Ok(())
    }

    fn debug_views(&self, _: &mut CpuContext, state: &State) -> Result<Vec<DebugView>, CpuError> {
        let Some(buffer) = &state.buffer else { return Ok(Vec::new()) };
        Ok(super::debug_views(&buffer.channel(0), &buffer.channel(1)))
    }
}
