//! Light depth maps on the GPU (twin: shadow-cpu's `passes::maps`): the light pass renders depth with the
//! pipeline's depth bias into one layer per projection; a map query runs `shadow_lookup` of
//! shadow_map.wgsl over the G-buffer, with the hardware comparison sampler for bilinear taps. Techniques
//! that look into the maps their own way add a fragment entry and bindings from 4 on ([`MapQuery::with_entry`]).
//! [`CutoutMaps`] holds the casters their texture cuts out alone, for the techniques built on silhouettes.

pub use super::cutout_maps::CutoutMaps;

use bytemuck::{Pod, Zeroable};
use shadow_core::frame::Coverage;
use shadow_core::light::atlas::LightTiles;
use shadow_core::light::{LightProjection, LightView};
use shadow_core::technique::maps::{Casters, DepthMap};
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
    tiles: [[f32; 4]; 6],
}

/// Where a light's depth maps lie: a layer of their own per projection, or a tile each in the one layer of
/// the frame's shadow atlas.
#[derive(Clone, Copy, Debug)]
pub struct MapsIn<'a> {
    /// The depth array holding them.
    pub texture: &'a wgpu::Texture,
    /// Their tiles, in an atlas; `None`: layer `k` is projection `k`'s map.
    pub tiles: Option<&'a LightTiles>,
}

impl<'a> From<&'a wgpu::Texture> for MapsIn<'a> {
    /// Maps of their own, a layer each.
    fn from(texture: &'a wgpu::Texture) -> Self {
        Self { texture, tiles: None }
    }
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
        self.group_of(cx, maps, &map_params(maps.into(), light, lookup, extras.settings, None), g, extras)
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

/// The parameters of a lookup into `maps` (a layer or a tile per projection of `light`), with `filter` in
/// `settings.x` where a host reads it (the backend's own query compiles its filter in).
fn map_params(
    maps: MapsIn<'_>,
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
    let mut tiles = [[0.0f32; 4]; 6];
    for (slot, origin) in tiles.iter_mut().zip(maps.tiles.iter().flat_map(|t| &t.origins)) {
        *slot = [origin.x as f32, origin.y as f32, maps.tiles.map_or(0, |t| t.side) as f32, 0.0];
    }
    let side = maps.tiles.map_or(maps.texture.width(), |t| t.side);
    MapParams {
        proj,
        light: LightRaw::from(&light.light),
        settings: [filter, lookup.radius, side as f32, lookup.receiver_offset],
        planes,
        extra,
        cascade,
        cascade_axis,
        cascade_far,
        tiles,
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

    /// Writes the visibility of every receiver through the maps (a layer or an atlas tile per light
    /// projection).
    ///
    /// # Errors
    /// A GPU failure.
    pub fn run<'m>(
        &self,
        cx: &WgpuContext,
        maps: impl Into<MapsIn<'m>>,
        light: &LightView,
        g: &GpuGBuffer,
        out: &GpuVisibility,
        extras: &QueryExtras<'_>,
    ) -> Result<(), WgpuError> {
        // The filter rides in `settings.x` for a host; the backend's own query compiles it in.
        let maps = maps.into();
        let lent = self.filter.filter(|_| self.lent);
        let params = map_params(maps, light, self.lookup, extras.settings, lent);
        if let Some(filter) = lent {
            cx.host_maps.lend(|| crate::HostMap { texture: maps.texture.clone(), params, filter });
        }
        cx.scoped("the shadow-map query", |cx| {
            let group = self.bindings.group_of(cx, maps.texture, &params, g, extras);
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
    clear_tile: std::cell::OnceCell<wgpu::RenderPipeline>,
}

impl LightPipelines {
    fn new(cx: &WgpuContext, module: &wgpu::ShaderModule, bias: wgpu::DepthBiasState, ids: bool) -> Self {
        let solid = light_pipeline(cx, module, bias, ids, false);
        let (cutout, clear_tile) = Default::default();
        Self { solid, module: module.clone(), bias, ids, cutout, clear_tile }
    }

    /// The pipeline of the casters their texture cuts out.
    fn cutout(&self, cx: &WgpuContext) -> &wgpu::RenderPipeline {
        self.cutout.get_or_init(|| light_pipeline(cx, &self.module, self.bias, self.ids, true))
    }

    /// The pipeline clearing one tile of an atlas to the far plane (made by the first light drawn in one).
    fn clear_tile(&self, cx: &WgpuContext) -> &wgpu::RenderPipeline {
        self.clear_tile.get_or_init(|| {
            cx.pipelines.render(&wgpu::RenderPipelineDescriptor {
                label: Some("atlas tile clear"),
                layout: Some(&cx.pipelines.layout("atlas tile clear", &[])),
                vertex: wgpu::VertexState {
                    module: &self.module,
                    entry_point: Some("vs_clear_tile"),
                    compilation_options: Default::default(),
                    buffers: &[],
                },
                primitive: wgpu::PrimitiveState::default(),
                depth_stencil: Some(wgpu::DepthStencilState {
                    format: MAP_DEPTH,
                    depth_write_enabled: Some(true),
                    depth_compare: Some(wgpu::CompareFunction::Always),
                    stencil: Default::default(),
                    bias: wgpu::DepthBiasState::default(),
                }),
                multisample: Default::default(),
                fragment: None,
                multiview_mask: None,
                cache: None,
            })
        })
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
    render_casters(cx, pipelines, (frame, Casters::All), light, (maps.into(), ids), instances);
}

/// [`render_maps`] of the casters `casters` names, into the maps' layers or their atlas tiles (without
/// IDs); a caster wholly outside a projection's frustum is not drawn into its map (it would draw nothing
/// there) where the frame saves so.
fn render_casters(
    cx: &WgpuContext,
    pipelines: &LightPipelines,
    (frame, casters): (&FrameInputs, Casters),
    light: &LightView,
    (maps, ids): (MapsIn<'_>, Option<&wgpu::Texture>),
    instances: &wgpu::Buffer,
) {
    let res = maps.tiles.map_or(maps.texture.width(), |t| t.side);
    let drawn = (frame, casters, frame.has_cutout_casters());
    let mut enc = cx.encoder("light pass");
    match maps.tiles {
        // An atlas's tiles, in one pass: each drawn within its viewport and cleared by a draw (the pass's
        // clear would clear the other lights' tiles too).
        Some(tiles) => {
            let mut pass = begin_light_pass(&mut enc, &layer_view(maps.texture, 0), wgpu::LoadOp::Load, None);
            for (p, origin) in light.projections.iter().zip(&tiles.origins) {
                pass.set_viewport(origin.x as f32, origin.y as f32, res as f32, res as f32, 0.0, 1.0);
                pass.set_scissor_rect(origin.x, origin.y, res, res);
                pass.set_pipeline(pipelines.clear_tile(cx));
                pass.draw(0..3, 0..1);
                draw_casters(cx, &mut pass, pipelines, drawn, (p, res), instances);
            }
        }
        None => {
            for (k, p) in light.projections.iter().enumerate() {
                let ids = ids.map(|t| layer_view(t, k as u32));
                let depth = layer_view(maps.texture, k as u32);
                let mut pass = begin_light_pass(&mut enc, &depth, wgpu::LoadOp::Clear(1.0), ids.as_ref());
                draw_casters(cx, &mut pass, pipelines, drawn, (p, res), instances);
            }
        }
    }
    cx.submit(enc);
}

/// A light pass into `depth` (loaded as `load`), and into `ids` cleared to no caster where given.
fn begin_light_pass<'e>(
    enc: &'e mut wgpu::CommandEncoder,
    depth: &wgpu::TextureView,
    load: wgpu::LoadOp<f32>,
    ids: Option<&wgpu::TextureView>,
) -> wgpu::RenderPass<'e> {
    let id_attachment = ids.map(|view| wgpu::RenderPassColorAttachment {
        view,
        depth_slice: None,
        resolve_target: None,
        ops: wgpu::Operations { load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT), store: wgpu::StoreOp::Store },
    });
    let colour = [id_attachment];
    enc.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some("light pass"),
        color_attachments: if ids.is_some() { &colour } else { &[] },
        depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
            view: depth,
            depth_ops: Some(wgpu::Operations { load, store: wgpu::StoreOp::Store }),
            stencil_ops: None,
        }),
        timestamp_writes: None,
        occlusion_query_set: None,
        multiview_mask: None,
    })
}

/// Draws the casters `casters` names into projection `p`'s map of side `res`: those everywhere, then those
/// their texture cuts out (where `cutouts`: the frame has any); a caster wholly outside the projection's
/// frustum is not drawn where the frame saves so.
fn draw_casters(
    cx: &WgpuContext,
    pass: &mut wgpu::RenderPass<'_>,
    pipelines: &LightPipelines,
    (frame, casters, cutouts): (&FrameInputs, Casters, bool),
    (p, res): (&LightProjection, u32),
    instances: &wgpu::Buffer,
) {
    let culling = frame.savings.culling;
    let in_view = |i: &Instance| !culling || p.may_hold(i.bounds);
    let group = cx.shared.frame_group(cx, &ViewRaw::new(p.clip_from_world, glam::Vec3::ZERO, res, res), instances);
    pass.set_bind_group(0, &group, &[]);
    if casters != Casters::CutOut {
        pass.set_pipeline(&pipelines.solid);
        let solid = |i: &Instance| casters.takes(i) && i.coverage() == Coverage::Solid && in_view(i);
        draw_instances(cx, pass, frame, solid, false);
    }
    if cutouts && casters != Casters::Solid {
        pass.set_pipeline(pipelines.cutout(cx));
        let cut_out = |i: &Instance| casters.takes(i) && i.coverage() == Coverage::Cutout && in_view(i);
        draw_textured(cx, pass, frame, cut_out, false);
    }
}

/// The context's shadow atlas of `side` texels (one layer), made when no atlas of that side was made
/// before.
///
/// # Errors
/// A side larger than the device allows.
pub fn shadow_atlas(cx: &mut WgpuContext, side: u32) -> Result<wgpu::Texture, WgpuError> {
    check_size(cx, "shadow atlas", side, side)?;
    match &cx.shadow_atlas {
        Some(atlas) if atlas.width() == side => Ok(atlas.clone()),
        _ => {
            let atlas = cx.scoped("allocating the shadow atlas", |cx| map_texture(cx, side, 1))?;
            Ok(cx.shadow_atlas.insert(atlas).clone())
        }
    }
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
    /// The atlas tiles of the last render, when it drew into the frame's atlas.
    tiles: Option<LightTiles>,
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
        Self {
            pipelines: light_pass_pipeline(cx, module, depth_bias(map)),
            maps: None,
            tiles: None,
            casters: Casters::All,
        }
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
        let own = self.maps.as_ref().filter(|m| self.tiles.is_none() && m.width() == resolution);
        let maps = match own {
            Some(m) if m.depth_or_array_layers() == layers => m.clone(),
            _ => cx.scoped("allocating shadow maps", |cx| map_texture(cx, resolution, layers))?,
        };
        self.draw(cx, frame, light, maps, None)
    }

    /// Renders the casters' depth from every projection of `light` into its tiles of the frame's shadow
    /// atlas (the texture the context keeps for atlases of their side), each as a map of the tiles' side.
    ///
    /// # Errors
    /// An atlas larger than the device allows, or a GPU failure.
    pub fn render_tiles(
        &mut self,
        cx: &mut WgpuContext,
        frame: &FrameInputs,
        light: &LightView,
        tiles: &LightTiles,
    ) -> Result<(), WgpuError> {
        let atlas = shadow_atlas(cx, tiles.atlas)?;
        self.draw(cx, frame, light, atlas, Some(tiles))
    }

    fn draw(
        &mut self,
        cx: &mut WgpuContext,
        frame: &FrameInputs,
        light: &LightView,
        maps: wgpu::Texture,
        tiles: Option<&LightTiles>,
    ) -> Result<(), WgpuError> {
        self.tiles = tiles.cloned();
        let maps = self.maps.insert(maps).clone();
        cx.upload_meshes(frame);
        cx.upload_textures(frame)?;
        let instances = cx.instances(frame);
        let target = MapsIn { texture: &maps, tiles };
        cx.scoped("the shadow-map light pass", |cx| {
            render_casters(cx, &self.pipelines, (frame, self.casters), light, (target, None), &instances)
        })
    }

    /// The maps of the last render, one layer per light projection (or the atlas they are tiles of: see
    /// [`Self::source`]).
    #[must_use]
    pub fn maps(&self) -> Option<&wgpu::Texture> {
        self.maps.as_ref()
    }

    /// The maps of the last render and where they lie in them: for a lookup.
    #[must_use]
    pub fn source(&self) -> Option<MapsIn<'_>> {
        self.maps.as_ref().map(|texture| MapsIn { texture, tiles: self.tiles.as_ref() })
    }
}
