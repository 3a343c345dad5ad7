//! `smoothies` on the wgpu backend, through its public API: `shadow-map`'s light pass for the blockers'
//! depth, two passes drawing the smoothies into the buffer (buffer.wgsl), and a query over the G-buffer
//! with `shadow-map`'s bindings and three of its own (query.wgsl). The smoothies themselves are built on
//! the CPU by the shared [`super::geometry`] and uploaded, as the thesis's host code built them.

use bytemuck::{Pod, Zeroable};
use shadow_core::light::LightProjection;
use shadow_core::technique::LightPass;
use shadow_core::technique::{DebugView, ShadowTechnique, TechniqueError};
use shadow_wgpu::frame::{layer_view, layered};
use shadow_wgpu::passes::maps::{DepthMaps, LookupParams, MapQuery, QueryExtras};
use shadow_wgpu::pipelines::{FragmentEntry, MAP_DEPTH, buffer_entry, depth_entry};
use shadow_wgpu::{GpuGBuffer, GpuVisibility, TransientRing, WgpuBackend, WgpuContext, WgpuError, readback, shaders};

use super::geometry::{Ramp, SmoothieTriangle};
use super::{FalloffTable, Smoothies};
use crate::min_target;

/// GPU twin of `BufferParams` in buffer.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct BufferParams {
    depth: [f32; 4],
    smoothie: [f32; 4],
}

/// One smoothie vertex: corner (u, v, depth), ramp kind, ramp data.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct SmoothieVertex {
    corner: [f32; 3],
    kind: f32,
    ramp: [f32; 4],
}

const VERTEX_LAYOUT: wgpu::VertexBufferLayout<'static> = wgpu::VertexBufferLayout {
    array_stride: std::mem::size_of::<SmoothieVertex>() as u64,
    step_mode: wgpu::VertexStepMode::Vertex,
    attributes: &wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32, 2 => Float32x4],
};

/// Pipelines, the blockers' map, the smoothie buffer of the last build.
pub struct State {
    map: DepthMaps,
    buffer_layout: wgpu::BindGroupLayout,
    depth_pass: wgpu::RenderPipeline,
    alpha_pass: wgpu::RenderPipeline,
    query: MapQuery,
    falloff: wgpu::Buffer,
    /// Nearest smoothie depth and minimum alpha, each a one-layer depth texture.
    buffer: Option<[wgpu::Texture; 2]>,
    /// The smoothies' vertices, each frame's (their number follows the silhouettes).
    vertices: TransientRing,
}

fn vertices(triangles: &[SmoothieTriangle]) -> Vec<SmoothieVertex> {
    triangles
        .iter()
        .flat_map(|tri| {
            let (kind, ramp) = match tri.ramp {
                Ramp::Edge { origin, outward } => (0.0, [origin.x, origin.y, outward.x, outward.y]),
                Ramp::Corner { vertex } => (1.0, [vertex.x, vertex.y, 0.0, 0.0]),
            };
            tri.corners.map(|c| SmoothieVertex { corner: c.to_array(), kind, ramp })
        })
        .collect()
}

impl State {
    /// Draws `triangles` into the buffer over `maps` (the blockers' depth) of projection `proj`.
    fn render_buffer(
        &mut self,
        cx: &WgpuContext,
        maps: &wgpu::Texture,
        proj: &LightProjection,
        triangles: &[SmoothieTriangle],
        (t, remap): (f32, bool),
    ) {
        let res = maps.width();
        if self.buffer.as_ref().is_none_or(|b| b[0].width() != res) {
            self.buffer = Some([0, 1].map(|_| layered(cx, "smoothie buffer", res, res, 1, MAP_DEPTH)));
        }
        let Some(buffer) = &self.buffer else { return };
        let params = BufferParams {
            depth: [proj.near, proj.far, f32::from(u8::from(proj.orthographic)), res as f32],
            smoothie: [t, f32::from(u8::from(remap)), 0.0, 0.0],
        };
        let group = min_target::bind(cx, &self.buffer_layout, "smoothie buffer", &params, maps);
        let data = vertices(triangles);
        let vertices = min_target::vertex_buffer(cx, &mut self.vertices, &data);
        let mut enc = cx.encoder("smoothies");
        for (target, pipeline) in buffer.iter().zip([&self.depth_pass, &self.alpha_pass]) {
            min_target::draw(&mut enc, target, pipeline, &group, vertices.as_ref());
        }
        cx.submit(enc);
    }
}

impl ShadowTechnique<WgpuBackend> for Smoothies {
    type State = State;

    fn name(&self) -> &'static str {
        Self::NAME
    }

    fn create_state(&self, cx: &mut WgpuContext) -> Result<State, WgpuError> {
        let map = DepthMaps::new(cx, &self.depth);
        let falloff = FalloffTable::new(self.falloff);
        cx.scoped("creating the smoothie pipelines", |cx| {
            let buffer_module = cx.pipelines.module("smoothie buffer", buffer_shader());
            let buffer_layout = min_target::layout(cx, "smoothie buffer");
            let pass = |entry| {
                let vertex = ("vs_smoothie", VERTEX_LAYOUT);
                min_target::pipeline(cx, "smoothie buffer", &buffer_module, &buffer_layout, vertex, entry)
            };
            let (depth_pass, alpha_pass) = (pass("fs_smoothie_depth"), pass("fs_smoothie_alpha"));
            let query_module = cx.pipelines.module("smoothie query", query_shader());
            let storage = wgpu::BufferBindingType::Storage { read_only: true };
            let extra = [depth_entry(4), depth_entry(5), buffer_entry(6, storage, wgpu::ShaderStages::FRAGMENT)];
            let lookup = LookupParams { radius: 0.0, receiver_offset: self.depth.receiver_offset() };
            let query = MapQuery::with_entry(cx, &query_module, FragmentEntry::from("fs_smoothie_query"), &extra)
                .with_lookup(lookup);
            let falloff = cx.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("smoothie falloff"),
                contents: bytemuck::cast_slice(falloff.samples()),
                usage: wgpu::BufferUsages::STORAGE,
            });
            let vertices = TransientRing::new("smoothie vertices");
            State { map, buffer_layout, depth_pass, alpha_pass, query, falloff, buffer: None, vertices }
        })
    }

    fn build(&self, cx: &mut WgpuContext, state: &mut State, pass: LightPass<'_>) -> Result<(), WgpuError> {
        let LightPass { frame, light, stats, .. } = pass;
        let proj = Self::projection(light)?;
        state.map.render(cx, frame, light, self.depth.resolution)?;
        let t0 = std::time::Instant::now();
        let (t, smoothies) = self.construct(frame, light, proj, stats);
        let maps = state.map.maps().ok_or_else(|| TechniqueError::NotBuilt(Self::NAME.into()))?.clone();
        cx.scoped("the smoothie buffer", |cx| {
            state.render_buffer(cx, &maps, proj, &smoothies.triangles, (t, self.remap.is_on()));
        })?;
        stats.timings.extra.insert("smoothies".into(), shadow_core::stats::ms(t0.elapsed()));
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
        let not_built = || TechniqueError::NotBuilt(Self::NAME.into());
        let (Some(maps), Some(buffer)) = (state.map.maps(), &state.buffer) else { return Err(not_built().into()) };
        let views = buffer.each_ref().map(|t| layer_view(t, 0));
        let entries = [
            wgpu::BindGroupEntry { binding: 4, resource: wgpu::BindingResource::TextureView(&views[0]) },
            wgpu::BindGroupEntry { binding: 5, resource: wgpu::BindingResource::TextureView(&views[1]) },
            wgpu::BindGroupEntry { binding: 6, resource: state.falloff.as_entire_binding() },
        ];
        let extras = QueryExtras { settings: [0.0; 4], entries: &entries };
        state.query.run(cx, maps, light, g, out, &extras)
    }

    fn debug_views(&self, cx: &mut WgpuContext, state: &State) -> Result<Vec<DebugView>, WgpuError> {
        let Some([depth, alpha]) = &state.buffer else { return Ok(Vec::new()) };
        let depth = readback::read_f32(cx, depth, 0, wgpu::TextureAspect::DepthOnly)?;
        let alpha = readback::read_f32(cx, alpha, 0, wgpu::TextureAspect::DepthOnly)?;
        Ok(super::debug_views(&depth, &alpha))
    }
}

/// The technique's shaders as compiled, by name (its registry entry's WGSL).
#[must_use]
pub fn shaders() -> Vec<(&'static str, String)> {
    vec![("smoothie buffer", buffer_shader()), ("smoothie query", query_shader())]
}

/// The WGSL of the smoothie buffer passes.
#[must_use]
pub fn buffer_shader() -> String {
    include_str!("buffer.wgsl").to_string()
}

/// The WGSL of the smoothie query: the shadow-map shader, then the query.
#[must_use]
pub fn query_shader() -> String {
    shaders::with_shadow_map(include_str!("query.wgsl"))
}
