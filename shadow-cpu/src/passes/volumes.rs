//! Stencil shadow volumes on the CPU (twin: shadow-wgpu's `passes::volumes`): the volumes of every caster
//! from the shared extrusion (`FrameInputs::shadow_volumes`), rasterized into an 8-bit stencil with
//! two-sided wrapping ops against the G-buffer's depth, z-pass or z-fail (DESIGN 4), through a computation
//! mask when one is given. A pixel is lit when its count is zero.

use std::ops::Range;

use glam::{Mat4, Vec4};
use shadow_core::FrameInputs;
use shadow_core::frame::InstanceVolume;
use shadow_core::geometry::volume::Caps;
use shadow_core::geometry::volume::VolumeCounting;
use shadow_core::light::LightView;
use shadow_core::technique::FrameStats;

use crate::gbuffer::GBuffer;
use crate::raster::{
    CompareFn, ComputationMask, DepthState, DepthStencil, Indexed, RasterCounters, RasterState, Soup, StencilFace,
    StencilOp, StencilState, TriangleSource, draw_depth_masked,
};

/// The volumes of every caster with `caps`, and the build's counters (silhouette edges, volume
/// triangles).
#[must_use]
pub fn build_volumes(
    frame: &FrameInputs,
    light: &LightView,
    caps: Caps,
    stats: &mut FrameStats,
) -> Vec<InstanceVolume> {
    let volumes = frame.shadow_volumes(light, caps);
    InstanceVolume::count(&volumes, &mut stats.counters);
    volumes
}

/// Two-sided stencil state of a counting.
#[must_use]
pub fn stencil_state(counting: VolumeCounting) -> StencilState {
    let face = |pass, depth_fail| StencilFace { compare: CompareFn::Always, fail: StencilOp::Keep, depth_fail, pass };
    let (front, back) = match counting {
        VolumeCounting::ZPass => {
            (face(StencilOp::IncrementWrap, StencilOp::Keep), face(StencilOp::DecrementWrap, StencilOp::Keep))
        }
        VolumeCounting::ZFail => {
            (face(StencilOp::Keep, StencilOp::DecrementWrap), face(StencilOp::Keep, StencilOp::IncrementWrap))
        }
    };
    StencilState { front, back, read_mask: 0xff, write_mask: 0xff, reference: 0 }
}

/// The state of a counting draw.
#[must_use]
pub fn counting_state(counting: VolumeCounting) -> RasterState {
    RasterState { depth: Some(DepthState::LESS_READ), stencil: Some(stencil_state(counting)), ..RasterState::default() }
}

/// One instance's volume in the G-buffer's clip space, to be drawn whole or a run of pieces at a time:
/// sides, and for z-fail the near caps on the G-buffer's own clip-space vertices and the far caps at
/// infinity.
pub struct ClipVolume<'a> {
    sides: Vec<[Vec4; 3]>,
    /// The G-buffer's clip-space vertices of the instance.
    near: &'a [Vec4],
    /// The mesh's vertices projected to infinity.
    far: Vec<Vec4>,
    /// Caps cast as wound, and cast turned around, as the mesh winds them.
    forward: Vec<[u32; 3]>,
    reversed: Vec<[u32; 3]>,
    /// The forward caps re-wound, for the far cap.
    far_forward: Vec<[u32; 3]>,
    mirrored: bool,
}

/// Runs of a volume's sides, forward caps and reversed caps (one
/// [`shadow_core::geometry::volume::VolumePiece`]'s, or several's).
pub type Runs = [Range<usize>; 3];

impl<'a> ClipVolume<'a> {
    /// The volume `iv` of `frame` in `g`'s clip space; with `caps` false, the sides alone.
    #[must_use]
    pub fn new(frame: &FrameInputs, g: &'a GBuffer, iv: &InstanceVolume, caps: bool) -> Self {
        let inst = &frame.instances[iv.instance];
        let vol = &iv.volume;
        let clip_from_local: Mat4 = g.clip_from_world * inst.world_from_local;
        let sides = vol.sides.iter().map(|t| t.map(|v| clip_from_local * v)).collect();
        let tris = inst.mesh.triangles();
        let pick = |ids: &[u32], reverse: bool| -> Vec<[u32; 3]> {
            ids.iter().map(|&f| tris[f as usize]).map(|[a, b, c]| if reverse { [a, c, b] } else { [a, b, c] }).collect()
        };
        let (forward, reversed, far_forward, far) = if caps {
            let light = vol.light;
            let far = inst.mesh.positions().iter().map(|&p| clip_from_local * light.extrude(p)).collect();
            (pick(&vol.caps_forward, false), pick(&vol.caps_reversed, false), pick(&vol.caps_forward, true), far)
        } else {
            Default::default()
        };
        Self {
            sides,
            near: &g.clip_vertices[iv.instance],
            far,
            forward,
            reversed,
            far_forward,
            mirrored: inst.mirrored,
        }
    }

    /// All of it.
    #[must_use]
    pub fn whole(&self) -> Runs {
        [0..self.sides.len(), 0..self.forward.len(), 0..self.reversed.len()]
    }

    /// The volume cut down to the given runs, in order.
    #[must_use]
    pub fn gathered(&self, runs: &[Runs]) -> Self {
        let gather = |all: &[[u32; 3]], k: usize| runs.iter().flat_map(|r| all[r[k].clone()].iter().copied()).collect();
        Self {
            sides: runs.iter().flat_map(|r| self.sides[r[0].clone()].iter().copied()).collect(),
            near: self.near,
            far: self.far.clone(),
            forward: gather(&self.forward, 1),
            reversed: gather(&self.reversed, 2),
            far_forward: gather(&self.far_forward, 1),
            mirrored: self.mirrored,
        }
    }

    /// The draws of the runs `[sides, forward caps, reversed caps]`: the sides, then the near caps (in
    /// the mesh's own winding; faces cast turned around are drawn with front and back swapped rather
    /// than re-wound, so their depths stay bit-identical to the G-buffer's), then the far caps (forward
    /// ones re-wound). Empty runs give empty draws.
    #[must_use]
    pub fn draws(&self, [sides, forward, reversed]: Runs) -> [VolumeDraw<'_>; 5] {
        let flip = self.mirrored;
        let indexed = |positions, triangles, flip| {
            VolumeDraw::Caps(Indexed { positions, triangles, prim_base: 0, flip, cull_back: false })
        };
        [
            VolumeDraw::Sides(Soup { triangles: &self.sides[sides], prim_base: 0, flip }),
            indexed(self.near, &self.forward[forward.clone()], flip),
            indexed(self.near, &self.reversed[reversed.clone()], !flip),
            indexed(&self.far, &self.far_forward[forward], flip),
            indexed(&self.far, &self.reversed[reversed], flip),
        ]
    }
}

/// One draw of a [`ClipVolume`].
pub enum VolumeDraw<'a> {
    /// Sides, corner by corner.
    Sides(Soup<'a>),
    /// Caps, indexed into the near or the far vertices.
    Caps(Indexed<'a>),
}

impl VolumeDraw<'_> {
    /// As a triangle source.
    #[must_use]
    pub fn source(&self) -> &dyn TriangleSource {
        match self {
            Self::Sides(s) => s,
            Self::Caps(c) => c,
        }
    }
}

/// Rasterizes shadow volumes into the stencil of `ds` (which holds the G-buffer depth): sides, and for
/// z-fail the caps ([`ClipVolume`]); only the pixels of `mask` when one is given (`hybrid`).
pub fn rasterize_volumes(
    frame: &FrameInputs,
    g: &GBuffer,
    volumes: &[InstanceVolume],
    counting: VolumeCounting,
    ds: &mut DepthStencil,
    mask: Option<&ComputationMask>,
) -> RasterCounters {
    let state = counting_state(counting);
    let mut c = RasterCounters::default();
    for iv in volumes {
        let caps = counting == VolumeCounting::ZFail;
        let clip = ClipVolume::new(frame, g, iv, caps);
        for d in &clip.draws(clip.whole())[..if caps { 5 } else { 1 }] {
            c += draw_depth_masked(ds, d.source(), &state, mask);
        }
    }
    c
}
