//! Light depth maps on the CPU (twin: shadow-wgpu's `passes::maps`): rendered with Vulkan's depth bias,
//! one per light projection (a point light's six cube faces), optionally with McCool's object-ID channel;
//! looked up per receiver through `shadow_core::lookup::shadow_lookup` with each filter. Casters cut out
//! by their texture discard the fragments of clear texels, each read over the footprint of one map texel.
//! [`CutoutMaps`] holds those casters alone, for the techniques built on silhouettes.

use rayon::prelude::*;
use shadow_core::frame::FrameError;
use shadow_core::glam::{Vec2, Vec3};
use shadow_core::light::{LightProjection, LightView, Reach};
use shadow_core::lookup::shadow_lookup;
use shadow_core::technique::DebugView;
use shadow_core::technique::maps::{Casters, CutoutMap};
use shadow_core::technique::settings::{DepthBias, Filter};
use shadow_core::{FrameInputs, Image, Instance};

use super::per_receiver;
use crate::alpha_test::{Drawn, draw_alpha_tested};
use crate::clip_space::ClipVertices;
use crate::context::{CpuError, MAX_MAP_TEXELS, check_size};
use crate::gbuffer::GBuffer;
use crate::raster::{
    Batch, CullMode, DepthState, DepthStencil, Fragment, Indexed, RasterCounters, RasterState, draw_depth, draw_flat,
};

/// Refuses a set of `count` square maps of side `res` before anything is allocated.
///
/// # Errors
/// [`CpuError::BadSize`] over the limits.
pub fn check_maps(res: u32, count: usize) -> Result<(), CpuError> {
    check_size("shadow map", u64::from(res), u64::from(res), u64::MAX)?;
    let total = u64::from(res) * u64::from(res) * count as u64;
    if total > MAX_MAP_TEXELS {
        return Err(CpuError::BadSize {
            what: "shadow maps",
            width: u64::from(res),
            height: u64::from(res),
            why: format!("{count} maps of this size are {total} texels, over the limit of {MAX_MAP_TEXELS}"),
        });
    }
    Ok(())
}

/// Renders the depth of the casting instances `casters` names from one light projection into a
/// `res x res` map, in the storage of `reuse` when given (last frame's map: its pages are already mapped).
/// Casters cut out by their texture are drawn after the others, through their alpha test
/// ([`crate::alpha_test`]).
///
/// # Errors
/// [`FrameError::TooManyTriangles`] for casters of more triangles than a draw can number.
pub fn render_depth_map(
    frame: &FrameInputs,
    (proj, casters): (&LightProjection, Casters),
    res: u32,
    bias: DepthBias,
    cull: CullMode,
    reuse: Option<Image<f32>>,
) -> Result<(Image<f32>, RasterCounters), FrameError> {
    let n = res as usize * res as usize;
    let mut depth = reuse.map(Image::into_vec).unwrap_or_default();
    depth.clear();
    depth.resize(n, 1.0);
    let mut ds = DepthStencil::from_parts(res, res, depth, vec![0; n]);
    let state =
        RasterState { cull, depth: Some(DepthState { bias, ..DepthState::LESS_WRITE }), ..RasterState::default() };
    let casters = LightCasters::new(frame, proj, casters);
    let mut counters = draw_depth(&mut ds, &casters.solid()?, &state);
    if !casters.drawn.cutout.is_empty() {
        let mut none = Image::new(res, res, ());
        counters +=
            draw_alpha_tested(&mut ds, &mut none, (&casters.cutout()?, &casters.drawn.tests), &state, |_| Some(()));
    }
    Ok((ds.into_depth_image(), counters))
}

/// The shadow casters of a frame that may lie in one light projection's frustum (the others, culled by
/// their bounds where the frame saves so, would draw nothing), sorted by their coverage (in frame order within each kind), with
/// their vertices in that projection's clip space.
struct LightCasters<'a> {
    frame: &'a FrameInputs,
    drawn: Drawn<'a>,
    /// The clip-space vertices of each of `drawn.solid`, then of each of `drawn.cutout`.
    clip: ClipVertices,
}

impl<'a> LightCasters<'a> {
    fn new(frame: &'a FrameInputs, proj: &LightProjection, casters: Casters) -> Self {
        let culling = frame.savings.culling;
        let drawn = Drawn::sort(frame, |i| casters.takes(i) && (!culling || proj.may_hold(i.bounds)));
        let casting: Vec<&Instance> = drawn.solid.iter().chain(&drawn.cutout).map(|&k| &frame.instances[k]).collect();
        let clip = ClipVertices::of_instances(&casting, proj.clip_from_world);
        Self { frame, drawn, clip }
    }

    /// The instances `list` (whose clip-space vertices start at `clip[first]`) as one draw, in order.
    fn batch<'b>(&'b self, list: &[usize], first: usize) -> Result<Batch<'b>, FrameError> {
        let part = |(j, &k): (usize, &usize)| Indexed::instance(&self.frame.instances[k], &self.clip[first + j]);
        Batch::new(list.par_iter().enumerate().with_min_len(1024).map(part).collect())
    }

    /// The solid casters as one draw; its parts are in the order of `drawn.solid`.
    fn solid(&self) -> Result<Batch<'_>, FrameError> {
        self.batch(&self.drawn.solid, 0)
    }

    /// The cut-out casters as one draw; its parts are in the order of `drawn.cutout`.
    fn cutout(&self) -> Result<Batch<'_>, FrameError> {
        self.batch(&self.drawn.cutout, self.drawn.solid.len())
    }
}

/// Renders one depth map per projection of `light` (after checking their size), each in the storage of the
/// map it replaces in `maps`.
///
/// # Errors
/// [`CpuError::BadSize`] over the limits, [`FrameError::TooManyTriangles`] for casters a draw cannot number.
pub fn render_depth_maps(
    frame: &FrameInputs,
    light: &LightView,
    res: u32,
    bias: DepthBias,
    maps: &mut Vec<Image<f32>>,
) -> Result<(), CpuError> {
    render_caster_maps(frame, (light, Casters::All), res, bias, maps)
}

/// [`render_depth_maps`] of the casters `casters` names.
///
/// # Errors
/// As [`render_depth_maps`].
pub fn render_caster_maps(
    frame: &FrameInputs,
    (light, casters): (&LightView, Casters),
    res: u32,
    bias: DepthBias,
    maps: &mut Vec<Image<f32>>,
) -> Result<(), CpuError> {
    check_maps(res, light.projections.len())?;
    let mut old = std::mem::take(maps).into_iter();
    *maps = light
        .projections
        .iter()
        .map(|p| Ok(render_depth_map(frame, (p, casters), res, bias, CullMode::None, old.next())?.0))
        .collect::<Result<_, CpuError>>()?;
    Ok(())
}

/// Renders one depth map per projection of `light` as [`render_depth_maps`] does, and with each an ID map:
/// 1 + the index in `frame.instances` of the caster a texel shows, 0 where it shows none (McCool's object-ID
/// channel, section 3.2; the GPU backend's light pass writes the same values).
///
/// # Errors
/// As [`render_depth_maps`].
pub fn render_depth_and_id_maps(
    frame: &FrameInputs,
    light: &LightView,
    res: u32,
    bias: DepthBias,
    maps: &mut Vec<Image<f32>>,
    ids: &mut Vec<Image<u32>>,
) -> Result<(), CpuError> {
    check_maps(res, light.projections.len())?;
    let state = RasterState { depth: Some(DepthState { bias, ..DepthState::LESS_WRITE }), ..RasterState::default() };
    maps.clear();
    ids.clear();
    for p in &light.projections {
        let mut ds = DepthStencil::new(res, res, 1.0, 0);
        let mut id = Image::new(res, res, 0u32);
        let casters = LightCasters::new(frame, p, Casters::All);
        let (solid, list) = (casters.solid()?, &casters.drawn.solid);
        draw_flat(&mut ds, &mut id, &solid, &state, |prim| list[solid.part_of(prim).0] as u32 + 1);
        if !casters.drawn.cutout.is_empty() {
            let (cutout, list) = (casters.cutout()?, &casters.drawn.cutout);
            let id_of = |f: &Fragment| Some(list[cutout.part_of(f.prim).0] as u32 + 1);
            draw_alpha_tested(&mut ds, &mut id, (&cutout, &casters.drawn.tests), &state, id_of);
        }
        maps.push(ds.into_depth_image());
        ids.push(id);
    }
    Ok(())
}

/// Where a receiver looks into a light's maps.
#[derive(Clone, Copy, Debug)]
pub struct MapPosition {
    /// The projection (cube face) it falls in.
    pub projection: usize,
    /// Map coordinates.
    pub uv: Vec2,
    /// NDC depth.
    pub depth: f32,
    /// The world point looked up (moved towards the light under `bias=world`).
    pub world: Vec3,
}

/// Where a receiver at `p` looks into the light's maps, after moving it `receiver_offset` towards the
/// light (`bias=world`).
#[must_use]
#[inline]
pub fn map_position(light: &LightView, mut p: Vec3, receiver_offset: f32) -> MapPosition {
    if receiver_offset != 0.0 {
        p += light.light.to_light(p) * receiver_offset;
    }
    let k = light.projection_index(p);
    let (uv, depth) = light.projections[k].uv_depth(p);
    MapPosition { projection: k, uv, depth, world: p }
}

/// How a receiver reads a light's maps, the lookup every map-based technique shares: the receiver moved
/// `receiver_offset` towards the light (`bias=world`), projected into its map and compared through
/// `filter` with a kernel of `radius` texels; with cascades, faded into the next cascade's answer over the
/// blend band at its far end.
#[derive(Clone, Copy, Debug)]
pub struct MapLookup {
    /// The filter.
    pub filter: Filter,
    /// Its kernel's radius in texels.
    pub radius: f32,
    /// How far a receiver moves towards the light before its lookup, in world units.
    pub receiver_offset: f32,
}

impl MapLookup {
    /// Every receiver within `reach` looked up in `maps` (one per projection of `light`) into `out`.
    pub fn query(&self, maps: &[Image<f32>], light: &LightView, reach: &Reach, g: &GBuffer, out: &mut Image<f32>) {
        per_receiver(g, reach, out, |x, y, i| self.visibility(maps, light, g.position.data()[i], (x, y)));
    }

    /// The visibility of the receiver at `p`, seen at pixel `px`, through `maps` (one per projection of
    /// `light`); with cascades, faded into the next cascade's answer over the blend band at its far end.
    fn visibility(&self, maps: &[Image<f32>], light: &LightView, p: Vec3, px: (u32, u32)) -> f32 {
        let Self { filter, radius, receiver_offset } = *self;
        let m = map_position(light, p, receiver_offset);
        let v = shadow_lookup(&maps[m.projection], m.uv, m.depth, filter, radius, px);
        match light.cascade_pick(m.world).and_then(|pick| pick.next) {
            Some((next, weight)) => {
                let (uv, depth) = light.projections[next].uv_depth(m.world);
                let w = shadow_lookup(&maps[next], uv, depth, filter, radius, px);
                v * (1.0 - weight) + w * weight
            }
            None => v,
        }
    }
}

/// The depth maps of the casters their texture cuts out, alone ([`Casters::CutOut`]), and how they are
/// read ([`CutoutMap`]): where the techniques built on silhouettes (which give such casters no volume or
/// wedge) take those casters' shadows from (twin: shadow-wgpu's `passes::maps::CutoutMaps`). A frame
/// without cut-out casters renders none, and every receiver is lit by them.
#[derive(Default)]
pub struct CutoutMaps {
    maps: Vec<Image<f32>>,
    /// The view the maps were rendered from, and how they are read; `None` when there are none.
    lookup: Option<(LightView, MapLookup)>,
}

impl CutoutMaps {
    /// Renders the maps of `frame`'s cut-out casters from every projection of `view` (the light's own, or
    /// its cascades over the camera's view) as `settings` asks, or, for a frame without such casters, lets
    /// last frame's go.
    ///
    /// # Errors
    /// As [`render_depth_maps`].
    pub fn render(&mut self, frame: &FrameInputs, view: &LightView, settings: &CutoutMap) -> Result<(), CpuError> {
        if !frame.has_cutout_casters() {
            *self = Self::default();
            return Ok(());
        }
        let map = settings.map();
        let (res, bias) = (map.resolution, map.depth_bias());
        let lookup = MapLookup {
            filter: settings.filter,
            radius: settings.filter_radius(),
            receiver_offset: map.receiver_offset(),
        };
        self.lookup = None;
        render_caster_maps(frame, (view, Casters::CutOut), res, bias, &mut self.maps)?;
        self.lookup = Some((view.clone(), lookup));
        Ok(())
    }

    /// The share of the light the cut-out casters of the last render leave the receiver at `p`, seen at
    /// pixel `px`: 1 when that frame had none.
    #[must_use]
    #[inline]
    pub fn visibility(&self, p: Vec3, px: (u32, u32)) -> f32 {
        match &self.lookup {
            Some((view, lookup)) => lookup.visibility(&self.maps, view, p, px),
            None => 1.0,
        }
    }

    /// Whether the last render drew maps (its frame had cut-out casters).
    #[must_use]
    pub fn is_rendered(&self) -> bool {
        self.lookup.is_some()
    }

    /// The maps, named `{prefix}{k}` ([`depth_views`]).
    #[must_use]
    pub fn views(&self, prefix: &str) -> Vec<DebugView> {
        depth_views(prefix, &self.maps)
    }
}

/// False-colour pictures of depth maps, named `{prefix}{k}`.
#[must_use]
pub fn depth_views(prefix: &str, maps: &[Image<f32>]) -> Vec<DebugView> {
    maps.iter()
        .enumerate()
        .map(|(k, m)| {
            let lo = m.data().iter().copied().fold(1.0f32, f32::min);
            DebugView { name: format!("{prefix}{k}"), image: shadow_core::image::false_colour(m, lo, 1.0) }
        })
        .collect()
}
