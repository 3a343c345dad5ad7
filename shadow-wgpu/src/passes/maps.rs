//! Light depth maps on the GPU (twin: shadow-cpu's `passes::maps`): the light pass renders depth with the
//! pipeline's depth bias into one layer per projection; a map query runs `shadow_lookup` of
//! shadow_map.wgsl over the G-buffer, with the hardware comparison sampler for bilinear taps. Techniques
//! that look into the maps their own way add a fragment entry and bindings from 4 on ([`MapQuery::with_entry`]).
//! [`CutoutMaps`] holds the casters their texture cuts out alone, for the techniques built on silhouettes.

use bytemuck::{Pod, Zeroable};
use shadow_core::frame::Coverage;
use shadow_core::light::LightView;
use shadow_core::technique::maps::{Casters, CutoutMap, DepthMap};
use shadow_core::technique::settings::{BiasMode, Filter};
use shadow_core::{FrameInputs, Instance};

use crate::context::{WgpuContext, WgpuError};
use crate::frame::{GpuVisibility, layer_view, layered};
use crate::gbuffer::{GpuGBuffer, check_size, draw_instances, draw_textured};
use crate::pipelines::{
    FragmentEntry, LightRaw, MAP_DEPTH, POSITION_LAYOUT, UV_LAYOUT, VISIBILITY, ViewRaw, attribute_entry, buffer_entry,
    depth_array_entry, full_screen_pipeline,
};
use crate::shaders;

/// How a map lookup reads one light's maps: GPU twin of `MapParams` in shadow_map.wgsl, and of
/// `ShadowlabMap` in the host module (`host_wgsl::MAPS`), which reads the filter from `settings.x`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct MapParams {
    proj: [[[f32; 4]; 4]; 6],
    light: LightRaw,
    settings: [f32; 4],
    planes: [[[f32; 4]; 4]; 6],
    extra: [f32; 4],
    cascade: [f32; 4],
    cascade_axis: [f32; 4],
    cascade_far: [f32; 4],
}

/// The bindings every map lookup shares (group 1, bindings 0 to 3: G-buffer positions, the maps, the
/// comparison sampler, `MapParams`), with a technique's own from 4 on.
pub struct MapBindings {
    layout: wgpu::BindGroupLayout,
    sampler: wgpu::Sampler,
}

/// What a map query adds to the shared bindings (0 to 3): settings and resources.
pub struct QueryExtras<'a> {
    /// Technique-specific settings (`MapParams.extra`).
    pub settings: [f32; 4],
    /// Bindings from 4 on.
    pub entries: &'a [wgpu::BindGroupEntry<'a>],
}

impl QueryExtras<'_> {
    /// None: the plain shadow-map query.
    pub const NONE: QueryExtras<'static> = QueryExtras { settings: [0.0; 4], entries: &[] };
}

/// How a map lookup reads the maps: the filter's kernel radius in texels and the receiver offset
/// towards the light (`bias=world`).
#[derive(Clone, Copy, Debug, Default)]
pub struct LookupParams {
    /// Kernel radius in texels (jittered and Poisson filters).
    pub radius: f32,
    /// World distance a receiver moves towards the light before the lookup.
    pub receiver_offset: f32,
}

impl MapBindings {
    /// The layout: the shared bindings 0 to 3 and `extra` from 4 on.
    #[must_use]
    pub fn new(cx: &WgpuContext, extra: &[wgpu::BindGroupLayoutEntry]) -> Self {
        let mut entries = vec![
            attribute_entry(0),
            depth_array_entry(1),
            wgpu::BindGroupLayoutEntry {
                binding: 2,
                visibility: wgpu::ShaderStages::FRAGMENT,
                ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Comparison),
                count: None,
            },
            buffer_entry(3, wgpu::BufferBindingType::Uniform, wgpu::ShaderStages::FRAGMENT),
        ];
        entries.extend_from_slice(extra);
        let layout = cx.pipelines.group_layout("map query", &entries);
        // The sampler a host's lookup into lent maps makes too: the bilinear taps compare alike.
        let sampler = cx.device.create_sampler(&crate::HostMap::sampler_descriptor());
        Self { layout, sampler }
    }

    /// The group-1 layout, for pipelines that look into the maps.
    #[must_use]
    pub fn layout(&self) -> &wgpu::BindGroupLayout {
        &self.layout
    }

    /// The group for looking into `maps` (one layer per projection of `light`) from the receivers of `g`.
    #[must_use]
    pub fn group(
        &self,
        cx: &WgpuContext,
        maps: &wgpu::Texture,
        light: &LightView,
        g: &GpuGBuffer,
        lookup: LookupParams,
        extras: &QueryExtras<'_>,
    ) -> wgpu::BindGroup {
        self.group_of(cx, maps, &map_params(maps, light, lookup, extras.settings, None), g, extras)
    }

    /// [`Self::group`] with the lookup's parameters made already.
    fn group_of(
        &self,
        cx: &WgpuContext,
        maps: &wgpu::Texture,
        params: &MapParams,
        g: &GpuGBuffer,
        extras: &QueryExtras<'_>,
    ) -> wgpu::BindGroup {
        let params = cx.transient(bytemuck::bytes_of(params));
        let maps_view = maps.create_view(&wgpu::TextureViewDescriptor {
            dimension: Some(wgpu::TextureViewDimension::D2Array),
            ..Default::default()
        });
        let mut entries = vec![
            wgpu::BindGroupEntry { binding: 0, resource: wgpu::BindingResource::TextureView(&g.position) },
            wgpu::BindGroupEntry { binding: 1, resource: wgpu::BindingResource::TextureView(&maps_view) },
            wgpu::BindGroupEntry { binding: 2, resource: wgpu::BindingResource::Sampler(&self.sampler) },
            wgpu::BindGroupEntry { binding: 3, resource: params.binding() },
        ];
        entries.extend_from_slice(extras.entries);
        cx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("map query"),
            layout: &self.layout,
            entries: &entries,
        })
    }
}

/// The parameters of a lookup into `maps` (one layer per projection of `light`), with `filter` in
/// `settings.x` where a host reads it (the backend's own query compiles its filter in).
fn map_params(
    maps: &wgpu::Texture,
    light: &LightView,
    lookup: LookupParams,
    extra: [f32; 4],
    filter: Option<Filter>,
) -> MapParams {
    let (mut proj, mut planes) = ([[[0.0f32; 4]; 4]; 6], [[[0.0f32; 4]; 4]; 6]);
    for ((slot, plane), p) in proj.iter_mut().zip(&mut planes).zip(&light.projections) {
        *slot = p.clip_from_world.to_cols_array_2d();
        *plane = p.clip_plane_from_world_plane.to_cols_array_2d();
    }
    let (mut cascade, mut cascade_axis, mut cascade_far) = ([0.0f32; 4], [0.0f32; 4], [0.0f32; 4]);
    if let Some(c) = &light.cascades {
        cascade = [c.far.len() as f32, c.blend, c.near, 0.0];
        cascade_axis = c.axis.extend(-c.axis.dot(c.eye)).to_array();
        cascade_far[..c.far.len()].copy_from_slice(&c.far);
    }
    let filter = filter.map_or(0.0, |f| filter_code(f) as f32);
    MapParams {
        proj,
        light: LightRaw::from(&light.light),
        settings: [filter, lookup.radius, maps.width() as f32, lookup.receiver_offset],
        planes,
        extra,
        cascade,
        cascade_axis,
        cascade_far,
    }
}

/// The lookup every map-based technique shares (twin: `query_maps` in shadow-cpu): a full-screen pass
/// running `shadow_lookup` of shadow_map.wgsl over the G-buffer.
pub struct MapQuery {
    pipeline: wgpu::RenderPipeline,
    bindings: MapBindings,
    lookup: LookupParams,
    /// The filter of the plain lookup (`None` for a technique's own entry).
    filter: Option<Filter>,
    /// Whether a recorded frame lends the maps to the host ([`Self::lent_to_hosts`]).
    lent: bool,
}

impl MapQuery {
    /// Creates the query pipeline from the shadow-map module, specialized for `filter`.
    #[must_use]
    pub fn new(cx: &WgpuContext, module: &wgpu::ShaderModule, filter: Filter) -> Self {
        let constants = [("FILTER", filter_code(filter))];
        let entry = FragmentEntry { name: "fs_shadow_map_query", constants: &constants };
        Self { filter: Some(filter), ..Self::with_entry(cx, module, entry, &[]) }
    }

    /// A query pipeline running `entry` of `module` (the shadow-map shader with more after it), with the
    /// shared bindings 0 to 3 and `extra` from 4 on.
    #[must_use]
    pub fn with_entry(
        cx: &WgpuContext,
        module: &wgpu::ShaderModule,
        entry: FragmentEntry<'_>,
        extra: &[wgpu::BindGroupLayoutEntry],
    ) -> Self {
        let bindings = MapBindings::new(cx, extra);
        let pipeline = full_screen_pipeline(
            &cx.pipelines,
            "map query",
            module,
            entry,
            &[&cx.shared.frame_layout, bindings.layout()],
            Some(VISIBILITY),
            None,
        );
        Self { pipeline, bindings, lookup: LookupParams::default(), filter: None, lent: false }
    }

    /// The same query, reading the maps with `lookup` (the kernel radius and the receiver offset its
    /// settings ask for; none by default).
    #[must_use]
    pub fn with_lookup(self, lookup: LookupParams) -> Self {
        Self { lookup, ..self }
    }

    /// The same query, lending its maps to a host in recorded frames
    /// ([`FrameRecorder::map`](crate::FrameRecorder::map)): for a technique whose visibility is this one
    /// plain lookup and nothing more. A technique's own entry lends nothing.
    #[must_use]
    pub fn lent_to_hosts(self) -> Self {
        Self { lent: self.filter.is_some(), ..self }
    }

    /// Writes the visibility of every receiver through the maps (one layer per light projection).
    ///
    /// # Errors
    /// A GPU failure.
    pub fn run(
        &self,
        cx: &WgpuContext,
        maps: &wgpu::Texture,
        light: &LightView,
        g: &GpuGBuffer,
        out: &GpuVisibility,
        extras: &QueryExtras<'_>,
    ) -> Result<(), WgpuError> {
        // The filter rides in `settings.x` for a host; the backend's own query compiles it in.
        let lent = self.filter.filter(|_| self.lent);
        let params = map_params(maps, light, self.lookup, extras.settings, lent);
        if let Some(filter) = lent {
            cx.host_maps.lend(|| crate::HostMap { texture: maps.clone(), params, filter });
        }
        cx.scoped("the shadow-map query", |cx| {
            let group = self.bindings.group_of(cx, maps, &params, g, extras);
            super::answer(cx, ("map query", out, super::LIT), &self.pipeline, &[&g.frame_group, &group], None);
        })
    }
}

/// The depth-bias state of a shadow-map's light pass. wgpu takes the constant factor as an integer (in
/// units of the format's resolution, as Vulkan does), so it is rounded.
#[must_use]
pub fn depth_bias(s: &DepthMap) -> wgpu::DepthBiasState {
    match s.bias {
        BiasMode::None | BiasMode::World => wgpu::DepthBiasState::default(),
        BiasMode::Constant => {
            wgpu::DepthBiasState { constant: s.bias_constant.round() as i32, slope_scale: 0.0, clamp: 0.0 }
        }
        BiasMode::Slope => {
            wgpu::DepthBiasState { constant: s.bias_constant.round() as i32, slope_scale: s.bias_slope, clamp: 0.0 }
        }
    }
}

/// The light pass's pipelines: one for the casters that are everywhere (depth only, or depth and ID) and
/// one for those their texture cuts out, whose fragment stage discards the fragments of clear texels
/// (the texel rule of `texel.wgsl` over one map texel's footprint; group 2: the caster's texture). The
/// second is made by the first frame that has such casters, so a scene without them compiles nothing
/// for them.
pub struct LightPipelines {
    solid: wgpu::RenderPipeline,
    module: wgpu::ShaderModule,
    bias: wgpu::DepthBiasState,
    ids: bool,
    cutout: std::cell::OnceCell<wgpu::RenderPipeline>,
}

impl LightPipelines {
    fn new(cx: &WgpuContext, module: &wgpu::ShaderModule, bias: wgpu::DepthBiasState, ids: bool) -> Self {
        let solid = light_pipeline(cx, module, bias, ids, false);
        Self { solid, module: module.clone(), bias, ids, cutout: std::cell::OnceCell::new() }
    }

    /// The pipeline of the casters their texture cuts out.
    fn cutout(&self, cx: &WgpuContext) -> &wgpu::RenderPipeline {
        self.cutout.get_or_init(|| light_pipeline(cx, &self.module, self.bias, self.ids, true))
    }
}

/// The light pass: casters' depth, both faces, with `bias`.
#[must_use]
pub fn light_pass_pipeline(
    cx: &WgpuContext,
    module: &wgpu::ShaderModule,
    bias: wgpu::DepthBiasState,
) -> LightPipelines {
    LightPipelines::new(cx, module, bias, false)
}

/// The light pass with an object-ID target ([`ID_FORMAT`]): 1 + the instance index of the caster a texel
/// shows (McCool's ID channel).
#[must_use]
pub fn light_id_pipeline(cx: &WgpuContext, module: &wgpu::ShaderModule, bias: wgpu::DepthBiasState) -> LightPipelines {
    LightPipelines::new(cx, module, bias, true)
}

/// The format of the light pass's ID target.
pub const ID_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R32Uint;

fn light_pipeline(
    cx: &WgpuContext,
    module: &wgpu::ShaderModule,
    bias: wgpu::DepthBiasState,
    ids: bool,
    cutout: bool,
) -> wgpu::RenderPipeline {
    let layout = if cutout {
        cx.pipelines
            .layout("light pass cut out", &[Some(&cx.shared.frame_layout), None, Some(&cx.shared.material_layout)])
    } else {
        cx.pipelines.layout("light pass", &[Some(&cx.shared.frame_layout)])
    };
    let (vertex, fragment, label) = match (ids, cutout) {
        (false, false) => ("vs_light_depth", None, "light pass"),
        (true, false) => ("vs_light_id", Some("fs_light_id"), "light pass with IDs"),
        (false, true) => ("vs_light_cutout", Some("fs_light_cutout"), "light pass, cut out"),
        (true, true) => ("vs_light_cutout", Some("fs_light_id_cutout"), "light pass with IDs, cut out"),
    };
    let id_target = [Some(wgpu::ColorTargetState::from(ID_FORMAT))];
    let buffers = [Some(POSITION_LAYOUT), Some(UV_LAYOUT)];
    cx.pipelines.render(&wgpu::RenderPipelineDescriptor {
        label: Some(label),
        layout: Some(&layout),
        vertex: wgpu::VertexState {
            module,
            entry_point: Some(vertex),
            compilation_options: Default::default(),
            buffers: if cutout { &buffers } else { &buffers[..1] },
        },
        primitive: wgpu::PrimitiveState { cull_mode: None, ..Default::default() },
        depth_stencil: Some(wgpu::DepthStencilState {
            format: MAP_DEPTH,
            depth_write_enabled: Some(true),
            depth_compare: Some(wgpu::CompareFunction::Less),
            stencil: Default::default(),
            bias,
        }),
        multisample: Default::default(),
        fragment: fragment.map(|entry| wgpu::FragmentState {
            module,
            entry_point: Some(entry),
            compilation_options: Default::default(),
            targets: if ids { &id_target } else { &[] },
        }),
        multiview_mask: None,
        cache: None,
    })
}

/// Renders the casters' depth from every projection of `light` into the layers of `maps` (meshes,
/// textures and `instances` already uploaded), and their IDs into the layers of `ids` when given (with
/// pipelines from [`light_id_pipeline`]). Casters their texture cuts out are drawn through the alpha test
/// after the others; a masked caster with nothing there is drawn nowhere.
pub fn render_maps(
    cx: &WgpuContext,
    pipelines: &LightPipelines,
    frame: &FrameInputs,
    light: &LightView,
    maps: &wgpu::Texture,
    ids: Option<&wgpu::Texture>,
    instances: &wgpu::Buffer,
) {
    render_casters(cx, pipelines, (frame, Casters::All), light, (maps, ids), instances);
}

/// [`render_maps`] of the casters `casters` names; a caster wholly outside a projection's frustum is not
/// drawn into its map (it would draw nothing there) where the frame saves so.
fn render_casters(
    cx: &WgpuContext,
    pipelines: &LightPipelines,
    (frame, casters): (&FrameInputs, Casters),
    light: &LightView,
    (maps, ids): (&wgpu::Texture, Option<&wgpu::Texture>),
    instances: &wgpu::Buffer,
) {
    let res = maps.width();
    let cutouts = frame.has_cutout_casters();
    let mut enc = cx.encoder("light pass");
    let culling = frame.savings.culling;
    for (k, p) in light.projections.iter().enumerate() {
        let in_view = |i: &Instance| !culling || p.may_hold(i.bounds);
        let group = cx.shared.frame_group(cx, &ViewRaw::new(p.clip_from_world, glam::Vec3::ZERO, res, res), instances);
        let view = layer_view(maps, k as u32);
        let id_view = ids.map(|t| layer_view(t, k as u32));
        let id_attachment = id_view.as_ref().map(|view| wgpu::RenderPassColorAttachment {
            view,
            depth_slice: None,
            resolve_target: None,
            ops: wgpu::Operations { load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT), store: wgpu::StoreOp::Store },
        });
        let colour = [id_attachment];
        let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("light pass"),
            color_attachments: if ids.is_some() { &colour } else { &[] },
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &view,
                depth_ops: Some(wgpu::Operations { load: wgpu::LoadOp::Clear(1.0), store: wgpu::StoreOp::Store }),
                stencil_ops: None,
            }),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_bind_group(0, &group, &[]);
        if casters != Casters::CutOut {
            pass.set_pipeline(&pipelines.solid);
            let solid = |i: &Instance| casters.takes(i) && i.coverage() == Coverage::Solid && in_view(i);
            draw_instances(cx, &mut pass, frame, solid, false);
        }
        if cutouts && casters != Casters::Solid {
            pass.set_pipeline(pipelines.cutout(cx));
            let cut_out = |i: &Instance| casters.takes(i) && i.coverage() == Coverage::Cutout && in_view(i);
            draw_textured(cx, &mut pass, frame, cut_out, false);
        }
    }
    cx.submit(enc);
}

/// A depth array of `layers` square maps.
#[must_use]
pub fn map_texture(cx: &WgpuContext, res: u32, layers: u32) -> wgpu::Texture {
    layered(cx, "shadow maps", res, res, layers, MAP_DEPTH)
}

/// The value of the shader's `FILTER` constant.
fn filter_code(f: Filter) -> f64 {
    match f {
        Filter::None => 0.0,
        Filter::Bilinear => 1.0,
        Filter::Pcf3x3 => 2.0,
        Filter::Pcf4x4Jitter => 3.0,
        Filter::Poisson16 => 4.0,
    }
}

/// The light pass and the maps it last rendered: what every technique built on a depth map renders in its
/// build (twin: shadow-cpu's `passes::maps::render_depth_maps`).
pub struct DepthMaps {
    pipelines: LightPipelines,
    maps: Option<wgpu::Texture>,
    casters: Casters,
}

impl DepthMaps {
    /// The light pass for `map`'s bias, from the shadow-map shader.
    #[must_use]
    pub fn new(cx: &WgpuContext, map: &DepthMap) -> Self {
        let module = cx.pipelines.module("shadow_map", shaders::shadow_map());
        Self::with_module(cx, &module, map)
    }

    /// [`DepthMaps::new`] from a module already holding the shadow-map shader.
    #[must_use]
    pub fn with_module(cx: &WgpuContext, module: &wgpu::ShaderModule, map: &DepthMap) -> Self {
        Self { pipelines: light_pass_pipeline(cx, module, depth_bias(map)), maps: None, casters: Casters::All }
    }

    /// The same light pass drawing only the casters `casters` names.
    #[must_use]
    pub fn of(self, casters: Casters) -> Self {
        Self { casters, ..self }
    }

    /// Renders the casters' depth from every projection of `light` into one layer each of a
    /// `resolution`-square depth array, reusing last frame's array when it fits.
    ///
    /// # Errors
    /// A map larger than the device allows, or a GPU failure.
    pub fn render(
        &mut self,
        cx: &mut WgpuContext,
        frame: &FrameInputs,
        light: &LightView,
        resolution: u32,
    ) -> Result<(), WgpuError> {
        let layers = light.projections.len() as u32;
        check_size(cx, "shadow map", resolution, resolution)?;
        let maps = match &self.maps {
            Some(m) if m.width() == resolution && m.depth_or_array_layers() == layers => m.clone(),
            _ => {
                let m = cx.scoped("allocating shadow maps", |cx| map_texture(cx, resolution, layers))?;
                self.maps.insert(m).clone()
            }
        };
        cx.upload_meshes(frame);
        cx.upload_textures(frame)?;
        let instances = cx.instances(frame);
        cx.scoped("the shadow-map light pass", |cx| {
            render_casters(cx, &self.pipelines, (frame, self.casters), light, (&maps, None), &instances)
        })
    }

    /// The maps of the last render, one layer per light projection.
    #[must_use]
    pub fn maps(&self) -> Option<&wgpu::Texture> {
        self.maps.as_ref()
    }
}

/// The depth maps of the casters their texture cuts out, alone ([`Casters::CutOut`]), and their lookup
/// ([`CutoutMap`]): where the techniques built on silhouettes (which give such casters no volume or wedge)
/// take those casters' shadows from (twin: shadow-cpu's `passes::maps::CutoutMaps`). Its pipelines are
/// made by the first frame with such casters; a frame without them renders nothing.
#[derive(Default)]
pub struct CutoutMaps {
    passes: Option<CutoutPasses>,
    /// The view of the last render, when its frame had cut-out casters.
    rendered: Option<LightView>,
}

/// The light pass and the lookup of one [`CutoutMap`].
struct CutoutPasses {
    settings: CutoutMap,
    maps: DepthMaps,
    query: MapQuery,
}

impl CutoutMaps {
    /// Renders the maps of `frame`'s cut-out casters from every projection of `view` (the light's own, or
    /// its cascades over the camera's view) as `settings` asks; for a frame without such casters, nothing.
    ///
    /// # Errors
    /// As [`DepthMaps::render`].
    pub fn render(
        &mut self,
        cx: &mut WgpuContext,
        frame: &FrameInputs,
        view: &LightView,
        settings: &CutoutMap,
    ) -> Result<(), WgpuError> {
        self.rendered = None;
        if !frame.has_cutout_casters() {
            return Ok(());
        }
        let passes = match &mut self.passes {
            Some(p) if p.settings == *settings => p,
            _ => self.passes.insert(cx.scoped("creating the cut-out casters' map", |cx| {
                let module = cx.pipelines.module("shadow_map", shaders::shadow_map());
                let map = settings.map();
                let lookup = LookupParams { radius: settings.filter_radius(), receiver_offset: map.receiver_offset() };
                CutoutPasses {
                    settings: *settings,
                    maps: DepthMaps::with_module(cx, &module, &map).of(Casters::CutOut),
                    query: MapQuery::new(cx, &module, settings.filter).with_lookup(lookup),
                }
            })?),
        };
        passes.maps.render(cx, frame, view, settings.resolution)?;
        self.rendered = Some(view.clone());
        Ok(())
    }

    /// Whether the last render drew maps (its frame had cut-out casters).
    #[must_use]
    pub fn is_rendered(&self) -> bool {
        self.rendered.is_some()
    }

    /// Writes into `out` the share of the light the cut-out casters of the last render leave each receiver
    /// of `g`, and says so; says false and writes nothing when that frame had none.
    ///
    /// # Errors
    /// A GPU failure.
    pub fn query(&self, cx: &WgpuContext, g: &GpuGBuffer, out: &GpuVisibility) -> Result<bool, WgpuError> {
        let (Some(passes), Some(view)) = (&self.passes, &self.rendered) else { return Ok(false) };
        let Some(maps) = passes.maps.maps() else { return Ok(false) };
        passes.query.run(cx, maps, view, g, out, &QueryExtras::NONE)?;
        Ok(true)
    }
}
