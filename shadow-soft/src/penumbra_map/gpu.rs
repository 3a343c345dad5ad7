//! `penumbra-map` on the wgpu backend, through its public API: `shadow-map`'s light pass for the surfaces'
//! depth, one pass drawing the cones and sheets into the penumbra map (build.wgsl), and a query over the
//! G-buffer with `shadow-map`'s bindings and the penumbra map (query.wgsl). The cones and sheets are built
//! on the CPU by the shared [`super::geometry`] and uploaded.

use bytemuck::{Pod, Zeroable};
use shadow_core::light::LightProjection;
use shadow_core::technique::LightPass;
use shadow_core::technique::{DebugView, ShadowTechnique, TechniqueError};
use shadow_wgpu::frame::{layer_view, layered};
use shadow_wgpu::passes::maps::{DepthMaps, LookupParams, MapQuery, QueryExtras};
use shadow_wgpu::pipelines::{FragmentEntry, MAP_DEPTH, depth_entry};
use shadow_wgpu::{GpuGBuffer, GpuVisibility, TransientRing, WgpuBackend, WgpuContext, WgpuError, readback, shaders};

use super::PenumbraMap;
use super::geometry::PenumbraTriangle;
use crate::min_target;

/// GPU twin of `PenumbraParams` in build.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct PenumbraParams {
    clip_from_world: [[f32; 4]; 4],
    depth: [f32; 4],
}

/// One cone or sheet vertex: world position and its silhouette vertex's linear depth.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct ConeVertex {
    position: [f32; 3],
    vertex_depth: f32,
}

const VERTEX_LAYOUT: wgpu::VertexBufferLayout<'static> = wgpu::VertexBufferLayout {
    array_stride: std::mem::size_of::<ConeVertex>() as u64,
    step_mode: wgpu::VertexStepMode::Vertex,
    attributes: &wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32],
};

/// Pipelines, the surfaces' map and the penumbra map of the last build.
pub struct State {
    map: DepthMaps,
    build_layout: wgpu::BindGroupLayout,
    build: wgpu::RenderPipeline,
    query: MapQuery,
    /// The penumbra map: a one-layer depth texture holding the values.
    penumbra: Option<wgpu::Texture>,
    /// The cones' and sheets' vertices, each frame's (their number follows the silhouettes).
    vertices: TransientRing,
}

fn vertices(triangles: &[PenumbraTriangle]) -> Vec<ConeVertex> {
    triangles
        .iter()
        .flat_map(|t| {
            [0, 1, 2].map(|k| ConeVertex { position: t.corners[k].to_array(), vertex_depth: t.vertex_depth[k] })
        })
        .collect()
}

impl State {
    /// Draws `triangles` into the penumbra map over `maps` (the surfaces' depth) of projection `proj`.
    fn render_penumbra(
        &mut self,
        cx: &WgpuContext,
        maps: &wgpu::Texture,
        proj: &LightProjection,
        triangles: &[PenumbraTriangle],
    ) {
        let res = maps.width();
        let penumbra = match &self.penumbra {
            Some(t) if t.width() == res => t,
            _ => self.penumbra.insert(layered(cx, "penumbra map", res, res, 1, MAP_DEPTH)),
        };
        let params = PenumbraParams {
            clip_from_world: proj.clip_from_world.to_cols_array_2d(),
            depth: [proj.near, proj.far, 0.0, 0.0],
        };
        let group = min_target::bind(cx, &self.build_layout, "penumbra map", &params, maps);
        let data = vertices(triangles);
        let vertices = min_target::vertex_buffer(cx, &mut self.vertices, &data);
        let mut enc = cx.encoder("penumbra map");
        min_target::draw(&mut enc, penumbra, &self.build, &group, vertices.as_ref());
        cx.submit(enc);
    }
}

impl ShadowTechnique<WgpuBackend> for PenumbraMap {
    type State = State;

    fn name(&self) -> &'static str {
        Self::NAME
    }

    fn create_state(&self, cx: &mut WgpuContext) -> Result<State, WgpuError> {
        let map = DepthMaps::new(cx, &self.depth);
        cx.scoped("creating the penumbra-map pipelines", |cx| {
            let build_module = cx.pipelines.module("penumbra map", build_shader());
            let build_layout = min_target::layout(cx, "penumbra map");
            let vertex = ("vs_cone", VERTEX_LAYOUT);
            let build = min_target::pipeline(cx, "penumbra map", &build_module, &build_layout, vertex, "fs_penumbra");
            let query_module = cx.pipelines.module("penumbra query", query_shader());
            let entry = FragmentEntry::from("fs_penumbra_query");
            let lookup = LookupParams { radius: 0.0, receiver_offset: self.depth.receiver_offset() };
            let query = MapQuery::with_entry(cx, &query_module, entry, &[depth_entry(4)]).with_lookup(lookup);
            let vertices = TransientRing::new("penumbra-map cones");
            State { map, build_layout, build, query, penumbra: None, vertices }
        })
    }

    fn build(&self, cx: &mut WgpuContext, state: &mut State, pass: LightPass<'_>) -> Result<(), WgpuError> {
        let LightPass { frame, light, stats, .. } = pass;
        let t0 = std::time::Instant::now();
        let (proj, built) = Self::construct(frame, light, stats)?;
        let construct = t0.elapsed();
        state.map.render(cx, frame, light, self.depth.resolution)?;
        let t0 = std::time::Instant::now();
        let maps = state.map.maps().ok_or_else(|| TechniqueError::NotBuilt(Self::NAME.into()))?.clone();
        cx.scoped("the penumbra map", |cx| state.render_penumbra(cx, &maps, proj, &built.triangles))?;
        stats.timings.extra.insert("penumbra_map".into(), shadow_core::stats::ms(construct + t0.elapsed()));
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
        let LightPass { light, .. } = pass;
        let (Some(maps), Some(penumbra)) = (state.map.maps(), &state.penumbra) else {
            return Err(TechniqueError::NotBuilt(Self::NAME.into()).into());
        };
        let view = layer_view(penumbra, 0);
        let entries = [wgpu::BindGroupEntry { binding: 4, resource: wgpu::BindingResource::TextureView(&view) }];
        let extras = QueryExtras { settings: [0.0; 4], entries: &entries };
        state.query.run(cx, maps, light, g, out, &extras)
    }

    fn debug_views(&self, cx: &mut WgpuContext, state: &State) -> Result<Vec<DebugView>, WgpuError> {
        let Some(penumbra) = &state.penumbra else { return Ok(Vec::new()) };
        Ok(super::debug_views(&readback::read_f32(cx, penumbra, 0, wgpu::TextureAspect::DepthOnly)?))
    }
}

/// The technique's shaders as compiled, by name (its registry entry's WGSL).
#[must_use]
pub fn shaders() -> Vec<(&'static str, String)> {
    vec![("penumbra map", build_shader()), ("penumbra query", query_shader())]
}

/// The WGSL of the penumbra map's pass.
#[must_use]
pub fn build_shader() -> String {
    include_str!("build.wgsl").to_string()
}

/// The WGSL of the query: the shadow-map shader, then the query.
#[must_use]
pub fn query_shader() -> String {
    shaders::with_shadow_map(include_str!("query.wgsl"))
}
