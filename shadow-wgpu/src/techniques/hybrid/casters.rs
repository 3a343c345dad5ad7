//! hybrid's caster masks on the GPU (`caster_masks=on`, ours; twin: shadow-cpu's
//! techniques/caster_masks.rs): each small piece of the z-fail volumes is counted only at the silhouette
//! pixels its shaft holds ([`shadow_core::shafts`]), by compute passes instead of the rasterizer.
//!
//! The rasterizer cannot do this: the mask is a stencil bit, the same for every draw, and a piece's
//! pixels are known only once the classification has run on the GPU (read back, they would stall the
//! frame; as scissor rectangles, measured on the CPU, they would still leave 10% of tree's fill). So:
//!
//! - **Build** (CPU): the pieces of at most [`LISTED_TRIANGLES`] volume triangles (a tree's twigs, a
//!   cloud's cubes) are written out as triangles, each piece's shafts beside its run of them, and a grid
//!   per light projection lists the pieces whose shafts, widened by the largest tolerance a pixel there can
//!   have, meet each cell. Larger pieces (a single big mesh) stay rasterized through the stencil mask.
//! - **Query**: the mask pass lists its silhouette pixels, and the compute passes (hybrid_casters.wgsl)
//!   set each triangle up for the view (its rows of adj(M): homogeneous rasterization; copied into a
//!   texture, as the shafts and the grid are uploaded into textures: on lavapipe a texel fetch is several
//!   times faster than a load from a storage buffer, which Mesa 22.3 makes lane by lane) and gather each
//!   piece's caps' screen bounds; pair each listed pixel with the pieces of its light-space cell whose
//!   shafts hold it (each pair staged and counted as it is found, then given runs by a prefix sum and
//!   moved into them, so the shaft grid is searched once a pixel); count each piece at its pixels, a
//!   workgroup per piece, testing its triangles at each pixel's centre as the rasterizer would, and add the
//!   count beside the pixel. The answer shadows a silhouette pixel whose stencil count or listed count is
//!   not 0: every piece is closed and wound alike, so the pieces' counts at a point have one sign and
//!   cannot cancel.
//!
//! The work is the CPU's caster masks' (a listed pixel times its pieces' triangles, every fragment those
//! would make counted), with the same shafts: `volume_fragments` is what the compute passes cover plus
//! what the stencil lets through of the rasterized pieces; `listed_tests` counts the pixel-triangle pairs
//! tested, and `listed_alone` the listed pixels whose pairs did not fit in the room for them (the
//! setting `pair_room`), each counted by one invocation over all its pieces.

use std::ops::Range;

use bytemuck::{Pod, Zeroable};
use shadow_core::FrameInputs;
use shadow_core::LightKind;
use shadow_core::frame::InstanceVolume;
use shadow_core::geometry::LightSource;
use shadow_core::geometry::volume::ShadowVolume;
use shadow_core::glam::{Vec2, Vec4, Vec4Swizzles};
use shadow_core::light::LightView;
use shadow_core::shafts::{CasterShafts, Shaft, ShaftGrid, tolerance};
use wgpu::util::DeviceExt;

use super::tables::{TABLE_ROW, table};
use crate::context::{WgpuContext, WgpuError};
use crate::gbuffer::GpuGBuffer;
use crate::pipelines::buffer_entry;
use crate::{readback, shaders};

/// Pieces of at most this many volume triangles are counted by the compute passes at the pixels their
/// shafts hold; larger ones are rasterized through the whole mask, where a pixel's cost does not grow
/// with them. Measured on lavapipe (8 frames, two runs): double-torus's query is 31 to 33 ms with 256 or
/// 1024 here and 71 to 73 with every piece counted by the compute passes; cylinder and primitives do not
/// move measurably between 256, 1024 and every piece.
pub(super) const LISTED_TRIANGLES: usize = 1024;

/// The most projections a light has (a point light's cube faces).
const PROJECTIONS: usize = 6;

/// vec4 per triangle set up for the view (hybrid_casters.wgsl's `SETUP`).
const SETUP: u64 = 5;

/// The most triangles the compute passes can take on `cx`'s device: as many as the tallest setup texture
/// it allows holds (the triangle table, four texels a triangle, is shorter), within the largest storage
/// binding for the setup buffer it is copied from.
pub(super) fn setup_room(cx: &WgpuContext) -> usize {
    let limits = cx.device.limits();
    let binding = limits.max_storage_buffer_binding_size.min(limits.max_buffer_size);
    let row = u64::from(TABLE_ROW);
    let rows = u64::from(limits.max_texture_dimension_2d).min(binding / (16 * row));
    (rows * row / SETUP) as usize
}

/// Invocations per workgroup of the compute passes (hybrid_casters.wgsl's `GROUP`).
const GROUP: u32 = 64;

/// The most workgroups along one dimension of a dispatch.
const MAX_GROUPS: u32 = 65_535;

/// Bytes of the listed pixels' header (`Listed` in shaders.rs: five counters).
const HEADER: u64 = 20;

/// Listed pixels per invocation of the passes over them, were every pixel of the view listed: their
/// dispatches are sized by the view (the list's length is known only on the GPU), each invocation taking
/// every so many.
const PIXELS_PER_INVOCATION: u32 = 16;

/// Workgroups of the pass over the pixels whose pairs did not fit (`cs_alone`): few, since there are
/// usually none, and lavapipe pays for every workgroup it starts, work or none (256 took 2-3 ms on cubes
/// and 6 on tree to find nothing; 64, 0.7 on cubes).
const ALONE_GROUPS: u32 = 64;

/// hybrid_casters.wgsl's `CasterParams`.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct Params {
    view_from_world: [[[f32; 4]; 4]; PROJECTIONS],
    grid: [[f32; 4]; PROJECTIONS],
    cells: [[u32; 4]; PROJECTIONS],
    counts: [u32; 4],
    light: [f32; 4],
    lists: [u32; 4],
}

/// hybrid_casters.wgsl's `PieceRun`.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct PieceRun {
    first: u32,
    sides: u32,
    caps: u32,
    quads: u32,
}

/// A piece counted by the compute passes.
struct SmallPiece {
    /// Its index in the shafts ([`CasterShafts::pieces`]).
    shaft: usize,
    /// Its run of [`Split::triangles`] (four vec4 each): `sides` sides, then near caps, then as many far
    /// caps.
    triangles: Range<u32>,
    sides: u32,
    /// Whether its sides come in quads, two triangles each ([`Split::write_piece`]).
    quads: bool,
}

/// The volumes of a build split for the caster masks.
pub(super) struct Split {
    /// The small pieces' triangles, four vec4 each (hybrid_casters.wgsl's `triangles`).
    triangles: Vec<Vec4>,
    /// The small pieces, in the order of their runs.
    pieces: Vec<SmallPiece>,
    /// What is left to rasterize: the large pieces, a volume per instance that has any.
    pub(super) raster: Vec<InstanceVolume>,
}

impl Split {
    /// Splits `volumes` (whose pieces `shafts` lists in order) into the pieces of at most `limit` volume
    /// triangles, written out for the compute passes while their triangles number at most `room` in all,
    /// and the rest.
    pub(super) fn new(
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

    fn triangle_count(&self) -> u32 {
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
    /// edge (from its third corner to its first), where hybrid_casters.wgsl's `add_quads` leaves it out.
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

/// The runs a piece's triangles come in (hybrid_casters.wgsl's `group` of a triangle).
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
fn grids(shafts: &[&[Option<Shaft>]], windows: &[(Vec2, Vec2)], widest: f32, orthographic: &[bool]) -> Vec<ShaftGrid> {
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

/// `grids` as hybrid_casters.wgsl reads them: every grid's cell starts, one after another and counted
/// across all of them, one more, then every grid's lists.
fn flattened(grids: &[ShaftGrid]) -> Vec<u32> {
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

/// A projection's view in its light space ([`shadow_core::shafts::light_coords`]), with a margin of a
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

/// The compute passes' pipelines and their group-1 layout.
pub(super) struct CasterPasses {
    layout: wgpu::BindGroupLayout,
    setup: wgpu::ComputePipeline,
    tally: wgpu::ComputePipeline,
    offsets: wgpu::ComputePipeline,
    fill: wgpu::ComputePipeline,
    pieces: wgpu::ComputePipeline,
    alone: wgpu::ComputePipeline,
}

/// One build's small pieces on the GPU.
pub(super) struct CasterPieces {
    params: wgpu::Buffer,
    triangles: wgpu::Texture,
    setups: wgpu::Buffer,
    setup_texels: wgpu::Texture,
    runs: wgpu::Buffer,
    shaft_texels: wgpu::Texture,
    grid: wgpu::Texture,
    /// Per instance of the frame, its `world_from_local`, a column a texel.
    instance_texels: wgpu::Texture,
    triangle_count: u32,
    /// Pieces counted by the compute passes.
    pub(super) pieces: usize,
}

/// The listed pixels and their counts, for one view size, and the compute passes' work buffer, for up to
/// so many pieces too.
pub(super) struct ListedPixels {
    /// The header (counters) and the pixels.
    pub(super) listed: wgpu::Buffer,
    /// Per pixel of the view, the map's class the mask pass found there, or at the listed pixels the
    /// count the compute passes found.
    pub(super) counts: wgpu::Buffer,
    /// Per piece its pixel count, first pair and cursor, the staged pairs' count, per listed pixel a flag,
    /// then the pairs and the staged pairs (hybrid_casters.wgsl's `work`).
    work: wgpu::Buffer,
    staging: wgpu::Buffer,
    /// The view's size, and the pieces the work buffer has room for (at least those of the build it was
    /// made for, rounded up to a power of two, so builds under a moving light reuse it).
    pub(super) size: (u32, u32),
    pub(super) capacity: usize,
    /// The room for pairs asked for (`Hybrid::pair_room`).
    pub(super) asked: Option<u32>,
}

/// Words of the work buffer per piece (hybrid_casters.wgsl's `PIECE`): its pixels, first pair and
/// cursor, and the screen bounds of its near and of its far caps.
const PIECE: u64 = 11;

/// Pairs of a listed pixel and a piece the work buffer has room for by default, per pixel of the view:
/// tree has about 4 per silhouette pixel. A pixel whose pairs do not fit is counted by itself, more slowly.
const PAIRS_PER_PIXEL: u64 = 8;

impl ListedPixels {
    /// Buffers for a view of `width x height`, `pieces` pieces and room for `asked` pairs (by default
    /// [`PAIRS_PER_PIXEL`] per pixel), within the device's limits.
    pub(super) fn new(cx: &WgpuContext, (width, height): (u32, u32), pieces: usize, asked: Option<u32>) -> Self {
        use wgpu::BufferUsages as U;
        let pixels = u64::from(width) * u64::from(height);
        let buffer = |label, size, usage| {
            cx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage,
                mapped_at_creation: false,
            })
        };
        let capacity = pieces.next_power_of_two();
        // The pieces' words, the staged pairs' count and the pixels' flags.
        let fixed = PIECE * capacity as u64 + 1 + pixels;
        let largest = {
            let limits = cx.device.limits();
            limits.max_storage_buffer_binding_size.min(limits.max_buffer_size) / 4
        };
        // Each pair's room is three words: its place in a run and, staged, its pixel and piece.
        let pairs = asked.map_or(PAIRS_PER_PIXEL * pixels, u64::from).min(largest.saturating_sub(fixed) / 3);
        Self {
            listed: buffer("hybrid listed pixels", HEADER + 4 * pixels, U::STORAGE | U::COPY_SRC | U::COPY_DST),
            counts: buffer("hybrid listed counts", 4 * pixels.max(1), U::STORAGE),
            work: buffer("hybrid caster work", 4 * (fixed + 3 * pairs), U::STORAGE | U::COPY_DST),
            staging: buffer("hybrid listed readback", HEADER, U::COPY_DST | U::MAP_READ),
            size: (width, height),
            capacity,
            asked,
        }
    }

    /// Empties the list (before the mask pass).
    pub(super) fn clear(&self, enc: &mut wgpu::CommandEncoder) {
        enc.clear_buffer(&self.listed, 0, Some(HEADER));
    }

    /// Reads back the pixels listed, the fragments the compute pass's triangles made at them, its stencil
    /// updates, its pixel-triangle tests and the pixels counted alone.
    pub(super) fn counters(&self, cx: &WgpuContext) -> Result<[u64; 5], WgpuError> {
        let mut enc = cx.device.create_command_encoder(&Default::default());
        enc.copy_buffer_to_buffer(&self.listed, 0, &self.staging, 0, HEADER);
        cx.queue.submit([enc.finish()]);
        let d = readback::map_read(cx, &self.staging, "reading the hybrid caster counters")?;
        let word = |i: usize| u64::from(u32::from_le_bytes([d[4 * i], d[4 * i + 1], d[4 * i + 2], d[4 * i + 3]]));
        Ok([word(0), word(1), word(2), word(3), word(4)])
    }
}

/// A compute-stage binding of group 1.
fn compute_entry(binding: u32, ty: wgpu::BindingType) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry { binding, visibility: wgpu::ShaderStages::COMPUTE, ty, count: None }
}

fn storage(binding: u32, read_only: bool) -> wgpu::BindGroupLayoutEntry {
    buffer_entry(binding, wgpu::BufferBindingType::Storage { read_only }, wgpu::ShaderStages::COMPUTE)
}

impl CasterPasses {
    pub(super) fn new(cx: &WgpuContext) -> Self {
        let texture = |sample_type| wgpu::BindingType::Texture {
            sample_type,
            view_dimension: wgpu::TextureViewDimension::D2,
            multisampled: false,
        };
        let floats = texture(wgpu::TextureSampleType::Float { filterable: false });
        let layout = cx.device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("hybrid casters"),
            entries: &[
                compute_entry(0, floats),
                storage(8, false),
                storage(9, false),
                buffer_entry(11, wgpu::BufferBindingType::Uniform, wgpu::ShaderStages::COMPUTE),
                compute_entry(12, texture(wgpu::TextureSampleType::Uint)),
                storage(13, false),
                storage(14, true),
                compute_entry(15, texture(wgpu::TextureSampleType::Uint)),
                storage(16, false),
                compute_entry(17, floats),
                compute_entry(18, floats),
                compute_entry(19, floats),
            ],
        });
        let module = shaders::module(&cx.device, "hybrid casters", shaders::hybrid_casters());
        let pipeline_layout = cx.device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("hybrid casters"),
            bind_group_layouts: &[Some(&cx.shared.frame_layout), Some(&layout)],
            immediate_size: 0,
        });
        let pipeline = |entry: &str| {
            cx.device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(entry),
                layout: Some(&pipeline_layout),
                module: &module,
                entry_point: Some(entry),
                compilation_options: Default::default(),
                cache: None,
            })
        };
        Self {
            setup: pipeline("cs_setup"),
            tally: pipeline("cs_tally"),
            offsets: pipeline("cs_offsets"),
            fill: pipeline("cs_fill"),
            pieces: pipeline("cs_pieces"),
            alone: pipeline("cs_alone"),
            layout,
        }
    }

    /// Uploads a build's small pieces: their triangles, shafts and grids.
    pub(super) fn upload(
        cx: &WgpuContext,
        frame: &FrameInputs,
        light: &LightView,
        split: &Split,
        shafts: &CasterShafts,
    ) -> Result<CasterPieces, WgpuError> {
        let projections = light.projections.len().min(PROJECTIONS);
        let piece_shafts: Vec<&[Option<Shaft>]> =
            split.pieces.iter().map(|p| shafts.shafts[p.shaft].as_slice()).collect();
        // The largest world tolerance of any pixel: the farthest corner of the frame's bounds from the eye.
        let far = frame.bounds.corners().iter().map(|c| c.distance(frame.camera.eye)).fold(0.0f32, f32::max);
        let widest = tolerance(far, frame.camera.near);
        let orthographic: Vec<bool> = light.projections.iter().map(|p| p.orthographic).collect();
        let windows: Vec<(Vec2, Vec2)> = light.projections[..projections].iter().map(window).collect();
        let per_projection = grids(&piece_shafts, &windows, widest, &orthographic);
        let grid = flattened(&per_projection);
        let mut params = Params::zeroed();
        let mut first_cell = 0u32;
        for (j, (proj, g)) in light.projections.iter().zip(&per_projection).enumerate() {
            params.view_from_world[j] = proj.view_from_world.to_cols_array_2d();
            params.grid[j] = [g.origin.x, g.origin.y, g.scale.x, g.scale.y];
            params.cells[j] = [g.side as u32, first_cell, u32::from(proj.orthographic), 0];
            first_cell += (g.side * g.side) as u32;
        }
        let point = match light.light.kind {
            LightKind::Point { position } => Some(position),
            _ => None,
        };
        params.counts =
            [u32::from(point.is_some()), projections as u32, split.pieces.len() as u32, split.triangle_count()];
        params.light = point.unwrap_or_default().extend(frame.camera.near).to_array();
        params.lists = [first_cell + 1, 0, 0, 0];
        let runs: Vec<PieceRun> = split
            .pieces
            .iter()
            .map(|piece| {
                let (run, sides) = (&piece.triangles, piece.sides);
                let caps = (run.end - run.start - sides) / 2;
                PieceRun { first: run.start, sides, caps, quads: u32::from(piece.quads) }
            })
            .collect();
        // Per piece, per projection: lo, hi, (near, 1 where bounded).
        let shaft_texels: Vec<[f32; 4]> = split
            .pieces
            .iter()
            .flat_map(|piece| {
                shafts.shafts[piece.shaft][..projections].iter().flat_map(|s| match s {
                    Some(s) => [s.lo.to_array(), s.hi.to_array(), [s.near, 1.0, 0.0, 0.0]],
                    None => [[0.0; 4]; 3],
                })
            })
            .collect();
        let init = |label, contents: &[u8], usage| {
            cx.device.create_buffer_init(&wgpu::util::BufferInitDescriptor { label: Some(label), contents, usage })
        };
        use wgpu::BufferUsages as U;
        use wgpu::TextureFormat as F;
        // A build with no small piece still binds its buffers: at least one element each.
        let nonempty = |bytes: &[u8]| {
            let mut v = bytes.to_vec();
            v.resize(v.len().max(std::mem::size_of::<PieceRun>()), 0);
            v
        };
        let shaft_bytes: &[u8] = bytemuck::cast_slice(&shaft_texels);
        let instance_columns: Vec<[[f32; 4]; 4]> =
            frame.instances.iter().map(|i| i.world_from_local.to_cols_array_2d()).collect();
        let setup_texels =
            table(cx, "hybrid caster setups", F::Rgba32Float, u64::from(split.triangle_count()) * SETUP, None)?;
        Ok(CasterPieces {
            params: init("hybrid caster params", bytemuck::bytes_of(&params), U::UNIFORM),
            triangles: table(
                cx,
                "hybrid caster triangles",
                F::Rgba32Uint,
                split.triangles.len() as u64,
                Some(bytemuck::cast_slice(&split.triangles)),
            )?,
            setups: cx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("hybrid caster setups"),
                size: u64::from(setup_texels.height()) * u64::from(TABLE_ROW) * 16,
                usage: U::STORAGE | U::COPY_SRC,
                mapped_at_creation: false,
            }),
            setup_texels,
            runs: init("hybrid caster runs", &nonempty(bytemuck::cast_slice(&runs)), U::STORAGE),
            shaft_texels: table(
                cx,
                "hybrid caster shafts",
                F::Rgba32Float,
                shaft_texels.len() as u64,
                Some(shaft_bytes),
            )?,
            grid: table(cx, "hybrid caster grid", F::R32Uint, grid.len() as u64, Some(bytemuck::cast_slice(&grid)))?,
            instance_texels: table(
                cx,
                "hybrid caster instances",
                F::Rgba32Float,
                4 * frame.instances.len() as u64,
                Some(bytemuck::cast_slice(&instance_columns)),
            )?,
            triangle_count: split.triangle_count(),
            pieces: split.pieces.len(),
        })
    }

    /// Records the compute passes (hybrid_casters.wgsl): set up the triangles for `g`'s view, pair each
    /// listed pixel with its pieces, count each piece at its pixels.
    pub(super) fn record(
        &self,
        cx: &WgpuContext,
        enc: &mut wgpu::CommandEncoder,
        pieces: &CasterPieces,
        listed: &ListedPixels,
        g: &GpuGBuffer,
    ) {
        fn buffer(binding: u32, b: &wgpu::Buffer) -> wgpu::BindGroupEntry<'_> {
            wgpu::BindGroupEntry { binding, resource: b.as_entire_binding() }
        }
        let (triangles, setups, shafts, grid, instances) = (
            pieces.triangles.create_view(&Default::default()),
            pieces.setup_texels.create_view(&Default::default()),
            pieces.shaft_texels.create_view(&Default::default()),
            pieces.grid.create_view(&Default::default()),
            pieces.instance_texels.create_view(&Default::default()),
        );
        let view = |binding, v| wgpu::BindGroupEntry { binding, resource: wgpu::BindingResource::TextureView(v) };
        let group = cx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("hybrid casters"),
            layout: &self.layout,
            entries: &[
                view(0, &g.position),
                buffer(8, &listed.listed),
                buffer(9, &listed.counts),
                buffer(11, &pieces.params),
                view(12, &triangles),
                buffer(13, &pieces.setups),
                buffer(14, &pieces.runs),
                view(15, &grid),
                buffer(16, &listed.work),
                view(17, &setups),
                view(18, &shafts),
                view(19, &instances),
            ],
        });
        // The pieces' words and the staged pairs' count.
        enc.clear_buffer(&listed.work, 0, Some(4 * (PIECE * pieces.pieces as u64 + 1)));
        let begin = |enc: &mut wgpu::CommandEncoder| {
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("hybrid casters"),
                timestamp_writes: None,
            });
            pass.set_bind_group(0, &g.frame_group, &[]);
            pass.set_bind_group(1, &group, &[]);
            pass.forget_lifetime()
        };
        let spread = |pass: &mut wgpu::ComputePass<'_>, pipeline, groups: u32| {
            pass.set_pipeline(pipeline);
            pass.dispatch_workgroups(groups.clamp(1, MAX_GROUPS), groups.div_ceil(MAX_GROUPS).max(1), 1);
        };
        if pieces.triangle_count > 0 {
            let mut pass = begin(enc);
            spread(&mut pass, &self.setup, pieces.triangle_count.div_ceil(GROUP));
            drop(pass);
            let size = pieces.setup_texels.size();
            enc.copy_buffer_to_texture(
                wgpu::TexelCopyBufferInfo {
                    buffer: &pieces.setups,
                    layout: wgpu::TexelCopyBufferLayout {
                        offset: 0,
                        bytes_per_row: Some(TABLE_ROW * 16),
                        rows_per_image: None,
                    },
                },
                pieces.setup_texels.as_image_copy(),
                size,
            );
        }
        let mut pass = begin(enc);
        // The passes over the listed pixels, whose number only the GPU knows, are sized by the view.
        let (w, h) = listed.size;
        let over_pixels = (w * h).div_ceil(GROUP * PIXELS_PER_INVOCATION);
        spread(&mut pass, &self.tally, over_pixels);
        spread(&mut pass, &self.offsets, 1);
        spread(&mut pass, &self.fill, over_pixels);
        spread(&mut pass, &self.pieces, pieces.pieces as u32);
        spread(&mut pass, &self.alone, ALONE_GROUPS);
    }
}

#[cfg(test)]
mod tests {
    use std::collections::HashMap;

    use shadow_core::geometry::volume::Caps;
    use shadow_core::glam::{Vec2, Vec4};
    use shadow_core::scenes::{self, SceneParams};
    use shadow_core::shafts::{CasterShafts, Shaft, outline};

    use super::{Split, flattened, grids};

    /// The cell a light-space point looks in (hybrid_casters.wgsl's `candidates`).
    fn cell_of(frame: (Vec2, Vec2, usize), first: usize, xy: Vec2) -> usize {
        let (origin, scale, side) = frame;
        let c = ((xy - origin) * scale).floor();
        let clamp = |v: f32| (v.max(0.0) as usize).min(side - 1);
        first + clamp(c.y) * side + clamp(c.x)
    }

    #[test]
    fn split_writes_closed_pieces_and_leaves_the_large_ones_to_rasterize() {
        // primitives: a sphere of more volume triangles than the limit, and smaller casters.
        let s = scenes::build("primitives", &SceneParams::default()).expect("scene");
        let frame = shadow_core::FrameInputs::from_scene(&s, s.cameras().next().expect("camera").0).expect("frame");
        let light = frame.light_view(&frame.lights[0]).expect("light view");
        let volumes = frame.shadow_volumes(&light, Caps::Both);
        let shafts = CasterShafts::new(&frame, &light, &volumes);
        let limit = 256;
        let split = Split::new(&frame, &volumes, &shafts, limit, usize::MAX);
        let sizes: Vec<usize> = volumes
            .iter()
            .flat_map(|iv| {
                iv.volume.pieces.iter().map(|p| p.sides.len() + 2 * (p.caps_forward.len() + p.caps_reversed.len()))
            })
            .collect();
        let (small, large): (Vec<usize>, Vec<usize>) = sizes.iter().partition(|&&n| n <= limit);
        assert!(!small.is_empty() && !large.is_empty(), "primitives has pieces on both sides of {limit}: {sizes:?}");
        assert_eq!(split.pieces.len(), small.len());
        assert_eq!(split.triangle_count() as usize, small.iter().sum::<usize>());
        let rasterized = |s: &Split| s.raster.iter().map(|v| v.volume.triangle_count()).sum::<usize>();
        assert_eq!(rasterized(&split), large.iter().sum::<usize>());
        // With room for half the small pieces' triangles, those that do not fit are rasterized too.
        let room = small.iter().sum::<usize>() / 2;
        let half = Split::new(&frame, &volumes, &shafts, limit, room);
        assert!(half.triangle_count() as usize <= room, "{} triangles in a room of {room}", half.triangle_count());
        assert!(!half.pieces.is_empty() && half.pieces.len() < small.len(), "{} pieces", half.pieces.len());
        assert_eq!(half.triangle_count() as usize + rasterized(&half), sizes.iter().sum::<usize>());
        // Each piece written out is closed and wound alike: every directed edge between two corners comes
        // with its reverse (far caps turned around, mirrored instances turned back).
        let key = |v: Vec4| v.to_array().map(f32::to_bits);
        for piece in &split.pieces {
            let (k, run, sides) = (piece.shaft, &piece.triangles, piece.sides as usize);
            // Sides, near caps, as many far caps, in runs.
            let groups: Vec<u32> = run.clone().map(|t| split.triangles[4 * t as usize + 3].z.to_bits()).collect();
            let caps = (groups.len() - sides) / 2;
            let runs = [(0, sides), (1, caps), (2, caps)];
            let expected: Vec<u32> = runs.iter().flat_map(|&(g, n)| std::iter::repeat_n(g, n)).collect();
            assert_eq!(groups, expected, "piece {k}: triangles out of their runs");
            let mut edges: HashMap<([u32; 4], [u32; 4]), i32> = HashMap::new();
            for t in run.clone() {
                let c = &split.triangles[4 * t as usize..4 * t as usize + 3];
                for (a, b) in [(c[0], c[1]), (c[1], c[2]), (c[2], c[0])] {
                    *edges.entry((key(a), key(b))).or_default() += 1;
                    *edges.entry((key(b), key(a))).or_default() -= 1;
                }
            }
            let open = edges.values().filter(|&&n| n != 0).count();
            assert_eq!(open, 0, "piece {k}: {open} directed edges without their reverse");
        }
    }

    #[test]
    fn side_quads_keep_their_diagonal_in_the_rows_add_quads_leaves_out() {
        use shadow_core::glam::{Mat4, Vec3};
        use shadow_core::{Camera, Light, Material, Scene};

        // A cube as it is and a mirrored one (front faces wound the other way), under a spot light, which
        // sides come in quads for, and a directional light, which they do not.
        let mut s = Scene::new();
        let grey = s.add_material(Material::colored("grey", Vec3::splat(0.75)));
        let cube = s.add_mesh(shadow_core::procedural::cuboid(Vec3::splat(0.3)).expect("shape"));
        let tilt = Mat4::from_rotation_x(0.4) * Mat4::from_rotation_y(0.7);
        let at = |x: f32| Mat4::from_translation(Vec3::new(x, 0.5, 0.0)) * tilt;
        s.add_instance("cube", cube, grey, at(-0.4)).expect("cube");
        s.add_instance("mirrored", cube, grey, at(0.4) * Mat4::from_scale(Vec3::new(-1.0, 1.0, 1.0))).expect("cube");
        let camera = Camera::look_at(Vec3::new(0.0, 1.5, 2.5), Vec3::ZERO, 45.0);
        for (light, quads) in [
            (Light::spot(Vec3::new(0.5, 3.0, 1.0), Vec3::ZERO, 60.0), true),
            (Light::directional(Vec3::new(-0.3, -1.0, -0.2)), false),
        ] {
            let frame = shadow_core::FrameInputs::new(&s, camera, vec![light]).expect("frame");
            let light = frame.light_view(&frame.lights[0]).expect("light view");
            let volumes = frame.shadow_volumes(&light, Caps::Both);
            let shafts = CasterShafts::new(&frame, &light, &volumes);
            let split = Split::new(&frame, &volumes, &shafts, usize::MAX, usize::MAX);
            let mirrored: Vec<bool> = frame.instances.iter().map(|i| i.mirrored).collect();
            assert_eq!(mirrored, [false, true]);
            assert_eq!(split.pieces.len(), 2, "a piece per cube");
            for piece in &split.pieces {
                assert_eq!(piece.quads, quads);
                if !quads {
                    continue;
                }
                let corners = |t: u32| &split.triangles[4 * t as usize..4 * t as usize + 3];
                let sides = piece.triangles.start..piece.triangles.start + piece.sides;
                for t in sides.step_by(2) {
                    let (first, second) = (corners(t), corners(t + 1));
                    // The diagonal, from b to a_inf, is each triangle's edge from its third corner to its
                    // first, once each way; the corner off it is a (finite) in the first, b_inf in the second.
                    assert_eq!((first[0], first[2]), (second[2], second[0]), "side quad at {t}");
                    assert_eq!([first[0].w, first[2].w].iter().sum::<f32>(), 1.0, "one end at infinity");
                    assert_eq!((first[1].w, second[1].w), (1.0, 0.0), "side quad at {t}");
                }
            }
        }
    }

    #[test]
    fn every_point_a_shaft_holds_finds_its_piece_in_its_cell() {
        // Random shafts in two projections (a second view, shifted), some unbounded, some far outside the
        // view, and random points with tolerances no larger than the grids were widened for, looked up in
        // the flattened grids as the shader does.
        let mut seed = 0x2545_f491_u32;
        let mut next = move || {
            seed ^= seed << 13;
            seed ^= seed >> 17;
            seed ^= seed << 5;
            seed as f32 / u32::MAX as f32
        };
        let widest = 0.01;
        let mut shafts: Vec<Vec<Option<Shaft>>> = Vec::new();
        let windows = [(Vec2::splat(-1.0), Vec2::splat(1.0)), (Vec2::splat(-0.5), Vec2::splat(1.5))];
        for k in 0..300 {
            let mut shaft = || {
                let centre = Vec2::new(next() * 3.0 - 1.5, next() * 3.0 - 1.5) * if k % 10 == 0 { 8.0 } else { 1.0 };
                let half = Vec2::new(next(), next()) * 0.2;
                let (a, b) = (outline(centre - half), outline(centre + half));
                Shaft {
                    lo: a.min(b).min(outline(centre + half * Vec2::new(1.0, -1.0))),
                    hi: a.max(b).max(outline(centre + half * Vec2::new(-1.0, 1.0))),
                    near: 0.5 + next(),
                }
            };
            let (first, second) = (shaft(), shaft());
            shafts.push(vec![(k % 37 != 0).then_some(first), (k % 23 != 0).then_some(second)]);
        }
        let refs: Vec<&[Option<Shaft>]> = shafts.iter().map(Vec::as_slice).collect();
        let per_projection = grids(&refs, &windows, widest, &[false, false]);
        let cells = flattened(&per_projection);
        let g = |j: usize| &per_projection[j];
        let first_cells = [0, g(0).side * g(0).side];
        let lists = first_cells[1] + g(1).side * g(1).side + 1;
        let (mut held, mut missed) = (0, Vec::new());
        for i in 0..40_000 {
            let j = i % 2;
            let xy = Vec2::new(next() * 4.0 - 2.0, next() * 4.0 - 2.0);
            let (tol, d) = (next() * widest, 0.3 + next() * 2.0);
            let side = 2.0 * tol / d;
            let c = cell_of((g(j).origin, g(j).scale, g(j).side), first_cells[j], xy);
            assert_eq!(c - first_cells[j], g(j).cell_of(xy), "the shader's cell is the grid's");
            let listed = &cells[lists + cells[c] as usize..lists + cells[c + 1] as usize];
            for (k, s) in shafts.iter().enumerate() {
                let holds = s[j].is_none_or(|s| s.holds(outline(xy), d, side, tol));
                if holds {
                    held += 1;
                    if !listed.contains(&(k as u32)) {
                        missed.push((k, xy));
                    }
                }
            }
        }
        assert!(held > 40_000, "the points fall in some shafts: {held}");
        assert!(
            missed.is_empty(),
            "{} points held by a shaft not listed in their cell: {:?}",
            missed.len(),
            &missed[..missed.len().min(5)]
        );
    }
}
