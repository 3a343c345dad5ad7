//! hybrid's caster masks on the GPU (`caster_masks=on`, ours; twin: cpu/casters.rs): each small piece of the z-fail volumes is counted only at the silhouette
//! pixels its shaft holds ([`crate::hybrid::shafts`]), by compute passes instead of the rasterizer.
//!
//! The rasterizer cannot do this: the mask is a stencil bit, the same for every draw, and a piece's
//! pixels are known only once the classification has run on the GPU (read back, they would stall the
//! frame; as scissor rectangles, measured on the CPU, they would still leave 10% of tree's fill). So:
//!
//! - **Build** (CPU): the pieces of at most [`LISTED_TRIANGLES`] volume triangles (a tree's twigs, a
//!   cloud's cubes) are written out as triangles, each piece's shafts beside its run of them, and a grid
//!   per light projection lists the pieces whose shafts, widened by the largest tolerance a pixel there can
//!   have, meet each cell. Larger pieces (a single big mesh) stay rasterized through the stencil mask.
//! - **Query**: the mask pass lists its silhouette pixels, and the compute passes (casters.wgsl)
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

mod pieces;

pub(super) use pieces::Split;
use pieces::{PieceRun, PieceTables};

use crate::hybrid::shafts::CasterShafts;
use shadow_core::FrameInputs;
use shadow_core::light::LightView;

use super::tables::{TABLE_ROW, table};
use shadow_wgpu::context::{WgpuContext, WgpuError};
use shadow_wgpu::gbuffer::GpuGBuffer;
use shadow_wgpu::pipelines::buffer_entry;
use shadow_wgpu::{Transient, readback};

/// Pieces of at most this many volume triangles are counted by the compute passes at the pixels their
/// shafts hold; larger ones are rasterized through the whole mask, where a pixel's cost does not grow
/// with them. Measured on lavapipe (8 frames, two runs): double-torus's query is 31 to 33 ms with 256 or
/// 1024 here and 71 to 73 with every piece counted by the compute passes; cylinder and primitives do not
/// move measurably between 256, 1024 and every piece.
pub(super) const LISTED_TRIANGLES: usize = 1024;

/// vec4 per triangle set up for the view (casters.wgsl's `SETUP`).
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

/// Invocations per workgroup of the compute passes (casters.wgsl's `GROUP`).
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
#[derive(Clone)]
pub(super) struct CasterPieces {
    params: Transient,
    triangles: wgpu::Texture,
    setups: wgpu::Buffer,
    setup_texels: wgpu::Texture,
    runs: Transient,
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
    /// then the pairs and the staged pairs (casters.wgsl's `work`).
    work: wgpu::Buffer,
    staging: wgpu::Buffer,
    /// The view's size, and the pieces the work buffer has room for (at least those of the build it was
    /// made for, rounded up to a power of two, so builds under a moving light reuse it).
    pub(super) size: (u32, u32),
    pub(super) capacity: usize,
    /// The room for pairs asked for (`GpuOptions::pair_room`).
    pub(super) asked: Option<u32>,
}

/// Words of the work buffer per piece (casters.wgsl's `PIECE`): its pixels, first pair and
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
            cx.create_buffer(&wgpu::BufferDescriptor { label: Some(label), size, usage, mapped_at_creation: false })
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
        let mut enc = cx.encoder("readback");
        enc.copy_buffer_to_buffer(&self.listed, 0, &self.staging, 0, HEADER);
        cx.submit(enc);
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
        let layout = cx.pipelines.group_layout(
            "hybrid casters",
            &[
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
        );
        let module = cx.pipelines.module("hybrid casters", super::shaders::casters());
        let pipeline_layout = cx.pipelines.layout("hybrid casters", &[Some(&cx.shared.frame_layout), Some(&layout)]);
        let pipeline = |entry: &str| {
            cx.pipelines.compute(&wgpu::ComputePipelineDescriptor {
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

    /// Uploads a build's small pieces: their triangles, shafts and grids, into the tables of `kept` (this
    /// light's last build's) where they fit; their parameters and runs go to the frame's transient buffer.
    pub(super) fn upload(
        cx: &WgpuContext,
        (frame, light): (&FrameInputs, &LightView),
        split: &Split,
        shafts: &CasterShafts,
        kept: Option<CasterPieces>,
    ) -> Result<CasterPieces, WgpuError> {
        let PieceTables { params, runs, shaft_texels, grid } = PieceTables::new(frame, light, split, shafts);
        use wgpu::TextureFormat as F;
        // A build with no small piece still binds its runs: at least one element.
        let mut runs = bytemuck::cast_slice::<_, u8>(&runs).to_vec();
        runs.resize(runs.len().max(std::mem::size_of::<PieceRun>()), 0);
        let instance_columns: Vec<[[f32; 4]; 4]> =
            frame.instances.iter().map(|i| i.world_from_local.to_cols_array_2d()).collect();
        let kept = kept.map(|k| (k.triangles, (k.setups, k.setup_texels), k.shaft_texels, k.grid, k.instance_texels));
        let (triangles, setups, shafts, grids, instances) = match kept {
            Some((t, s, sh, g, i)) => (Some(t), Some(s), Some(sh), Some(g), Some(i)),
            None => (None, None, None, None, None),
        };
        let setup_n = u64::from(split.triangle_count()) * SETUP;
        let setup_texels =
            table(cx, "hybrid caster setups", F::Rgba32Float, (setup_n, None), setups.as_ref().map(|s| s.1.clone()))?;
        let setup_bytes = u64::from(setup_texels.height()) * u64::from(TABLE_ROW) * 16;
        let setups = match setups {
            Some((buffer, _)) if buffer.size() == setup_bytes => buffer,
            _ => cx.create_buffer(&wgpu::BufferDescriptor {
                label: Some("hybrid caster setups"),
                size: setup_bytes,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            }),
        };
        let triangle_bytes = bytemuck::cast_slice(&split.triangles);
        Ok(CasterPieces {
            params: cx.transient(bytemuck::bytes_of(&params)),
            triangles: table(
                cx,
                "hybrid caster triangles",
                F::Rgba32Uint,
                (split.triangles.len() as u64, Some(triangle_bytes)),
                triangles,
            )?,
            setups,
            setup_texels,
            runs: cx.transient(&runs),
            shaft_texels: table(
                cx,
                "hybrid caster shafts",
                F::Rgba32Float,
                (shaft_texels.len() as u64, Some(bytemuck::cast_slice(&shaft_texels))),
                shafts,
            )?,
            grid: table(
                cx,
                "hybrid caster grid",
                F::R32Uint,
                (grid.len() as u64, Some(bytemuck::cast_slice(&grid))),
                grids,
            )?,
            instance_texels: table(
                cx,
                "hybrid caster instances",
                F::Rgba32Float,
                (4 * frame.instances.len() as u64, Some(bytemuck::cast_slice(&instance_columns))),
                instances,
            )?,
            triangle_count: split.triangle_count(),
            pieces: split.pieces.len(),
        })
    }

    /// Records the compute passes (casters.wgsl): set up the triangles for `g`'s view, pair each
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
                wgpu::BindGroupEntry { binding: 11, resource: pieces.params.binding() },
                view(12, &triangles),
                buffer(13, &pieces.setups),
                wgpu::BindGroupEntry { binding: 14, resource: pieces.runs.binding() },
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
mod tests;
