//! `penumbra-wedges` on the wgpu backend (twin: [`super::cpu`]), through its public API: the shared
//! quads and wedges, uploaded by the query, which draws both over the G-buffer in one pass into a buffer
//! of occluded shares (wedges.wgsl, with coverage.wgsl's terms), then resolves it full-screen; with cut-out
//! casters, times the visibility their map's lookup wrote into a target of its own first.

use bytemuck::{Pod, Zeroable};
use shadow_core::glam::Vec4;
use shadow_core::light::PixelRect;
use shadow_core::technique::LightPass;
use shadow_core::technique::{ShadowTechnique, TechniqueError};
use shadow_wgpu::pipelines::{VISIBILITY, attribute_entry, buffer_entry, full_screen_pipeline};
use shadow_wgpu::{GpuGBuffer, GpuVisibility, TransientRing, WgpuBackend, WgpuContext, WgpuError, passes, shaders};

use super::PenumbraWedges;
use super::coverage::SphereLight;
use super::geometry::{LAYERS, PixelScale, QUAD_DEPTH_BIAS, WedgeEdge, WedgeGeometry};
use shadow_wgpu::passes::maps::CutoutMaps;

/// GPU twin of `WedgeParams` in wedges.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct WedgeParams {
    light: [f32; 4],
    eye: [f32; 4],
    eye_counts: [f32; 4],
    size: [u32; 4],
}

/// One quad or wedge corner: its homogeneous world point and its edge's index.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct EdgeVertex {
    position: [f32; 4],
    edge: u32,
}

/// GPU twin of `Edge` in wedges.wgsl: the ends, with the weight and the layer, and the wedge's planes.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct GpuEdge {
    a: [f32; 4],
    b: [f32; 4],
    planes: [[f32; 4]; 4],
}

impl From<&WedgeEdge> for GpuEdge {
    fn from(e: &WedgeEdge) -> Self {
        Self {
            a: e.a.extend(e.weight).to_array(),
            b: e.b.extend(e.layer as u32 as f32).to_array(),
            planes: e.planes.map(|p| p.to_array()),
        }
    }
}

const VERTEX_LAYOUT: wgpu::VertexBufferLayout<'static> = wgpu::VertexBufferLayout {
    array_stride: std::mem::size_of::<EdgeVertex>() as u64,
    step_mode: wgpu::VertexStepMode::Vertex,
    attributes: &wgpu::vertex_attr_array![0 => Float32x4, 1 => Uint32],
};

/// Pipelines, and the last build's uploads.
pub struct State {
    layout: wgpu::BindGroupLayout,
    module: wgpu::ShaderModule,
    quads: wgpu::RenderPipeline,
    wedges: wgpu::RenderPipeline,
    resolve: wgpu::RenderPipeline,
    built: Option<Built>,
    /// Each frame's edges, side quads and wedges: their number follows the silhouette, so they have
    /// buffers of their own, which a figure's silhouette growing as it moves seldom outgrows.
    geometry: TransientRing,
    /// The per-pixel sums, one view's worth per layer, kept while the view's size does not change.
    occluded: Option<wgpu::Buffer>,
    /// The cut-out casters' map, and, made by the first frame with such casters, the resolve that
    /// multiplies by its visibility and the target that visibility is written into (at the view's size).
    cutouts: CutoutMaps,
    cutout_resolve: Option<(wgpu::BindGroupLayout, wgpu::RenderPipeline)>,
    cutout_target: Option<wgpu::Texture>,
}

/// The bindings of the resolve's group 1: the passes', and with `cutouts` the cut-out visibility (5).
fn group_entries(cutouts: bool) -> Vec<wgpu::BindGroupLayoutEntry> {
    let read_write = wgpu::BufferBindingType::Storage { read_only: false };
    let mut entries = vec![
        attribute_entry(0),
        buffer_entry(1, read_write, wgpu::ShaderStages::FRAGMENT),
        buffer_entry(2, wgpu::BufferBindingType::Uniform, wgpu::ShaderStages::FRAGMENT),
        attribute_entry(3),
        buffer_entry(4, wgpu::BufferBindingType::Storage { read_only: true }, wgpu::ShaderStages::FRAGMENT),
    ];
    if cutouts {
        entries.push(attribute_entry(5));
    }
    entries
}

/// One build's geometry, as vertices and edges: uploaded by each query into the frame's transient
/// buffer, so a kept build costs no allocation and a moving light none either. The side quads are grown
/// by a margin in the view's pixels ([`WedgeGeometry::side_quads`]), so each query makes them afresh.
struct Built {
    geometry: WedgeGeometry,
    light: SphereLight,
    edges: Vec<GpuEdge>,
    wedges: Vec<EdgeVertex>,
}

/// The corners of `triangles`, each with its edge's index (`edge_of(triangle)`).
fn vertices(triangles: &[[Vec4; 3]], edge_of: impl Fn(usize) -> u32) -> Vec<EdgeVertex> {
    triangles
        .iter()
        .enumerate()
        .flat_map(|(t, corners)| corners.map(|p| EdgeVertex { position: p.to_array(), edge: edge_of(t) }))
        .collect()
}

/// A pipeline drawing edge geometry against the G-buffer's depth, writing only the buffer.
fn edge_pipeline(
    cx: &WgpuContext,
    module: &wgpu::ShaderModule,
    layout: &wgpu::BindGroupLayout,
    (label, fragment): (&str, &str),
    (cull_mode, depth_compare, bias): (Option<wgpu::Face>, wgpu::CompareFunction, wgpu::DepthBiasState),
) -> wgpu::RenderPipeline {
    let pipeline_layout = cx.pipelines.layout(label, &[Some(&cx.shared.frame_layout), Some(layout)]);
    cx.pipelines.render(&wgpu::RenderPipelineDescriptor {
        label: Some(label),
        layout: Some(&pipeline_layout),
        vertex: wgpu::VertexState {
            module,
            entry_point: Some("vs_edge"),
            compilation_options: Default::default(),
            buffers: &[Some(VERTEX_LAYOUT)],
        },
        primitive: wgpu::PrimitiveState { cull_mode, ..Default::default() },
        depth_stencil: Some(wgpu::DepthStencilState {
            format: cx.depth_stencil,
            depth_write_enabled: Some(false),
            depth_compare: Some(depth_compare),
            stencil: Default::default(),
            bias,
        }),
        multisample: Default::default(),
        fragment: Some(wgpu::FragmentState {
            module,
            entry_point: Some(fragment),
            compilation_options: Default::default(),
            targets: &[],
        }),
        multiview_mask: None,
        cache: None,
    })
}

impl ShadowTechnique<WgpuBackend> for PenumbraWedges {
    type State = State;

    fn name(&self) -> &'static str {
        Self::NAME
    }

    fn create_state(&self, cx: &mut WgpuContext) -> Result<State, WgpuError> {
        cx.scoped("creating the penumbra-wedge pipelines", |cx| {
            let early = cx.device.features().contains(wgpu::Features::SHADER_EARLY_DEPTH_TEST);
            let module = cx.pipelines.module("penumbra wedges", shader(early));
            let layout = cx.pipelines.group_layout("penumbra wedges", &group_entries(false));
            // Side quads: the crossings in front of the receiver, and those within rounding of it (the
            // fragment decides); wedges: back faces behind the receiver.
            let bias = QUAD_DEPTH_BIAS;
            let quad_bias =
                wgpu::DepthBiasState { constant: bias.constant as i32, slope_scale: bias.slope, clamp: bias.clamp };
            let quad_state = (None, wgpu::CompareFunction::Less, quad_bias);
            let quads = edge_pipeline(cx, &module, &layout, ("side quads", "fs_quad"), quad_state);
            let wedge_state =
                (Some(wgpu::Face::Front), wgpu::CompareFunction::Greater, wgpu::DepthBiasState::default());
            let wedges = edge_pipeline(cx, &module, &layout, ("wedges", "fs_wedge"), wedge_state);
            let groups = [&cx.shared.frame_layout, &layout];
            let resolve = full_screen_pipeline(
                &cx.pipelines,
                "wedge resolve",
                &module,
                "fs_resolve",
                &groups,
                Some(VISIBILITY),
                None,
            );
            State {
                layout,
                module,
                quads,
                wedges,
                resolve,
                built: None,
                geometry: TransientRing::new("penumbra-wedge geometry"),
                occluded: None,
                cutouts: CutoutMaps::default(),
                cutout_resolve: None,
                cutout_target: None,
            }
        })
    }

    fn build(&self, cx: &mut WgpuContext, state: &mut State, pass: LightPass<'_>) -> Result<(), WgpuError> {
        let LightPass { frame, light, stats, .. } = pass;
        state.cutouts.render(cx, frame, light, &self.cutouts)?;
        let geometry = Self::construct(frame, light, stats)?;
        let light = Self::sphere(light)?;
        let edges = geometry.edges.iter().map(GpuEdge::from).collect();
        let wedges = vertices(&geometry.hulls, |t| geometry.hull_edges[t]);
        state.built = Some(Built { geometry, light, edges, wedges });
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
        let LightPass { frame, .. } = pass;
        let cutouts = cutout_visibility(cx, state, g)?;
        let built = state.built.as_ref().ok_or_else(|| TechniqueError::NotBuilt(Self::NAME.into()))?;
        let eye = g.camera.eye;
        let [closed, facing, turned] = built.geometry.eye_counts(frame, eye);
        let params = WedgeParams {
            light: built.light.centre.extend(built.light.radius).to_array(),
            eye: eye.extend(0.0).to_array(),
            eye_counts: [closed, facing, turned, 0.0],
            size: [g.width, g.height, 0, 0],
        };
        let size = u64::from(g.width) * u64::from(g.height) * 4 * LAYERS as u64;
        let occluded = match &state.occluded {
            Some(b) if b.size() == size => b,
            _ => state.occluded.insert(cx.create_buffer(&wgpu::BufferDescriptor {
                label: Some("occluded shares"),
                size,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })),
        };
        let quads = vertices(&built.geometry.side_quads(PixelScale::of(&g.camera, g.height)), |t| (t / 2) as u32);
        let wedges: &[EdgeVertex] = if self.wedges.is_on() { &built.wedges } else { &[] };
        let geometry = &mut state.geometry;
        cx.scoped("the penumbra wedges", |cx| {
            let uniform = cx.transient(bytemuck::bytes_of(&params));
            let parts =
                [bytemuck::cast_slice(&built.edges), bytemuck::cast_slice(&quads), bytemuck::cast_slice(wedges)];
            let [edges, quad_vertices, wedge_vertices] = geometry.write(cx, parts);
            let mut entries = vec![
                wgpu::BindGroupEntry { binding: 0, resource: wgpu::BindingResource::TextureView(&g.position) },
                wgpu::BindGroupEntry { binding: 1, resource: occluded.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 2, resource: uniform.binding() },
                wgpu::BindGroupEntry { binding: 3, resource: wgpu::BindingResource::TextureView(&g.geometric_normal) },
                wgpu::BindGroupEntry { binding: 4, resource: edges.binding() },
            ];
            let bind = |layout: &wgpu::BindGroupLayout, entries: &[wgpu::BindGroupEntry<'_>]| {
                cx.device.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("penumbra wedges"),
                    layout,
                    entries,
                })
            };
            let group = bind(&state.layout, &entries);
            let depth = g.depth_view();
            let mut enc = cx.encoder("penumbra wedges");
            enc.clear_buffer(occluded, 0, None);
            {
                let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some("penumbra wedges"),
                    color_attachments: &[],
                    depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                        view: &depth,
                        depth_ops: Some(wgpu::Operations { load: wgpu::LoadOp::Load, store: wgpu::StoreOp::Store }),
                        stencil_ops: None,
                    }),
                    timestamp_writes: None,
                    occlusion_query_set: None,
                    multiview_mask: None,
                });
                pass.set_bind_group(0, &g.frame_group, &[]);
                pass.set_bind_group(1, &group, &[]);
                let draws = [(&state.quads, quad_vertices, quads.len()), (&state.wedges, wedge_vertices, wedges.len())];
                for (pipeline, vertices, count) in draws.into_iter().filter(|(.., count)| *count > 0) {
                    pass.set_pipeline(pipeline);
                    pass.set_vertex_buffer(0, vertices.slice());
                    pass.draw(0..count as u32, 0..1);
                }
            }
            cx.submit(enc);
            match (&cutouts, &state.cutout_resolve) {
                (Some(visibility), Some((layout, resolve))) => {
                    let resource = wgpu::BindingResource::TextureView(visibility);
                    entries.push(wgpu::BindGroupEntry { binding: 5, resource });
                    let group = bind(layout, &entries);
                    passes::answer(cx, ("wedge resolve", out, passes::LIT), resolve, &[&g.frame_group, &group], None);
                }
                _ => {
                    let groups = [&g.frame_group, &group];
                    passes::answer(cx, ("wedge resolve", out, passes::LIT), &state.resolve, &groups, None);
                }
            }
        })
    }
}

/// The cut-out casters' visibility at every pixel of `g`, written by their map's lookup into the state's
/// target (made for the view's size) with the resolve that reads it made on first use; `None` when the
/// last build had no cut-out casters.
fn cutout_visibility(
    cx: &WgpuContext,
    state: &mut State,
    g: &GpuGBuffer,
) -> Result<Option<wgpu::TextureView>, WgpuError> {
    if !state.cutouts.is_rendered() {
        return Ok(None);
    }
    let target = match &state.cutout_target {
        Some(t) if (t.width(), t.height()) == (g.width, g.height) => t.clone(),
        _ => {
            let t = shadow_wgpu::frame::layered(cx, "cut-out visibility", g.width, g.height, 1, VISIBILITY);
            state.cutout_target.insert(t).clone()
        }
    };
    let view = target.create_view(&Default::default());
    let rect = PixelRect::full(g.width, g.height);
    let visibility = GpuVisibility { view: view.clone(), width: g.width, height: g.height, rect };
    state.cutouts.query(cx, g, &visibility)?;
    if state.cutout_resolve.is_none() {
        let layout = cx.pipelines.group_layout("penumbra wedges, cut out", &group_entries(true));
        let groups = [&cx.shared.frame_layout, &layout];
        let module = &state.module;
        let resolve = full_screen_pipeline(
            &cx.pipelines,
            "wedge resolve, cut out",
            module,
            "fs_resolve_cutouts",
            &groups,
            Some(VISIBILITY),
            None,
        );
        state.cutout_resolve = Some((layout, resolve));
    }
    Ok(Some(view))
}

/// The technique's shaders as compiled, by name (its registry entry's WGSL): with the depth tests
/// forced early and without.
#[must_use]
pub fn shaders() -> Vec<(&'static str, String)> {
    vec![("penumbra wedges", shader(true)), ("penumbra wedges, late depth tests", shader(false))]
}

/// The WGSL: the frame's bindings, the coverage terms, the passes, then the two entry points that draw
/// edges. With `early`, their depth tests are forced before the fragment: a fragment that writes storage
/// otherwise runs whatever its test says, and only the test "less" (quads behind the receiver) and
/// "greater" (wedges in front of it) keep a side quad or a wedge, which reach to infinity, from shading
/// most of the view (what they would add there is zero either way).
#[must_use]
pub fn shader(early: bool) -> String {
    let entries = if early { include_str!("edge_entries_early.wgsl") } else { include_str!("edge_entries.wgsl") };
    let passes = [include_str!("coverage.wgsl"), include_str!("wedges.wgsl"), entries].join("\n");
    shaders::with_common(&passes)
}
