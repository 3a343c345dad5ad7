//! `midpoint-shadow-map`, `second-depth-shadow-map` and `dual-shadow-map` on the GPU (twin: depth_layers/cpu.rs). Per light projection: pass 1 renders z1; pass 2 renders again with
//! fragments at z1 discarded (depth peeling), giving z2; a full-screen pass combines them and writes the
//! result as depth into that layer of the map array, which the ordinary shadow-map query then reads.
//! Culling is chosen per instance (closed meshes cull back faces under `culling=auto`), with clockwise
//! pipeline variants for mirrored instances.

use super::{DepthLayers, LayerCulling, LayerKind};
use bytemuck::{Pod, Zeroable};
use shadow_core::FrameInputs;
use shadow_core::frame::Coverage;
use shadow_core::light::LightProjection;
use shadow_core::technique::settings::Filter;
use shadow_core::technique::{BuildReads, LightPass};
use shadow_core::technique::{ShadowTechnique, TechniqueError};

use shadow_wgpu::frame::{GpuVisibility, layer_view};
use shadow_wgpu::gbuffer::{GpuGBuffer, check_size};
use shadow_wgpu::passes::maps::{LookupParams, MapQuery, QueryExtras, map_texture};
use shadow_wgpu::pipelines::{MAP_DEPTH, POSITION_LAYOUT, UV_LAYOUT, ViewRaw, buffer_entry, depth_entry, depth_pass};
use shadow_wgpu::shaders;
use shadow_wgpu::textures::read_texture;
use shadow_wgpu::{WgpuBackend, WgpuContext, WgpuError};

/// GPU twin of `LayerParams` in layers.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct LayerParams {
    view: [f32; 4],
    settings: [f32; 4],
}

/// Pipelines (index: `Pass::index`) and the maps of the last build.
pub struct State {
    /// Made with the state but for the cut-out passes, which the first frame with such casters makes.
    passes: Vec<std::cell::OnceCell<wgpu::RenderPipeline>>,
    /// The module and the pipeline layouts (without and with the caster's texture) the passes are made from.
    module: wgpu::ShaderModule,
    layouts: [wgpu::PipelineLayout; 2],
    combine: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
    query: MapQuery,
    maps: Option<wgpu::Texture>,
    scratch: Option<(wgpu::Texture, wgpu::Texture)>,
}

/// Which pass draws a caster: the peel pass or the first, culling back faces or not, fronts clockwise or
/// not, cut out by its texture or not.
#[derive(Clone, Copy)]
struct Pass {
    peel: bool,
    cull: bool,
    cw: bool,
    cutout: bool,
}

impl Pass {
    const COUNT: usize = 16;

    fn index(self) -> usize {
        usize::from(self.cutout) * 8 + usize::from(self.peel) * 4 + usize::from(self.cull) * 2 + usize::from(self.cw)
    }

    fn of(index: usize) -> Self {
        Self { cutout: index & 8 != 0, peel: index & 4 != 0, cull: index & 2 != 0, cw: index & 1 != 0 }
    }
}

fn kind_code(k: LayerKind) -> f32 {
    match k {
        LayerKind::Midpoint => 0.0,
        LayerKind::SecondDepth => 1.0,
        LayerKind::Dual => 2.0,
    }
}

/// A map depth target written with `compare`.
fn depth_state(compare: wgpu::CompareFunction) -> wgpu::DepthStencilState {
    wgpu::DepthStencilState {
        format: MAP_DEPTH,
        depth_write_enabled: Some(true),
        depth_compare: Some(compare),
        stencil: Default::default(),
        bias: Default::default(),
    }
}

/// One light pass of the layers: the nearest layer, or with `peel` the next one behind the first; back
/// faces culled when `cull`, fronts wound clockwise (mirrored instances) when `cw`, the fragments of
/// clear texels discarded when `cutout` (group 2: the caster's texture).
fn layer_pipeline(
    cx: &WgpuContext,
    layouts: [&wgpu::PipelineLayout; 2],
    module: &wgpu::ShaderModule,
    Pass { peel, cull, cw, cutout }: Pass,
) -> wgpu::RenderPipeline {
    let fragment = match (peel, cutout) {
        (false, false) => None,
        (true, false) => Some("fs_peel"),
        (false, true) => Some("fs_layer_cutout"),
        (true, true) => Some("fs_peel_cutout"),
    };
    let buffers = [Some(POSITION_LAYOUT), Some(UV_LAYOUT)];
    cx.pipelines.render(&wgpu::RenderPipelineDescriptor {
        label: Some(if cutout { "depth layer, cut out" } else { "depth layer" }),
        layout: Some(layouts[usize::from(cutout)]),
        vertex: wgpu::VertexState {
            module,
            entry_point: Some(if cutout { "vs_light_cutout" } else { "vs_layer" }),
            compilation_options: Default::default(),
            buffers: if cutout { &buffers } else { &buffers[..1] },
        },
        primitive: wgpu::PrimitiveState {
            front_face: if cw { wgpu::FrontFace::Cw } else { wgpu::FrontFace::Ccw },
            cull_mode: cull.then_some(wgpu::Face::Back),
            ..Default::default()
        },
        depth_stencil: Some(depth_state(wgpu::CompareFunction::Less)),
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

impl State {
    /// The pipeline of `pass`, made now if it is a cut-out one not made yet.
    fn pass(&self, cx: &WgpuContext, pass: Pass) -> &wgpu::RenderPipeline {
        let [plain, cut_out] = &self.layouts;
        self.passes[pass.index()].get_or_init(|| layer_pipeline(cx, [plain, cut_out], &self.module, pass))
    }

    fn new(cx: &WgpuContext, filter: Filter, lookup: LookupParams) -> Self {
        let module = cx.pipelines.module("depth_layers", shader());
        let map_module = cx.pipelines.module("shadow_map", shaders::shadow_map());
        let layout = cx.pipelines.group_layout(
            "depth layers",
            &[
                depth_entry(0),
                depth_entry(1),
                buffer_entry(2, wgpu::BufferBindingType::Uniform, wgpu::ShaderStages::FRAGMENT),
            ],
        );
        let groups = [Some(&cx.shared.frame_layout), Some(&layout), Some(&cx.shared.material_layout)];
        let pl = cx.pipelines.layout("depth layers", &groups[..2]);
        let cut_out = cx.pipelines.layout("depth layers, cut out", &groups);
        let passes: Vec<std::cell::OnceCell<wgpu::RenderPipeline>> = (0..Pass::COUNT)
            .map(|i| {
                let pass = Pass::of(i);
                let made = std::cell::OnceCell::new();
                if !pass.cutout {
                    let _ = made.set(layer_pipeline(cx, [&pl, &cut_out], &module, pass));
                }
                made
            })
            .collect();
        let combine = cx.pipelines.render(&wgpu::RenderPipelineDescriptor {
            label: Some("combine layers"),
            layout: Some(&pl),
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs_full_screen"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            primitive: Default::default(),
            depth_stencil: Some(depth_state(wgpu::CompareFunction::Always)),
            multisample: Default::default(),
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("fs_combine"),
                compilation_options: Default::default(),
                targets: &[],
            }),
            multiview_mask: None,
            cache: None,
        });
        Self {
            passes,
            module: module.clone(),
            layouts: [pl.clone(), cut_out],
            combine,
            layout,
            query: MapQuery::new(cx, &map_module, filter).with_lookup(lookup),
            maps: None,
            scratch: None,
        }
    }
}

/// Both layers and their combination for projection `proj`, into layer `k` of `maps`.
fn render_projection(
    s: &DepthLayers,
    cx: &WgpuContext,
    state: &State,
    frame: &FrameInputs,
    (k, proj): (u32, &LightProjection),
    maps: &wgpu::Texture,
    instances: &wgpu::Buffer,
) {
    let Some((z1, z2)) = &state.scratch else { return };
    let res = maps.width();
    let group0 = cx.shared.frame_group(cx, &ViewRaw::new(proj.clip_from_world, glam::Vec3::ZERO, res, res), instances);
    let params = LayerParams {
        view: [proj.near, proj.far, if proj.orthographic { 1.0 } else { 0.0 }, kind_code(s.kind)],
        settings: [s.z_offset, s.peel_epsilon, 0.0, 0.0],
    };
    let params = cx.transient(bytemuck::bytes_of(&params));
    let (v1, v2) = (z1.create_view(&Default::default()), z2.create_view(&Default::default()));
    let group1 = |a: &wgpu::TextureView, b: &wgpu::TextureView| {
        cx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("depth layers"),
            layout: &state.layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: wgpu::BindingResource::TextureView(a) },
                wgpu::BindGroupEntry { binding: 1, resource: wgpu::BindingResource::TextureView(b) },
                wgpu::BindGroupEntry { binding: 2, resource: params.binding() },
            ],
        })
    };
    // Pass 1 cannot bind z1 while writing it: it gets z2's texture as a stand-in it never reads.
    let (first, peel) = (group1(&v2, &v2), group1(&v1, &v1));
    let mut enc = cx.encoder("depth layers");
    for (peeling, target, group) in [(false, &v1, &first), (true, &v2, &peel)] {
        let mut pass = depth_pass(&mut enc, target, if peeling { "second layer" } else { "first layer" });
        pass.set_bind_group(0, &group0, &[]);
        pass.set_bind_group(1, group, &[]);
        // A run's instances share a mesh, a texture, a coverage and a winding (`DrawOrder`).
        let keep = |i: &shadow_core::Instance| i.casts_shadow && i.coverage() != Coverage::Absent;
        for (i, slots) in cx.cache.order().runs(frame, keep) {
            let inst = &frame.instances[i];
            let Some(m) = cx.cache.mesh(inst) else { continue };
            let cutout = inst.coverage() == Coverage::Cutout;
            if cutout {
                let texture = read_texture(inst).and_then(|t| cx.cache.textures.get(t));
                let (Some(texture), Some(uvs)) = (texture, m.uvs) else { continue };
                pass.set_bind_group(2, &texture.group, &[]);
                pass.set_vertex_buffer(1, uvs.slice(..));
            }
            let cull = s.culling == LayerCulling::Auto && inst.adjacency.closed();
            pass.set_pipeline(state.pass(cx, Pass { peel: peeling, cull, cw: inst.mirrored, cutout }));
            pass.set_vertex_buffer(0, m.positions.slice(..));
            pass.set_index_buffer(m.indices.slice(..), wgpu::IndexFormat::Uint32);
            pass.draw_indexed(0..m.index_count, 0, slots);
        }
    }
    {
        let out = layer_view(maps, k);
        let both = group1(&v1, &v2);
        let mut pass = depth_pass(&mut enc, &out, "combine layers");
        pass.set_pipeline(&state.combine);
        pass.set_bind_group(0, &group0, &[]);
        pass.set_bind_group(1, &both, &[]);
        pass.draw(0..3, 0..1);
    }
    cx.submit(enc);
}

impl ShadowTechnique<WgpuBackend> for DepthLayers {
    type State = State;

    fn name(&self) -> &'static str {
        self.kind.name()
    }

    fn create_state(&self, cx: &mut WgpuContext) -> Result<State, WgpuError> {
        cx.scoped("creating the depth-layer pipelines", |cx| {
            State::new(cx, self.filter, LookupParams { radius: self.filter_radius, receiver_offset: 0.0 })
        })
    }

    fn build(&self, cx: &mut WgpuContext, state: &mut State, pass: LightPass<'_>) -> Result<(), WgpuError> {
        let LightPass { frame, light, aspect, .. } = pass;
        let view = self.view(frame, light, aspect);
        let light = &*view;
        let (res, layers) = (self.resolution, light.projections.len() as u32);
        check_size(cx, "shadow map", res, res)?;
        if !state.maps.as_ref().is_some_and(|m| m.width() == res && m.depth_or_array_layers() == layers) {
            state.maps = Some(cx.scoped("allocating shadow maps", |cx| map_texture(cx, res, layers))?);
        }
        if state.scratch.as_ref().is_none_or(|(a, _)| a.width() != res) {
            state.scratch =
                Some(cx.scoped("allocating depth layers", |cx| (map_texture(cx, res, 1), map_texture(cx, res, 1)))?);
        }
        cx.upload_meshes(frame);
        cx.upload_textures(frame)?;
        let instances = cx.instances(frame);
        let maps = state.maps.clone().ok_or_else(|| TechniqueError::NotBuilt(self.kind.name().into()))?;
        cx.scoped("the depth-layer passes", |cx| {
            for (k, proj) in light.projections.iter().enumerate() {
                render_projection(self, cx, state, frame, (k as u32, proj), &maps, &instances);
            }
        })
    }

    fn query(
        &self,
        cx: &mut WgpuContext,
        state: &mut State,
        pass: LightPass<'_>,
        g: &GpuGBuffer,
        out: &mut GpuVisibility,
    ) -> Result<(), WgpuError> {
        let LightPass { frame, light, aspect, .. } = pass;
        let view = self.view(frame, light, aspect);
        let maps = state.maps.as_ref().ok_or_else(|| TechniqueError::NotBuilt(self.kind.name().into()))?;
        state.query.run(cx, maps, &view, g, out, &QueryExtras::NONE)
    }

    /// With cascades the maps follow the camera, which the build key does not hold.
    fn build_is_reusable(&self, _: &FrameInputs) -> bool {
        self.cascades == 0
    }

    /// Its build peels casters' layers in the light's maps and reads nothing else of the frame.
    fn build_reads(&self) -> BuildReads {
        BuildReads::LightViews
    }
}

/// The technique's shaders as compiled, by name (its registry entry's WGSL).
#[must_use]
pub fn shaders() -> Vec<(&'static str, String)> {
    vec![("depth layers", shader())]
}

/// The peeling and combination passes.
#[must_use]
pub fn shader() -> String {
    shaders::with_cutout_casters(include_str!("layers.wgsl"))
}
