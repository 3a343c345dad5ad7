//! Shadow volumes found and extruded on the GPU (twin: shadow-core's `geometry::silhouette` and
//! `geometry::volume`, which stay the reference; the conformance tests hold the two to the same stencil).
//!
//! Each mesh's adjacency is uploaded once ([`crate::upload::AdjacencyGpu`]). Per light, two compute
//! dispatches per casting instance weigh its faces, list its caps and list its silhouette edges
//! (`extrude.wgsl`); the counting pass then draws those lists through indirect draws whose counts the
//! dispatches wrote, so the host neither sees nor uploads a vertex: its part of a light's build is a
//! 64-byte uniform per instance and a handful of commands. Every buffer is made once per set of casting
//! instances and reused: the lists by every light in turn (the GPU runs them in order), the uniforms in
//! a place per light ([`LightPass::slot`](shadow_core::technique::LightPass)), since a frame recorded
//! into one command buffer sees every write before its first command, and in a buffer per frame that
//! may be in flight, used in turn as the transient buffers are, so a frame's writes never wait for one
//! still reading.

use shadow_core::geometry::LightSource;
use shadow_core::geometry::volume::{Caps, VolumeCounting};
use shadow_core::light::LightView;
use shadow_core::{FrameInputs, Instance};

use super::volumes::{Query, StencilVertex, count_all, counting_state, occlusion_query, stencil_pipeline};
use crate::context::{WgpuContext, WgpuError};
use crate::gbuffer::GpuGBuffer;
use crate::pipelines::POSITION_LAYOUT;
use crate::shaders;
use crate::upload::{BufferRange, BuffersKey};

/// Words of one instance's draw arguments (`extrude.wgsl`'s `ARG_*`): sides, near caps as wound, near
/// caps turned around, far caps, and the silhouette-edge counter.
const ARG_WORDS: u32 = 20;
const ARG_NEAR_FORWARD: u32 = 4;
const ARG_NEAR_REVERSED: u32 = 9;
const ARG_FAR: u32 = 14;
const ARG_EDGES: u32 = 19;
/// Bytes of `Extrusion` in `extrude.wgsl`.
const UNIFORM_BYTES: u64 = 64;
/// Invocations per workgroup (`extrude.wgsl`'s `WORKGROUP`).
const WORKGROUP: u32 = 64;

/// The extrusion's pipelines and the buffers it keeps for the frame's casting instances.
pub struct GpuExtrusion {
    faces: wgpu::ComputePipeline,
    edges: wgpu::ComputePipeline,
    compute_layout: wgpu::BindGroupLayout,
    draw_layout: wgpu::BindGroupLayout,
    /// Stencil counting, by `[vs_side, vs_near, vs_far]` and winding (`[ccw, cw]`).
    counting: [[wgpu::RenderPipeline; 2]; 3],
    /// Every fragment counted, nothing written (instrumented frames), by vertex stage.
    count_all: [wgpu::RenderPipeline; 3],
    jobs: Option<Jobs>,
    /// The frame turn whose uniforms the last build wrote, which its draws read (a build kept for later
    /// frames keeps its turn).
    built_turn: usize,
}

/// The extrusion of every casting instance of a frame, in the buffers they share.
struct Jobs {
    /// What the buffers were made for: each casting instance with the key of the buffers it binds.
    key: Vec<(usize, BuffersKey)>,
    list: Vec<Job>,
    args: wgpu::Buffer,
    /// The arguments every light starts from: no triangles, each list's first index.
    template: wgpu::Buffer,
    /// Per frame turn, each job's [`Uniform`] for each light slot (slot-major), `stride` bytes apart.
    uniforms: Vec<wgpu::Buffer>,
    stride: u64,
    slots: usize,
    /// Whether `caps` has room for every instance's caps.
    with_caps: bool,
    weights: wgpu::Buffer,
    records: wgpu::Buffer,
    caps: wgpu::Buffer,
    /// Per frame turn, each job's groups.
    compute_groups: Vec<Vec<wgpu::BindGroup>>,
    draw_groups: Vec<Vec<wgpu::BindGroup>>,
}

/// One casting instance's place in the shared buffers.
#[derive(Clone, Copy)]
struct Job {
    instance: usize,
    faces: u32,
    edges: u32,
    bergeron: bool,
    /// First word of its arguments.
    args: u32,
    /// First side record.
    records: u32,
    /// First face weight.
    weights: u32,
    /// First index of its near caps as wound, turned around, and of its far caps.
    caps: [u32; 3],
}

/// `Extrusion` in `extrude.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Uniform {
    light: [f32; 4],
    counts: [u32; 4],
    bases: [u32; 4],
    caps: [u32; 4],
}

/// What a light's volumes total: the counters `silhouette_edges` and `volume_triangles`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ExtrusionCounts {
    /// Silhouette edges (before weights).
    pub silhouette_edges: u64,
    /// Side, near-cap and far-cap triangles.
    pub triangles: u64,
}

impl GpuExtrusion {
    /// The pipelines, counting `counting`'s way.
    #[must_use]
    pub fn new(cx: &WgpuContext, counting: VolumeCounting) -> Self {
        let module = cx.pipelines.module("extrusion", shaders::extrusion());
        let compute_layout = layout(cx, "extrusion", wgpu::ShaderStages::COMPUTE, &COMPUTE_BINDINGS);
        let draw_layout = layout(cx, "extruded volumes", wgpu::ShaderStages::VERTEX, &DRAW_BINDINGS);
        let compute = |entry| compute_pipeline(cx, &module, &compute_layout, entry);
        let draw = |entry, front, state| draw_pipeline(cx, &module, &draw_layout, entry, front, state);
        let state = counting_state(cx.depth_stencil, counting, wgpu::CompareFunction::Always, 0xff, 0xff);
        let counting = STAGES
            .map(|entry| [wgpu::FrontFace::Ccw, wgpu::FrontFace::Cw].map(|front| draw(entry, front, state.clone())));
        let count_all = STAGES.map(|entry| draw(entry, wgpu::FrontFace::Ccw, count_all(cx.depth_stencil)));
        Self {
            faces: compute("cs_faces"),
            edges: compute("cs_edges"),
            compute_layout,
            draw_layout,
            counting,
            count_all,
            jobs: None,
            built_turn: 0,
        }
    }

    /// Records the finding and extrusion of `light`'s volumes, with `caps`, for every casting instance:
    /// light number `slot` of the frame.
    ///
    /// # Errors
    /// Lists larger than the device's storage bindings.
    pub fn build(
        &mut self,
        cx: &mut WgpuContext,
        frame: &FrameInputs,
        light: &LightView,
        slot: usize,
        caps: Caps,
    ) -> Result<(), WgpuError> {
        cx.upload_meshes(frame);
        cx.upload_adjacency(frame);
        let slots = frame.lights.len().max(slot + 1);
        let layouts = [&self.compute_layout, &self.draw_layout];
        let jobs = Jobs::for_frame(&mut self.jobs, cx, layouts, frame, slots, caps == Caps::Both)?;
        let world = light.source();
        let uniforms: Vec<u8> = jobs
            .list
            .iter()
            .flat_map(|job| {
                let local = world.transformed(frame.instances[job.instance].local_from_world);
                let slot = cx.cache.order().slot(job.instance);
                let mut bytes = bytemuck::bytes_of(&job.uniform(local, caps, slot)).to_vec();
                bytes.resize(jobs.stride as usize, 0);
                bytes
            })
            .collect();
        let turn = cx.frame_turn();
        cx.queue.write_buffer(&jobs.uniforms[turn], jobs.offset(slot, 0), &uniforms);
        self.built_turn = turn;
        let most = cx.device.limits().max_compute_workgroups_per_dimension;
        let mut enc = cx.encoder("shadow-volume extrusion");
        enc.copy_buffer_to_buffer(&jobs.template, 0, &jobs.args, 0, jobs.args.size());
        {
            let mut pass = enc
                .begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some("extrusion"), timestamp_writes: None });
            for (j, job) in jobs.list.iter().enumerate() {
                pass.set_bind_group(2, &jobs.compute_groups[turn][j], &[jobs.offset(slot, j) as u32]);
                pass.set_pipeline(&self.faces);
                let (x, y) = groups(job.faces, most);
                pass.dispatch_workgroups(x, y, 1);
                pass.set_pipeline(&self.edges);
                let (x, y) = groups(job.edges, most);
                pass.dispatch_workgroups(x, y, 1);
            }
        }
        cx.submit(enc);
        Ok(())
    }

    /// Reads back what the last [`Self::build`] made (instrumented frames).
    ///
    /// # Errors
    /// A GPU failure, or [`WgpuError::NotRecordable`] in a recorded frame.
    pub fn counts(&self, cx: &WgpuContext) -> Result<ExtrusionCounts, WgpuError> {
        let Some(jobs) = &self.jobs else { return Ok(ExtrusionCounts::default()) };
        cx.may_wait("reading the extrusion's counts")?;
        let staging = cx.create_buffer(&wgpu::BufferDescriptor {
            label: Some("extrusion counts"),
            size: jobs.args.size(),
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            mapped_at_creation: false,
        });
        let mut enc = cx.encoder("extrusion counts");
        enc.copy_buffer_to_buffer(&jobs.args, 0, &staging, 0, jobs.args.size());
        cx.submit(enc);
        let bytes = crate::readback::map_read(cx, &staging, "reading the extrusion's counts")?;
        let words: &[u32] = bytemuck::cast_slice(&bytes);
        let mut c = ExtrusionCounts::default();
        for job in &jobs.list {
            let w = |k: u32| u64::from(words[(job.args + k) as usize]);
            c.silhouette_edges += w(ARG_EDGES);
            // Sides are counted in vertices, caps in indices: three a triangle either way.
            c.triangles += (w(0) + w(ARG_NEAR_FORWARD) + w(ARG_NEAR_REVERSED) + w(ARG_FAR)) / 3;
        }
        Ok(c)
    }

    /// Counts light `slot`'s volumes (from the last [`Self::build`]) in the stencil of `depth`, cleared
    /// first; with `every_fragment`, counts every fragment they rasterize instead, the stencil kept. In an
    /// instrumented frame, returns an occlusion query of the samples that pass.
    #[must_use]
    pub fn draw(
        &self,
        cx: &WgpuContext,
        frame: &FrameInputs,
        g: &GpuGBuffer,
        depth: &wgpu::TextureView,
        slot: usize,
        every_fragment: bool,
    ) -> Option<Query> {
        let query = cx.instrumented().then(|| occlusion_query(cx));
        let label = if every_fragment { "count volume fragments" } else { "shadow volumes" };
        let mut enc = cx.encoder(label);
        {
            let stencil = if every_fragment { wgpu::LoadOp::Load } else { wgpu::LoadOp::Clear(0) };
            let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some(label),
                color_attachments: &[],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: depth,
                    depth_ops: Some(wgpu::Operations { load: wgpu::LoadOp::Load, store: wgpu::StoreOp::Store }),
                    stencil_ops: Some(wgpu::Operations { load: stencil, store: wgpu::StoreOp::Store }),
                }),
                timestamp_writes: None,
                occlusion_query_set: query.as_ref().map(|q| &q.0),
                multiview_mask: None,
            });
            pass.set_bind_group(0, &g.frame_group, &[]);
            if query.is_some() {
                pass.begin_occlusion_query(0);
            }
            let pick = |stage: usize, cw: bool| {
                if every_fragment { &self.count_all[stage] } else { &self.counting[stage][usize::from(cw)] }
            };
            let jobs =
                self.jobs.iter().flat_map(|jobs| jobs.list.iter().enumerate().map(move |(j, job)| (jobs, j, job)));
            for (jobs, j, job) in jobs {
                let Some((inst, mesh)) = frame.instances.get(job.instance).and_then(|i| Some((i, cx.cache.mesh(i)?)))
                else {
                    continue;
                };
                let m = inst.mirrored;
                let args = |word: u32| u64::from(4 * (job.args + word));
                pass.set_bind_group(1, &jobs.draw_groups[self.built_turn][j], &[jobs.offset(slot, j) as u32]);
                pass.set_pipeline(pick(0, m));
                pass.draw_indirect(&jobs.args, args(0));
                if !jobs.with_caps {
                    continue;
                }
                pass.set_vertex_buffer(0, mesh.positions.slice(..));
                pass.set_index_buffer(jobs.caps.slice(..), wgpu::IndexFormat::Uint32);
                // Faces cast turned around are drawn with fronts and backs swapped, not re-wound, so their
                // near caps rasterize exactly as the G-buffer drew them.
                for (stage, cw, word) in [(1, m, ARG_NEAR_FORWARD), (1, !m, ARG_NEAR_REVERSED), (2, m, ARG_FAR)] {
                    pass.set_pipeline(pick(stage, cw));
                    pass.draw_indexed_indirect(&jobs.args, args(word));
                }
            }
            if query.is_some() {
                pass.end_occlusion_query();
            }
        }
        if let Some((set, resolve)) = &query {
            enc.resolve_query_set(set, 0..1, resolve, 0);
        }
        cx.submit(enc);
        query
    }
}

impl Job {
    /// Its uniform for a light, given in its mesh's space, with its instance's slot in the instance buffer.
    fn uniform(&self, light: LightSource, caps: Caps, slot: u32) -> Uniform {
        Uniform {
            light: light.homogeneous().to_array(),
            counts: [slot, self.faces, self.edges, u32::from(self.bergeron)],
            bases: [u32::from(caps == Caps::Both), self.args, self.records, self.weights],
            caps: [self.caps[0], self.caps[1], self.caps[2], 0],
        }
    }

    /// Its draw arguments before a light's dispatches: no triangles, one instance, each cap list's
    /// first index (the sides' records are found through the uniform), no edges counted.
    fn initial_args(&self) -> [u32; ARG_WORDS as usize] {
        let [forward, reversed, far] = self.caps;
        [0, 1, 0, 0, 0, 1, forward, 0, 0, 0, 1, reversed, 0, 0, 0, 1, far, 0, 0, 0]
    }
}

impl Jobs {
    /// The buffers in `slot` for `frame`'s casting instances with uniforms for `slots` lights, and room
    /// for their caps where `caps` asks for them: those of the last frame while its casting instances
    /// and their meshes are the same and it had room for as many lights (and caps), made anew otherwise.
    fn for_frame<'a>(
        slot: &'a mut Option<Self>,
        cx: &WgpuContext,
        layouts: [&wgpu::BindGroupLayout; 2],
        frame: &FrameInputs,
        slots: usize,
        caps: bool,
    ) -> Result<&'a Self, WgpuError> {
        let key: Vec<(usize, BuffersKey)> = frame
            .instances
            .iter()
            .enumerate()
            .filter(|(_, inst)| inst.casts_solid_shadow())
            .map(|(i, inst)| (i, BuffersKey::of(inst)))
            .collect();
        if !slot.as_ref().is_some_and(|j| j.key == key && j.slots >= slots && (j.with_caps || !caps)) {
            *slot = None;
            *slot = Some(Self::new(cx, layouts, frame, key, slots, caps)?);
        }
        match slot {
            Some(jobs) => Ok(jobs),
            None => unreachable!("just made"),
        }
    }

    /// Lays the casting instances `key` out in shared buffers, with uniforms for `slots` lights, and
    /// lists for their caps where `with_caps` asks for them (z-pass draws none: a scene of many
    /// triangles would need room for nine indices a face it never writes).
    fn new(
        cx: &WgpuContext,
        [compute_layout, draw_layout]: [&wgpu::BindGroupLayout; 2],
        frame: &FrameInputs,
        key: Vec<(usize, BuffersKey)>,
        slots: usize,
        with_caps: bool,
    ) -> Result<Self, WgpuError> {
        let mut list = Vec::with_capacity(key.len());
        let (mut records, mut weights, mut caps) = (0u64, 0u64, 0u64);
        for &(instance, _) in &key {
            // A job is made only for a mesh whose vertices and adjacency are both uploaded: the groups
            // below bind them.
            let inst = &frame.instances[instance];
            let (Some(adj), Some(_)) = (cx.cache.adjacency(inst), cx.cache.mesh(inst)) else { continue };
            let adj = adj.topology;
            let faces = u64::from(adj.faces);
            let at = |n: u64| u32::try_from(n).map_err(|_| too_large("the extrusion's lists", 4 * n, u64::MAX));
            list.push(Job {
                instance,
                faces: adj.faces,
                edges: adj.edge_count,
                bergeron: !adj.closed,
                args: list.len() as u32 * ARG_WORDS,
                records: at(records)?,
                weights: at(weights)?,
                caps: if with_caps { [at(caps)?, at(caps + 3 * faces)?, at(caps + 6 * faces)?] } else { [0; 3] },
            });
            records += u64::from(adj.use_count);
            weights += faces;
            if with_caps {
                caps += 9 * faces;
            }
        }
        let limits = cx.device.limits();
        let most = limits.max_storage_buffer_binding_size.min(limits.max_buffer_size);
        let storage = |label: &'static str, words: u64, extra: wgpu::BufferUsages| {
            let bytes = 4 * words.max(4);
            if bytes > most {
                return Err(too_large(label, bytes, most));
            }
            Ok(cx.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: bytes,
                usage: wgpu::BufferUsages::STORAGE | extra,
                mapped_at_creation: false,
            }))
        };
        let template: Vec<u32> = list.iter().flat_map(Job::initial_args).collect();
        let copy = wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC;
        let stride = UNIFORM_BYTES.next_multiple_of(u64::from(limits.min_uniform_buffer_offset_alignment));
        let uniforms = (0..crate::resources::FRAMES)
            .map(|_| {
                cx.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("extrusion uniforms"),
                    size: (stride * (slots * list.len()).max(1) as u64),
                    usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                    mapped_at_creation: false,
                })
            })
            .collect();
        let mut jobs = Self {
            args: storage("extrusion arguments", template.len() as u64, wgpu::BufferUsages::INDIRECT | copy)?,
            template: cx.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("extrusion argument template"),
                contents: bytemuck::cast_slice(&template),
                usage: wgpu::BufferUsages::COPY_SRC,
            }),
            uniforms,
            stride,
            slots,
            weights: storage("face weights", weights, wgpu::BufferUsages::empty())?,
            records: storage("side records", records, wgpu::BufferUsages::empty())?,
            caps: storage("cap indices", caps, wgpu::BufferUsages::INDEX)?,
            compute_groups: Vec::new(),
            draw_groups: Vec::new(),
            key,
            list,
            with_caps,
        };
        let turns = 0..jobs.uniforms.len();
        for t in turns {
            let groups = jobs
                .list
                .iter()
                .map(|job| jobs.groups(cx, [compute_layout, draw_layout], &frame.instances[job.instance], t));
            let (compute, draw): (Vec<_>, Vec<_>) = groups.unzip();
            jobs.compute_groups.push(compute);
            jobs.draw_groups.push(draw);
        }
        Ok(jobs)
    }

    /// Byte offset of job `j`'s uniform for light `slot`.
    fn offset(&self, slot: usize, j: usize) -> u64 {
        (slot * self.list.len() + j) as u64 * self.stride
    }

    /// The uniforms of frame turn `turn`, bound at a job's offset.
    fn uniform_binding(&self, turn: usize) -> wgpu::BindingResource<'_> {
        wgpu::BindingResource::Buffer(wgpu::BufferBinding {
            buffer: &self.uniforms[turn],
            offset: 0,
            size: wgpu::BufferSize::new(UNIFORM_BYTES),
        })
    }

    /// Job `inst`'s groups for frame turn `turn`: the compute passes' (the uniform, the mesh's planes,
    /// edges, uses and indices, then the lists they write) and the draws' (the uniform, the welded
    /// positions, the edges and the side records).
    fn groups(
        &self,
        cx: &WgpuContext,
        [compute_layout, draw_layout]: [&wgpu::BindGroupLayout; 2],
        inst: &Instance,
        turn: usize,
    ) -> (wgpu::BindGroup, wgpu::BindGroup) {
        let (Some(adj), Some(mesh)) = (cx.cache.adjacency(inst), cx.cache.mesh(inst)) else {
            unreachable!("a job is made only for an uploaded mesh")
        };
        let group = |label, layout, first: u32, ranges: &[BufferRange<'_>]| {
            let mut entries = vec![wgpu::BindGroupEntry { binding: first, resource: self.uniform_binding(turn) }];
            entries.extend(
                ranges
                    .iter()
                    .zip(first + 1..)
                    .map(|(r, binding)| wgpu::BindGroupEntry { binding, resource: r.binding() }),
            );
            cx.device.create_bind_group(&wgpu::BindGroupDescriptor { label: Some(label), layout, entries: &entries })
        };
        let t = adj.topology;
        let lists = [&self.weights, &self.records, &self.caps, &self.args].map(BufferRange::whole);
        let compute = [adj.planes, t.edges(), t.uses(), BufferRange::whole(mesh.indices)];
        (
            group("extrusion", compute_layout, 0, &[compute, lists].concat()),
            group("extruded volumes", draw_layout, 1, &[adj.welded, t.edges(), BufferRange::whole(&self.records)]),
        )
    }
}

fn too_large(what: &str, bytes: u64, most: u64) -> WgpuError {
    WgpuError::TooLarge { what: what.to_string(), bytes, most }
}

/// Workgroups of 64 invocations covering `items`, spilling into y past `most` along x (the extrusion's
/// and the pose's kernels find their item the same way).
pub(crate) fn groups(items: u32, most: u32) -> (u32, u32) {
    let n = items.div_ceil(WORKGROUP);
    if n <= most { (n, 1) } else { (most, n.div_ceil(most)) }
}

/// The vertex stages of the draws: sides, near caps, far caps.
const STAGES: [&str; 3] = ["vs_side", "vs_near", "vs_far"];

/// The compute passes' group 2: the uniform, the mesh's planes, edges, uses and indices, then the
/// weights, records, caps and arguments they write.
const COMPUTE_BINDINGS: [(u32, Binding); 9] = [
    (0, Binding::Uniform),
    (1, Binding::Read),
    (2, Binding::Read),
    (3, Binding::Read),
    (4, Binding::Read),
    (5, Binding::Write),
    (6, Binding::Write),
    (7, Binding::Write),
    (8, Binding::Write),
];

/// The draws' group 1: the uniform, the welded positions, the edges and the side records.
const DRAW_BINDINGS: [(u32, Binding); 4] =
    [(1, Binding::Uniform), (2, Binding::Read), (3, Binding::Read), (4, Binding::Read)];

#[derive(Clone, Copy)]
enum Binding {
    /// The job's uniform, at a dynamic offset.
    Uniform,
    Read,
    Write,
}

fn layout(
    cx: &WgpuContext,
    label: &str,
    visibility: wgpu::ShaderStages,
    bindings: &[(u32, Binding)],
) -> wgpu::BindGroupLayout {
    let entries: Vec<wgpu::BindGroupLayoutEntry> = bindings
        .iter()
        .map(|&(binding, kind)| {
            let ty = match kind {
                Binding::Uniform => wgpu::BufferBindingType::Uniform,
                Binding::Read => wgpu::BufferBindingType::Storage { read_only: true },
                Binding::Write => wgpu::BufferBindingType::Storage { read_only: false },
            };
            let dynamic = matches!(kind, Binding::Uniform);
            let min_binding_size = if dynamic { wgpu::BufferSize::new(UNIFORM_BYTES) } else { None };
            wgpu::BindGroupLayoutEntry {
                binding,
                visibility,
                ty: wgpu::BindingType::Buffer { ty, has_dynamic_offset: dynamic, min_binding_size },
                count: None,
            }
        })
        .collect();
    cx.pipelines.group_layout(label, &entries)
}

fn compute_pipeline(
    cx: &WgpuContext,
    module: &wgpu::ShaderModule,
    layout: &wgpu::BindGroupLayout,
    entry: &str,
) -> wgpu::ComputePipeline {
    let layout = cx.pipelines.layout("extrusion", &[None, None, Some(layout)]);
    cx.pipelines.compute(&wgpu::ComputePipelineDescriptor {
        label: Some(entry),
        layout: Some(&layout),
        module,
        entry_point: Some(entry),
        compilation_options: Default::default(),
        cache: None,
    })
}

/// A stencil-only pipeline through vertex stage `entry` (sides pull their vertices; caps read the mesh's
/// positions), both faces drawn.
fn draw_pipeline(
    cx: &WgpuContext,
    module: &wgpu::ShaderModule,
    layout: &wgpu::BindGroupLayout,
    entry: &str,
    front_face: wgpu::FrontFace,
    depth_stencil: wgpu::DepthStencilState,
) -> wgpu::RenderPipeline {
    let buffers: &[Option<wgpu::VertexBufferLayout<'_>>] =
        if entry == "vs_side" { &[] } else { &[Some(POSITION_LAYOUT)] };
    let vertex = StencilVertex { module, entry, groups: &[&cx.shared.frame_layout, layout], buffers };
    stencil_pipeline(cx, &vertex, front_face, depth_stencil)
}
