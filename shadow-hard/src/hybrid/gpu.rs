//! `hybrid` (Chan, thesis chapter 3) on the GPU (twin: hybrid's cpu.rs).
//!
//! Build: the classifying maps, rendered as `shadow-map` renders them, and the z-fail volumes, built and
//! uploaded as `shadow-volume-zfail` does. Query, the thesis's section 3.2 in three passes over the
//! G-buffer's depth-stencil:
//!
//! 1. **Mask.** A full-screen pass classifies each receiver against the four nearest texels and discards
//!    every pixel but the silhouette pixels, on which the stencil's bit 7 is set ([`MASK`]).
//! 2. **Volumes.** The z-fail volumes, with the stencil test "bit 7 set": outside the mask the hardware's
//!    early stencil test can reject the fragments before any other work (on the H100 measured, it does
//!    not pay: the masked pass costs about what the unmasked one does). The count wraps in the other seven
//!    bits ([`COUNT`]), so it is exact up to 127 overlapping volumes.
//! 3. **Answer.** One colour pass, two draws: outside the mask the map's answer; inside it, 0 where the
//!    count is not 0 (the stencil is above 0x80). Silhouette pixels the volumes leave lit keep the cleared 1.
//!
//! With `gpu_mask=depth` the mask lives in a scratch depth-stencil instead, as Chan keeps it (section 3.2,
//! with the depth bounds test, which wgpu does not expose): the G-buffer's depth-stencil is copied into the
//! scratch, the mask pass sets bit 7 as before (for the answer) and then rasterizes a full-screen triangle
//! at depth 1 where the bit is clear (no depth written by a shader, so hierarchical depth can follow it),
//! and the volumes count z-fail's way with the depth test turned around: a fragment behind the receiver
//! fails `Less` exactly where it passes `GreaterEqual`, so the counting ops move from depth-fail to pass,
//! and outside the mask (depth 1) every fragment fails the test, which hierarchical depth can do a tile at
//! a time before rasterizing it. On an H100 it is slower than the stencil mask, and so is writing the
//! silhouette pixels' depth from the mask shader instead (see `GpuMask::Depth`).
//!
//! With `scissor_tile=N` the mask pass also marks, in a storage buffer, each N x N pixel tile that holds a
//! silhouette pixel; the CPU reads the marks back and the volume pass repeats its draws inside scissor
//! rectangles around the marked tiles (runs along each row, merged down while the run below spans the same
//! columns), so fragments elsewhere are never made; it trades the read-back and the repeated geometry for
//! them (measured in docs/hybrid.md: on an H100 from 0.63 to 1.56 times z-fail's query, against 0.67 to 1.30
//! without).
//!
//! With `edge_texels=paired` (both backends) the classification also masks every receiver facing the
//! light where two silhouette edges in front of it enter the square between its four texels and may hide
//! something there (the edge cells, made by shared code on the CPU and uploaded; edges_paired.wgsl), so
//! casters thinner than a texel still get volumes.
//!
//! With `caster_masks=on` (the default, as on the CPU; ours) each small piece of the volumes (one connected
//! component's) is counted only at the silhouette pixels its shaft holds, by compute passes over the
//! pixels the mask pass lists (`casters`); the pieces too large for that are rasterized as above, and
//! the answer's third draw shadows the silhouette pixels whose listed count is not 0.
//!
//! Without caster masks the map's classification runs twice, in the mask pass on every pixel and in the
//! answer outside the mask: a full-screen pass can write a colour or set the stencil for the pixels it
//! keeps, but not both for different pixels, and one more 4-texel lookup costs less than a class target
//! written and read. With them the mask pass also leaves each pixel's class in the per-pixel buffer the
//! compute passes write the listed pixels' counts to, and the answer reads it there, which is cheaper
//! than classifying twice.
//!
//! Counters come from occlusion queries: the mask pass's samples are `silhouette_pixels`; after the
//! answer, a pass with the depth test off and the mask's stencil test counts `volume_fragments` (those the
//! mask lets through), and with `unmasked_fill=on` one without the stencil test counts
//! `unmasked_volume_fragments`; both are timed as the sub-phase `count_fragments`. With caster masks the
//! compute passes count their own fragments and stencil updates, read back in the same sub-phase.

mod casters;
mod edges;
mod query;
pub mod shaders;
mod tables;
mod tiles;

use casters::{CasterPasses, CasterPieces, LISTED_TRIANGLES, ListedPixels, Split, setup_room};
use edges::edge_cell_maps;
use shadow_core::technique::LightPass;
use tiles::TileMarks;

use super::shafts::CasterShafts;
use super::{GpuMask, Hybrid};
use crate::cascaded_shadow_map::cutout_view;
use shadow_core::Image;
use shadow_core::frame::InstanceVolume;
use shadow_core::geometry::volume::Caps;
use shadow_core::geometry::volume::VolumeCounting;
use shadow_core::lookup::PixelClass;
use shadow_core::technique::{DebugView, ShadowTechnique, TechniqueError};

use shadow_wgpu::frame::GpuVisibility;
use shadow_wgpu::gbuffer::GpuGBuffer;
use shadow_wgpu::passes::maps::{CutoutMaps, DepthMaps, MapBindings};
use shadow_wgpu::passes::volumes::{
    VolumeDraw, count_all_pipeline, counting_state, upload_draws, upload_volumes, volume_pipeline,
};
use shadow_wgpu::pipelines::{
    FragmentEntry, VISIBILITY, attribute_entry, buffer_entry, float_array_entry, full_screen_pipeline,
};
use shadow_wgpu::readback;
use shadow_wgpu::{WgpuBackend, WgpuContext, WgpuError};

/// The stencil bit of the computation mask.
pub const MASK: u32 = 0x80;
/// The stencil bits the volumes count in.
pub const COUNT: u32 = 0x7f;

/// The format of the debug view's class codes.
const CODES: wgpu::TextureFormat = wgpu::TextureFormat::R32Uint;

/// Pipelines, the maps and volumes of the last build, and what the debug view needs of the last query.
pub struct State {
    /// The classifying maps (`shadow-map`'s own build, of the casters the volumes are extruded from).
    map: DepthMaps,
    /// The map of the casters their texture cuts out.
    cutouts: CutoutMaps,
    bindings: MapBindings,
    module: wgpu::ShaderModule,
    mask: wgpu::RenderPipeline,
    volumes_ccw: wgpu::RenderPipeline,
    volumes_cw: wgpu::RenderPipeline,
    answer_map: wgpu::RenderPipeline,
    answer_shadowed: wgpu::RenderPipeline,
    count_masked: wgpu::RenderPipeline,
    count_all: wgpu::RenderPipeline,
    /// The volumes rasterized through the mask: all of them, or with caster masks the large pieces.
    draws: Option<Vec<VolumeDraw>>,
    /// With caster masks.
    casters: Option<Casters>,
    /// With `gpu_mask=depth`: the scratch depth-stencil the mask is written into, at the view's size, and
    /// the draw that sets depth 1 outside the mask.
    scratch: Option<wgpu::Texture>,
    far: Option<wgpu::RenderPipeline>,
    /// With `scissor_tile` above 0: the tile marks, at the last view's grid.
    tiles: Option<TileMarks>,
    /// With `edge_texels=paired`: the edge cells of the last build, a layer per projection.
    edge_maps: Option<wgpu::Texture>,
    /// Per light of the frame, what its last build uploaded data into, for its next build to reuse: data
    /// written for one light must not land where another light of the same recorded frame reads.
    kept: Vec<Kept>,
    last: Option<LastQuery>,
}

/// What a light's last build uploaded its data into.
#[derive(Default)]
struct Kept {
    pieces: Option<CasterPieces>,
    edge_maps: Option<wgpu::Texture>,
}

/// What the caster masks keep: the compute passes, the answer's draw for the listed pixels, the last
/// build's small pieces (and with `unmasked_fill=on` every volume, for the unmasked fill), and the listed
/// pixels at the last view's size.
struct Casters {
    passes: CasterPasses,
    answer: wgpu::RenderPipeline,
    pieces: Option<CasterPieces>,
    all_draws: Option<Vec<VolumeDraw>>,
    listed: Option<ListedPixels>,
}

/// The volumes' depth-stencil state: z-fail counting in [`COUNT`]. The stencil mask: under the stencil
/// test "bit 7 set", the depth test `Less`. The depth mask: no stencil test, the depth test turned around
/// to a passing `GreaterEqual`; outside the mask only fragments at depth 1 (far caps) pass, and what they
/// count there stays in the low bits, which the answer does not read outside the mask.
fn volume_state(format: wgpu::TextureFormat, mask: GpuMask) -> wgpu::DepthStencilState {
    let test = match mask {
        GpuMask::Stencil => wgpu::CompareFunction::Equal,
        GpuMask::Depth => wgpu::CompareFunction::Always,
    };
    let mut state = counting_state(format, VolumeCounting::ZFail, test, MASK, COUNT);
    if mask == GpuMask::Depth {
        state.depth_compare = Some(wgpu::CompareFunction::GreaterEqual);
        for face in [&mut state.stencil.front, &mut state.stencil.back] {
            face.pass_op = face.depth_fail_op;
            face.depth_fail_op = wgpu::StencilOperation::Keep;
        }
    }
    state
}

/// The mask pass's depth-stencil state: sets bit 7 on the pixels it keeps.
fn mask_state(format: wgpu::TextureFormat) -> wgpu::DepthStencilState {
    let set_mask = wgpu::StencilFaceState {
        compare: wgpu::CompareFunction::Always,
        pass_op: wgpu::StencilOperation::Replace,
        ..Default::default()
    };
    wgpu::DepthStencilState {
        stencil: wgpu::StencilState { front: set_mask, back: set_mask, read_mask: 0, write_mask: MASK },
        ..stencil_test(format, wgpu::CompareFunction::Always, 0)
    }
}

/// The depth mask's second draw: a full-screen triangle at depth 1, rasterized (no depth written by a
/// shader, so hierarchical depth can follow it), drawn where bit 7 is clear.
fn far_pass(cx: &WgpuContext, module: &wgpu::ShaderModule, groups: &[&wgpu::BindGroupLayout]) -> wgpu::RenderPipeline {
    let groups: Vec<_> = groups.iter().map(|g| Some(*g)).collect();
    let layout = cx.pipelines.layout("hybrid far", &groups);
    let outside = wgpu::StencilFaceState { compare: wgpu::CompareFunction::Equal, ..Default::default() };
    cx.pipelines.render(&wgpu::RenderPipelineDescriptor {
        label: Some("hybrid far"),
        layout: Some(&layout),
        vertex: wgpu::VertexState {
            module,
            entry_point: Some("vs_hybrid_far"),
            compilation_options: Default::default(),
            buffers: &[],
        },
        primitive: Default::default(),
        depth_stencil: Some(wgpu::DepthStencilState {
            depth_write_enabled: Some(true),
            stencil: wgpu::StencilState { front: outside, back: outside, read_mask: MASK, write_mask: 0 },
            ..stencil_test(cx.depth_stencil, wgpu::CompareFunction::Always, 0)
        }),
        multisample: Default::default(),
        fragment: None,
        multiview_mask: None,
        cache: None,
    })
}

/// A depth-stencil target of the G-buffer's size and format, for the depth mask.
fn scratch_target(cx: &WgpuContext, width: u32, height: u32) -> wgpu::Texture {
    cx.create_texture(&wgpu::TextureDescriptor {
        label: Some("hybrid mask depth"),
        size: wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: cx.depth_stencil,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    })
}

/// The bindings and the depth-stencil of the last query, for the classes view.
struct LastQuery {
    frame_group: wgpu::BindGroup,
    map_group: wgpu::BindGroup,
    depth: wgpu::Texture,
}

/// A depth-stencil state (in `format`) that only tests the stencil: `compare` against the reference under
/// `read_mask`, the depth test off, nothing written.
fn stencil_test(
    format: wgpu::TextureFormat,
    compare: wgpu::CompareFunction,
    read_mask: u32,
) -> wgpu::DepthStencilState {
    let face = wgpu::StencilFaceState { compare, ..Default::default() };
    wgpu::DepthStencilState {
        format,
        depth_write_enabled: Some(false),
        depth_compare: Some(wgpu::CompareFunction::Always),
        stencil: wgpu::StencilState { front: face, back: face, read_mask, write_mask: 0 },
        bias: Default::default(),
    }
}

/// The stencil tests of the answer's draws, each with its reference: outside the mask; inside it with a
/// count that is not 0 (the stencil above `MASK`); inside it with a count of 0.
const OUTSIDE: (wgpu::CompareFunction, u32, u32) = (wgpu::CompareFunction::Equal, MASK, 0);
const SHADOWED: (wgpu::CompareFunction, u32, u32) = (wgpu::CompareFunction::Less, 0xff, MASK);
const LIT: (wgpu::CompareFunction, u32, u32) = (wgpu::CompareFunction::Equal, 0xff, MASK);

/// One pass of full-screen draws over the depth-stencil `depth` (each aspect loaded or cleared as its
/// load op says), into `target` loaded or cleared as its load op says when given; each draw a pipeline
/// and its stencil reference. With a `query` (an occlusion query set and its
/// resolve buffer), counts the samples of the first draw that pass.
fn full_screen_draws(
    cx: &WgpuContext,
    label: &str,
    target: Option<(&wgpu::TextureView, wgpu::LoadOp<wgpu::Color>)>,
    depth: (&wgpu::TextureView, wgpu::LoadOp<f32>, wgpu::LoadOp<u32>),
    groups: [&wgpu::BindGroup; 2],
    draws: &[(&wgpu::RenderPipeline, u32)],
    query: Option<&(wgpu::QuerySet, wgpu::Buffer)>,
) -> wgpu::CommandEncoder {
    let mut enc = cx.encoder(label);
    {
        let colour = target.map(|(view, load)| wgpu::RenderPassColorAttachment {
            view,
            depth_slice: None,
            resolve_target: None,
            ops: wgpu::Operations { load, store: wgpu::StoreOp::Store },
        });
        let colour = [colour];
        let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some(label),
            color_attachments: if target.is_some() { &colour } else { &[] },
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: depth.0,
                depth_ops: Some(wgpu::Operations { load: depth.1, store: wgpu::StoreOp::Store }),
                stencil_ops: Some(wgpu::Operations { load: depth.2, store: wgpu::StoreOp::Store }),
            }),
            timestamp_writes: None,
            occlusion_query_set: query.map(|q| &q.0),
            multiview_mask: None,
        });
        pass.push_debug_group(label);
        for (i, g) in groups.iter().enumerate() {
            pass.set_bind_group(i as u32, *g, &[]);
        }
        for (k, (pipeline, reference)) in draws.iter().enumerate() {
            pass.set_pipeline(pipeline);
            pass.set_stencil_reference(*reference);
            if query.is_some() && k == 0 {
                pass.begin_occlusion_query(0);
                pass.draw(0..3, 0..1);
                pass.end_occlusion_query();
            } else {
                pass.draw(0..3, 0..1);
            }
        }
        pass.pop_debug_group();
    }
    if let Some((set, resolve)) = query {
        enc.resolve_query_set(set, 0..1, resolve, 0);
    }
    enc
}

impl Hybrid {
    /// The bindings the query shader has beside the map's: the triangle attributes, and those of the
    /// variants that are on (edge cells, scissor tiles, listed counts).
    fn extra_bindings(&self) -> Vec<wgpu::BindGroupLayoutEntry> {
        let mut extras = vec![attribute_entry(4)];
        if self.edge_texels.is_on() {
            extras.push(float_array_entry(6));
        }
        let writable = wgpu::BufferBindingType::Storage { read_only: false };
        if self.gpu.scissor_tile > 0 {
            extras.push(buffer_entry(7, writable, wgpu::ShaderStages::FRAGMENT));
        }
        if self.caster_masks.is_on() {
            extras.push(buffer_entry(8, writable, wgpu::ShaderStages::FRAGMENT));
            extras.push(buffer_entry(9, writable, wgpu::ShaderStages::FRAGMENT));
        }
        extras
    }
}

impl ShadowTechnique<WgpuBackend> for Hybrid {
    type State = State;

    fn name(&self) -> &'static str {
        Self::NAME
    }

    /// Its build sizes the caster masks' tolerances by the camera, and leaves the volumes and the small
    /// pieces' parameters in the frame's transient buffer.
    fn build_is_reusable(&self, _: &shadow_core::FrameInputs) -> bool {
        false
    }

    fn create_state(&self, cx: &mut WgpuContext) -> Result<State, WgpuError> {
        if self.gpu.mask == GpuMask::Depth && cx.depth_stencil != wgpu::TextureFormat::Depth32FloatStencil8 {
            let message = "gpu_mask=depth copies the G-buffer's depth, which this device keeps as \
                           Depth24PlusStencil8 (it lacks DEPTH32FLOAT_STENCIL8), a format no copy takes"
                .to_string();
            return Err(TechniqueError::BadSettings { technique: Self::NAME.into(), message }.into());
        }
        let map = DepthMaps::new(cx, &self.depth).of(shadow_core::technique::maps::Casters::Solid);
        cx.scoped("creating the hybrid pipelines", |cx| {
            let caster_masks = self.caster_masks.is_on();
            let source = shaders::query(self.edge_texels, self.gpu.scissor_tile > 0, caster_masks);
            let module = cx.pipelines.module("hybrid", source);
            let volume_module = cx.pipelines.module("shadow_volume", shadow_wgpu::shaders::shadow_volume());
            let gpu_mask = self.gpu.mask;
            let bindings = MapBindings::new(cx, &self.extra_bindings());
            let groups = [&cx.shared.frame_layout, bindings.layout()];
            let mask = full_screen_pipeline(
                &cx.pipelines,
                "hybrid mask",
                &module,
                "fs_hybrid_mask",
                &groups,
                None,
                Some(mask_state(cx.depth_stencil)),
            );
            let far = (gpu_mask == GpuMask::Depth).then(|| far_pass(cx, &module, &groups));
            let counting = volume_state(cx.depth_stencil, gpu_mask);
            let volume = |front| volume_pipeline(cx, &volume_module, "vs_volume", front, counting.clone());
            let (volumes_ccw, volumes_cw) = (volume(wgpu::FrontFace::Ccw), volume(wgpu::FrontFace::Cw));
            let count = |state| volume_pipeline(cx, &volume_module, "vs_volume", wgpu::FrontFace::Ccw, state);
            let count_masked = count(stencil_test(cx.depth_stencil, wgpu::CompareFunction::Equal, MASK));
            let count_all = count_all_pipeline(cx, &volume_module);
            let answer = |entry, (compare, read_mask, _): (_, u32, u32)| {
                let state = stencil_test(cx.depth_stencil, compare, read_mask);
                full_screen_pipeline(
                    &cx.pipelines,
                    "hybrid answer",
                    &module,
                    entry,
                    &groups,
                    Some(VISIBILITY),
                    Some(state),
                )
            };
            let answer_map = answer("fs_hybrid_map", OUTSIDE);
            let answer_shadowed = answer("fs_hybrid_shadowed", SHADOWED);
            let casters = caster_masks.then(|| Casters {
                passes: CasterPasses::new(cx),
                answer: answer("fs_hybrid_listed", LIT),
                pieces: None,
                all_draws: None,
                listed: None,
            });
            State {
                map,
                cutouts: CutoutMaps::default(),
                bindings,
                module,
                mask,
                volumes_ccw,
                volumes_cw,
                answer_map,
                answer_shadowed,
                count_masked,
                count_all,
                draws: None,
                casters,
                scratch: None,
                far,
                tiles: None,
                edge_maps: None,
                kept: Vec::new(),
                last: None,
            }
        })
    }

    fn build(&self, cx: &mut WgpuContext, state: &mut State, pass: LightPass<'_>) -> Result<(), WgpuError> {
        let LightPass { frame, light, slot, aspect, stats, .. } = pass;
        state.map.render(cx, frame, light, self.depth.resolution)?;
        state.cutouts.render(cx, frame, &cutout_view(&self.cutouts, frame, light, aspect), &self.cutouts)?;
        cx.step("map");
        if state.kept.len() <= slot {
            state.kept.resize_with(slot + 1, Kept::default);
        }
        let kept = std::mem::take(&mut state.kept[slot]);
        let res = self.depth.resolution;
        // The edge maps' segments come from the volumes' own silhouette pass (unused with
        // `edge_texels=off`, where they cost two transforms per silhouette edge).
        let (volumes, segments) = frame.shadow_volumes_and_segments(light, Caps::Both);
        if self.edge_texels.is_on() {
            let maps = cx.scoped("the edge cells", |cx| edge_cell_maps(cx, &segments, light, res, kept.edge_maps))?;
            state.kept[slot].edge_maps = Some(maps.clone());
            state.edge_maps = Some(maps);
        }
        cx.step("edges");
        if let Some(casters) = &mut state.casters {
            // The small pieces go to the compute passes (as many as the device lets them set up), the rest
            // to the rasterizer.
            InstanceVolume::count(&volumes, &mut stats.counters);
            let shafts = CasterShafts::new(frame, light, &volumes);
            let split = Split::new(frame, &volumes, &shafts, LISTED_TRIANGLES, setup_room(cx));
            let pieces = CasterPasses::upload(cx, (frame, light), &split, &shafts, kept.pieces)?;
            state.kept[slot].pieces = Some(pieces.clone());
            casters.pieces = Some(pieces);
            state.draws = Some(upload_volumes(cx, frame, &split.raster)?);
            casters.all_draws = self.unmasked_fill.is_on().then(|| upload_volumes(cx, frame, &volumes)).transpose()?;
        } else {
            state.draws = Some(upload_draws(cx, frame, &volumes, stats)?);
        }
        cx.step("pieces");
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
        let LightPass { frame, light, stats, .. } = pass;
        let not_built = || WgpuError::from(TechniqueError::NotBuilt(Self::NAME.into()));
        if self.edge_texels.is_on() && state.edge_maps.is_none() {
            return Err(not_built());
        }
        // The views' resources first, made anew for a new view size: the depth-stencil the passes run
        // over (the G-buffer's, or for the depth mask a copy the mask pass sets to depth 1 outside the
        // mask), the tile marks and the caster masks' listed pixels.
        let target = match self.gpu.mask {
            GpuMask::Stencil => g.depth.clone(),
            GpuMask::Depth => query::scratch_depth(cx, &mut state.scratch, g),
        };
        query::fit_tiles(cx, &mut state.tiles, self.gpu.scissor_tile, g);
        if let Some(c) = &mut state.casters {
            query::fit_listed(cx, c, g, self.gpu.pair_room)?;
        }
        let (map_group, target) = {
            let state = &*state;
            let inputs = query::Inputs::of(self, state, g, target).ok_or_else(not_built)?;
            let map_group = inputs.map_group(cx, state, light, self.depth.receiver_offset());
            // The cut-out casters' visibility first, which the answer shadows more of; without them, lit.
            let answer_over = match state.cutouts.query(cx, g, out)? {
                true => wgpu::LoadOp::Load,
                false => wgpu::LoadOp::Clear(wgpu::Color::WHITE),
            };
            let counts = cx.scoped("the hybrid passes", |cx| {
                inputs.record(cx, state, (frame, &map_group), (out, answer_over))
            })??;
            // The counters are not the technique's work: after it is done, a sub-phase of their own.
            if cx.instrumented() {
                cx.end_of_work();
                cx.wait()?;
                let t = std::time::Instant::now();
                inputs.count(cx, state, (frame, counts), stats)?;
                stats.timings.extra.insert("count_fragments".into(), shadow_core::stats::ms(t.elapsed()));
            }
            (map_group, inputs.target)
        };
        state.last = Some(LastQuery { frame_group: g.frame_group.clone(), map_group, depth: target });
        Ok(())
    }

    fn debug_views(&self, cx: &mut WgpuContext, state: &State) -> Result<Vec<DebugView>, WgpuError> {
        let Some(last) = &state.last else { return Ok(Vec::new()) };
        let image = cx.scoped("the hybrid classes view", |cx| classes(cx, state, last))??;
        let image =
            Image::from_fn(image.width(), image.height(), |x, y| PixelClass::from_code(*image.get(x, y)).colour());
        Ok(vec![DebugView { name: "classes".into(), image }])
    }
}

/// The class code of every pixel (Fig. 3-5), drawn under the answer's stencil tests: the map's class
/// outside the mask, volume-shadowed and volume-lit inside it; 0 (no receiver) where nothing draws.
fn classes(cx: &WgpuContext, state: &State, last: &LastQuery) -> Result<Image<u32>, WgpuError> {
    let (w, h) = (last.depth.width(), last.depth.height());
    let target = cx.create_texture(&wgpu::TextureDescriptor {
        label: Some("hybrid classes"),
        size: wgpu::Extent3d { width: w, height: h, depth_or_array_layers: 1 },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: CODES,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
        view_formats: &[],
    });
    let code = |test: (wgpu::CompareFunction, u32, u32), class: u32| {
        let constants = [("CODE", f64::from(class)), ("SHADOWED_CODE", f64::from(PixelClass::VolumeShadowed as u32))];
        let entry = FragmentEntry { name: "fs_hybrid_code", constants: &constants };
        let groups = [&cx.shared.frame_layout, state.bindings.layout()];
        let depth_stencil = Some(stencil_test(cx.depth_stencil, test.0, test.1));
        let pipeline = full_screen_pipeline(
            &cx.pipelines,
            "hybrid classes",
            &state.module,
            entry,
            &groups,
            Some(CODES),
            depth_stencil,
        );
        (pipeline, test.2)
    };
    let draws =
        [code(OUTSIDE, 0), code(SHADOWED, PixelClass::VolumeShadowed as u32), code(LIT, PixelClass::VolumeLit as u32)];
    let draws: Vec<_> = draws.iter().map(|(p, r)| (p, *r)).collect();
    let depth = last.depth.create_view(&Default::default());
    let view = target.create_view(&Default::default());
    let pass = full_screen_draws(
        cx,
        "hybrid classes",
        Some((&view, wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT))),
        (&depth, wgpu::LoadOp::Load, wgpu::LoadOp::Load),
        [&last.frame_group, &last.map_group],
        &draws,
        None,
    );
    cx.submit(pass);
    readback::read_u32(cx, &target, 0)
}
