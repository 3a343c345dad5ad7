//! `hybrid` (Chan, thesis chapter 3): shadow maps where they are right, shadow volumes where they are not.
//!
//! Build: the classifying depth maps as `shadow-map` renders them, and the z-fail volumes of every caster
//! (shared geometry, as `shadow-volume-zfail` builds them). Query, the thesis's steps 2 to 4: each receiver
//! is compared with the four texels nearest its map position (`shadow_core::lookup::classify`); where they
//! disagree and the surface faces the light it is a silhouette pixel, otherwise the map's answer is final.
//! The silhouette pixels make a computation mask, tiled so the rasterizer skips whole tiles with none;
//! the volumes are counted z-fail through it, and a silhouette pixel is shadowed where its count is not 0.
//!
//! With `caster_masks=on` (the default; ours) each connected component's volume is counted only at the
//! silhouette pixels its shadow's light-space bounds hold (`casters`): its count is zero
//! everywhere else, so the stencil and the picture are the whole mask's, at a fraction of the fragments
//! where the volumes of many casters cross each other's shadows on screen (cubes, tree, crowd).
//!
//! With `edge_texels=paired` (the default; ours) a receiver facing the light is a silhouette pixel too
//! where two silhouette edges in front of it enter the square between its four texels and may cut off a
//! part of it that holds none of them (`edge_cells`, `near_edge_pair`): a branch, a gap or a corner thinner
//! than a texel, which Chan's rule misses.
//!
//! Counters: `silhouette_pixels`; `volume_fragments`, the fragments rasterized under the masks (the work
//! actually done); `caster_pieces`, of
//! them `caster_pieces_skipped` (no silhouette pixel in their shadow) and `caster_pieces_listed` (counted
//! at their own `caster_listed_pixels`), the rest drawn through the whole mask; `mask_tiles` and
//! `mask_tiles_total`; with `unmasked_fill=on`, `unmasked_volume_fragments`, what `shadow-volume-zfail`
//! rasterizes, from a second pass without the mask (timed as `count_fragments`). Sub-phases: `edge_maps`
//! (in the build), `classify` (the map test and the mask), `caster_lists` (each piece's pixels) and
//! `volumes` (lists included).

mod casters;

use super::Hybrid;
use super::edge_map::edge_cells;
use glam::Vec3;
use rayon::prelude::*;
use shadow_core::frame::InstanceVolume;
use shadow_core::geometry::volume::Caps;
use shadow_core::geometry::volume::VolumeCounting;
use shadow_core::light::LightView;
use shadow_core::lookup::{MapClass, PixelClass, classify, near_edge_pair};
use shadow_core::stats::ms;
use shadow_core::technique::LightPass;
use shadow_core::technique::maps::Casters;
use shadow_core::technique::{DebugView, ShadowTechnique, TechniqueError};
use shadow_core::{FrameInputs, Image};
use std::time::Instant;

use super::shafts::CasterShafts;
use crate::cascaded_shadow_map::cutout_view;
use casters::count_volumes;
use shadow_cpu::GBuffer;
use shadow_cpu::passes::maps::{CutoutMaps, map_position, render_caster_maps};
use shadow_cpu::passes::per_receiver;
use shadow_cpu::passes::volumes::rasterize_volumes;
use shadow_cpu::raster::{ComputationMask, DepthStencil};
use shadow_cpu::{CpuBackend, CpuContext, CpuError};

/// The maps and volumes of the last build; what the last query decided with (for the debug view, which
/// derives the classes from it only when asked).
#[derive(Default)]
pub struct State {
    maps: Vec<Image<f32>>,
    /// With `edge_texels` on: per projection, the edge map (`edge_maps`).
    edge_maps: Vec<Image<f32>>,
    volumes: Option<Vec<InstanceVolume>>,
    /// With `caster_masks=on`: where each volume piece's shadow can lie.
    shafts: CasterShafts,
    /// The map of the casters their texture cuts out.
    cutouts: CutoutMaps,
    last: Option<LastQuery>,
}

/// The map's classes, the receivers and the volumes' stencil of the last query.
struct LastQuery {
    map_class: Image<MapClass>,
    receiver: Image<bool>,
    stencil: Vec<u8>,
}

impl LastQuery {
    fn classes(&self) -> Image<PixelClass> {
        let (w, h) = (self.map_class.width(), self.map_class.height());
        Image::from_fn(w, h, |x, y| {
            let i = (y * w + x) as usize;
            if self.receiver.data()[i] {
                PixelClass::of(*self.map_class.get(x, y), self.stencil[i] != 0)
            } else {
                PixelClass::None
            }
        })
    }
}

/// The map's class of every receiver pixel (`Lit` elsewhere), rows in parallel; with `edge_maps` (the
/// edge cells of `edge_texels=paired`), a receiver facing the light where an edge pair in front of it may
/// hide something is a silhouette pixel too.
fn classify_receivers(
    maps: &[Image<f32>],
    edge_maps: &[Image<f32>],
    light: &LightView,
    g: &GBuffer,
    receiver_offset: f32,
) -> Image<MapClass> {
    let w = g.width() as usize;
    let mut classes = Image::new(g.width(), g.height(), MapClass::Lit);
    classes.data_mut().par_chunks_mut(w).enumerate().for_each(|(y, row)| {
        for (x, class) in row.iter_mut().enumerate() {
            let i = y * w + x;
            if !g.receiver.data()[i] {
                continue;
            }
            let p = g.position.data()[i];
            // Asked only where it decides: most receivers' four texels agree.
            let faces_light = || g.geometric_normal.data()[i].dot(light.light.to_light(p)) > 0.0;
            let m = map_position(light, p, receiver_offset);
            let map = &maps[m.projection];
            *class = match classify(map, m.uv, m.depth, true) {
                MapClass::Silhouette if !faces_light() => MapClass::Shadowed,
                class => class,
            };
            let near = |cells: &Image<f32>| near_edge_pair(cells, map, m.uv, m.depth);
            if *class != MapClass::Silhouette && edge_maps.get(m.projection).is_some_and(near) && faces_light() {
                *class = MapClass::Silhouette;
            }
        }
    });
    classes
}

/// The edge cells of `edge_texels=paired`, one map per projection of `light`, from the casters'
/// silhouette `segments` (world space).
fn edge_maps(segments: &[[Vec3; 2]], light: &LightView, maps: &[Image<f32>], res: u32) -> Vec<Image<f32>> {
    light.projections.iter().zip(maps).map(|(p, map)| edge_cells(segments, p, res, Some(map))).collect()
}

impl ShadowTechnique<CpuBackend> for Hybrid {
    type State = State;

    fn name(&self) -> &'static str {
        Self::NAME
    }

    /// Cascades of the cut-out casters' map follow the camera.
    fn build_is_reusable(&self, frame: &FrameInputs) -> bool {
        !self.cutouts.follows_the_camera(frame)
    }

    fn create_state(&self, _: &mut CpuContext) -> Result<State, CpuError> {
        Ok(State::default())
    }

    fn build(&self, _: &mut CpuContext, state: &mut State, pass: LightPass<'_>) -> Result<(), CpuError> {
        let LightPass { frame, light, aspect, stats, .. } = pass;
        let (res, bias) = (self.depth.resolution, self.depth.depth_bias());
        render_caster_maps(frame, (light, Casters::Solid), res, bias, &mut state.maps)?;
        state.cutouts.render(frame, &cutout_view(&self.cutouts, frame, light, aspect), &self.cutouts)?;
        // The edge maps' segments come from the volumes' own silhouette pass (unused with
        // `edge_texels=off`, where they cost two transforms per silhouette edge).
        let (volumes, segments) = frame.shadow_volumes_and_segments(light, Caps::Both);
        InstanceVolume::count(&volumes, &mut stats.counters);
        state.edge_maps.clear();
        if self.edge_texels.is_on() {
            let t = Instant::now();
            state.edge_maps = edge_maps(&segments, light, &state.maps, self.depth.resolution);
            stats.timings.extra.insert("edge_maps".into(), ms(t.elapsed()));
        }
        state.shafts =
            if self.caster_masks.is_on() { CasterShafts::new(frame, light, &volumes) } else { CasterShafts::default() };
        state.volumes = Some(volumes);
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
        let LightPass { frame, light, stats, reach, .. } = pass;
        let volumes = state.volumes.as_ref().ok_or_else(|| TechniqueError::NotBuilt(Self::NAME.into()))?;
        if state.maps.len() != light.projections.len() {
            return Err(TechniqueError::NotBuilt(Self::NAME.into()).into());
        }
        let (w, h) = (g.width(), g.height());
        let t = Instant::now();
        let map_class = classify_receivers(&state.maps, &state.edge_maps, light, g, self.depth.receiver_offset());
        let silhouette = |x, y| *map_class.get(x, y) == MapClass::Silhouette;
        let mask = ComputationMask::from_fn(w, h, self.cpu.mask_tile, silhouette);
        stats.timings.extra.insert("classify".into(), ms(t.elapsed()));
        let t = Instant::now();
        let mut ds = DepthStencil::from_depth(&g.depth, 0);
        let c = if self.caster_masks.is_on() {
            let (c, casters) = count_volumes(frame, light, g, volumes, &state.shafts, &mask, &mut ds);
            let extra = &mut stats.counters.extra;
            extra.insert("caster_pieces".into(), casters.pieces as f64);
            extra.insert("caster_pieces_skipped".into(), casters.skipped as f64);
            extra.insert("caster_pieces_listed".into(), casters.listed as f64);
            extra.insert("caster_listed_pixels".into(), casters.listed_pixels as f64);
            stats.timings.extra.insert("caster_lists".into(), casters.listing_ms);
            c
        } else {
            rasterize_volumes(frame, g, volumes, VolumeCounting::ZFail, &mut ds, Some(&mask))
        };
        stats.timings.extra.insert("volumes".into(), ms(t.elapsed()));
        // Lit where the hybrid's answer and the cut-out casters' map both say lit.
        let cutouts = &state.cutouts;
        per_receiver(g, &reach, out, |x, y, i| {
            let lit = match map_class.get(x, y) {
                MapClass::Lit => true,
                MapClass::Shadowed => false,
                MapClass::Silhouette => ds.stencil[i] == 0,
            };
            if lit { cutouts.visibility(g.position.data()[i], (x, y)) } else { 0.0 }
        });
        let counters = &mut stats.counters;
        counters.silhouette_pixels = Some(mask.count() as u64);
        counters.volume_fragments = Some(c.fragments);
        counters.stencil_updates = Some(c.stencil_updates);
        let (tiles, all_tiles) = mask.tiles_in();
        counters.extra.insert("mask_tiles".into(), tiles as f64);
        counters.extra.insert("mask_tiles_total".into(), all_tiles as f64);
        state.last = Some(LastQuery { map_class, receiver: g.receiver.clone(), stencil: ds.stencil });
        if self.unmasked_fill.is_on() {
            let t = Instant::now();
            let mut scratch = DepthStencil::from_depth(&g.depth, 0);
            let all = rasterize_volumes(frame, g, volumes, VolumeCounting::ZFail, &mut scratch, None).fragments;
            stats.counters.extra.insert("unmasked_volume_fragments".into(), all as f64);
            stats.timings.extra.insert("count_fragments".into(), ms(t.elapsed()));
        }
        Ok(())
    }

    fn debug_views(&self, _: &mut CpuContext, state: &State) -> Result<Vec<DebugView>, CpuError> {
        let classes = state.last.iter().map(|last| {
            let c = last.classes();
            DebugView {
                name: "classes".into(),
                image: Image::from_fn(c.width(), c.height(), |x, y| c.get(x, y).colour()),
            }
        });
        Ok(classes.chain(state.cutouts.views("cutout-depth")).collect())
    }
}
