//! The camera G-buffer on the GPU: the context's depth-stencil format plus world position (w: receives shadow),
//! shading normal and albedo (w: covered), all f32 so shading matches the CPU's.

use std::ops::Range;

use shadow_core::frame::{Coverage, Surfaces};
use shadow_core::glam::Vec3;
use shadow_core::scene::Camera;
use shadow_core::{FrameInputs, Image};

use crate::context::{WgpuContext, WgpuError};
use crate::pipelines::{ATTRIBUTE, FaceCull, ViewRaw};
use crate::textures::read_texture;

/// The camera view of a frame, on the GPU.
pub struct GpuGBuffer {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// The camera.
    pub camera: Camera,
    /// Depth and stencil.
    pub depth: wgpu::Texture,
    /// World position, w = receives shadow.
    pub position: wgpu::TextureView,
    /// Shading normal.
    pub normal: wgpu::TextureView,
    /// Unit face normal, turned towards the viewer.
    pub geometric_normal: wgpu::TextureView,
    /// Albedo, w = covered.
    pub albedo: wgpu::TextureView,
    /// Group 0 for the camera view.
    pub frame_group: wgpu::BindGroup,
}

impl GpuGBuffer {
    /// A view of the depth-stencil texture.
    #[must_use]
    pub fn depth_view(&self) -> wgpu::TextureView {
        self.depth.create_view(&wgpu::TextureViewDescriptor::default())
    }
}

/// Largest view side, on top of the adapter's own limit.
pub const MAX_VIEW_SIDE: u32 = 16384;

/// Checks a view size against this backend's and the adapter's limits.
///
/// # Errors
/// [`WgpuError::BadSize`].
pub fn check_size(cx: &WgpuContext, what: &'static str, width: u32, height: u32) -> Result<(), WgpuError> {
    let limit = cx.device.limits().max_texture_dimension_2d.min(MAX_VIEW_SIDE);
    let why = if width == 0 || height == 0 {
        "a side is zero".to_string()
    } else if width > limit || height > limit {
        format!("a side is over the limit of {limit}")
    } else {
        return Ok(());
    };
    Err(WgpuError::BadSize { what, width: u64::from(width), height: u64::from(height), why })
}

fn target(cx: &WgpuContext, label: &str, w: u32, h: u32, format: wgpu::TextureFormat) -> wgpu::Texture {
    cx.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d { width: w, height: h, depth_or_array_layers: 1 },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT
            | wgpu::TextureUsages::TEXTURE_BINDING
            | wgpu::TextureUsages::COPY_SRC,
        view_formats: &[],
    })
}

/// The G-buffer's targets, kept from frame to frame while the view's size stays: a frame then allocates
/// none of them.
#[derive(Clone)]
pub(crate) struct GBufferTargets {
    width: u32,
    height: u32,
    depth: wgpu::Texture,
    /// Position, normal, albedo, geometric normal.
    attributes: [wgpu::TextureView; 4],
}

impl GBufferTargets {
    fn new(cx: &WgpuContext, width: u32, height: u32) -> Self {
        Self {
            width,
            height,
            depth: target(cx, "depth", width, height, cx.depth_stencil),
            attributes: ["position", "normal", "albedo", "geometric normal"]
                .map(|l| target(cx, l, width, height, ATTRIBUTE).create_view(&Default::default())),
        }
    }
}

/// Renders the G-buffer of a frame, into the targets of the frame before when its view had this size.
///
/// # Errors
/// A bad size or a GPU failure.
pub fn render(cx: &mut WgpuContext, frame: &FrameInputs, width: u32, height: u32) -> Result<GpuGBuffer, WgpuError> {
    fill(cx, frame, (width, height), "the G-buffer pass", |cx, pass| {
        for cull in FaceCull::ALL {
            let here = |i: &shadow_core::Instance| FaceCull::of(i) == cull;
            pass.set_pipeline(&cx.shared.gbuffer[cull.index()]);
            let untextured = |i: &shadow_core::Instance| read_texture(i).is_none() && i.coverage() != Coverage::Absent;
            draw_instances(cx, pass, frame, |i| here(i) && untextured(i), true);
            pass.set_pipeline(&cx.shared.gbuffer_textured[cull.index()]);
            draw_textured(cx, pass, frame, here, true);
        }
    })
}

/// Renders the G-buffer of a frame and reads it back: the surface each pixel shows on this backend, for
/// measuring its results at its own points.
///
/// # Errors
/// A bad size or a GPU failure.
pub fn read(cx: &mut WgpuContext, frame: &FrameInputs, width: u32, height: u32) -> Result<Surfaces, WgpuError> {
    let g = render(cx, frame, width, height)?;
    let read = |view: &wgpu::TextureView| crate::readback::read_rgba32(cx, view.texture());
    let (position, albedo) = (read(&g.position)?, read(&g.albedo)?);
    let xyz = |image: Image<[f32; 4]>| image.map(|&[x, y, z, _]| Vec3::new(x, y, z));
    let flag = |image: &Image<[f32; 4]>| image.map(|v| v[3] > 0.0);
    Ok(Surfaces {
        receiver: flag(&position),
        covered: flag(&albedo),
        position: xyz(position),
        albedo: xyz(albedo),
        normal: xyz(read(&g.normal)?),
        geometric_normal: xyz(read(&g.geometric_normal)?),
    })
}

/// What an engine that renders its own depth and normals lends a recorded frame in place of the G-buffer
/// pass ([`crate::FrameRecorder::record_visibility`]).
///
/// Shadow volumes count against this depth: their near caps lie on the surfaces exactly only where the
/// engine rasterized with shadowlab's transform (`clip_from_world * world_from_local`, as its G-buffer
/// does) and the depth is kept as f32 on both sides (Depth32FloatStencil8 on shadowlab's context: a
/// 24-bit depth read and written again may come back a unit off); elsewhere a lit surface facing the
/// light may count its own cap.
pub struct HostSurfaces<'a> {
    /// The camera's depth as the frame's camera projects it, 1 where nothing was drawn: a view of a
    /// `Depth32Float` texture, or the depth aspect of a depth-stencil one.
    pub depth: &'a wgpu::TextureView,
    /// Unit world-space normals in rgb: a view of a float texture (`Rgba16Float`, `Rgba32Float`, ...).
    pub normals: &'a wgpu::TextureView,
    /// The view's width in pixels, the two textures' too.
    pub width: u32,
    /// Its height.
    pub height: u32,
}

/// The pass that turns a host's depth and normals into the G-buffer (`import.wgsl`).
pub struct ImportPass {
    pipeline: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
}

impl ImportPass {
    /// The pipeline.
    #[must_use]
    pub fn new(cx: &WgpuContext) -> Self {
        use crate::pipelines::{attribute_entry, buffer_entry, depth_entry};
        let layout = cx.pipelines.group_layout(
            "host surfaces",
            &[
                depth_entry(0),
                attribute_entry(1),
                buffer_entry(2, wgpu::BufferBindingType::Uniform, wgpu::ShaderStages::FRAGMENT),
            ],
        );
        let module = cx.pipelines.module("import", crate::shaders::import());
        let target =
            Some(wgpu::ColorTargetState { format: ATTRIBUTE, blend: None, write_mask: wgpu::ColorWrites::ALL });
        let depth = wgpu::DepthStencilState {
            format: cx.depth_stencil,
            depth_write_enabled: Some(true),
            depth_compare: Some(wgpu::CompareFunction::Always),
            stencil: Default::default(),
            bias: Default::default(),
        };
        let pipeline = crate::pipelines::full_screen_pipeline_to(
            &cx.pipelines,
            ("host surfaces", &module, "fs_import".into()),
            &[&cx.shared.frame_layout, &layout],
            &[target.clone(), target.clone(), target.clone(), target],
            Some(depth),
        );
        Self { pipeline, layout }
    }
}

/// The G-buffer of a frame from a host's depth and normals (`pass`): world positions from the depth
/// through the camera, the normals as both the shading and the face normal (turned towards the eye),
/// a white albedo, every covered pixel a receiver.
///
/// # Errors
/// A bad size or a GPU failure.
pub fn import(
    cx: &mut WgpuContext,
    frame: &FrameInputs,
    host: &HostSurfaces<'_>,
    pass: &ImportPass,
) -> Result<GpuGBuffer, WgpuError> {
    let (width, height) = (host.width, host.height);
    fill(cx, frame, (width, height), "the host surfaces' import", |cx, render| {
        // Made once the frame's transient data has started over, which the fill does first.
        let clip_from_world = frame.camera.clip_from_world(width as f32 / height as f32);
        let world_from_clip = cx.transient(bytemuck::bytes_of(&clip_from_world.inverse().to_cols_array()));
        let group = cx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("host surfaces"),
            layout: &pass.layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: wgpu::BindingResource::TextureView(host.depth) },
                wgpu::BindGroupEntry { binding: 1, resource: wgpu::BindingResource::TextureView(host.normals) },
                wgpu::BindGroupEntry { binding: 2, resource: world_from_clip.binding() },
            ],
        });
        render.set_pipeline(&pass.pipeline);
        render.set_bind_group(1, &group, &[]);
        render.draw(0..3, 0..1);
    })
}

/// Fills the G-buffer's targets (those of the frame before when its view had this size, cleared) in one
/// pass that `draw` records, with the camera's group 0 bound.
fn fill(
    cx: &mut WgpuContext,
    frame: &FrameInputs,
    (width, height): (u32, u32),
    during: &str,
    draw: impl FnOnce(&WgpuContext, &mut wgpu::RenderPass<'_>),
) -> Result<GpuGBuffer, WgpuError> {
    check_size(cx, "view", width, height)?;
    // A frame begins with its G-buffer: its transient data starts over.
    cx.begin_transient();
    cx.upload_meshes(frame);
    cx.upload_textures(frame)?;
    let instances = cx.instances(frame);
    let targets = match cx.gbuffer_targets.take() {
        Some(t) if (t.width, t.height) == (width, height) => t,
        _ => GBufferTargets::new(cx, width, height),
    };
    cx.gbuffer_targets = Some(targets.clone());
    cx.scoped(during, |cx| {
        let clip_from_world = frame.camera.clip_from_world(width as f32 / height as f32);
        let view = ViewRaw::new(clip_from_world, frame.camera.eye, width, height);
        let frame_group = cx.shared.frame_group(cx, &view, &instances);
        let GBufferTargets { depth, attributes: [position, normal, albedo, geometric_normal], .. } = targets;
        let depth_view = depth.create_view(&Default::default());
        let mut enc = cx.encoder("gbuffer");
        {
            let clear = |v| {
                Some(wgpu::RenderPassColorAttachment {
                    view: v,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                        store: wgpu::StoreOp::Store,
                    },
                })
            };
            let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("gbuffer"),
                color_attachments: &[clear(&position), clear(&normal), clear(&albedo), clear(&geometric_normal)],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &depth_view,
                    depth_ops: Some(wgpu::Operations { load: wgpu::LoadOp::Clear(1.0), store: wgpu::StoreOp::Store }),
                    stencil_ops: Some(wgpu::Operations { load: wgpu::LoadOp::Clear(0), store: wgpu::StoreOp::Store }),
                }),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.push_debug_group("gbuffer");
            pass.set_bind_group(0, &frame_group, &[]);
            draw(cx, &mut pass);
            pass.pop_debug_group();
        }
        cx.submit(enc);
        GpuGBuffer {
            width,
            height,
            camera: frame.camera,
            depth,
            position,
            normal,
            albedo,
            geometric_normal,
            frame_group,
        }
    })
}

/// Draws every instance whose material reads a texture ([`read_texture`]) and that passes `keep`, with
/// its own mesh, its texture coordinates in the slot after the positions (and the normals, with
/// `normals`) and its texture's group as group 2: one instanced draw a run of the [`DrawOrder`]
/// (instance index = slot).
///
/// [`DrawOrder`]: crate::draw_order::DrawOrder
pub fn draw_textured(
    cx: &WgpuContext,
    pass: &mut wgpu::RenderPass<'_>,
    frame: &FrameInputs,
    keep: impl Fn(&shadow_core::Instance) -> bool,
    normals: bool,
) {
    for (i, slots) in cx.cache.order().runs(frame, |i| keep(i) && read_texture(i).is_some()) {
        let inst = &frame.instances[i];
        let Some(texture) = read_texture(inst).and_then(|t| cx.cache.textures.get(t)) else { continue };
        let Some((m, uvs)) = cx.cache.mesh(inst).and_then(|m| Some((m, m.uvs?))) else { continue };
        pass.set_bind_group(2, &texture.group, &[]);
        pass.set_vertex_buffer(if normals { 2 } else { 1 }, uvs.slice(..));
        draw_mesh(pass, m, slots, normals);
    }
}

/// Draws every instance that passes `keep` with its own mesh: one instanced draw a run of the
/// [`DrawOrder`] (instance index = slot).
///
/// [`DrawOrder`]: crate::draw_order::DrawOrder
pub fn draw_instances(
    cx: &WgpuContext,
    pass: &mut wgpu::RenderPass<'_>,
    frame: &FrameInputs,
    keep: impl Fn(&shadow_core::Instance) -> bool,
    normals: bool,
) {
    for (i, slots) in cx.cache.order().runs(frame, keep) {
        let Some(m) = cx.cache.mesh(&frame.instances[i]) else { continue };
        draw_mesh(pass, m, slots, normals);
    }
}

/// Draws mesh `m` as the instances in `slots`: its positions in slot 0 (and its normals in slot 1, with
/// `normals`).
fn draw_mesh(pass: &mut wgpu::RenderPass<'_>, m: crate::upload::MeshView<'_>, slots: Range<u32>, normals: bool) {
    pass.set_vertex_buffer(0, m.positions.slice(..));
    if normals {
        pass.set_vertex_buffer(1, m.normals.slice(..));
    }
    pass.set_index_buffer(m.indices.slice(..), wgpu::IndexFormat::Uint32);
    pass.draw_indexed(0..m.index_count, 0, slots);
}
