//! hybrid's query on the GPU, step by step: the view's resources fitted, the map lookup's bindings, the
//! passes recorded (mask, caster masks' compute passes, volumes, answer), then the counters read.

use shadow_core::FrameInputs;
use shadow_core::light::LightView;
use shadow_core::technique::FrameStats;
use shadow_wgpu::gbuffer::GpuGBuffer;
use shadow_wgpu::passes::maps::{LookupParams, QueryExtras};
use shadow_wgpu::passes::volumes::{Query, VolumeDraw, VolumePass, occlusion_query, read_query};
use shadow_wgpu::{GpuVisibility, WgpuContext, WgpuError};

use super::casters::{CasterPasses, CasterPieces, ListedPixels};
use super::tiles::TileMarks;
use super::{Casters, LIT, MASK, OUTSIDE, SHADOWED, State, full_screen_draws, scratch_target};
use crate::hybrid::Hybrid;

/// What the caster masks bring to one query: their compute passes, the answer's draw for the listed
/// pixels, the build's small pieces and the listed pixels.
type CasterQuery<'a> = (&'a CasterPasses, &'a wgpu::RenderPipeline, &'a CasterPieces, &'a ListedPixels);

/// The scratch depth-stencil of `gpu_mask=depth`, at the view's size.
pub(super) fn scratch_depth(cx: &WgpuContext, scratch: &mut Option<wgpu::Texture>, g: &GpuGBuffer) -> wgpu::Texture {
    match scratch {
        Some(t) if (t.width(), t.height()) == (g.width, g.height) => t.clone(),
        _ => scratch.insert(scratch_target(cx, g.width, g.height)).clone(),
    }
}

/// The tile marks of `scissor_tile` (0: none), at the view's grid.
pub(super) fn fit_tiles(cx: &WgpuContext, tiles: &mut Option<TileMarks>, tile: u32, g: &GpuGBuffer) {
    if tile > 0 {
        let (columns, rows) = (g.width.div_ceil(tile), g.height.div_ceil(tile));
        if tiles.as_ref().is_none_or(|t| (t.columns, t.rows) != (columns, rows)) {
            *tiles = Some(TileMarks::new(cx, columns, rows));
        }
    }
}

/// The caster masks' listed pixels, made anew for a new view size, more pieces or another room.
///
/// # Errors
/// A GPU failure.
pub(super) fn fit_listed(
    cx: &WgpuContext,
    c: &mut Casters,
    g: &GpuGBuffer,
    room: Option<u32>,
) -> Result<(), WgpuError> {
    let Some(pieces) = &c.pieces else { return Ok(()) };
    let size = (g.width, g.height);
    let listed = match c.listed.take() {
        Some(l) if l.size == size && l.capacity >= pieces.pieces && l.asked == room => l,
        _ => cx.scoped("the hybrid listed pixels", |cx| ListedPixels::new(cx, size, pieces.pieces, room))?,
    };
    c.listed = Some(listed);
    Ok(())
}

/// Everything one query reads, the view's resources fitted.
pub(super) struct Inputs<'a> {
    hybrid: &'a Hybrid,
    g: &'a GpuGBuffer,
    draws: &'a [VolumeDraw],
    maps: &'a wgpu::Texture,
    /// The depth-stencil the passes run over: the G-buffer's, or the depth mask's scratch.
    pub(super) target: wgpu::Texture,
    depth: wgpu::TextureView,
    edge_cells: Option<wgpu::TextureView>,
    tiles: Option<&'a TileMarks>,
    casters: Option<CasterQuery<'a>>,
}

/// What the passes leave to count: the mask pass's and the volume pass's occlusion queries (instrumented
/// frames), and how many scissor rectangles the volumes were drawn in.
pub(super) struct Counts {
    silhouettes: Option<Query>,
    passed: Option<Query>,
    rects: Option<usize>,
}

impl<'a> Inputs<'a> {
    /// The inputs of a query of `hybrid` over `g`; `None` before a build.
    pub(super) fn of(hybrid: &'a Hybrid, state: &'a State, g: &'a GpuGBuffer, target: wgpu::Texture) -> Option<Self> {
        let casters = match &state.casters {
            Some(c) => Some((&c.passes, &c.answer, c.pieces.as_ref()?, c.listed.as_ref()?)),
            None => None,
        };
        let edge_cells = state.edge_maps.as_ref().map(|t| {
            t.create_view(&wgpu::TextureViewDescriptor {
                dimension: Some(wgpu::TextureViewDimension::D2Array),
                ..Default::default()
            })
        });
        Some(Self {
            hybrid,
            g,
            draws: state.draws.as_deref()?,
            maps: state.map.maps()?,
            depth: target.create_view(&Default::default()),
            target,
            edge_cells,
            tiles: state.tiles.as_ref().filter(|_| hybrid.gpu.scissor_tile > 0),
            casters,
        })
    }

    /// The map lookup's bind group: the shared bindings, the receivers' normals (4), the edge cells (6), the
    /// tile marks (7) and the listed pixels with their counts (8, 9), as the settings ask.
    pub(super) fn map_group(
        &self,
        cx: &WgpuContext,
        state: &State,
        light: &LightView,
        receiver_offset: f32,
    ) -> wgpu::BindGroup {
        let texture =
            |binding, view| wgpu::BindGroupEntry { binding, resource: wgpu::BindingResource::TextureView(view) };
        let mut extras = vec![texture(4, &self.g.geometric_normal)];
        if let Some(view) = &self.edge_cells {
            extras.push(texture(6, view));
        }
        if let Some(t) = self.tiles {
            extras.push(wgpu::BindGroupEntry { binding: 7, resource: t.marks.as_entire_binding() });
        }
        if let Some((.., l)) = self.casters {
            extras.push(wgpu::BindGroupEntry { binding: 8, resource: l.listed.as_entire_binding() });
            extras.push(wgpu::BindGroupEntry { binding: 9, resource: l.counts.as_entire_binding() });
        }
        let tile = self.hybrid.gpu.scissor_tile;
        let settings = [tile as f32, self.tiles.map_or(0.0, |t| t.columns as f32), 0.0, 0.0];
        let lookup = LookupParams { radius: 0.0, receiver_offset };
        state.bindings.group(cx, self.maps, light, self.g, lookup, &QueryExtras { settings, entries: &extras })
    }

    /// Records and submits the passes: the scratch copied and the marks and lists cleared, the mask, the
    /// caster masks' compute passes, the volumes under the mask (in scissor rectangles around the marked
    /// tiles with `scissor_tile`), and the answer into `out`, loaded as `load` says (cleared to lit, or
    /// holding the cut-out casters' visibility, which the answer's shadowed pixels write 0 over).
    ///
    /// # Errors
    /// A GPU failure (reading the tile marks back).
    pub(super) fn record(
        &self,
        cx: &WgpuContext,
        state: &State,
        (frame, map_group): (&FrameInputs, &wgpu::BindGroup),
        (out, load): (&GpuVisibility, wgpu::LoadOp<wgpu::Color>),
    ) -> Result<Counts, WgpuError> {
        let g = self.g;
        let groups = [&g.frame_group, map_group];
        let silhouettes = cx.instrumented().then(|| occlusion_query(cx));
        let mut enc = cx.encoder("hybrid mask depth");
        if self.target != g.depth {
            enc.copy_texture_to_texture(
                g.depth.as_image_copy(),
                self.target.as_image_copy(),
                wgpu::Extent3d { width: g.width, height: g.height, depth_or_array_layers: 1 },
            );
        }
        if let Some(t) = self.tiles {
            enc.clear_buffer(&t.marks, 0, None);
        }
        if let Some((.., l)) = self.casters {
            l.clear(&mut enc);
        }
        cx.submit(enc);
        cx.step("setup");
        let mut mask_draws = vec![(&state.mask, MASK)];
        if let Some(far) = &state.far {
            mask_draws.push((far, 0));
        }
        let stencil = (&self.depth, wgpu::LoadOp::Load, wgpu::LoadOp::Clear(0));
        cx.submit(full_screen_draws(cx, "hybrid mask", None, stencil, groups, &mask_draws, silhouettes.as_ref()));
        cx.step("mask");
        if let Some((passes, _, pieces, l)) = self.casters {
            let mut enc = cx.encoder("hybrid caster masks");
            passes.record(cx, &mut enc, pieces, l, g);
            cx.submit(enc);
            cx.step("casters");
        }
        let tile = self.hybrid.gpu.scissor_tile;
        let rects = self.tiles.map(|t| t.rectangles(cx, tile, (g.width, g.height))).transpose()?;
        let counting = VolumePass {
            label: "hybrid volumes",
            ccw: &state.volumes_ccw,
            cw: &state.volumes_cw,
            stencil: wgpu::LoadOp::Load,
            reference: MASK,
            scissors: rects.as_deref(),
        };
        let passed = counting.run(cx, self.draws, frame, g, &self.depth);
        cx.step("volumes");
        let mut answers = vec![(&state.answer_map, OUTSIDE.2), (&state.answer_shadowed, SHADOWED.2)];
        if let Some((_, answer, ..)) = self.casters {
            answers.push((answer, LIT.2));
        }
        let target = Some((&out.view, load));
        let stencil = (&self.depth, wgpu::LoadOp::Load, wgpu::LoadOp::Load);
        cx.submit(full_screen_draws(cx, "hybrid answer", target, stencil, groups, &answers, None));
        cx.step("answer");
        Ok(Counts { silhouettes, passed, rects: rects.map(|r| r.len()) })
    }

    /// Reads the counters: silhouette pixels, the fragments the mask let through and their stencil updates
    /// (the compute passes' added), the listed pixels' counters, and with `unmasked_fill` z-fail's whole
    /// fill in a pass of its own.
    ///
    /// # Errors
    /// A GPU failure.
    pub(super) fn count(
        &self,
        cx: &WgpuContext,
        state: &State,
        (frame, counts): (&FrameInputs, Counts),
        stats: &mut FrameStats,
    ) -> Result<(), WgpuError> {
        let (g, draws) = (self.g, self.draws);
        let masked = VolumePass { reference: MASK, ..VolumePass::count(&state.count_masked, "count masked fragments") };
        let processed = cx.scoped("the masked fragment count", |cx| masked.run(cx, draws, frame, g, &self.depth))?;
        let c = &mut stats.counters;
        if let Some(n) = counts.rects {
            c.extra.insert("scissor_rects".into(), n as f64);
        }
        c.silhouette_pixels = Some(read_query(cx, counts.silhouettes.as_ref())?);
        let processed = read_query(cx, processed.as_ref())?;
        // Z-fail updates the count where the depth test fails.
        let rasterized_updates = processed - read_query(cx, counts.passed.as_ref())?.min(processed);
        // What the compute passes covered and updated at the listed pixels.
        let [computed, computed_updates] = match self.casters {
            Some((_, _, pieces, l)) => {
                let [pixels, fragments, updates, tests, alone] = l.counters(cx)?;
                c.extra.insert("listed_pieces".into(), pieces.pieces as f64);
                c.extra.insert("listed_pixels".into(), pixels as f64);
                c.extra.insert("listed_tests".into(), tests as f64);
                c.extra.insert("listed_alone".into(), alone as f64);
                [fragments, updates]
            }
            None => [0, 0],
        };
        c.volume_fragments = Some(processed + computed);
        c.stencil_updates = Some(rasterized_updates + computed_updates);
        if self.hybrid.unmasked_fill.is_on() {
            let every = VolumePass::count(&state.count_all, "count volume fragments");
            let all_draws = state.casters.as_ref().and_then(|c| c.all_draws.as_deref()).unwrap_or(draws);
            let all = cx.scoped("the volume fragment count", |cx| every.run(cx, all_draws, frame, g, &self.depth))?;
            c.extra.insert("unmasked_volume_fragments".into(), read_query(cx, all.as_ref())? as f64);
        }
        Ok(())
    }
}
