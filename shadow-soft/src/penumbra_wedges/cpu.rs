//! `penumbra-wedges` on the CPU backend (twin: [`super::gpu`]), through its public rasterizer: the side
//! quads and the wedges drawn over the G-buffer into per-pixel sums of occluded shares, one per
//! [`super::geometry::Layer`], then combined.

use shadow_core::Image;
use shadow_core::glam::{Mat4, Vec4};
use shadow_core::technique::LightPass;
use shadow_core::technique::{DebugView, ShadowTechnique, TechniqueError};
use shadow_cpu::passes::maps::CutoutMaps;
use shadow_cpu::passes::per_receiver;
use shadow_cpu::raster::{CompareFn, CullMode, DepthBias, DepthState, DepthStencil, Fragment, RasterState, Soup, draw};
use shadow_cpu::{CpuBackend, CpuContext, CpuError, GBuffer};

use super::PenumbraWedges;
use super::coverage::{SphereLight, count_step, horizon_share, wedge_term};
use super::geometry::{LAYERS, PixelScale, QUAD_DEPTH_BIAS, WedgeEdge, WedgeGeometry};

/// The geometry and the cut-out casters' map of the last build.
#[derive(Default)]
pub struct State {
    built: Option<(WedgeGeometry, SphereLight)>,
    cutouts: CutoutMaps,
}

/// The back faces of the wedges, behind the receiver: the receiver may be inside.
const WEDGE_STATE: RasterState = RasterState {
    cull: CullMode::Front,
    depth: Some(DepthState { compare: CompareFn::Greater, write: false, bias: DepthBias::NONE, clamp: false }),
    ..QUAD_STATE
};

/// The side quads in front of the receiver, or so nearly level with it that the fragment must decide
/// (see [`QUAD_DEPTH_BIAS`]).
const QUAD_STATE: RasterState = RasterState {
    cull: CullMode::None,
    front_face: shadow_cpu::raster::FrontFace::Ccw,
    depth: Some(DepthState { compare: CompareFn::Less, write: false, bias: QUAD_DEPTH_BIAS, clamp: false }),
    stencil: None,
    early_tests: true,
};

/// Draws `triangles` (homogeneous world points) over `g`, adding `term(edge, receiver)` of each
/// fragment's edge (`edge_of(prim)`) into its layer's sum in `occluded`. Returns the fragment count.
fn accumulate(
    g: &GBuffer,
    ds: &mut DepthStencil,
    occluded: &mut Image<[f32; LAYERS]>,
    (triangles, state): (&[[Vec4; 3]], &RasterState),
    edge_of: impl Fn(u32) -> WedgeEdge + Sync,
    term: impl Fn(&WedgeEdge, shadow_core::glam::Vec3) -> f32 + Sync,
) -> u64 {
    let clip_from_world: Mat4 = g.clip_from_world;
    let clip: Vec<[Vec4; 3]> = triangles.iter().map(|t| t.map(|v| clip_from_world * v)).collect();
    let width = g.width();
    let shader = |f: &Fragment| {
        let i = (f.y * width + f.x) as usize;
        g.receiver.data()[i].then(|| {
            let edge = edge_of(f.prim);
            let mut sums = [0.0; LAYERS];
            sums[edge.layer as usize] = edge.weight * term(&edge, g.position.data()[i]);
            sums
        })
    };
    let add = |d: &mut [f32; LAYERS], s: [f32; LAYERS]| d.iter_mut().zip(s).for_each(|(d, s)| *d += s);
    draw(ds, occluded, &Soup { triangles: &clip, prim_base: 0, flip: false }, state, shader, add).fragments
}

impl ShadowTechnique<CpuBackend> for PenumbraWedges {
    type State = State;

    fn name(&self) -> &'static str {
        Self::NAME
    }

    fn create_state(&self, _: &mut CpuContext) -> Result<State, CpuError> {
        Ok(State::default())
    }

    fn build(&self, _: &mut CpuContext, state: &mut State, pass: LightPass<'_>) -> Result<(), CpuError> {
        let LightPass { frame, light, stats, .. } = pass;
        state.built = Some((Self::construct(frame, light, stats)?, Self::sphere(light)?));
        state.cutouts.render(frame, light, &self.cutouts)
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
        let (built, light) = state.built.as_ref().ok_or_else(|| TechniqueError::NotBuilt(Self::NAME.into()))?;
        let (eye, c) = (g.camera.eye, light.centre);
        let eye_counts = built.eye_counts(frame, eye);
        let mut occluded = Image::new(g.width(), g.height(), [0.0f32; LAYERS]);
        let mut ds = DepthStencil::from_depth(&g.depth, 0);
        let edges = &built.edges;
        let quads = accumulate(
            g,
            &mut ds,
            &mut occluded,
            (&built.side_quads(PixelScale::of(&g.camera, g.height())), &QUAD_STATE),
            |prim| edges[prim as usize / 2],
            |e, p| count_step(p, eye, e.a, e.b, c),
        );
        let wedges = if self.wedges.is_on() {
            accumulate(
                g,
                &mut ds,
                &mut occluded,
                (&built.hulls, &WEDGE_STATE),
                |prim| edges[built.hull_edges[prim as usize] as usize],
                |e, p| wedge_term(p, e.a, e.b, &e.planes, *light),
            )
        } else {
            0
        };
        // The soft visibility, times the cut-out casters' map's.
        let cutouts = &state.cutouts;
        per_receiver(g, &reach, out, |x, y, i| {
            let p = g.position.data()[i];
            let horizon = horizon_share(p, g.geometric_normal.data()[i], *light);
            let [closed, facing, turned] = std::array::from_fn(|k| eye_counts[k] + occluded.data()[i][k]);
            (1.0 - closed - facing.max(turned) - horizon).clamp(0.0, 1.0) * cutouts.visibility(p, (x, y))
        });
        stats.counters.volume_fragments = Some(quads);
        stats.counters.extra.insert("wedge_fragments".into(), wedges as f64);
        Ok(())
    }

    fn debug_views(&self, _: &mut CpuContext, state: &State) -> Result<Vec<DebugView>, CpuError> {
        Ok(state.cutouts.views("cutout-depth"))
    }
}
