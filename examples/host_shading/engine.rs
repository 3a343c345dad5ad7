//! The engine of the `host_shading` example: a small deferred renderer of its own (its G-buffer pass,
//! its shading pass, its WGSL) that takes from shadowlab only each light's visibility. Its depth and
//! normals go to [`FrameRecorder::record_visibility`](shadow_wgpu::FrameRecorder::record_visibility); its
//! shading reads the visibility through the WGSL module shadow-wgpu ships
//! ([`shadow_wgpu::host_wgsl::VISIBILITY`]), pasted before its own.

use bytemuck::Zeroable;
use glam::{Mat4, Vec3};
use shadow_core::image::Rgb8;
use shadow_core::metrics::{SizeMismatch, flip_mean};
use shadow_core::scene::LightKind;
use shadow_core::shading::{AMBIENT, BACKGROUND, cone_cosines};
use shadow_core::technique::TechniqueSpec;
use shadow_core::{FrameInputs, Image};
use shadow_wgpu::pipelines::{attribute_entry, buffer_entry, depth_entry, float_array_entry};
use shadow_wgpu::{ColorTarget, FrameRecorder, HostSurfaces, WgpuContext};
use shadowlab::TechniqueRegistry;
use wgpu::util::DeviceExt;

const DEPTH: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
const NORMALS: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;
const BASE_COLORS: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;
/// The shaded picture's format.
pub const COLOR: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8UnormSrgb;

/// A vertex of the engine's meshes, in world space.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Vertex {
    position: [f32; 3],
    normal: [f32; 3],
    base_color: [f32; 3],
    /// 1: two-sided, 2: back faces culled (`gbuffer.wgsl`).
    flags: u32,
}

/// A light as `shade.wgsl` reads it.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct GpuLight {
    position: [f32; 4],
    direction: [f32; 4],
    color: [f32; 4],
    cone: [f32; 4],
}

/// What the shading pass reads besides the lights (`shade.wgsl`'s `Shading`).
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct ShadingUniform {
    world_from_clip: [f32; 16],
    size: [f32; 4],
    background: [f32; 4],
    count: [u32; 4],
}

/// Why the engine cannot draw a scene.
#[derive(Debug)]
pub struct Unsupported(pub String);

impl std::fmt::Display for Unsupported {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for Unsupported {}

/// The engine's pipelines.
pub struct Engine {
    gbuffer: wgpu::RenderPipeline,
    camera_layout: wgpu::BindGroupLayout,
    shade: wgpu::RenderPipeline,
    shade_layout: wgpu::BindGroupLayout,
}

/// A frame's scene as the engine holds it on the GPU: its meshes baked into one vertex buffer, its camera
/// and lights.
pub struct Scene {
    vertices: wgpu::Buffer,
    count: u32,
    clip_from_world: Mat4,
    lights: Vec<GpuLight>,
}

/// The engine's G-buffer of one view.
pub struct GBuffer {
    /// The camera's depth (what shadowlab is lent).
    pub depth: wgpu::Texture,
    /// World normals (what shadowlab is lent).
    pub normals: wgpu::Texture,
    base_colors: wgpu::Texture,
    /// The view's width in pixels.
    pub width: u32,
    /// Its height.
    pub height: u32,
}

impl GBuffer {
    /// The engine's targets for a `width x height` view.
    #[must_use]
    pub fn new(device: &wgpu::Device, width: u32, height: u32) -> Self {
        let target = |label, format| {
            device.create_texture(&wgpu::TextureDescriptor {
                label: Some(label),
                size: wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format,
                usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
                view_formats: &[],
            })
        };
        Self {
            depth: target("engine depth", DEPTH),
            normals: target("engine normals", NORMALS),
            base_colors: target("engine base colours", BASE_COLORS),
            width,
            height,
        }
    }
}

fn view(texture: &wgpu::Texture) -> wgpu::TextureView {
    texture.create_view(&wgpu::TextureViewDescriptor::default())
}

/// A render pipeline of `module`'s `vs` and `fs` over `layout`.
fn pipeline(
    device: &wgpu::Device,
    module: &wgpu::ShaderModule,
    (vs, fs): (&str, &str),
    layout: &wgpu::BindGroupLayout,
    buffers: &[Option<wgpu::VertexBufferLayout<'_>>],
    targets: &[Option<wgpu::ColorTargetState>],
    depth_stencil: Option<wgpu::DepthStencilState>,
) -> wgpu::RenderPipeline {
    let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some(fs),
        bind_group_layouts: &[Some(layout)],
        immediate_size: 0,
    });
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(fs),
        layout: Some(&layout),
        vertex: wgpu::VertexState { module, entry_point: Some(vs), compilation_options: Default::default(), buffers },
        primitive: wgpu::PrimitiveState { cull_mode: None, ..Default::default() },
        depth_stencil,
        multisample: Default::default(),
        fragment: Some(wgpu::FragmentState {
            module,
            entry_point: Some(fs),
            compilation_options: Default::default(),
            targets,
        }),
        multiview_mask: None,
        cache: None,
    })
}

impl Engine {
    /// The engine's pipelines on `device`.
    #[must_use]
    pub fn new(device: &wgpu::Device) -> Self {
        let fragment = wgpu::ShaderStages::FRAGMENT;
        let camera_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("engine camera"),
            entries: &[buffer_entry(0, wgpu::BufferBindingType::Uniform, wgpu::ShaderStages::VERTEX)],
        });
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("engine gbuffer"),
            source: wgpu::ShaderSource::Wgsl(include_str!("gbuffer.wgsl").into()),
        });
        let attributes = wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3, 2 => Float32x3, 3 => Uint32];
        let vertices = wgpu::VertexBufferLayout {
            array_stride: size_of::<Vertex>() as u64,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &attributes,
        };
        let written = |format| Some(wgpu::ColorTargetState { format, blend: None, write_mask: wgpu::ColorWrites::ALL });
        let depth = wgpu::DepthStencilState {
            format: DEPTH,
            depth_write_enabled: Some(true),
            depth_compare: Some(wgpu::CompareFunction::Less),
            stencil: Default::default(),
            bias: Default::default(),
        };
        let gbuffer = pipeline(
            device,
            &module,
            ("vs_mesh", "fs_mesh"),
            &camera_layout,
            &[Some(vertices)],
            &[written(NORMALS), written(BASE_COLORS)],
            Some(depth),
        );
        let shade_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("engine shading"),
            entries: &[
                buffer_entry(0, wgpu::BufferBindingType::Uniform, fragment),
                buffer_entry(1, wgpu::BufferBindingType::Storage { read_only: true }, fragment),
                depth_entry(2),
                attribute_entry(3),
                attribute_entry(4),
                float_array_entry(5),
            ],
        });
        // shadowlab's module first, the engine's shader after it.
        let source = format!("{}\n{}", shadow_wgpu::host_wgsl::VISIBILITY, include_str!("shade.wgsl"));
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("engine shading"),
            source: wgpu::ShaderSource::Wgsl(source.into()),
        });
        let shade =
            pipeline(device, &module, ("vs_full_screen", "fs_shade"), &shade_layout, &[], &[written(COLOR)], None);
        Self { gbuffer, camera_layout, shade, shade_layout }
    }

    /// `frame`'s meshes, camera and lights uploaded for a view of aspect `width / height`.
    ///
    /// # Errors
    /// A material with a base-colour texture: this engine draws base colours only.
    pub fn upload(device: &wgpu::Device, frame: &FrameInputs, width: u32, height: u32) -> Result<Scene, Unsupported> {
        let mut vertices = Vec::new();
        for instance in &frame.instances {
            if instance.base_color_texture.is_some() {
                return Err(Unsupported(format!(
                    "this engine draws base colours only, and a mesh of the scene has a base-colour texture \
                     (material '{}')",
                    instance.material.name
                )));
            }
            let flags = u32::from(instance.two_sided) | (u32::from(instance.cull_back_faces) << 1);
            let mesh = &instance.mesh;
            let world = instance.world_from_local;
            let normal_from_local = world.inverse().transpose();
            let vertex = |i: u32| {
                let (p, n) = (mesh.positions()[i as usize], mesh.normals()[i as usize]);
                Vertex {
                    position: world.transform_point3(p).to_array(),
                    normal: normal_from_local.transform_vector3(n).normalize_or_zero().to_array(),
                    base_color: instance.base_color.to_array(),
                    flags,
                }
            };
            for &[a, b, c] in mesh.triangles() {
                // A mirroring transform turns the winding: wind front faces counter-clockwise again.
                let corners = if instance.mirrored { [a, c, b] } else { [a, b, c] };
                vertices.extend(corners.map(vertex));
            }
        }
        let buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("engine meshes"),
            contents: bytemuck::cast_slice(&vertices),
            usage: wgpu::BufferUsages::VERTEX,
        });
        let lights = frame.lights.iter().map(gpu_light).collect();
        let clip_from_world = frame.camera.clip_from_world(width as f32 / height as f32);
        Ok(Scene { vertices: buffer, count: vertices.len() as u32, clip_from_world, lights })
    }

    /// Records the G-buffer pass of `scene` into `encoder`.
    pub fn draw_gbuffer(&self, device: &wgpu::Device, encoder: &mut wgpu::CommandEncoder, scene: &Scene, g: &GBuffer) {
        let camera = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("engine camera"),
            contents: bytemuck::cast_slice(&scene.clip_from_world.to_cols_array()),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("engine camera"),
            layout: &self.camera_layout,
            entries: &[wgpu::BindGroupEntry { binding: 0, resource: camera.as_entire_binding() }],
        });
        let (normals, base_colors, depth) = (view(&g.normals), view(&g.base_colors), view(&g.depth));
        let cleared = |view| {
            Some(wgpu::RenderPassColorAttachment {
                view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                    store: wgpu::StoreOp::Store,
                },
            })
        };
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("engine gbuffer"),
            color_attachments: &[cleared(&normals), cleared(&base_colors)],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &depth,
                depth_ops: Some(wgpu::Operations { load: wgpu::LoadOp::Clear(1.0), store: wgpu::StoreOp::Store }),
                stencil_ops: None,
            }),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&self.gbuffer);
        pass.set_bind_group(0, &group, &[]);
        pass.set_vertex_buffer(0, scene.vertices.slice(..));
        pass.draw(0..scene.count, 0..1);
    }

    /// Records the shading pass into `encoder`: `g` shaded with every light of `scene` scaled by its layer
    /// of `visibility` (`FrameRecorder::visibility`), into `target` (a [`COLOR`] view of `g`'s size).
    pub fn shade(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        scene: &Scene,
        g: &GBuffer,
        visibility: &wgpu::Texture,
        target: &wgpu::TextureView,
    ) {
        let (w, h) = (g.width as f32, g.height as f32);
        let uniform = ShadingUniform {
            world_from_clip: scene.clip_from_world.inverse().to_cols_array(),
            size: [w, h, 1.0 / w, 1.0 / h],
            background: BACKGROUND.extend(AMBIENT).to_array(),
            count: [scene.lights.len() as u32, 0, 0, 0],
        };
        let init = |label, contents: &[u8], usage| {
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor { label: Some(label), contents, usage })
        };
        let uniform = init("engine shading", bytemuck::bytes_of(&uniform), wgpu::BufferUsages::UNIFORM);
        // A storage buffer may not be empty: a frame without lights binds one unused light.
        let lights = if scene.lights.is_empty() { vec![GpuLight::zeroed()] } else { scene.lights.clone() };
        let lights = init("engine lights", bytemuck::cast_slice(&lights), wgpu::BufferUsages::STORAGE);
        let depth = g
            .depth
            .create_view(&wgpu::TextureViewDescriptor { aspect: wgpu::TextureAspect::DepthOnly, ..Default::default() });
        let layers = visibility.create_view(&wgpu::TextureViewDescriptor {
            dimension: Some(wgpu::TextureViewDimension::D2Array),
            ..Default::default()
        });
        let (normals, base_colors) = (view(&g.normals), view(&g.base_colors));
        let texture = wgpu::BindingResource::TextureView;
        let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("engine shading"),
            layout: &self.shade_layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: uniform.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 1, resource: lights.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 2, resource: texture(&depth) },
                wgpu::BindGroupEntry { binding: 3, resource: texture(&normals) },
                wgpu::BindGroupEntry { binding: 4, resource: texture(&base_colors) },
                wgpu::BindGroupEntry { binding: 5, resource: texture(&layers) },
            ],
        });
        full_screen(encoder, target, &self.shade, &group);
    }
}

/// Records a pass of `pipeline`'s full-screen triangle with `group` bound at 0, into `target` cleared.
pub fn full_screen(
    encoder: &mut wgpu::CommandEncoder,
    target: &wgpu::TextureView,
    pipeline: &wgpu::RenderPipeline,
    group: &wgpu::BindGroup,
) {
    let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some("engine full-screen pass"),
        color_attachments: &[Some(wgpu::RenderPassColorAttachment {
            view: target,
            depth_slice: None,
            resolve_target: None,
            ops: wgpu::Operations { load: wgpu::LoadOp::Clear(wgpu::Color::BLACK), store: wgpu::StoreOp::Store },
        })],
        depth_stencil_attachment: None,
        timestamp_writes: None,
        occlusion_query_set: None,
        multiview_mask: None,
    });
    pass.set_pipeline(pipeline);
    pass.set_bind_group(0, group, &[]);
    pass.draw(0..3, 0..1);
}

/// `light` as the shading pass reads it.
fn gpu_light(light: &shadow_core::Light) -> GpuLight {
    let (kind, position, direction) = match light.kind {
        LightKind::Spot { position, direction, .. } => (0.0, position, direction.normalize_or_zero()),
        LightKind::Directional { direction } => (1.0, Vec3::ZERO, direction.normalize_or_zero()),
        LightKind::Point { position } => (2.0, position, Vec3::ZERO),
    };
    let (outer, inner) = cone_cosines(light).unwrap_or((-1.0, -1.0));
    GpuLight {
        position: position.extend(1.0).to_array(),
        direction: direction.extend(0.0).to_array(),
        color: (light.color * light.intensity).extend(0.0).to_array(),
        cone: [outer, inner, light.range.unwrap_or(0.0), kind],
    }
}

/// A failure of the example: the device, the scene, the technique or the GPU.
pub type Failure = Box<dyn std::error::Error>;

/// The engine's device, as it would make it for itself, with what shadowlab needs of it.
pub fn device() -> Result<(wgpu::Adapter, wgpu::Device, wgpu::Queue), Failure> {
    let instance = wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle());
    let adapters = pollster::block_on(instance.enumerate_adapters(wgpu::Backends::PRIMARY));
    let adapter = adapters.into_iter().find(WgpuContext::can_use).ok_or("no adapter shadowlab can use")?;
    let (device, queue) = pollster::block_on(adapter.request_device(&WgpuContext::device_descriptor()))?;
    Ok((adapter, device, queue))
}

/// A texture of the engine's: `format`, `layers` layers of `width x height`, for `usage`.
fn texture(
    device: &wgpu::Device,
    (width, height, layers): (u32, u32, u32),
    format: wgpu::TextureFormat,
    usage: wgpu::TextureUsages,
) -> wgpu::Texture {
    device.create_texture(&wgpu::TextureDescriptor {
        label: Some("engine picture"),
        size: wgpu::Extent3d { width, height, depth_or_array_layers: layers },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage,
        view_formats: &[],
    })
}

/// One frame drawn three ways on one device: by the engine with shadowlab's visibility, by the engine
/// with every light unshadowed, and by shadowlab's own G-buffer and shading (`FrameRecorder::record`).
pub struct Pictures {
    /// The engine's picture, shadowed through `record_visibility`.
    pub engine: Image<Rgb8>,
    /// The engine's picture with every light's visibility 1.
    pub unshadowed: Image<Rgb8>,
    /// shadowlab's own picture of the frame.
    pub shadowlab: Image<Rgb8>,
}

impl Pictures {
    /// The three pictures of `frame` with `technique` (a spec, `shadow-map:res=1024`) at `width x height`.
    ///
    /// # Errors
    /// No adapter shadowlab can use, a bad technique, a scene the engine does not draw, or a GPU failure.
    pub fn render(frame: &FrameInputs, technique: &str, width: u32, height: u32) -> Result<Self, Failure> {
        let (adapter, device, queue) = device()?;
        let mut shadows = WgpuContext::from_host(&adapter, device.clone(), queue.clone())?;
        let mut technique = TechniqueRegistry::builtin().wgpu(&TechniqueSpec::parse(technique)?)?;
        let mut recorder = FrameRecorder::new();
        let picture = || {
            let usage = wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC;
            texture(&device, (width, height, 1), COLOR, usage)
        };

        // The engine's frame: its G-buffer, shadowlab's shadows from its depth and normals, its shading.
        let engine = Engine::new(&device);
        let scene = Engine::upload(&device, frame, width, height)?;
        let g = GBuffer::new(&device, width, height);
        let (shadowed, unshadowed) = (picture(), picture());
        let mut encoder = device.create_command_encoder(&Default::default());
        engine.draw_gbuffer(&device, &mut encoder, &scene, &g);
        let (depth, normals) = (view(&g.depth), view(&g.normals));
        let surfaces = HostSurfaces { depth: &depth, normals: &normals, width, height };
        recorder.record_visibility(&mut shadows, &mut encoder, frame, technique.as_mut(), &surfaces)?;
        let visibility = recorder.visibility().ok_or("no visibility after a recorded frame")?;
        engine.shade(&device, &mut encoder, &scene, &g, visibility, &view(&shadowed));
        // The same shading with every light unshadowed: what the shadows change.
        let layers = frame.lights.len().max(1) as u32;
        let lit = texture(
            &device,
            (width, height, layers),
            wgpu::TextureFormat::R32Float,
            wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        );
        let ones = vec![1.0f32; (width * height * layers) as usize];
        queue.write_texture(
            lit.as_image_copy(),
            bytemuck::cast_slice(&ones),
            wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(width * 4), rows_per_image: Some(height) },
            lit.size(),
        );
        engine.shade(&device, &mut encoder, &scene, &g, &lit, &view(&unshadowed));
        queue.submit([encoder.finish()]);

        // shadowlab's own G-buffer and shading of the same frame.
        let own = picture();
        let own_view = view(&own);
        let target = ColorTarget { view: &own_view, format: COLOR, width, height };
        let mut encoder = device.create_command_encoder(&Default::default());
        recorder.record(&mut shadows, &mut encoder, frame, technique.as_mut(), &target)?;
        queue.submit([encoder.finish()]);

        let read = |t: &wgpu::Texture| shadow_wgpu::readback::read_rgb8(&shadows, t);
        Ok(Self { engine: read(&shadowed)?, unshadowed: read(&unshadowed)?, shadowlab: read(&own)? })
    }

    /// The mean FLIP between the engine's picture and shadowlab's.
    ///
    /// # Errors
    /// Never for pictures made by [`Self::render`] (they have one size).
    pub fn flip(&self) -> Result<f64, SizeMismatch> {
        flip_mean(&self.engine, &self.shadowlab, &Image::new(self.engine.width(), self.engine.height(), true))
    }

    /// The mean FLIP between the engine's unshadowed picture and shadowlab's: what the shadows account
    /// for, the scale [`Self::flip`] is small against.
    ///
    /// # Errors
    /// As [`Self::flip`].
    pub fn flip_of_the_shadows(&self) -> Result<f64, SizeMismatch> {
        flip_mean(&self.unshadowed, &self.shadowlab, &Image::new(self.engine.width(), self.engine.height(), true))
    }
}
