//! `volume-reconstruction` (McCool 2000): the light's depth map becomes a polygonal shadow-volume boundary
//! (`shadow_core::reconstruction`, shared with the GPU backend), resolved with one stencil bit.
//!
//! Build: depth maps as `shadow-map` renders them (its bias settings, with a smaller default slope; a point
//! light's cube faces widened so their maps meet, see `LightView::with_seamless_faces`), then per map the
//! edge flags and the reconstructed triangles (`super::reconstruction::projection`). Query: the near-plane cap for this view, then every triangle drawn with its stencil bit
//! inverted wherever it is in front of the G-buffer (front and back faces alike, one pass), the caps
//! inverted without a depth test, and the bit read: set means shadowed.

use super::reconstruction::HomTriangle;
use super::reconstruction::projection::{
    Projection, caps_for_view, coverage_view, edge_view, reconstruct_projection, record_build,
};
use super::{ObjectIds, VolumeReconstruction};
use shadow_core::Image;
use shadow_core::glam::{Mat4, Vec4};
use shadow_core::image::Rgb8;
use shadow_core::technique::LightPass;
use shadow_core::technique::{DebugView, ShadowTechnique, TechniqueError};

use shadow_cpu::GBuffer;
use shadow_cpu::passes::maps::{render_depth_and_id_maps, render_depth_maps};
use shadow_cpu::passes::per_receiver;
use shadow_cpu::raster::{
    CompareFn, DepthState, DepthStencil, RasterCounters, RasterState, Soup, StencilFace, StencilOp, StencilState,
    draw_depth,
};
use shadow_cpu::{CpuBackend, CpuContext, CpuError};

/// The projections of the last build, and the last query's view and caps (for the debug views).
#[derive(Default)]
pub struct State {
    maps: Vec<Image<f32>>,
    /// The ID channel, when `ids` is not `off`.
    ids: Vec<Image<u32>>,
    projections: Vec<Projection>,
    last_view: Option<(Mat4, u32, u32, Vec<HomTriangle>)>,
}

/// The one-bit parity state: invert bit 0 on every fragment that passes `depth`, both faces.
fn parity_state(depth: DepthState) -> RasterState {
    let face = StencilFace {
        compare: CompareFn::Always,
        fail: StencilOp::Keep,
        depth_fail: StencilOp::Keep,
        pass: StencilOp::Invert,
    };
    RasterState {
        depth: Some(depth),
        stencil: Some(StencilState { front: face, back: face, read_mask: 1, write_mask: 1, reference: 0 }),
        ..RasterState::default()
    }
}

/// Caps drawn at mid depth with the depth test off: they lie on the near plane, which would clip them, and
/// every visible surface is behind it anyway.
#[must_use]
pub fn cap_clip(eye: Mat4, t: &HomTriangle) -> [Vec4; 3] {
    t.map(|p| {
        let c = eye * p;
        Vec4::new(c.x, c.y, 0.5 * c.w, c.w)
    })
}

impl ShadowTechnique<CpuBackend> for VolumeReconstruction {
    type State = State;

    fn name(&self) -> &'static str {
        Self::NAME
    }

    fn create_state(&self, _: &mut CpuContext) -> Result<State, CpuError> {
        Ok(State::default())
    }

    fn build(&self, _: &mut CpuContext, state: &mut State, pass: LightPass<'_>) -> Result<(), CpuError> {
        let LightPass { frame, light, stats, .. } = pass;
        let res = self.depth.resolution;
        let view = light.with_seamless_faces(res);
        let bias = self.depth.depth_bias();
        if self.ids == ObjectIds::Off {
            render_depth_maps(frame, &view, res, bias, &mut state.maps)?;
            state.ids.clear();
        } else {
            render_depth_and_id_maps(frame, &view, res, bias, &mut state.maps, &mut state.ids)?;
        }
        state.projections = view
            .projections
            .iter()
            .enumerate()
            .map(|(k, &p)| reconstruct_projection(self, &view, p, &state.maps[k], state.ids.get(k)))
            .collect();
        record_build(&state.projections, stats);
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
        let LightPass { stats, reach, .. } = pass;
        if state.projections.is_empty() {
            return Err(TechniqueError::NotBuilt(Self::NAME.into()).into());
        }
        let eye = g.clip_from_world;
        let (invert, caps) =
            if self.capping.is_on() { caps_for_view(&state.projections, eye) } else { (false, Vec::new()) };
        let mut ds = DepthStencil::from_depth(&g.depth, u8::from(invert));
        let sides: Vec<[Vec4; 3]> =
            state.projections.iter().flat_map(|p| &p.triangles).map(|t| t.map(|v| eye * v)).collect();
        let mut c: RasterCounters = draw_depth(
            &mut ds,
            &Soup { triangles: &sides, prim_base: 0, flip: false },
            &parity_state(DepthState::LESS_READ),
        );
        let capped: Vec<[Vec4; 3]> = caps.iter().map(|t| cap_clip(eye, t)).collect();
        let always = DepthState { compare: CompareFn::Always, ..DepthState::LESS_READ };
        c += draw_depth(&mut ds, &Soup { triangles: &capped, prim_base: 0, flip: false }, &parity_state(always));
        per_receiver(g, &reach, out, |_, _, i| if ds.stencil[i] & 1 == 0 { 1.0 } else { 0.0 });
        let counters = &mut stats.counters;
        counters.volume_triangles = Some((sides.len() + capped.len()) as u64);
        counters.volume_fragments = Some(c.fragments);
        counters.stencil_updates = Some(c.stencil_updates);
        counters.extra.insert("cap_triangles".into(), capped.len() as f64);
        counters.extra.insert("cap_inverted".into(), f64::from(u8::from(invert)));
        state.last_view = Some((eye, g.width(), g.height(), caps));
        Ok(())
    }

    fn debug_views(&self, _: &mut CpuContext, state: &State) -> Result<Vec<DebugView>, CpuError> {
        let mut views: Vec<DebugView> = state
            .projections
            .iter()
            .enumerate()
            .map(|(k, p)| DebugView { name: format!("edges{k}"), image: edge_view(&p.samples, &p.mesh_edges) })
            .collect();
        if let Some((eye, w, h, caps)) = &state.last_view {
            let image = volume_view(*eye, *w, *h, &state.projections, caps);
            views.push(DebugView { name: "volume".into(), image });
        }
        Ok(views)
    }
}

/// The reconstructed volume in the eye's view: how many boundary and cap triangles cover each pixel, with
/// no depth test (`coverage_view`; the GPU backend draws the same counts in its stencil).
#[must_use]
pub fn volume_view(eye: Mat4, w: u32, h: u32, projections: &[Projection], caps: &[HomTriangle]) -> Image<Rgb8> {
    let mut ds = DepthStencil::new(w, h, 1.0, 0);
    let count = StencilFace {
        compare: CompareFn::Always,
        fail: StencilOp::Keep,
        depth_fail: StencilOp::Keep,
        pass: StencilOp::IncrementClamp,
    };
    let state = RasterState {
        depth: Some(DepthState { compare: CompareFn::Always, ..DepthState::LESS_READ }),
        stencil: Some(StencilState { front: count, back: count, read_mask: 0xff, write_mask: 0xff, reference: 0 }),
        ..RasterState::default()
    };
    let mut clip: Vec<[Vec4; 3]> = projections.iter().flat_map(|p| &p.triangles).map(|t| t.map(|v| eye * v)).collect();
    clip.extend(caps.iter().map(|t| cap_clip(eye, t)));
    let _ = draw_depth(&mut ds, &Soup { triangles: &clip, prim_base: 0, flip: false }, &state);
    let counts = Image::from_fn(w, h, |x, y| ds.stencil[(y * w + x) as usize]);
    coverage_view(&counts)
}
