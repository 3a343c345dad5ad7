//! `planar-shadow`: Blinn's projected planar shadows ("Me and my (fake) shadow", 1988; the survey of
//! Nealen 2005, section 2), written outside the workspace crates against their public APIs only.
//!
//! Every caster triangle is squashed onto the receiver plane y = `plane_y` by the projection from the
//! light, then drawn in the camera's view; a pixel is shadowed when the projection covers it and its
//! surface lies on that plane. Exact for the ground plane, blind to every other receiver: the classic
//! limitation the survey points out.

use glam::{Mat4, Vec3, Vec4};
use shadow_core::light::LightView;
use shadow_core::scene::LightKind;
use shadow_core::technique::LightPass;
use shadow_core::technique::ShadowTechnique;
use shadow_core::technique::settings::SettingKey;
use shadow_core::{FrameInputs, Image};
use shadow_cpu::raster::{DepthStencil, RasterState, Soup, draw};
use shadow_cpu::{CpuBackend, CpuContext, CpuError, GBuffer};
use shadow_wgpu::{GpuGBuffer, GpuVisibility, WgpuBackend, WgpuContext, WgpuError};
use shadowlab::{TechniqueEntry, TechniqueRegistry};
use wgpu::util::DeviceExt;

shadow_core::technique_settings! {
    /// The settings: which horizontal plane receives.
    pub struct PlanarShadow {
        /// Height of the receiving plane.
        pub plane_y: f32 = SettingKey::float("plane_y", "0", -1e6, 1e6, "height of the horizontal receiving plane"),
    }
}

/// Blinn's shadow matrix: projects points onto the plane `p` (n.x + d = 0) from the homogeneous light
/// `l` (w = 1 for a point, 0 for a direction towards the light): M = (p . l) I - l p^T.
#[must_use]
pub fn shadow_matrix(plane: Vec4, l: Vec4) -> Mat4 {
    let d = plane.dot(l);
    Mat4::from_cols(
        Vec4::new(d, 0.0, 0.0, 0.0) - l * plane.x,
        Vec4::new(0.0, d, 0.0, 0.0) - l * plane.y,
        Vec4::new(0.0, 0.0, d, 0.0) - l * plane.z,
        Vec4::new(0.0, 0.0, 0.0, d) - l * plane.w,
    )
}

impl PlanarShadow {
    fn plane(&self) -> Vec4 {
        Vec4::new(0.0, 1.0, 0.0, -self.plane_y)
    }

    /// Every caster triangle projected onto the plane, in the camera's clip space.
    fn projected(&self, frame: &FrameInputs, light: &LightView, clip_from_world: Mat4) -> Vec<[Vec4; 3]> {
        let l = match light.light.kind {
            LightKind::Spot { position, .. } | LightKind::Point { position } => position.extend(1.0),
            LightKind::Directional { direction } => (-direction).extend(0.0),
        };
        let m = clip_from_world * shadow_matrix(self.plane(), l);
        let mut out = Vec::new();
        for inst in frame.instances.iter().filter(|i| i.casts_shadow) {
            let mm = m * inst.world_from_local;
            let p: Vec<Vec4> = inst.mesh.positions().iter().map(|&v| mm * v.extend(1.0)).collect();
            for t in inst.mesh.triangles() {
                // A triangle lying in the plane (the ground itself) projects onto itself: skip it.
                let world = t.map(|k| inst.world_from_local.transform_point3(inst.mesh.positions()[k as usize]));
                if world.iter().all(|w| (w.y - self.plane_y).abs() < 1e-5) {
                    continue;
                }
                out.push(t.map(|k| p[k as usize]));
            }
        }
        out
    }

    fn on_plane(&self, p: Vec3) -> bool {
        (p.y - self.plane_y).abs() < 1e-3
    }
}

/// What both backends keep: the projected triangles of the last build, in camera clip space.
#[derive(Default)]
pub struct State {
    light: Option<LightView>,
}

impl ShadowTechnique<CpuBackend> for PlanarShadow {
    type State = State;
    fn name(&self) -> &'static str {
        "planar-shadow"
    }
    fn create_state(&self, _: &mut CpuContext) -> Result<State, CpuError> {
        Ok(State::default())
    }
    fn build(&self, _: &mut CpuContext, state: &mut State, pass: LightPass<'_>) -> Result<(), CpuError> {
        let LightPass { light, .. } = pass;
        state.light = Some(light.clone());
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
        let LightPass { frame, light, .. } = pass;
        let tris = self.projected(frame, state.light.as_ref().unwrap_or(light), g.clip_from_world);
        let mut ds = DepthStencil::new(g.width(), g.height(), 1.0, 0);
        let st = RasterState { depth: None, ..RasterState::default() };
        let src = Soup { triangles: &tris, prim_base: 0, flip: false };
        draw(
            &mut ds,
            out,
            &src,
            &st,
            |f| {
                let i = g.position.index(f.x, f.y);
                (g.receiver.data()[i] && self.on_plane(g.position.data()[i])).then_some(0.0)
            },
            |d, s| *d = s,
        );
        Ok(())
    }
}

const WGSL: &str = include_str!("planar.wgsl");

/// The GPU state: one pipeline and its layout, made once.
pub struct GpuState {
    pipeline: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
}

impl ShadowTechnique<WgpuBackend> for PlanarShadow {
    type State = GpuState;
    fn name(&self) -> &'static str {
        "planar-shadow"
    }
    fn create_state(&self, cx: &mut WgpuContext) -> Result<GpuState, WgpuError> {
        cx.scoped("creating the planar-shadow pipeline", |cx| {
            let d = &cx.device;
            let module = d.create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some("planar"),
                source: wgpu::ShaderSource::Wgsl(WGSL.into()),
            });
            let layout = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("planar"),
                entries: &[
                    shadow_wgpu::pipelines::attribute_entry(0),
                    shadow_wgpu::pipelines::buffer_entry(
                        1,
                        wgpu::BufferBindingType::Uniform,
                        wgpu::ShaderStages::FRAGMENT,
                    ),
                ],
            });
            let pl = d.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("planar"),
                bind_group_layouts: &[Some(&layout)],
                immediate_size: 0,
            });
            let pipeline = d.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some("planar"),
                layout: Some(&pl),
                vertex: wgpu::VertexState {
                    module: &module,
                    entry_point: Some("vs"),
                    compilation_options: Default::default(),
                    buffers: &[Some(shadow_wgpu::pipelines::POSITION_LAYOUT)],
                },
                primitive: wgpu::PrimitiveState { cull_mode: None, ..Default::default() },
                depth_stencil: None,
                multisample: Default::default(),
                fragment: Some(wgpu::FragmentState {
                    module: &module,
                    entry_point: Some("fs"),
                    compilation_options: Default::default(),
                    targets: &[Some(wgpu::ColorTargetState {
                        format: shadow_wgpu::pipelines::VISIBILITY,
                        blend: None,
                        write_mask: wgpu::ColorWrites::ALL,
                    })],
                }),
                multiview_mask: None,
                cache: None,
            });
            GpuState { pipeline, layout }
        })
    }
    fn build(&self, _: &mut WgpuContext, _: &mut GpuState, _: LightPass<'_>) -> Result<(), WgpuError> {
        Ok(())
    }
    fn query(
        &self,
        cx: &mut WgpuContext,
        state: &mut GpuState,
        pass: LightPass<'_>,
        g: &GpuGBuffer,
        out: &mut GpuVisibility,
    ) -> Result<(), WgpuError> {
        let LightPass { frame, light, .. } = pass;
        let clip_from_world = g.camera.clip_from_world(g.width as f32 / g.height as f32);
        let tris = self.projected(frame, light, clip_from_world);
        cx.scoped("the planar-shadow pass", |cx| {
            let d = &cx.device;
            let group = d.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("planar"),
                layout: &state.layout,
                entries: &[
                    wgpu::BindGroupEntry { binding: 0, resource: wgpu::BindingResource::TextureView(&g.position) },
                    wgpu::BindGroupEntry {
                        binding: 1,
                        resource: d
                            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                                label: None,
                                contents: bytemuck::cast_slice(&[self.plane_y, 0.0, 0.0, 0.0]),
                                usage: wgpu::BufferUsages::UNIFORM,
                            })
                            .as_entire_binding(),
                    },
                ],
            });
            let verts: Vec<Vec4> = tris.iter().flatten().copied().collect();
            let mut enc = d.create_command_encoder(&Default::default());
            {
                let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some("planar"),
                    color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                        view: &out.view,
                        depth_slice: None,
                        resolve_target: None,
                        ops: wgpu::Operations {
                            load: wgpu::LoadOp::Clear(wgpu::Color::WHITE),
                            store: wgpu::StoreOp::Store,
                        },
                    })],
                    depth_stencil_attachment: None,
                    timestamp_writes: None,
                    occlusion_query_set: None,
                    multiview_mask: None,
                });
                if !verts.is_empty() {
                    let vb = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                        label: None,
                        contents: bytemuck::cast_slice(&verts),
                        usage: wgpu::BufferUsages::VERTEX,
                    });
                    pass.set_pipeline(&state.pipeline);
                    pass.set_bind_group(0, &group, &[]);
                    pass.set_vertex_buffer(0, vb.slice(..));
                    pass.draw(0..verts.len() as u32, 0..1);
                }
            }
            cx.queue.submit([enc.finish()]);
        })
    }
}

/// Adds `planar-shadow` to a registry, on both backends.
pub fn register(registry: &mut TechniqueRegistry) {
    registry.register(TechniqueEntry::on_both::<PlanarShadow>(
        "planar-shadow",
        "caster triangles squashed onto the ground plane from the light (fake shadows)",
        "Blinn 1988 (survey: Nealen 2005)",
    ));
}
