//! `volume-reconstruction` on the GPU (twin: volume_reconstruction/cpu.rs). As in the
//! paper (section 2): the light pass renders the depth maps, they are read back (timed as the build's
//! `depth_readback`), shadow-core reconstructs the boundary on the CPU, and it is uploaded as homogeneous
//! world triangles. The query draws them with the stencil's bit 0 inverted wherever a fragment is in front
//! of the G-buffer (both faces, one pass), then the near-plane caps with the depth test off, the stencil
//! starting at 1 where the cap inverts the whole view; the resolve marks pixels whose bit is set.
//!
//! With `ids` other than `off` the light pass also renders each caster's ID into an R32Uint layer per map,
//! read back with the depths (timed as `id_readback`).
//!
//! Counters come from occlusion queries: samples passing the parity pass (stencil updates), and, in a
//! second pass with the depth test off, every rasterized fragment (inside the query phase, timed as its
//! sub-phase `count_fragments` so it can be taken out).

use super::reconstruction::HomTriangle;
use super::reconstruction::projection::{
    Projection, caps_for_view, coverage_view, edge_view, reconstruct_projection, record_build,
};
use super::{ObjectIds, VolumeReconstruction};
use shadow_core::glam::Vec4;
use shadow_core::technique::LightPass;
use shadow_core::technique::{DebugView, ShadowTechnique, TechniqueError};

use shadow_wgpu::frame::{GpuVisibility, layered};
use shadow_wgpu::gbuffer::{GpuGBuffer, check_size};
use shadow_wgpu::passes::maps::{
    ID_FORMAT, LightPipelines, depth_bias, light_id_pipeline, light_pass_pipeline, map_texture, render_maps,
};
use shadow_wgpu::passes::volumes::{StencilResolve, count_all, occlusion_query, read_query, volume_pipeline};
use shadow_wgpu::{WgpuBackend, WgpuContext, WgpuError};
use shadow_wgpu::{readback, shaders};

/// Pipelines, the maps and the reconstruction of the last build.
pub struct State {
    /// The light pass, with the ID target when `ids` is not `off`.
    light_pass: LightPipelines,
    /// Parity passes: the boundary with the depth test, the caps without.
    boundary: wgpu::RenderPipeline,
    caps: wgpu::RenderPipeline,
    /// The same with the stencil off and the depth test off, for the fragment count.
    count_boundary: wgpu::RenderPipeline,
    count_caps: wgpu::RenderPipeline,
    /// The same with the stencil counting every fragment, for the volume debug view.
    coverage_boundary: wgpu::RenderPipeline,
    coverage_caps: wgpu::RenderPipeline,
    resolve: StencilResolve,
    maps: Option<wgpu::Texture>,
    /// The ID layers, when `ids` is not `off`.
    ids: Option<wgpu::Texture>,
    projections: Vec<Projection>,
    /// The boundary's vertices and their count.
    boundary_vertices: Option<(wgpu::Buffer, u32)>,
    /// The last query's view, size and caps, for the volume debug view.
    last_view: Option<LastView>,
}

struct LastView {
    group: wgpu::BindGroup,
    width: u32,
    height: u32,
    caps: Option<(wgpu::Buffer, u32)>,
}

/// Bit 0 inverted on every fragment that passes `depth_compare`, both faces (in `format`).
fn parity(format: wgpu::TextureFormat, depth_compare: wgpu::CompareFunction) -> wgpu::DepthStencilState {
    let face = wgpu::StencilFaceState {
        compare: wgpu::CompareFunction::Always,
        fail_op: wgpu::StencilOperation::Keep,
        depth_fail_op: wgpu::StencilOperation::Keep,
        pass_op: wgpu::StencilOperation::Invert,
    };
    wgpu::DepthStencilState {
        format,
        depth_write_enabled: Some(false),
        depth_compare: Some(depth_compare),
        stencil: wgpu::StencilState { front: face, back: face, read_mask: 1, write_mask: 1 },
        bias: Default::default(),
    }
}

/// Every fragment counted in the stencil (clamped at 255), both faces, the depth test off (in `format`).
fn coverage(format: wgpu::TextureFormat) -> wgpu::DepthStencilState {
    let face = wgpu::StencilFaceState {
        compare: wgpu::CompareFunction::Always,
        fail_op: wgpu::StencilOperation::Keep,
        depth_fail_op: wgpu::StencilOperation::Keep,
        pass_op: wgpu::StencilOperation::IncrementClamp,
    };
    wgpu::DepthStencilState {
        stencil: wgpu::StencilState { front: face, back: face, read_mask: 0xff, write_mask: 0xff },
        ..count_all(format)
    }
}

fn vertex_buffer(cx: &WgpuContext, label: &str, triangles: &[HomTriangle]) -> Option<(wgpu::Buffer, u32)> {
    if triangles.is_empty() {
        return None;
    }
    let vertices: Vec<Vec4> = triangles.iter().flatten().copied().collect();
    let buffer = cx.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some(label),
        contents: bytemuck::cast_slice(&vertices),
        usage: wgpu::BufferUsages::VERTEX,
    });
    Some((buffer, vertices.len() as u32))
}

impl ShadowTechnique<WgpuBackend> for VolumeReconstruction {
    type State = State;

    fn name(&self) -> &'static str {
        Self::NAME
    }

    fn create_state(&self, cx: &mut WgpuContext) -> Result<State, WgpuError> {
        cx.scoped("creating the volume-reconstruction pipelines", |cx| {
            let maps = cx.pipelines.module("shadow_map", shaders::shadow_map());
            let module = cx.pipelines.module("volume_reconstruction", shader());
            let (ccw, ds) = (wgpu::FrontFace::Ccw, cx.depth_stencil);
            State {
                light_pass: if self.ids == ObjectIds::Off {
                    light_pass_pipeline(cx, &maps, depth_bias(&self.depth))
                } else {
                    light_id_pipeline(cx, &maps, depth_bias(&self.depth))
                },
                boundary: volume_pipeline(cx, &module, "vs_boundary", ccw, parity(ds, wgpu::CompareFunction::Less)),
                caps: volume_pipeline(cx, &module, "vs_cap", ccw, parity(ds, wgpu::CompareFunction::Always)),
                count_boundary: volume_pipeline(cx, &module, "vs_boundary", ccw, count_all(ds)),
                count_caps: volume_pipeline(cx, &module, "vs_cap", ccw, count_all(ds)),
                coverage_boundary: volume_pipeline(cx, &module, "vs_boundary", ccw, coverage(ds)),
                coverage_caps: volume_pipeline(cx, &module, "vs_cap", ccw, coverage(ds)),
                resolve: StencilResolve::new(cx, &module, 1),
                maps: None,
                ids: None,
                projections: Vec::new(),
                boundary_vertices: None,
                last_view: None,
            }
        })
    }

    fn build(&self, cx: &mut WgpuContext, state: &mut State, pass: LightPass<'_>) -> Result<(), WgpuError> {
        let LightPass { frame, light, stats, .. } = pass;
        let res = self.depth.resolution;
        check_size(cx, "depth map", res, res)?;
        let view = light.with_seamless_faces(res);
        let layers = view.projections.len() as u32;
        let fits = state.maps.as_ref().is_some_and(|m| m.width() == res && m.depth_or_array_layers() == layers);
        if !fits {
            state.maps = Some(cx.scoped("allocating depth maps", |cx| map_texture(cx, res, layers))?);
            state.ids = None;
        }
        if self.ids != ObjectIds::Off && state.ids.is_none() {
            state.ids =
                Some(cx.scoped("allocating ID maps", |cx| layered(cx, "light IDs", res, res, layers, ID_FORMAT))?);
        }
        let maps = state.maps.clone().ok_or_else(|| TechniqueError::NotBuilt(Self::NAME.into()))?;
        let id_maps = state.ids.clone();
        cx.upload_meshes(frame);
        cx.upload_textures(frame)?;
        let instances = cx.instances(frame);
        cx.scoped("the light pass", |cx| {
            render_maps(cx, &state.light_pass, frame, &view, &maps, id_maps.as_ref(), &instances);
        })?;
        let t = std::time::Instant::now();
        let depths = (0..layers)
            .map(|k| readback::read_f32(cx, &maps, k, wgpu::TextureAspect::DepthOnly))
            .collect::<Result<Vec<_>, _>>()?;
        stats.timings.extra.insert("depth_readback".into(), shadow_core::stats::ms(t.elapsed()));
        let ids = match &id_maps {
            Some(tex) => {
                let t = std::time::Instant::now();
                let ids = (0..layers).map(|k| readback::read_u32(cx, tex, k)).collect::<Result<Vec<_>, _>>()?;
                stats.timings.extra.insert("id_readback".into(), shadow_core::stats::ms(t.elapsed()));
                ids
            }
            None => Vec::new(),
        };
        state.projections = view
            .projections
            .iter()
            .enumerate()
            .map(|(k, &p)| reconstruct_projection(self, &view, p, &depths[k], ids.get(k)))
            .collect();
        record_build(&state.projections, stats);
        let triangles: Vec<HomTriangle> = state.projections.iter().flat_map(|p| p.triangles.iter().copied()).collect();
        state.boundary_vertices =
            cx.scoped("uploading the boundary", |cx| vertex_buffer(cx, "boundary", &triangles))?;
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
        let LightPass { stats, .. } = pass;
        if state.projections.is_empty() {
            return Err(TechniqueError::NotBuilt(Self::NAME.into()).into());
        }
        let eye = g.camera.clip_from_world(g.width as f32 / g.height as f32);
        let (invert, caps) =
            if self.capping.is_on() { caps_for_view(&state.projections, eye) } else { (false, Vec::new()) };
        let cap_vertices = cx.scoped("uploading the caps", |cx| vertex_buffer(cx, "caps", &caps))?;
        let draws = [(&state.boundary_vertices, &state.boundary), (&cap_vertices, &state.caps)];
        let depth = g.depth_view();
        let passed = cx.scoped("the parity pass", |cx| {
            let q = parity_pass(cx, g, &depth, &draws, Some(u32::from(invert)));
            state.resolve.run(cx, g, out, &depth);
            q
        })?;
        if !cx.instrumented() {
            return Ok(());
        }
        cx.end_of_work();
        let passed = read_query(cx, Some(&passed))?;
        // Every rasterized fragment, after the resolve so it cannot disturb it, timed on its own.
        let t = std::time::Instant::now();
        let counting = [(&state.boundary_vertices, &state.count_boundary), (&cap_vertices, &state.count_caps)];
        let all = cx.scoped("the fragment count", |cx| parity_pass(cx, g, &depth, &counting, None))?;
        let all = read_query(cx, Some(&all))?;
        stats.timings.extra.insert("count_fragments".into(), shadow_core::stats::ms(t.elapsed()));
        let boundary = state.projections.iter().map(|p| p.triangles.len()).sum::<usize>();
        let c = &mut stats.counters;
        c.volume_triangles = Some((boundary + caps.len()) as u64);
        c.volume_fragments = Some(all);
        c.stencil_updates = Some(passed);
        c.extra.insert("cap_triangles".into(), caps.len() as f64);
        c.extra.insert("cap_inverted".into(), f64::from(u8::from(invert)));
        state.last_view =
            Some(LastView { group: g.frame_group.clone(), width: g.width, height: g.height, caps: cap_vertices });
        Ok(())
    }

    fn debug_views(&self, cx: &mut WgpuContext, state: &State) -> Result<Vec<DebugView>, WgpuError> {
        let mut views: Vec<DebugView> = state
            .projections
            .iter()
            .enumerate()
            .map(|(k, p)| DebugView { name: format!("edges{k}"), image: edge_view(&p.samples, &p.mesh_edges) })
            .collect();
        if let Some(last) = &state.last_view {
            let counts = cx.scoped("the volume view", |cx| coverage_counts(cx, state, last))??;
            views.push(DebugView { name: "volume".into(), image: coverage_view(&counts) });
        }
        Ok(views)
    }
}

/// How many boundary and cap triangles cover each pixel of the last query's view (twin: cpu.rs's
/// `volume_view`), counted in the stencil of a scratch depth-stencil target and read back.
fn coverage_counts(cx: &WgpuContext, state: &State, last: &LastView) -> Result<shadow_core::Image<u8>, WgpuError> {
    let target = cx.create_texture(&wgpu::TextureDescriptor {
        label: Some("volume view"),
        size: wgpu::Extent3d { width: last.width, height: last.height, depth_or_array_layers: 1 },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: cx.depth_stencil,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
        view_formats: &[],
    });
    let view = target.create_view(&wgpu::TextureViewDescriptor::default());
    let mut enc = cx.encoder("volume view");
    {
        let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("volume view"),
            color_attachments: &[],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &view,
                depth_ops: Some(wgpu::Operations { load: wgpu::LoadOp::Clear(1.0), store: wgpu::StoreOp::Store }),
                stencil_ops: Some(wgpu::Operations { load: wgpu::LoadOp::Clear(0), store: wgpu::StoreOp::Store }),
            }),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_bind_group(0, &last.group, &[]);
        for (vertices, pipeline) in
            [(&state.boundary_vertices, &state.coverage_boundary), (&last.caps, &state.coverage_caps)]
        {
            if let Some((buffer, count)) = vertices {
                pass.set_pipeline(pipeline);
                pass.set_vertex_buffer(0, buffer.slice(..));
                pass.draw(0..*count, 0..1);
            }
        }
    }
    cx.submit(enc);
    readback::read_stencil(cx, &target)
}

type Draw<'a> = (&'a Option<(wgpu::Buffer, u32)>, &'a wgpu::RenderPipeline);

/// The draws in one pass inside an occlusion query; `clear` starts the stencil at that value (else it is
/// kept).
fn parity_pass(
    cx: &WgpuContext,
    g: &GpuGBuffer,
    depth: &wgpu::TextureView,
    draws: &[Draw<'_>],
    clear: Option<u32>,
) -> (wgpu::QuerySet, wgpu::Buffer) {
    let (set, resolve) = occlusion_query(cx);
    let mut enc = cx.encoder("parity");
    {
        let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("parity"),
            color_attachments: &[],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: depth,
                depth_ops: Some(wgpu::Operations { load: wgpu::LoadOp::Load, store: wgpu::StoreOp::Store }),
                stencil_ops: Some(wgpu::Operations {
                    load: clear.map_or(wgpu::LoadOp::Load, wgpu::LoadOp::Clear),
                    store: wgpu::StoreOp::Store,
                }),
            }),
            timestamp_writes: None,
            occlusion_query_set: Some(&set),
            multiview_mask: None,
        });
        pass.set_bind_group(0, &g.frame_group, &[]);
        pass.begin_occlusion_query(0);
        for (vertices, pipeline) in draws {
            if let Some((buffer, count)) = vertices {
                pass.set_pipeline(pipeline);
                pass.set_vertex_buffer(0, buffer.slice(..));
                pass.draw(0..*count, 0..1);
            }
        }
        pass.end_occlusion_query();
    }
    enc.resolve_query_set(&set, 0..1, &resolve, 0);
    cx.submit(enc);
    (set, resolve)
}

/// The technique's shaders as compiled, by name (its registry entry's WGSL).
#[must_use]
pub fn shaders() -> Vec<(&'static str, String)> {
    vec![("volume reconstruction", shader())]
}

/// The boundary and cap passes, after the shadow-volume shader (its resolve).
#[must_use]
pub fn shader() -> String {
    format!("{}\n{}", shaders::shadow_volume(), include_str!("boundary.wgsl"))
}
