//! State every pass shares: the frame bind-group layout (view uniform and instance data), the
//! G-buffer and shading pipelines, and the formats.

use bytemuck::{Pod, Zeroable};
use glam::{Mat4, Vec3};
use shadow_core::light::PixelRect;
use shadow_core::scene::{Light, LightKind};

use crate::pipeline_cache::PipelineCache;
use crate::shaders;

/// Light-space depth maps.
pub const MAP_DEPTH: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
/// G-buffer attributes.
pub const ATTRIBUTE: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;
/// Visibility.
pub const VISIBILITY: wgpu::TextureFormat = wgpu::TextureFormat::R32Float;
/// The shaded image (sRGB encoded by the shader).
pub const COLOR: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;

/// GPU twin of `View` in common.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub struct ViewRaw {
    clip_from_world: [[f32; 4]; 4],
    eye: [f32; 4],
    size: [f32; 4],
}

impl ViewRaw {
    /// A view of a `width x height` target.
    #[must_use]
    pub fn new(clip_from_world: Mat4, eye: Vec3, width: u32, height: u32) -> Self {
        let (w, h) = (width as f32, height as f32);
        Self {
            clip_from_world: clip_from_world.to_cols_array_2d(),
            eye: eye.extend(1.0).to_array(),
            size: [w, h, 1.0 / w, 1.0 / h],
        }
    }
}

/// GPU twin of `Light` in common.wgsl: the one encoding of a light every pass reads (the shading's light
/// table, every map lookup's `MapParams`), with a spot light's cone cosines computed once, here.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct LightRaw {
    kind: [u32; 4],
    position: [f32; 4],
    direction: [f32; 4],
    cone: [f32; 4],
    color: [f32; 4],
}

impl LightRaw {
    /// The light, reaching only the pixels of `rect` in the shading pass (it adds nothing elsewhere):
    /// `kind.y` and `kind.z` hold its first and one-past-last column and row, 16 bits each.
    #[must_use]
    pub fn within(self, rect: PixelRect) -> Self {
        let pack = |x: u32, y: u32| x.min(0xffff) | (y.min(0xffff) << 16);
        let [kind, _, _, w] = self.kind;
        Self { kind: [kind, pack(rect.x0, rect.y0), pack(rect.x1, rect.y1), w], ..self }
    }
}

impl From<&Light> for LightRaw {
    fn from(l: &Light) -> Self {
        let (kind, position, direction, cone) = match l.kind {
            LightKind::Spot { position, direction, .. } => {
                let (outer, inner) = shadow_core::shading::cone_cosines(l).unwrap_or((0.0, 0.0));
                (0, position, direction.normalize(), [outer, inner])
            }
            LightKind::Directional { direction } => (1, Vec3::ZERO, direction.normalize(), [0.0, 0.0]),
            LightKind::Point { position } => (2, position, Vec3::NEG_Y, [0.0, 0.0]),
        };
        Self {
            // y, z: every pixel (see `within`).
            kind: [kind, 0, u32::MAX, 0],
            position: position.extend(1.0).to_array(),
            direction: direction.extend(0.0).to_array(),
            // z: the range, 0 for none.
            cone: [cone[0], cone[1], l.range.unwrap_or(0.0), 0.0],
            color: (l.color * l.intensity).extend(1.0).to_array(),
        }
    }
}

/// Vertex layout of homogeneous positions (location 0).
pub const POSITION_LAYOUT: wgpu::VertexBufferLayout<'static> = wgpu::VertexBufferLayout {
    array_stride: 16,
    step_mode: wgpu::VertexStepMode::Vertex,
    attributes: &wgpu::vertex_attr_array![0 => Float32x4],
};

/// Vertex layout of normals (location 1).
pub const NORMAL_LAYOUT: wgpu::VertexBufferLayout<'static> = wgpu::VertexBufferLayout {
    array_stride: 16,
    step_mode: wgpu::VertexStepMode::Vertex,
    attributes: &wgpu::vertex_attr_array![1 => Float32x4],
};

/// Vertex layout of texture coordinates, `vec2<f32>` (location 2, whichever slot holds them).
pub const UV_LAYOUT: wgpu::VertexBufferLayout<'static> = wgpu::VertexBufferLayout {
    array_stride: 8,
    step_mode: wgpu::VertexStepMode::Vertex,
    attributes: &wgpu::vertex_attr_array![2 => Float32x2],
};

/// A material's texture (`textures::TEXTURE_FORMAT`), read by index with `textureLoad` in the fragment stage.
#[must_use]
pub fn material_texture_entry(binding: u32) -> wgpu::BindGroupLayoutEntry {
    texture_entry(binding, wgpu::TextureSampleType::Float { filterable: false }, wgpu::TextureViewDimension::D2)
}

fn texture_entry(
    binding: u32,
    sample_type: wgpu::TextureSampleType,
    dim: wgpu::TextureViewDimension,
) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::FRAGMENT,
        ty: wgpu::BindingType::Texture { sample_type, view_dimension: dim, multisampled: false },
        count: None,
    }
}

/// An unfilterable float 2D texture binding (G-buffer attributes).
#[must_use]
pub fn attribute_entry(binding: u32) -> wgpu::BindGroupLayoutEntry {
    texture_entry(binding, wgpu::TextureSampleType::Float { filterable: false }, wgpu::TextureViewDimension::D2)
}

/// A depth 2D-array texture binding (the light projections' maps), read with `textureLoad` or a
/// comparison sampler.
#[must_use]
pub fn depth_array_entry(binding: u32) -> wgpu::BindGroupLayoutEntry {
    texture_entry(binding, wgpu::TextureSampleType::Depth, wgpu::TextureViewDimension::D2Array)
}

/// A float 2D-array texture binding read with `textureLoad` (hybrid's edge cells).
#[must_use]
pub fn float_array_entry(binding: u32) -> wgpu::BindGroupLayoutEntry {
    texture_entry(binding, wgpu::TextureSampleType::Float { filterable: false }, wgpu::TextureViewDimension::D2Array)
}

/// A depth 2D texture binding (one layer), read with `textureLoad`.
#[must_use]
pub fn depth_entry(binding: u32) -> wgpu::BindGroupLayoutEntry {
    texture_entry(binding, wgpu::TextureSampleType::Depth, wgpu::TextureViewDimension::D2)
}

/// A uniform or storage buffer binding.
#[must_use]
pub fn buffer_entry(
    binding: u32,
    ty: wgpu::BufferBindingType,
    visibility: wgpu::ShaderStages,
) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility,
        ty: wgpu::BindingType::Buffer { ty, has_dynamic_offset: false, min_binding_size: None },
        count: None,
    }
}

/// Which faces of an instance the camera's view leaves out: none, or the back faces of a single-sided
/// material (`Instance::cull_back_faces`), whose fronts wind clockwise on screen where the instance is
/// mirrored.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FaceCull {
    /// Both faces drawn.
    None,
    /// Back faces culled, fronts counter-clockwise.
    Back,
    /// Back faces culled, fronts clockwise (a mirrored instance).
    BackMirrored,
}

impl FaceCull {
    /// Every mode, in the order of [`FaceCull::index`].
    pub const ALL: [Self; 3] = [Self::None, Self::Back, Self::BackMirrored];

    /// The mode of an instance in the camera's view.
    #[must_use]
    pub fn of(inst: &shadow_core::Instance) -> Self {
        match (inst.cull_back_faces, inst.mirrored) {
            (false, _) => Self::None,
            (true, false) => Self::Back,
            (true, true) => Self::BackMirrored,
        }
    }

    /// Its place in [`FaceCull::ALL`].
    #[must_use]
    pub fn index(self) -> usize {
        self as usize
    }

    fn primitive(self) -> wgpu::PrimitiveState {
        let (front_face, cull_mode) = match self {
            Self::None => (wgpu::FrontFace::Ccw, None),
            Self::Back => (wgpu::FrontFace::Ccw, Some(wgpu::Face::Back)),
            Self::BackMirrored => (wgpu::FrontFace::Cw, Some(wgpu::Face::Back)),
        };
        wgpu::PrimitiveState { front_face, cull_mode, ..Default::default() }
    }
}

/// Pipelines and layouts every frame uses.
pub struct Shared {
    /// Group 0: view uniform and instance data.
    pub frame_layout: wgpu::BindGroupLayout,
    /// A material's base-colour texture, as every pass that reads one binds it (group 2, binding 0).
    pub material_layout: wgpu::BindGroupLayout,
    /// The G-buffer pipelines, one per [`FaceCull`] (index: `FaceCull::of`).
    pub gbuffer: [wgpu::RenderPipeline; 3],
    /// The G-buffer pipelines of instances whose material reads a texture (group 2: the texture), with
    /// their texture coordinates in vertex slot 2; one per [`FaceCull`].
    pub gbuffer_textured: [wgpu::RenderPipeline; 3],
    /// Group 1 of the shading pass.
    pub shade_layout: wgpu::BindGroupLayout,
    /// The shading pipeline.
    pub shade: wgpu::RenderPipeline,
    /// Counts receiver pixels (same layout as shading).
    pub receivers: wgpu::RenderPipeline,
}

impl Shared {
    /// Creates the shared pipelines.
    #[must_use]
    pub fn new(pipelines: &PipelineCache, depth_stencil: wgpu::TextureFormat) -> Self {
        let all = wgpu::ShaderStages::VERTEX | wgpu::ShaderStages::FRAGMENT | wgpu::ShaderStages::COMPUTE;
        let frame_layout = pipelines.group_layout(
            "frame",
            &[
                buffer_entry(0, wgpu::BufferBindingType::Uniform, all),
                buffer_entry(1, wgpu::BufferBindingType::Storage { read_only: true }, all),
            ],
        );
        let material_layout = pipelines.group_layout("material texture", &[material_texture_entry(0)]);
        let gmod = pipelines.module("gbuffer", shaders::gbuffer());
        let gbuffer_pipeline =
            |label, groups: &[Option<&wgpu::BindGroupLayout>], buffers: &[_], entries: [&str; 2], cull: FaceCull| {
                let target =
                    Some(wgpu::ColorTargetState { format: ATTRIBUTE, blend: None, write_mask: wgpu::ColorWrites::ALL });
                pipelines.render(&wgpu::RenderPipelineDescriptor {
                    label: Some(label),
                    layout: Some(&pipelines.layout(label, groups)),
                    vertex: wgpu::VertexState {
                        module: &gmod,
                        entry_point: Some(entries[0]),
                        compilation_options: Default::default(),
                        buffers,
                    },
                    primitive: cull.primitive(),
                    depth_stencil: Some(wgpu::DepthStencilState {
                        format: depth_stencil,
                        depth_write_enabled: Some(true),
                        depth_compare: Some(wgpu::CompareFunction::Less),
                        stencil: Default::default(),
                        bias: Default::default(),
                    }),
                    multisample: Default::default(),
                    fragment: Some(wgpu::FragmentState {
                        module: &gmod,
                        entry_point: Some(entries[1]),
                        compilation_options: Default::default(),
                        targets: &[target.clone(), target.clone(), target.clone(), target],
                    }),
                    multiview_mask: None,
                    cache: None,
                })
            };
        let gbuffer = FaceCull::ALL.map(|cull| {
            gbuffer_pipeline(
                "gbuffer",
                &[Some(&frame_layout)],
                &[Some(POSITION_LAYOUT), Some(NORMAL_LAYOUT)],
                ["vs_gbuffer", "fs_gbuffer"],
                cull,
            )
        });
        let gbuffer_textured = FaceCull::ALL.map(|cull| {
            gbuffer_pipeline(
                "gbuffer textured",
                &[Some(&frame_layout), None, Some(&material_layout)],
                &[Some(POSITION_LAYOUT), Some(NORMAL_LAYOUT), Some(UV_LAYOUT)],
                ["vs_gbuffer_textured", "fs_gbuffer_textured"],
                cull,
            )
        });
        let shade_layout = pipelines.group_layout(
            "shade",
            &[
                attribute_entry(0),
                attribute_entry(1),
                attribute_entry(2),
                texture_entry(
                    3,
                    wgpu::TextureSampleType::Float { filterable: false },
                    wgpu::TextureViewDimension::D2Array,
                ),
                buffer_entry(4, wgpu::BufferBindingType::Uniform, wgpu::ShaderStages::FRAGMENT),
            ],
        );
        let smod = pipelines.module("shade", shaders::shade());
        let shade = full_screen_pipeline(
            pipelines,
            "shade",
            &smod,
            "fs_shade",
            &[&frame_layout, &shade_layout],
            Some(COLOR),
            None,
        );
        let receivers = full_screen_pipeline(
            pipelines,
            "receivers",
            &smod,
            "fs_receivers",
            &[&frame_layout, &shade_layout],
            Some(COLOR),
            None,
        );
        Self { frame_layout, material_layout, gbuffer, gbuffer_textured, shade_layout, shade, receivers }
    }

    /// A group-0 bind group for a view (camera or light) over a frame's instances, the view in this frame's
    /// transient buffer.
    #[must_use]
    pub fn frame_group(&self, cx: &crate::WgpuContext, view: &ViewRaw, instances: &wgpu::Buffer) -> wgpu::BindGroup {
        let view = cx.transient(bytemuck::bytes_of(view));
        self.frame_group_over(&cx.device, view.binding(), instances)
    }

    fn frame_group_over(
        &self,
        device: &wgpu::Device,
        view: wgpu::BindingResource<'_>,
        instances: &wgpu::Buffer,
    ) -> wgpu::BindGroup {
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("frame"),
            layout: &self.frame_layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: view },
                wgpu::BindGroupEntry { binding: 1, resource: instances.as_entire_binding() },
            ],
        })
    }
}

/// A fragment entry point with the values of its pipeline-overridable constants.
#[derive(Clone, Copy, Debug)]
pub struct FragmentEntry<'a> {
    /// The entry point.
    pub name: &'a str,
    /// `override` constants by name.
    pub constants: &'a [(&'a str, f64)],
}

impl<'a> From<&'a str> for FragmentEntry<'a> {
    fn from(name: &'a str) -> Self {
        Self { name, constants: &[] }
    }
}

/// A pipeline drawing `vertices` through `vertex` (and `fragment`, when given) of `module` into a
/// [`MAP_DEPTH`] target, both faces, the depth test "less" with writes: every texel keeps the nearest depth
/// drawn or, where the fragment stage writes its depth, the smallest value (a minimum blend at full
/// precision).
#[must_use]
pub fn min_depth_pipeline(
    pipelines: &PipelineCache,
    label: &str,
    module: &wgpu::ShaderModule,
    groups: &[&wgpu::BindGroupLayout],
    (vertex, vertices): (&str, wgpu::VertexBufferLayout<'_>),
    fragment: Option<&str>,
) -> wgpu::RenderPipeline {
    let groups: Vec<_> = groups.iter().map(|&g| Some(g)).collect();
    let layout = pipelines.layout(label, &groups);
    pipelines.render(&wgpu::RenderPipelineDescriptor {
        label: Some(label),
        layout: Some(&layout),
        vertex: wgpu::VertexState {
            module,
            entry_point: Some(vertex),
            compilation_options: Default::default(),
            buffers: &[Some(vertices)],
        },
        primitive: wgpu::PrimitiveState { cull_mode: None, ..Default::default() },
        depth_stencil: Some(wgpu::DepthStencilState {
            format: MAP_DEPTH,
            depth_write_enabled: Some(true),
            depth_compare: Some(wgpu::CompareFunction::Less),
            stencil: Default::default(),
            bias: Default::default(),
        }),
        multisample: Default::default(),
        fragment: fragment.map(|entry| wgpu::FragmentState {
            module,
            entry_point: Some(entry),
            compilation_options: Default::default(),
            targets: &[],
        }),
        multiview_mask: None,
        cache: None,
    })
}

/// A pipeline drawing `vs_full_screen` into one colour target of `format` (none: a pass that only tests
/// and writes the stencil), optionally with a depth-stencil state.
#[must_use]
pub fn full_screen_pipeline<'a>(
    pipelines: &PipelineCache,
    label: &str,
    module: &wgpu::ShaderModule,
    fragment: impl Into<FragmentEntry<'a>>,
    groups: &[&wgpu::BindGroupLayout],
    format: Option<wgpu::TextureFormat>,
    depth_stencil: Option<wgpu::DepthStencilState>,
) -> wgpu::RenderPipeline {
    let targets: Vec<_> = format
        .map(|format| Some(wgpu::ColorTargetState { format, blend: None, write_mask: wgpu::ColorWrites::ALL }))
        .into_iter()
        .collect();
    full_screen_pipeline_to(pipelines, (label, module, fragment.into()), groups, &targets, depth_stencil)
}

/// [`full_screen_pipeline`] into any colour targets: `(label, module, fragment entry)`.
pub fn full_screen_pipeline_to(
    pipelines: &PipelineCache,
    (label, module, fragment): (&str, &wgpu::ShaderModule, FragmentEntry<'_>),
    groups: &[&wgpu::BindGroupLayout],
    targets: &[Option<wgpu::ColorTargetState>],
    depth_stencil: Option<wgpu::DepthStencilState>,
) -> wgpu::RenderPipeline {
    let groups: Vec<_> = groups.iter().map(|&g| Some(g)).collect();
    let layout = pipelines.layout(label, &groups);
    pipelines.render(&wgpu::RenderPipelineDescriptor {
        label: Some(label),
        layout: Some(&layout),
        vertex: wgpu::VertexState {
            module,
            entry_point: Some("vs_full_screen"),
            compilation_options: Default::default(),
            buffers: &[],
        },
        primitive: Default::default(),
        depth_stencil,
        multisample: Default::default(),
        fragment: Some(wgpu::FragmentState {
            module,
            entry_point: Some(fragment.name),
            compilation_options: wgpu::PipelineCompilationOptions {
                constants: fragment.constants,
                ..Default::default()
            },
            targets,
        }),
        multiview_mask: None,
        cache: None,
    })
}

/// A depth-only render pass over one depth view, cleared to 1 (the far plane) and stored: the pass of a
/// light's depth layers, a minimum target and hybrid's edge maps.
pub fn depth_pass<'e>(
    enc: &'e mut wgpu::CommandEncoder,
    view: &'e wgpu::TextureView,
    label: &'e str,
) -> wgpu::RenderPass<'e> {
    enc.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some(label),
        color_attachments: &[],
        depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
            view,
            depth_ops: Some(wgpu::Operations { load: wgpu::LoadOp::Clear(1.0), store: wgpu::StoreOp::Store }),
            stencil_ops: None,
        }),
        timestamp_writes: None,
        occlusion_query_set: None,
        multiview_mask: None,
    })
}
