//! Stencil shadow volumes on the GPU (twin: shadow-cpu's `passes::volumes`). The volumes come from the
//! shared CPU geometry, uploaded per frame; near caps are drawn from the mesh's own vertex buffer with the
//! G-buffer's clip transform, so their depths match the G-buffer's exactly. Two-sided stencil with
//! wrapping ops counts; a full-screen pass with the stencil test "count != 0" writes the shadowed
//! receivers. Occlusion queries count what a pass rasterizes.

use shadow_core::FrameInputs;
use shadow_core::frame::InstanceVolume;
use shadow_core::geometry::volume::Caps;
use shadow_core::geometry::volume::VolumeCounting;
use shadow_core::light::LightView;
use shadow_core::technique::FrameStats;

use crate::context::{WgpuContext, WgpuError};
use crate::frame::GpuVisibility;
use crate::gbuffer::GpuGBuffer;
use crate::pipelines::{POSITION_LAYOUT, VISIBILITY, attribute_entry, full_screen_pipeline};
use crate::resources::Transient;

/// One draw of volume geometry: vertices, optional indices, instance, winding.
pub struct VolumeDraw {
    vertices: Option<Transient>,
    indices: Option<(Transient, u32)>,
    count: u32,
    /// The instance's index in the frame.
    instance: u32,
    /// Front faces wind clockwise (a mirrored instance, or faces cast turned around).
    cw: bool,
    /// Use the instance's mesh vertex buffer (near caps).
    mesh_vertices: bool,
}

/// The depth-stencil state (in `format`, the context's `depth_stencil`) of a volume pass counting
/// `counting`'s way with wrapping ops in the bits of `write_mask`, on the fragments whose stencil passes
/// `test` against the reference under `read_mask`; the depth test `Less`, no depth writes.
pub fn counting_state(
    format: wgpu::TextureFormat,
    counting: VolumeCounting,
    test: wgpu::CompareFunction,
    read_mask: u32,
    write_mask: u32,
) -> wgpu::DepthStencilState {
    use wgpu::StencilOperation as Op;
    let face =
        |pass_op, depth_fail_op| wgpu::StencilFaceState { compare: test, fail_op: Op::Keep, depth_fail_op, pass_op };
    let (front, back) = match counting {
        VolumeCounting::ZPass => (face(Op::IncrementWrap, Op::Keep), face(Op::DecrementWrap, Op::Keep)),
        VolumeCounting::ZFail => (face(Op::Keep, Op::DecrementWrap), face(Op::Keep, Op::IncrementWrap)),
    };
    wgpu::DepthStencilState {
        format,
        depth_write_enabled: Some(false),
        depth_compare: Some(wgpu::CompareFunction::Less),
        stencil: wgpu::StencilState { front, back, read_mask, write_mask },
        bias: Default::default(),
    }
}

/// Every fragment passes, nothing written (in `format`, the context's `depth_stencil`): for counting what
/// a pass rasterizes (occlusion queries).
pub fn count_all(format: wgpu::TextureFormat) -> wgpu::DepthStencilState {
    wgpu::DepthStencilState {
        format,
        depth_write_enabled: Some(false),
        depth_compare: Some(wgpu::CompareFunction::Always),
        stencil: Default::default(),
        bias: Default::default(),
    }
}

/// The volumes' whole fill: [`count_all`] over the volume vertices (both faces; it does not cull).
pub fn count_all_pipeline(cx: &WgpuContext, module: &wgpu::ShaderModule) -> wgpu::RenderPipeline {
    volume_pipeline(cx, module, "vs_volume", wgpu::FrontFace::Ccw, count_all(cx.depth_stencil))
}

/// A stencil-only pipeline drawing homogeneous points through `entry` (both faces).
pub fn volume_pipeline(
    cx: &WgpuContext,
    module: &wgpu::ShaderModule,
    entry: &str,
    front_face: wgpu::FrontFace,
    depth_stencil: wgpu::DepthStencilState,
) -> wgpu::RenderPipeline {
    let vertex = StencilVertex { module, entry, groups: &[&cx.shared.frame_layout], buffers: &[Some(POSITION_LAYOUT)] };
    stencil_pipeline(cx, &vertex, front_face, depth_stencil)
}

/// The vertex stage of a stencil-only pipeline: its entry, the bind groups its layout holds and its
/// vertex buffers.
pub struct StencilVertex<'a> {
    /// The module.
    pub module: &'a wgpu::ShaderModule,
    /// The vertex entry point.
    pub entry: &'a str,
    /// The layouts of bind groups 0, 1, ...
    pub groups: &'a [&'a wgpu::BindGroupLayout],
    /// The vertex buffers.
    pub buffers: &'a [Option<wgpu::VertexBufferLayout<'a>>],
}

/// A pipeline with no fragment stage drawing both faces through `vertex`, `front_face` deciding which
/// face the stencil's front ops apply to.
pub fn stencil_pipeline(
    cx: &WgpuContext,
    vertex: &StencilVertex<'_>,
    front_face: wgpu::FrontFace,
    depth_stencil: wgpu::DepthStencilState,
) -> wgpu::RenderPipeline {
    let groups: Vec<Option<&wgpu::BindGroupLayout>> = vertex.groups.iter().copied().map(Some).collect();
    let layout = cx.pipelines.layout(vertex.entry, &groups);
    cx.pipelines.render(&wgpu::RenderPipelineDescriptor {
        label: Some(vertex.entry),
        layout: Some(&layout),
        vertex: wgpu::VertexState {
            module: vertex.module,
            entry_point: Some(vertex.entry),
            compilation_options: Default::default(),
            buffers: vertex.buffers,
        },
        primitive: wgpu::PrimitiveState { front_face, cull_mode: None, ..Default::default() },
        depth_stencil: Some(depth_stencil),
        multisample: Default::default(),
        fragment: None,
        multiview_mask: None,
        cache: None,
    })
}

/// The resolve both stencil techniques share: a full-screen pass that writes 0 (shadowed) to the receivers
/// whose stencil, under `read_mask`, is not 0.
pub struct StencilResolve {
    pipeline: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
}

impl StencilResolve {
    /// The pipeline, from a module holding shadow_volume.wgsl's `fs_volume_resolve`.
    pub fn new(cx: &WgpuContext, module: &wgpu::ShaderModule, read_mask: u32) -> Self {
        let layout = cx.pipelines.group_layout("stencil resolve", &[attribute_entry(0)]);
        let test = wgpu::StencilFaceState { compare: wgpu::CompareFunction::NotEqual, ..Default::default() };
        let state = wgpu::DepthStencilState {
            format: cx.depth_stencil,
            depth_write_enabled: Some(false),
            depth_compare: Some(wgpu::CompareFunction::Always),
            stencil: wgpu::StencilState { front: test, back: test, read_mask, write_mask: 0 },
            bias: Default::default(),
        };
        let pipeline = full_screen_pipeline(
            &cx.pipelines,
            "stencil resolve",
            module,
            "fs_volume_resolve",
            &[&cx.shared.frame_layout, &layout],
            Some(VISIBILITY),
            Some(state),
        );
        Self { pipeline, layout }
    }

    /// Writes the visibility from the stencil of `depth` (G-buffer `g`'s depth-stencil).
    pub fn run(&self, cx: &WgpuContext, g: &GpuGBuffer, out: &GpuVisibility, depth: &wgpu::TextureView) {
        let group = self.group(cx, g);
        let groups = [&g.frame_group, &group];
        super::answer(cx, ("stencil resolve", out, super::LIT), &self.pipeline, &groups, Some((depth, 0)));
    }

    /// Shadows the receivers whose stencil is not 0 in the visibility `out` already holds (what another
    /// pass wrote there), leaving the others as they are: a receiver stays lit only where both say lit.
    pub fn run_onto(&self, cx: &WgpuContext, g: &GpuGBuffer, out: &GpuVisibility, depth: &wgpu::TextureView) {
        let group = self.group(cx, g);
        let groups = [&g.frame_group, &group];
        let target = ("stencil resolve", out, wgpu::LoadOp::Load);
        super::answer(cx, target, &self.pipeline, &groups, Some((depth, 0)));
    }

    fn group(&self, cx: &WgpuContext, g: &GpuGBuffer) -> wgpu::BindGroup {
        cx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("stencil resolve"),
            layout: &self.layout,
            entries: &[wgpu::BindGroupEntry { binding: 0, resource: wgpu::BindingResource::TextureView(&g.position) }],
        })
    }
}

/// A one-query occlusion set and the buffer it resolves into.
pub fn occlusion_query(cx: &WgpuContext) -> Query {
    let set = cx.device.create_query_set(&wgpu::QuerySetDescriptor {
        label: Some("fragments"),
        ty: wgpu::QueryType::Occlusion,
        count: 1,
    });
    let resolve = cx.create_buffer(&wgpu::BufferDescriptor {
        label: Some("occlusion"),
        size: 8,
        usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    (set, resolve)
}

/// Builds the volumes of `light`'s casters with `caps` (shared geometry), records their counters
/// (silhouette edges, volume triangles) and uploads them.
pub fn build_draws(
    cx: &mut WgpuContext,
    frame: &FrameInputs,
    light: &LightView,
    caps: Caps,
    stats: &mut FrameStats,
) -> Result<Vec<VolumeDraw>, WgpuError> {
    upload_draws(cx, frame, &frame.shadow_volumes(light, caps), stats)
}

/// [`build_draws`] from volumes already found (`hybrid` finds them with its edge maps' segments).
pub fn upload_draws(
    cx: &mut WgpuContext,
    frame: &FrameInputs,
    volumes: &[InstanceVolume],
    stats: &mut FrameStats,
) -> Result<Vec<VolumeDraw>, WgpuError> {
    InstanceVolume::count(volumes, &mut stats.counters);
    upload_volumes(cx, frame, volumes)
}

/// Uploads `volumes` (and the meshes their near caps are drawn from) without recording counters.
pub fn upload_volumes(
    cx: &mut WgpuContext,
    frame: &FrameInputs,
    volumes: &[InstanceVolume],
) -> Result<Vec<VolumeDraw>, WgpuError> {
    cx.upload_meshes(frame);
    cx.scoped("uploading shadow volumes", |cx| upload(cx, frame, volumes))
}

/// Uploads the volumes into the frame's transient buffer: sides and far caps as homogeneous vertices,
/// near caps as index lists into the mesh's own vertex buffer.
fn upload(cx: &WgpuContext, frame: &FrameInputs, volumes: &[InstanceVolume]) -> Vec<VolumeDraw> {
    let vbuf = |data: &[glam::Vec4]| cx.transient(bytemuck::cast_slice(data));
    let ibuf = |data: &[u32]| (cx.transient(bytemuck::cast_slice(data)), data.len() as u32);
    let mut draws = Vec::new();
    for iv in volumes {
        let inst = &frame.instances[iv.instance];
        let (instance, m) = (iv.instance as u32, inst.mirrored);
        let vol = &iv.volume;
        if !vol.sides.is_empty() {
            let sides: Vec<glam::Vec4> = vol.sides.iter().flatten().copied().collect();
            draws.push(VolumeDraw {
                vertices: Some(vbuf(&sides)),
                indices: None,
                count: sides.len() as u32,
                instance,
                cw: m,
                mesh_vertices: false,
            });
        }
        let tris = inst.mesh.triangles();
        let indices = |ids: &[u32], reverse: bool| -> Vec<u32> {
            ids.iter()
                .flat_map(|&f| {
                    let [a, b, c] = tris[f as usize];
                    if reverse { [a, c, b] } else { [a, b, c] }
                })
                .collect()
        };
        let far: Vec<glam::Vec4> = inst.mesh.positions().iter().map(|&p| vol.light.extrude(p)).collect();
        let far_buf = (!vol.caps_forward.is_empty() || !vol.caps_reversed.is_empty()).then(|| vbuf(&far));
        for (ids, near_cw, far_reverse) in [(&vol.caps_forward, m, true), (&vol.caps_reversed, !m, false)] {
            if ids.is_empty() {
                continue;
            }
            // Near caps in the mesh's own winding (turned-around faces drawn with clockwise fronts).
            let near = ibuf(&indices(ids, false));
            draws.push(VolumeDraw {
                vertices: None,
                count: near.1,
                indices: Some(near),
                instance,
                cw: near_cw,
                mesh_vertices: true,
            });
            // Far caps at infinity, forward faces reversed.
            let farc = ibuf(&indices(ids, far_reverse));
            draws.push(VolumeDraw {
                vertices: far_buf.clone(),
                count: farc.1,
                indices: Some(farc),
                instance,
                cw: m,
                mesh_vertices: false,
            });
        }
    }
    draws
}

/// One pass over every volume draw inside an occlusion query: the pipelines for either winding, how the
/// stencil starts and the stencil reference.
pub struct VolumePass<'a> {
    /// For debuggers.
    pub label: &'static str,
    /// The pipeline for counter-clockwise front faces.
    pub ccw: &'a wgpu::RenderPipeline,
    /// The pipeline for clockwise front faces.
    pub cw: &'a wgpu::RenderPipeline,
    /// Clear or keep the stencil.
    pub stencil: wgpu::LoadOp<u32>,
    /// The stencil reference the pipelines test against.
    pub reference: u32,
    /// Scissor rectangles `[x, y, width, height]` the draws are repeated in (hybrid's tiles), or `None`
    /// for the whole view.
    pub scissors: Option<&'a [[u32; 4]]>,
}

impl<'a> VolumePass<'a> {
    /// A counting pass: `pipeline` for both windings (it does not cull), the stencil kept.
    pub fn count(pipeline: &'a wgpu::RenderPipeline, label: &'static str) -> Self {
        Self { label, ccw: pipeline, cw: pipeline, stencil: wgpu::LoadOp::Load, reference: 0, scissors: None }
    }

    /// Draws `draws` over the depth-stencil `depth` of `g`; in an instrumented frame, returns an occlusion
    /// query of the samples that pass.
    pub fn run(
        &self,
        cx: &WgpuContext,
        draws: &[VolumeDraw],
        frame: &FrameInputs,
        g: &GpuGBuffer,
        depth: &wgpu::TextureView,
    ) -> Option<Query> {
        let query = cx.instrumented().then(|| occlusion_query(cx));
        let mut enc = cx.encoder(self.label);
        {
            let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some(self.label),
                color_attachments: &[],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: depth,
                    depth_ops: Some(wgpu::Operations { load: wgpu::LoadOp::Load, store: wgpu::StoreOp::Store }),
                    stencil_ops: Some(wgpu::Operations { load: self.stencil, store: wgpu::StoreOp::Store }),
                }),
                timestamp_writes: None,
                occlusion_query_set: query.as_ref().map(|q| &q.0),
                multiview_mask: None,
            });
            pass.push_debug_group(self.label);
            pass.set_bind_group(0, &g.frame_group, &[]);
            pass.set_stencil_reference(self.reference);
            if query.is_some() {
                pass.begin_occlusion_query(0);
            }
            let whole = [[0, 0, g.width, g.height]];
            for &[x, y, w, h] in self.scissors.unwrap_or(&whole) {
                pass.set_scissor_rect(x, y, w, h);
                for d in draws {
                    pass.set_pipeline(if d.cw { self.cw } else { self.ccw });
                    let mesh = frame.instances.get(d.instance as usize).and_then(|i| cx.cache.mesh(i));
                    let slot = cx.cache.order().slot(d.instance as usize);
                    match (&d.vertices, d.mesh_vertices, mesh) {
                        (Some(v), _, _) => pass.set_vertex_buffer(0, v.slice()),
                        (None, true, Some(m)) => pass.set_vertex_buffer(0, m.positions.slice(..)),
                        _ => continue,
                    }
                    match &d.indices {
                        Some((ib, n)) => {
                            pass.set_index_buffer(ib.slice(), wgpu::IndexFormat::Uint32);
                            pass.draw_indexed(0..*n, 0, slot..slot + 1);
                        }
                        None => pass.draw(0..d.count, slot..slot + 1),
                    }
                }
            }
            if query.is_some() {
                pass.end_occlusion_query();
            }
            pass.pop_debug_group();
        }
        if let Some((set, resolve)) = &query {
            enc.resolve_query_set(set, 0..1, resolve, 0);
        }
        cx.submit(enc);
        query
    }
}

/// An occlusion query and the buffer it resolves into.
pub type Query = (wgpu::QuerySet, wgpu::Buffer);

/// Reads an occlusion query's resolved count; a frame recorded into a host's encoder makes none.
///
/// # Errors
/// [`WgpuError::NotRecordable`] without a query, or a GPU failure.
pub fn read_query(cx: &WgpuContext, q: Option<&Query>) -> Result<u64, WgpuError> {
    let Some(q) = q else { return Err(WgpuError::NotRecordable { what: "an occlusion count".into() }) };
    let staging = cx.create_buffer(&wgpu::BufferDescriptor {
        label: Some("occlusion readback"),
        size: 8,
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    });
    let mut enc = cx.encoder("readback");
    enc.copy_buffer_to_buffer(&q.1, 0, &staging, 0, 8);
    cx.submit(enc);
    let d = crate::readback::map_read(cx, &staging, "reading an occlusion query")?;
    Ok(u64::from_le_bytes([d[0], d[1], d[2], d[3], d[4], d[5], d[6], d[7]]))
}
