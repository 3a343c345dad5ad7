//! The caster masks' CPU side (see [`super`]): the volumes split into the small pieces the compute passes
//! count and the rest, the pieces' triangles laid out for casters.wgsl, a grid of their shafts per light
//! projection, and the tables a build uploads.

use std::ops::Range;

use bytemuck::{Pod, Zeroable};
use shadow_core::FrameInputs;
use shadow_core::LightKind;
use shadow_core::frame::InstanceVolume;
use shadow_core::geometry::LightSource;
use shadow_core::geometry::volume::ShadowVolume;
use shadow_core::glam::{Vec2, Vec4, Vec4Swizzles};
use shadow_core::light::LightView;

use crate::hybrid::shafts::{CasterShafts, Shaft, ShaftGrid, tolerance};

/// The most projections a light has (a point light's cube faces).
const PROJECTIONS: usize = 6;

/// What a build uploads for its small pieces, laid out as casters.wgsl reads it.
pub(super) struct PieceTables {
    pub(super) params: Params,
    /// A run of triangles per piece.
    pub(super) runs: Vec<PieceRun>,
    /// Per piece, per projection, its shaft (three texels).
    pub(super) shaft_texels: Vec<[f32; 4]>,
    /// The shaft grids, flattened.
    pub(super) grid: Vec<u32>,
}

impl PieceTables {
    /// The tables of `split`'s small pieces, whose shafts `shafts` holds, for `light`.
    pub(super) fn new(frame: &FrameInputs, light: &LightView, split: &Split, shafts: &CasterShafts) -> Self {
        let projections = light.projections.len().min(PROJECTIONS);
        let piece_shafts: Vec<&[Option<Shaft>]> =
            split.pieces.iter().map(|p| shafts.shafts[p.shaft].as_slice()).collect();
        // The largest world tolerance of any pixel: the farthest corner of the frame's bounds from the eye.
        let far = frame.bounds.corners().iter().map(|c| c.distance(frame.camera.eye)).fold(0.0f32, f32::max);
        let widest = tolerance(far, frame.camera.near);
        let orthographic: Vec<bool> = light.projections.iter().map(|p| p.orthographic).collect();
        let windows: Vec<(Vec2, Vec2)> = light.projections[..projections].iter().map(window).collect();
        let per_projection = grids(&piece_shafts, &windows, widest, &orthographic);
        Self {
            grid: flattened(&per_projection),
            params: params(frame, light, split, &per_projection),
            runs: split.pieces.iter().map(PieceRun::of).collect(),
            shaft_texels: shaft_texels(split, shafts, projections),
        }
    }
}

/// casters.wgsl's `CasterParams`.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub(super) struct Params {
    view_from_world: [[[f32; 4]; 4]; PROJECTIONS],
    grid: [[f32; 4]; PROJECTIONS],
    cells: [[u32; 4]; PROJECTIONS],
    counts: [u32; 4],
    light: [f32; 4],
    lists: [u32; 4],
}

/// casters.wgsl's `PieceRun`.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub(super) struct PieceRun {
    first: u32,
    sides: u32,
    caps: u32,
    quads: u32,
}

impl PieceRun {
    fn of(piece: &SmallPiece) -> Self {
        let (run, sides) = (&piece.triangles, piece.sides);
        let caps = (run.end - run.start - sides) / 2;
        Self { first: run.start, sides, caps, quads: u32::from(piece.quads) }
    }
}

/// A piece counted by the compute passes.
pub(super) struct SmallPiece {
    /// Its index in the shafts ([`CasterShafts::pieces`]).
    pub(super) shaft: usize,
    /// Its run of [`Split::triangles`] (four vec4 each): `sides` sides, then near caps, then as many far
    /// caps.
    pub(super) triangles: Range<u32>,
    pub(super) sides: u32,
    /// Whether its sides come in quads, two triangles each ([`Split::write_piece`]).
    pub(super) quads: bool,
}

/// The volumes of a build split for the caster masks.
pub(in crate::hybrid::gpu) struct Split {
    /// The small pieces' triangles, four vec4 each (casters.wgsl's `triangles`).
    pub(super) triangles: Vec<Vec4>,
    /// The small pieces, in the order of their runs.
    pub(super) pieces: Vec<SmallPiece>,
    /// What is left to rasterize: the large pieces, a volume per instance that has any.
    pub(in crate::hybrid::gpu) raster: Vec<InstanceVolume>,
}

impl Split {
    /// Splits `volumes` (whose pieces `shafts` lists in order) into the pieces of at most `limit` volume
    /// triangles, written out for the compute passes while their triangles number at most `room` in all,
    /// and the rest.
    pub(in crate::hybrid::gpu) fn new(
        frame: &FrameInputs,
        volumes: &[InstanceVolume],
        shafts: &CasterShafts,
        limit: usize,
        room: usize,
    ) -> Self {
        let mut split = Self { triangles: Vec::new(), pieces: Vec::new(), raster: Vec::new() };
        let mut k = 0;
        for iv in volumes {
            let inst = &frame.instances[iv.instance];
            let vol = &iv.volume;
            let mut rest = ShadowVolume {
                sides: Vec::new(),
                caps_forward: Vec::new(),
                caps_reversed: Vec::new(),
                light: vol.light,
                pieces: Vec::new(),
            };
            for piece in &vol.pieces {
                let r = |r: &Range<u32>| r.start as usize..r.end as usize;
                let (sides, forward, reversed) = (
                    &vol.sides[r(&piece.sides)],
                    &vol.caps_forward[r(&piece.caps_forward)],
                    &vol.caps_reversed[r(&piece.caps_reversed)],
                );
                let n = sides.len() + 2 * (forward.len() + reversed.len());
                if n > limit || split.triangle_count() as usize + n > room {
                    rest.sides.extend_from_slice(sides);
                    rest.caps_forward.extend_from_slice(forward);
                    rest.caps_reversed.extend_from_slice(reversed);
                } else {
                    let first = split.triangle_count();
                    let quads = split.write_piece(iv, inst, sides, forward, reversed);
                    let triangles = first..split.triangle_count();
                    split.pieces.push(SmallPiece { shaft: k, triangles, sides: sides.len() as u32, quads });
                }
                k += 1;
            }
            if rest.triangle_count() > 0 {
                split.raster.push(InstanceVolume { instance: iv.instance, volume: rest, silhouette_edges: 0 });
            }
        }
        debug_assert_eq!(k, shafts.pieces.len(), "the shafts list every piece");
        split
    }

    pub(super) fn triangle_count(&self) -> u32 {
        (self.triangles.len() / 4) as u32
    }

    /// Writes one piece's triangles as the rasterizer would draw them (shadow_volume.rs's `upload`):
    /// sides as built, near caps from the mesh's vertices, far caps extruded and turned around for faces
    /// that cast as wound; each wound so its front face is counter-clockwise. In that order, sides, near
    /// caps and far caps each in a run of their own, with the piece's index, so the caps can be passed
    /// over together where their bounds on screen are away from a pixel.
    ///
    /// Returns whether the sides come in quads: every light but a directional one extrudes a silhouette
    /// edge (a, b) into the two triangles (b, a, a_inf) and (b, a_inf, b_inf) (`geometry::volume::extrude`).
    /// Each is then turned, keeping its winding, so that the quad's diagonal from b to a_inf is its second
    /// edge (from its third corner to its first), where casters.wgsl's `add_quads` leaves it out.
    fn write_piece(
        &mut self,
        iv: &InstanceVolume,
        inst: &shadow_core::Instance,
        sides: &[[Vec4; 3]],
        forward: &[u32],
        reversed: &[u32],
    ) -> bool {
        let m = inst.mirrored;
        let (tris, positions) = (inst.mesh.triangles(), inst.mesh.positions());
        let (instance, piece) = (iv.instance as u32, self.pieces.len() as u32);
        let mut push = |[a, b, c]: [Vec4; 3], cw: bool, group: Group| {
            let (b, c) = if cw { (c, b) } else { (b, c) };
            let info = Vec4::new(
                f32::from_bits(instance * 2 + u32::from(group != Group::Side)),
                f32::from_bits(piece),
                f32::from_bits(group as u32),
                0.0,
            );
            self.triangles.extend([a, b, c, info]);
        };
        let quads = !matches!(iv.volume.light, LightSource::Directional(_)) && sides.len().is_multiple_of(2);
        for (i, s) in sides.iter().enumerate() {
            // The corner off the diagonal (a in the first triangle, b_inf in the second) goes where `push`
            // leaves it in the middle (it swaps the last two corners when mirrored).
            let (off, want) = (if i % 2 == 0 { 1 } else { 2 }, if m { 2 } else { 1 });
            let turned = if quads { std::array::from_fn(|j| s[(j + off + 3 - want) % 3]) } else { *s };
            push(turned, m, Group::Side);
        }
        let light = iv.volume.light;
        let faces = || forward.iter().map(|&f| (f, m, true)).chain(reversed.iter().map(|&f| (f, !m, false)));
        let corners = |f: u32| tris[f as usize].map(|v| positions[v as usize]);
        for (f, near_cw, _) in faces() {
            push(corners(f).map(|p| p.extend(1.0)), near_cw, Group::Near);
        }
        for (f, _, far_reverse) in faces() {
            let far = corners(f).map(|p| light.extrude(p));
            push(if far_reverse { [far[0], far[2], far[1]] } else { far }, m, Group::Far);
        }
        quads
    }
}

/// The runs a piece's triangles come in (casters.wgsl's `group` of a triangle).
#[derive(Clone, Copy, PartialEq, Eq)]
enum Group {
    Side = 0,
    Near = 1,
    Far = 2,
}

/// Per projection, a grid ([`ShaftGrid`]) over the light-space bounds of the small pieces' shafts within
/// the projection's view (`windows`: silhouette pixels lie in it, the map classifying nothing else), each
/// shaft widened by the largest sideways tolerance a pixel it can hold may have; a piece unbounded in the
/// projection, or whose widening cannot be bounded, is listed in every cell.
pub(super) fn grids(
    shafts: &[&[Option<Shaft>]],
    windows: &[(Vec2, Vec2)],
    widest: f32,
    orthographic: &[bool],
) -> Vec<ShaftGrid> {
    // The box of a bounded shaft, widened; `None` where a pixel's tolerance cannot be bounded.
    let widened = |s: &Shaft, j: usize| -> Option<(Vec2, Vec2)> {
        let side = if orthographic[j] {
            2.0 * widest
        } else {
            let d = s.near - widest;
            if d <= 0.0 {
                return None;
            }
            2.0 * widest / d
        };
        Some((s.lo.xy() - side, s.hi.xy() + side))
    };
    let everywhere = (Vec2::NEG_INFINITY, Vec2::INFINITY);
    // About four cells a piece: a pixel tests the pieces of its own cell only.
    let side = ((shafts.len() as f64).sqrt() * 2.0).clamp(1.0, 256.0) as usize;
    windows
        .iter()
        .enumerate()
        .map(|(j, window)| {
            let boxes: Vec<Option<(Vec2, Vec2)>> =
                shafts.iter().map(|s| s[j].as_ref().and_then(|s| widened(s, j))).collect();
            let (lo, hi) = boxes
                .iter()
                .flatten()
                .fold((Vec2::INFINITY, Vec2::NEG_INFINITY), |(lo, hi), b| (lo.min(b.0), hi.max(b.1)));
            let listed: Vec<_> = boxes.iter().map(|b| Some(b.unwrap_or(everywhere))).collect();
            ShaftGrid::new(lo.max(window.0), hi.min(window.1), side, &listed)
        })
        .collect()
}

/// `grids` as casters.wgsl reads them: every grid's cell starts, one after another and counted
/// across all of them, one more, then every grid's lists.
pub(super) fn flattened(grids: &[ShaftGrid]) -> Vec<u32> {
    let mut out = Vec::new();
    let mut before = 0;
    for g in grids {
        out.extend(g.starts[..g.starts.len() - 1].iter().map(|s| s + before));
        before += g.pieces.len() as u32;
    }
    out.push(before);
    for g in grids {
        out.extend_from_slice(&g.pieces);
    }
    out
}

/// The uniforms of a build: per projection its view, grid window and cell range; the light; the counts.
fn params(frame: &FrameInputs, light: &LightView, split: &Split, grids: &[ShaftGrid]) -> Params {
    let mut params = Params::zeroed();
    let mut first_cell = 0u32;
    for (j, (proj, g)) in light.projections.iter().zip(grids).enumerate() {
        params.view_from_world[j] = proj.view_from_world.to_cols_array_2d();
        params.grid[j] = [g.origin.x, g.origin.y, g.scale.x, g.scale.y];
        params.cells[j] = [g.side as u32, first_cell, u32::from(proj.orthographic), 0];
        first_cell += (g.side * g.side) as u32;
    }
    let point = match light.light.kind {
        LightKind::Point { position } => Some(position),
        _ => None,
    };
    let projections = light.projections.len().min(PROJECTIONS);
    params.counts = [u32::from(point.is_some()), projections as u32, split.pieces.len() as u32, split.triangle_count()];
    params.light = point.unwrap_or_default().extend(frame.camera.near).to_array();
    params.lists = [first_cell + 1, 0, 0, 0];
    params
}

/// Per piece, per projection, its shaft as three texels: lo, hi, (near, 1 where bounded); zeros where the
/// piece has no shaft there.
fn shaft_texels(split: &Split, shafts: &CasterShafts, projections: usize) -> Vec<[f32; 4]> {
    split
        .pieces
        .iter()
        .flat_map(|piece| {
            shafts.shafts[piece.shaft][..projections].iter().flat_map(|s| match s {
                Some(s) => [s.lo.to_array(), s.hi.to_array(), [s.near, 1.0, 0.0, 0.0]],
                None => [[0.0; 4]; 3],
            })
        })
        .collect()
}

/// A projection's view in its light space ([`crate::hybrid::shafts::light_coords`]), with a margin of a
/// hundredth of its size.
fn window(proj: &shadow_core::light::LightProjection) -> (Vec2, Vec2) {
    let view_from_clip = proj.clip_from_view.inverse();
    let (lo, hi) = [(-1.0, -1.0), (1.0, -1.0), (-1.0, 1.0), (1.0, 1.0)].iter().fold(
        (Vec2::INFINITY, Vec2::NEG_INFINITY),
        |(lo, hi), &(x, y)| {
            let v = view_from_clip.project_point3(shadow_core::glam::Vec3::new(x, y, 0.5));
            let xy = if proj.orthographic { v.truncate() } else { v.truncate() / -v.z };
            (lo.min(xy), hi.max(xy))
        },
    );
    let margin = (hi - lo) * 0.01;
    (lo - margin, hi + margin)
}
