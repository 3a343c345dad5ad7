//! `silhouette-map` on the GPU (twin: silhouette_map/cpu.rs). Pass 1 is the
//! shadow-map light pass (same bias). Pass 2 draws every silhouette segment, projected on the CPU by the
//! shared code, as a widened quad into an Rg32Float map one texel smaller than the depth map; the
//! fragment shader picks the point (Fig. 4, corner rule), drops hidden ones, and writes the point's depth
//! so that a less-or-equal depth test keeps the point nearest the light (`keep=nearest`; `keep=last`
//! draws with the test off, so rasterization order keeps the last). The query runs
//! `fs_silhouette_query` of query.wgsl over the G-buffer.
//!
//! Counters: the query counts the pixels whose corner tests disagree (`silhouette_pixels`) with an
//! atomic; after it, a compute pass counts the non-empty texels (`silhouette_texels`) and both are read
//! back, timed as the `count_silhouette` sub-phase of the query.

use super::SilhouetteMap;
use super::points::{CornerDepth, Keep, MapSegment, overlay, project_segments};
use bytemuck::{Pod, Zeroable};
use shadow_core::light::LightView;
use shadow_core::technique::LightPass;
use shadow_core::technique::{DebugView, ShadowTechnique, TechniqueError};

use shadow_wgpu::frame::{GpuVisibility, layer_view, layered};
use shadow_wgpu::gbuffer::{GpuGBuffer, check_size};
use shadow_wgpu::passes::maps::{
    LightPipelines, LookupParams, MapQuery, QueryExtras, depth_bias, light_pass_pipeline, map_texture, render_maps,
};
use shadow_wgpu::pipelines::{MAP_DEPTH, attribute_entry, buffer_entry, depth_array_entry};
use shadow_wgpu::{Transient, WgpuBackend, WgpuContext, WgpuError};
use shadow_wgpu::{readback, shaders};

/// The silhouette points' format: two offsets in texel space.
const POINTS: wgpu::TextureFormat = wgpu::TextureFormat::Rg32Float;

/// GPU twin of `BuildParams` in build.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct BuildParams {
    settings: [f32; 4],
}

/// The maps of the last build.
struct Maps {
    depth: wgpu::Texture,
    points: wgpu::Texture,
    /// The depth of each stored point (for `keep=nearest`).
    point_depth: wgpu::Texture,
}

/// Pipelines, the maps of the last build and the two counters.
pub struct State {
    light_pass: LightPipelines,
    points: wgpu::RenderPipeline,
    points_layout: wgpu::BindGroupLayout,
    count: wgpu::ComputePipeline,
    query: MapQuery,
    /// Nearest-texel sampler for the query's corner gather.
    corners: wgpu::Sampler,
    maps: Option<Maps>,
    /// Non-empty texels, then silhouette pixels: one u32 each, 256 bytes apart (storage offset alignment).
    counters: wgpu::Buffer,
}

const COUNTER_STRIDE: u64 = 256;

fn storage_entry(binding: u32, read_only: bool, visibility: wgpu::ShaderStages) -> wgpu::BindGroupLayoutEntry {
    buffer_entry(binding, wgpu::BufferBindingType::Storage { read_only }, visibility)
}

/// Pass 2's pipeline and its layout: each silhouette segment a widened quad into the point map, the depth
/// test keeping the nearest point (`keep=nearest`) or none (`keep=last`: rasterization order decides).
fn points_pipeline(
    cx: &WgpuContext,
    build_module: &wgpu::ShaderModule,
    keep: Keep,
) -> (wgpu::RenderPipeline, wgpu::BindGroupLayout) {
    let both = wgpu::ShaderStages::VERTEX | wgpu::ShaderStages::FRAGMENT;
    let points_layout = cx.pipelines.group_layout(
        "silhouette points",
        &[storage_entry(0, true, both), depth_array_entry(1), buffer_entry(2, wgpu::BufferBindingType::Uniform, both)],
    );
    let pl = cx.pipelines.layout("silhouette points", &[Some(&points_layout)]);
    let compare = match keep {
        Keep::Nearest => wgpu::CompareFunction::LessEqual,
        Keep::Last => wgpu::CompareFunction::Always,
    };
    let points = cx.pipelines.render(&wgpu::RenderPipelineDescriptor {
        label: Some("silhouette points"),
        layout: Some(&pl),
        vertex: wgpu::VertexState {
            module: build_module,
            entry_point: Some("vs_segment_quad"),
            compilation_options: Default::default(),
            buffers: &[],
        },
        primitive: wgpu::PrimitiveState { cull_mode: None, ..Default::default() },
        depth_stencil: Some(wgpu::DepthStencilState {
            format: MAP_DEPTH,
            depth_write_enabled: Some(true),
            depth_compare: Some(compare),
            stencil: Default::default(),
            bias: Default::default(),
        }),
        multisample: Default::default(),
        fragment: Some(wgpu::FragmentState {
            module: build_module,
            entry_point: Some("fs_silhouette_point"),
            compilation_options: Default::default(),
            targets: &[Some(wgpu::ColorTargetState {
                format: POINTS,
                blend: None,
                write_mask: wgpu::ColorWrites::ALL,
            })],
        }),
        multiview_mask: None,
        cache: None,
    });
    (points, points_layout)
}

/// The query's pipeline: the map lookup's bindings and the points (4), the G-buffer's face normals (5), the
/// counters (6) and the corners' sampler (7).
fn query_pipeline(cx: &WgpuContext, map_module: &wgpu::ShaderModule) -> MapQuery {
    MapQuery::with_entry(
        cx,
        map_module,
        "fs_silhouette_query".into(),
        &[
            wgpu::BindGroupLayoutEntry {
                binding: 4,
                visibility: wgpu::ShaderStages::FRAGMENT,
                ty: wgpu::BindingType::Texture {
                    sample_type: wgpu::TextureSampleType::Float { filterable: false },
                    view_dimension: wgpu::TextureViewDimension::D2Array,
                    multisampled: false,
                },
                count: None,
            },
            attribute_entry(5),
            storage_entry(6, false, wgpu::ShaderStages::FRAGMENT),
            wgpu::BindGroupLayoutEntry {
                binding: 7,
                visibility: wgpu::ShaderStages::FRAGMENT,
                ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::NonFiltering),
                count: None,
            },
        ],
    )
}

impl State {
    fn new(cx: &WgpuContext, s: &SilhouetteMap) -> Self {
        let map_module = cx.pipelines.module("silhouette_query", query_shader());
        let build_module = cx.pipelines.module("silhouette_build", build_shader());
        let (points, points_layout) = points_pipeline(cx, &build_module, s.keep);
        let count = cx.pipelines.compute(&wgpu::ComputePipelineDescriptor {
            label: Some("count silhouette texels"),
            layout: None,
            module: &build_module,
            entry_point: Some("cs_count_texels"),
            compilation_options: Default::default(),
            cache: None,
        });
        let lookup = LookupParams { radius: 0.0, receiver_offset: s.depth.receiver_offset() };
        let query = query_pipeline(cx, &map_module).with_lookup(lookup);
        let counters = cx.create_buffer(&wgpu::BufferDescriptor {
            label: Some("silhouette counters"),
            size: COUNTER_STRIDE + 4,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        Self {
            light_pass: light_pass_pipeline(cx, &map_module, depth_bias(&s.depth)),
            points,
            points_layout,
            count,
            query,
            corners: cx.device.create_sampler(&wgpu::SamplerDescriptor {
                label: Some("silhouette corners"),
                address_mode_u: wgpu::AddressMode::ClampToEdge,
                address_mode_v: wgpu::AddressMode::ClampToEdge,
                mag_filter: wgpu::FilterMode::Nearest,
                min_filter: wgpu::FilterMode::Nearest,
                ..Default::default()
            }),
            maps: None,
            counters,
        }
    }

    /// Allocates the maps for `layers` projections of side `res`, unless the last build's fit.
    fn allocate(&mut self, cx: &WgpuContext, res: u32, layers: u32) -> Result<(), WgpuError> {
        if self.maps.as_ref().is_some_and(|m| m.depth.width() == res && m.depth.depth_or_array_layers() == layers) {
            return Ok(());
        }
        self.maps = Some(cx.scoped("allocating silhouette maps", |cx| Maps {
            depth: map_texture(cx, res, layers),
            points: layered(cx, "silhouette points", res - 1, res - 1, layers, POINTS),
            point_depth: layered(cx, "silhouette point depth", res - 1, res - 1, 1, MAP_DEPTH),
        })?);
        Ok(())
    }
}

/// The segments of every projection in one slice of the transient buffer, and each projection's range in it.
fn upload_segments(
    cx: &WgpuContext,
    edges: &[[glam::Vec3; 2]],
    light: &LightView,
    res: u32,
) -> (Transient, Vec<std::ops::Range<u32>>) {
    let mut all: Vec<MapSegment> = Vec::new();
    let mut ranges = Vec::new();
    for p in &light.projections {
        let start = all.len() as u32;
        all.extend(project_segments(edges, p, res));
        ranges.push(start..all.len() as u32);
    }
    if all.is_empty() {
        // A storage binding cannot be empty; nothing is drawn from it.
        all.push(MapSegment::default());
    }
    (cx.transient(bytemuck::cast_slice(&all)), ranges)
}

/// Pass 2 for every projection, after zeroing both counters.
fn draw_points(
    cx: &WgpuContext,
    state: &State,
    maps: &Maps,
    segments: &Transient,
    ranges: &[std::ops::Range<u32>],
    margin: f32,
) {
    let res = maps.depth.width();
    let side = res - 1;
    let depth_view = maps.depth.create_view(&wgpu::TextureViewDescriptor {
        dimension: Some(wgpu::TextureViewDimension::D2Array),
        ..Default::default()
    });
    let point_depth = maps.point_depth.create_view(&Default::default());
    let mut enc = cx.encoder("silhouette map");
    enc.clear_buffer(&state.counters, 0, None);
    for (k, range) in ranges.iter().enumerate() {
        let params = BuildParams { settings: [res as f32, side as f32, margin, k as f32] };
        let params = cx.transient(bytemuck::bytes_of(&params));
        let group = cx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("silhouette points"),
            layout: &state.points_layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: segments.binding() },
                wgpu::BindGroupEntry { binding: 1, resource: wgpu::BindingResource::TextureView(&depth_view) },
                wgpu::BindGroupEntry { binding: 2, resource: params.binding() },
            ],
        });
        let layer = layer_view(&maps.points, k as u32);
        {
            let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("silhouette points"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &layer,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color { r: -1.0, g: -1.0, b: 0.0, a: 0.0 }),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &point_depth,
                    depth_ops: Some(wgpu::Operations { load: wgpu::LoadOp::Clear(1.0), store: wgpu::StoreOp::Discard }),
                    stencil_ops: None,
                }),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            if !range.is_empty() {
                pass.set_pipeline(&state.points);
                pass.set_bind_group(0, &group, &[]);
                pass.draw(0..6, range.clone());
            }
        }
    }
    cx.submit(enc);
}

/// Counts the non-empty texels of every layer into the first counter, then reads both counters:
/// (non-empty texels, silhouette pixels).
fn count(cx: &WgpuContext, state: &State, maps: &Maps) -> Result<(u64, u64), WgpuError> {
    let side = maps.points.width();
    let mut enc = cx.encoder("count texels");
    for k in 0..maps.points.depth_or_array_layers() {
        let layer = layer_view(&maps.points, k);
        let group = cx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("count silhouette texels"),
            layout: &state.count.get_bind_group_layout(0),
            entries: &[
                wgpu::BindGroupEntry { binding: 3, resource: wgpu::BindingResource::TextureView(&layer) },
                wgpu::BindGroupEntry {
                    binding: 4,
                    resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                        buffer: &state.counters,
                        offset: 0,
                        size: wgpu::BufferSize::new(4),
                    }),
                },
            ],
        });
        let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("count silhouette texels"),
            timestamp_writes: None,
        });
        pass.set_pipeline(&state.count);
        pass.set_bind_group(0, &group, &[]);
        pass.dispatch_workgroups(side.div_ceil(8), side.div_ceil(8), 1);
    }
    cx.submit(enc);
    read_counters(cx, &state.counters)
}

/// Reads both counters: (non-empty texels, silhouette pixels).
fn read_counters(cx: &WgpuContext, counters: &wgpu::Buffer) -> Result<(u64, u64), WgpuError> {
    let staging = cx.create_buffer(&wgpu::BufferDescriptor {
        label: Some("silhouette counters readback"),
        size: COUNTER_STRIDE + 4,
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    });
    let mut enc = cx.encoder("readback");
    enc.copy_buffer_to_buffer(counters, 0, &staging, 0, COUNTER_STRIDE + 4);
    cx.submit(enc);
    let d = readback::map_read(cx, &staging, "reading the silhouette counters")?;
    let word = |at: usize| u64::from(u32::from_le_bytes([d[at], d[at + 1], d[at + 2], d[at + 3]]));
    Ok((word(0), word(COUNTER_STRIDE as usize)))
}

impl ShadowTechnique<WgpuBackend> for SilhouetteMap {
    type State = State;

    fn name(&self) -> &'static str {
        Self::NAME
    }

    fn create_state(&self, cx: &mut WgpuContext) -> Result<State, WgpuError> {
        cx.scoped("creating the silhouette-map pipelines", |cx| State::new(cx, self))
    }

    /// With cascades the maps follow the camera, which the build key does not hold.
    fn build_is_reusable(&self, _: &shadow_core::FrameInputs) -> bool {
        self.cascades == 0
    }

    fn build(&self, cx: &mut WgpuContext, state: &mut State, pass: LightPass<'_>) -> Result<(), WgpuError> {
        let LightPass { frame, light, stats, aspect, .. } = pass;
        let view = self.view(frame, light, aspect);
        let light = &*view;
        let res = self.depth.resolution;
        check_size(cx, "shadow map", res, res)?;
        state.allocate(cx, res, light.projections.len() as u32)?;
        let Some(maps) = &state.maps else { return Err(TechniqueError::NotBuilt(Self::NAME.into()).into()) };
        cx.upload_meshes(frame);
        cx.upload_textures(frame)?;
        let instances = cx.instances(frame);
        let edges = frame.silhouette_segments(light);
        cx.scoped("the silhouette-map passes", |cx| {
            render_maps(cx, &state.light_pass, frame, light, &maps.depth, None, &instances);
            let (segments, ranges) = upload_segments(cx, &edges, light, res);
            draw_points(cx, state, maps, &segments, &ranges, self.corner_margin);
        })?;
        stats.counters.silhouette_edges = Some(edges.len() as u64);
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
        let LightPass { frame, light, stats, aspect, .. } = pass;
        let view = self.view(frame, light, aspect);
        let light = &*view;
        let maps = state.maps.as_ref().ok_or_else(|| TechniqueError::NotBuilt(Self::NAME.into()))?;
        let points = maps.points.create_view(&wgpu::TextureViewDescriptor {
            dimension: Some(wgpu::TextureViewDimension::D2Array),
            ..Default::default()
        });
        let entries = [
            wgpu::BindGroupEntry { binding: 4, resource: wgpu::BindingResource::TextureView(&points) },
            wgpu::BindGroupEntry { binding: 5, resource: wgpu::BindingResource::TextureView(&g.geometric_normal) },
            wgpu::BindGroupEntry {
                binding: 6,
                resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                    buffer: &state.counters,
                    offset: COUNTER_STRIDE,
                    size: wgpu::BufferSize::new(4),
                }),
            },
            wgpu::BindGroupEntry { binding: 7, resource: wgpu::BindingResource::Sampler(&state.corners) },
        ];
        let receiver_plane = if self.corner_depth == CornerDepth::ReceiverPlane { 1.0 } else { 0.0 };
        let extras = QueryExtras { settings: [receiver_plane, 0.0, 0.0, 0.0], entries: &entries };
        state.query.run(cx, &maps.depth, light, g, out, &extras)?;
        // The counters cost a compute pass and a readback that the technique itself does not need: a
        // sub-phase of their own, after the query's work is done, so they can be told apart.
        if !cx.instrumented() {
            return Ok(());
        }
        cx.wait()?;
        let t = std::time::Instant::now();
        let (texels, pixels) = cx.scoped("the silhouette counters", |cx| count(cx, state, maps))??;
        stats.timings.extra.insert("count_silhouette".into(), shadow_core::stats::ms(t.elapsed()));
        stats.counters.extra.insert("silhouette_texels".into(), texels as f64);
        stats.counters.silhouette_pixels = Some(pixels);
        Ok(())
    }

    fn debug_views(&self, cx: &mut WgpuContext, state: &State) -> Result<Vec<DebugView>, WgpuError> {
        let Some(maps) = &state.maps else { return Ok(Vec::new()) };
        let mut views = Vec::new();
        for k in 0..maps.depth.depth_or_array_layers() {
            let depth = readback::read_f32(cx, &maps.depth, k, wgpu::TextureAspect::DepthOnly)?;
            let points = readback::read_rg32(cx, &maps.points, k)?;
            let nearest = depth.data().iter().copied().fold(1.0f32, f32::min);
            let image = shadow_core::image::false_colour(&depth, nearest, 1.0);
            views.push(DebugView { name: format!("depth{k}"), image });
            views.push(DebugView { name: format!("silhouette{k}"), image: overlay(&depth, &points) });
        }
        Ok(views)
    }
}

/// The query: the shadow-map shader and the reconstruction.
#[must_use]
pub fn query_shader() -> String {
    shaders::with_shadow_map(include_str!("query.wgsl"))
}

/// Pass 2 (the points) and the texel count; it reads no frame state, so it stands alone.
#[must_use]
pub fn build_shader() -> String {
    include_str!("build.wgsl").to_string()
}

/// Every shader, by name, for validation.
#[must_use]
pub fn shaders() -> Vec<(&'static str, String)> {
    vec![("silhouette-map query", query_shader()), ("silhouette-map build", build_shader())]
}
