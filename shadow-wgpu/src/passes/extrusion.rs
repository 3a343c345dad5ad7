//! Shadow volumes found and extruded on the GPU (twin: shadow-core's `geometry::silhouette` and
//! `geometry::volume`, which stay the reference; the conformance tests hold the two to the same stencil).
//!
//! Each mesh's adjacency is uploaded once ([`crate::upload::AdjacencyGpu`]). The casting instances of a
//! mesh that wind alike are a run; per light, two compute dispatches per run weigh the faces of all its
//! instances, list their caps and list their silhouette edges (`extrude.wgsl`), and the counting pass
//! then draws the run's lists through four indirect draws whose counts the dispatches wrote, so the host
//! neither sees nor uploads a vertex: its part of a light's build is 32 bytes per instance (the light in
//! its mesh's space) and a handful of commands per mesh, however many instances draw it. Every buffer is
//! made once per set of casting instances and reused: the lists by every light in turn (the GPU runs
//! them in order), the lights in a place per light ([`LightPass::slot`](shadow_core::technique::LightPass)),
//! since a frame recorded into one command buffer sees every write before its first command, and in a
//! buffer per frame that may be in flight, used in turn as the transient buffers are, so a frame's
//! writes never wait for one still reading.

use std::collections::HashMap;

use shadow_core::geometry::volume::{Caps, VolumeCounting};
use shadow_core::light::LightView;
use shadow_core::{FrameInputs, Instance};

use super::volumes::{Query, StencilVertex, count_all, counting_state, occlusion_query, stencil_pipeline};
use crate::context::{WgpuContext, WgpuError};
use crate::gbuffer::GpuGBuffer;
use crate::shaders;
use crate::upload::{BufferRange, BuffersKey};

/// Words of one run's draw arguments (`extrude.wgsl`'s `ARG_*`): the `draw_indirect` arguments of its
/// sides, near caps as wound, near caps turned around and far caps, and the silhouette-edge counter.
const ARG_WORDS: u32 = 17;
const ARG_NEAR_FORWARD: u32 = 4;
const ARG_NEAR_REVERSED: u32 = 8;
const ARG_FAR: u32 = 12;
const ARG_EDGES: u32 = 16;
/// Bytes of `Run` in `extrude.wgsl`.
const RUN_BYTES: u64 = 64;
/// Bytes of `Job` in `extrude.wgsl`.
const JOB_BYTES: u64 = 32;
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
    /// The frame turn whose lights the last build wrote, which its draws read (a build kept for later
    /// frames keeps its turn).
    built_turn: usize,
}

/// What the buffers of a frame's extrusion were made for: each casting instance (in the frame's order)
/// with the key of the buffers it binds and its winding.
type JobsKey = Vec<(usize, BuffersKey, bool)>;

/// The extrusion of every casting instance of a frame, run by run, in the buffers they share.
struct Jobs {
    key: JobsKey,
    /// Each job's instance (its index in the frame), run by run.
    jobs: Vec<usize>,
    runs: Vec<Run>,
    args: wgpu::Buffer,
    /// The arguments every light starts from: no triangles, each list's first vertex.
    template: wgpu::Buffer,
    /// Each run's [`RunRaw`], `run_stride` bytes apart.
    run_uniforms: wgpu::Buffer,
    run_stride: u64,
    /// Per frame turn, every job's [`JobRaw`] for each light slot (slot-major), `light_stride` bytes
    /// apart.
    lights: Vec<wgpu::Buffer>,
    light_stride: u64,
    slots: usize,
    /// Whether `records` has room for every run's caps.
    with_caps: bool,
    weights: wgpu::Buffer,
    /// Side and cap records.
    records: wgpu::Buffer,
    /// Per frame turn, each run's groups.
    compute_groups: Vec<Vec<wgpu::BindGroup>>,
    draw_groups: Vec<Vec<wgpu::BindGroup>>,
}

/// The casting instances of one mesh that wind alike, and their place in the shared buffers.
#[derive(Clone, Copy)]
struct Run {
    /// Its first instance (its index in the frame), whose buffers it binds.
    instance: usize,
    /// Its instances are mirrored: their front faces wind clockwise.
    mirrored: bool,
    first_job: u32,
    jobs: u32,
    faces: u32,
    edges: u32,
    bergeron: bool,
    /// First word of its arguments.
    args: u32,
    /// First side record.
    records: u32,
    /// First face weight.
    weights: u32,
    /// First record of its near caps as wound, turned around, and of its far caps.
    caps: [u32; 3],
}

/// `Run` in `extrude.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct RunRaw {
    counts: [u32; 4],
    bases: [u32; 4],
    caps: [u32; 4],
    unused: [u32; 4],
}

/// `Job` in `extrude.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct JobRaw {
    light: [f32; 4],
    info: [u32; 4],
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
        let order = cx.cache.order();
        let lights: Vec<JobRaw> = jobs
            .jobs
            .iter()
            .map(|&i| JobRaw {
                light: world.transformed(frame.instances[i].local_from_world).homogeneous().to_array(),
                info: [order.slot(i), u32::from(caps == Caps::Both), 0, 0],
            })
            .collect();
        let turn = cx.frame_turn();
        cx.queue.write_buffer(&jobs.lights[turn], jobs.light_offset(slot), bytemuck::cast_slice(&lights));
        self.built_turn = turn;
        let most = cx.device.limits().max_compute_workgroups_per_dimension;
        let mut enc = cx.encoder("shadow-volume extrusion");
        enc.copy_buffer_to_buffer(&jobs.template, 0, &jobs.args, 0, jobs.args.size());
        {
            let mut pass = enc
                .begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some("extrusion"), timestamp_writes: None });
            for (r, run) in jobs.runs.iter().enumerate() {
                pass.set_bind_group(2, &jobs.compute_groups[turn][r], &jobs.offsets(r, slot));
                pass.set_pipeline(&self.faces);
                let (x, y) = groups(run.jobs * run.faces, most);
                pass.dispatch_workgroups(x, y, 1);
                pass.set_pipeline(&self.edges);
                let (x, y) = groups(run.jobs * run.edges, most);
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
        for run in &jobs.runs {
            let w = |k: u32| u64::from(words[(run.args + k) as usize]);
            c.silhouette_edges += w(ARG_EDGES);
            // Every list is counted in vertices: three a triangle.
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
                self.jobs.iter().flat_map(|jobs| jobs.runs.iter().enumerate().map(move |(r, run)| (jobs, r, run)));
            for (jobs, r, run) in jobs {
                let m = run.mirrored;
                let args = |word: u32| u64::from(4 * (run.args + word));
                pass.set_bind_group(1, &jobs.draw_groups[self.built_turn][r], &jobs.offsets(r, slot));
                pass.set_pipeline(pick(0, m));
                pass.draw_indirect(&jobs.args, args(0));
                if !jobs.with_caps {
                    continue;
                }
                // Faces cast turned around are drawn with fronts and backs swapped, not re-wound, so their
                // near caps rasterize exactly as the G-buffer drew them.
                for (stage, cw, word) in [(1, m, ARG_NEAR_FORWARD), (1, !m, ARG_NEAR_REVERSED), (2, m, ARG_FAR)] {
                    pass.set_pipeline(pick(stage, cw));
                    pass.draw_indirect(&jobs.args, args(word));
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

impl Run {
    /// Its uniform.
    fn raw(&self) -> RunRaw {
        RunRaw {
            counts: [self.first_job, self.jobs, self.faces, self.edges],
            bases: [u32::from(self.bergeron), self.args, self.records, self.weights],
            caps: [self.caps[0], self.caps[1], self.caps[2], 0],
            unused: [0; 4],
        }
    }

    /// Its draw arguments before a light's dispatches: no triangles, one instance, each cap list's first
    /// vertex (three a record), no edges counted.
    fn initial_args(&self) -> [u32; ARG_WORDS as usize] {
        let [forward, reversed, far] = self.caps.map(|c| 3 * c);
        [0, 1, 0, 0, 0, 1, forward, 0, 0, 1, reversed, 0, 0, 1, far, 0, 0]
    }
}

impl Jobs {
    /// The buffers in `slot` for `frame`'s casting instances with lights for `slots` lights, and room
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
        let key: JobsKey = frame
            .instances
            .iter()
            .enumerate()
            .filter(|(_, inst)| inst.casts_solid_shadow())
            .map(|(i, inst)| (i, BuffersKey::of(inst), inst.mirrored))
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

    /// Lays the casting instances `key` out in runs in shared buffers, with lights for `slots` lights,
    /// and lists for their caps where `with_caps` asks for them (z-pass draws none: a scene of many
    /// triangles would need room for six words a face it never writes).
    fn new(
        cx: &WgpuContext,
        [compute_layout, draw_layout]: [&wgpu::BindGroupLayout; 2],
        frame: &FrameInputs,
        key: JobsKey,
        slots: usize,
        with_caps: bool,
    ) -> Result<Self, WgpuError> {
        // A job is made only for a mesh whose vertices and adjacency are both uploaded: the groups
        // below bind them.
        let uploaded = |i: usize| {
            cx.cache.adjacency(&frame.instances[i]).is_some() && cx.cache.mesh(&frame.instances[i]).is_some()
        };
        let mut members: Vec<Vec<usize>> = Vec::new();
        let mut run_of: HashMap<(BuffersKey, bool), usize> = HashMap::new();
        for &(i, buffers, mirrored) in key.iter().filter(|&&(i, _, _)| uploaded(i)) {
            let r = *run_of.entry((buffers, mirrored)).or_insert_with(|| {
                members.push(Vec::new());
                members.len() - 1
            });
            members[r].push(i);
        }
        let at = |n: u64| u32::try_from(n).map_err(|_| too_large("the extrusion's lists", 8 * n, u64::MAX));
        let (mut runs, mut records, mut weights) = (Vec::with_capacity(members.len()), 0u64, 0u64);
        let mut first_job = 0u64;
        for run in &members {
            let inst = &frame.instances[run[0]];
            let Some(adj) = cx.cache.adjacency(inst) else { unreachable!("kept only when uploaded") };
            let t = adj.topology;
            let jobs = run.len() as u64;
            let faces = jobs * u64::from(t.faces);
            at(jobs * u64::from(t.edge_count))?;
            runs.push(Run {
                instance: run[0],
                mirrored: inst.mirrored,
                first_job: at(first_job)?,
                jobs: at(jobs)?,
                faces: t.faces,
                edges: t.edge_count,
                bergeron: !t.closed,
                args: at(runs.len() as u64 * u64::from(ARG_WORDS))?,
                records: at(records)?,
                weights: at(weights)?,
                caps: [0; 3],
            });
            first_job += jobs;
            records += jobs * u64::from(t.use_count);
            weights += faces;
        }
        if with_caps {
            for run in &mut runs {
                let faces = u64::from(run.jobs) * u64::from(run.faces);
                run.caps = [at(records)?, at(records + faces)?, at(records + 2 * faces)?];
                at(3 * (records + 3 * faces))?;
                records += 3 * faces;
            }
        }
        let limits = cx.device.limits();
        let most = limits.max_storage_buffer_binding_size.min(limits.max_buffer_size);
        let storage = |label: &'static str, bytes: u64, extra: wgpu::BufferUsages| {
            let bytes = bytes.max(16);
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
        let template: Vec<u32> = runs.iter().flat_map(Run::initial_args).collect();
        let copy = wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC;
        let run_stride = RUN_BYTES.next_multiple_of(u64::from(limits.min_uniform_buffer_offset_alignment));
        let mut run_bytes = vec![0u8; (run_stride * runs.len().max(1) as u64) as usize];
        for (r, run) in runs.iter().enumerate() {
            let at = r * run_stride as usize;
            run_bytes[at..at + RUN_BYTES as usize].copy_from_slice(bytemuck::bytes_of(&run.raw()));
        }
        let job_count = first_job.max(1);
        let light_stride =
            (JOB_BYTES * job_count).next_multiple_of(u64::from(limits.min_storage_buffer_offset_alignment));
        if light_stride > most {
            return Err(too_large("the extrusion's lights", light_stride, most));
        }
        let lights = (0..crate::resources::FRAMES)
            .map(|_| {
                cx.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("extrusion lights"),
                    size: light_stride * slots as u64,
                    usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
                    mapped_at_creation: false,
                })
            })
            .collect();
        let mut jobs = Self {
            args: storage("extrusion arguments", 4 * template.len() as u64, wgpu::BufferUsages::INDIRECT | copy)?,
            template: cx.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("extrusion argument template"),
                contents: bytemuck::cast_slice(&template),
                usage: wgpu::BufferUsages::COPY_SRC,
            }),
            run_uniforms: cx.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("extrusion runs"),
                contents: &run_bytes,
                usage: wgpu::BufferUsages::UNIFORM,
            }),
            run_stride,
            lights,
            light_stride,
            slots,
            weights: storage("face weights", 4 * weights, wgpu::BufferUsages::empty())?,
            records: storage("extrusion records", 8 * records, wgpu::BufferUsages::empty())?,
            compute_groups: Vec::new(),
            draw_groups: Vec::new(),
            jobs: members.concat(),
            runs,
            key,
            with_caps,
        };
        for t in 0..jobs.lights.len() {
            let groups = jobs
                .runs
                .iter()
                .map(|run| jobs.groups(cx, [compute_layout, draw_layout], &frame.instances[run.instance], t));
            let (compute, draw): (Vec<_>, Vec<_>) = groups.unzip();
            jobs.compute_groups.push(compute);
            jobs.draw_groups.push(draw);
        }
        Ok(jobs)
    }

    /// The dynamic offsets of run `r`'s groups for light `slot`: its uniform, then the light's jobs.
    fn offsets(&self, r: usize, slot: usize) -> [u32; 2] {
        [r as u64 * self.run_stride, self.light_offset(slot)].map(|o| o as u32)
    }

    /// Byte offset of light `slot`'s jobs.
    fn light_offset(&self, slot: usize) -> u64 {
        slot as u64 * self.light_stride
    }

    /// The run's groups for frame turn `turn`, through the buffers of `inst`, its first instance: the
    /// compute passes' (the run, the lights, the mesh's planes, edges, uses and indices, then the lists
    /// they write) and the draws' (the run, the lights, the welded positions, the edges, the records, the
    /// mesh's positions and indices).
    fn groups(
        &self,
        cx: &WgpuContext,
        [compute_layout, draw_layout]: [&wgpu::BindGroupLayout; 2],
        inst: &Instance,
        turn: usize,
    ) -> (wgpu::BindGroup, wgpu::BindGroup) {
        let (Some(adj), Some(mesh)) = (cx.cache.adjacency(inst), cx.cache.mesh(inst)) else {
            unreachable!("a run is made only for an uploaded mesh")
        };
        let group = |label, layout, first: u32, ranges: &[BufferRange<'_>]| {
            let run =
                wgpu::BufferBinding { buffer: &self.run_uniforms, offset: 0, size: wgpu::BufferSize::new(RUN_BYTES) };
            let lights = wgpu::BufferBinding {
                buffer: &self.lights[turn],
                offset: 0,
                size: wgpu::BufferSize::new(JOB_BYTES * self.jobs.len().max(1) as u64),
            };
            let mut entries = vec![
                wgpu::BindGroupEntry { binding: first, resource: wgpu::BindingResource::Buffer(run) },
                wgpu::BindGroupEntry { binding: first + 1, resource: wgpu::BindingResource::Buffer(lights) },
            ];
            entries.extend(
                ranges
                    .iter()
                    .zip(first + 2..)
                    .map(|(r, binding)| wgpu::BindGroupEntry { binding, resource: r.binding() }),
            );
            cx.device.create_bind_group(&wgpu::BindGroupDescriptor { label: Some(label), layout, entries: &entries })
        };
        let t = adj.topology;
        let [weights, records, args] = [&self.weights, &self.records, &self.args].map(BufferRange::whole);
        let indices = BufferRange::whole(mesh.indices);
        let compute = [adj.planes, t.edges(), t.uses(), indices, weights, records, args];
        let draw = [adj.welded, t.edges(), records, BufferRange::whole(mesh.positions), indices];
        (group("extrusion", compute_layout, 0, &compute), group("extruded volumes", draw_layout, 1, &draw))
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

/// The compute passes' group 2: the run, the lights, the mesh's planes, edges, uses and indices, then
/// the weights, records and arguments they write.
const COMPUTE_BINDINGS: [(u32, Binding); 9] = [
    (0, Binding::Run),
    (1, Binding::Lights),
    (2, Binding::Read),
    (3, Binding::Read),
    (4, Binding::Read),
    (5, Binding::Read),
    (6, Binding::Write),
    (7, Binding::Write),
    (8, Binding::Write),
];

/// The draws' group 1: the run, the lights, the welded positions, the edges, the records, the mesh's
/// positions and indices.
const DRAW_BINDINGS: [(u32, Binding); 7] = [
    (1, Binding::Run),
    (2, Binding::Lights),
    (3, Binding::Read),
    (4, Binding::Read),
    (5, Binding::Read),
    (6, Binding::Read),
    (7, Binding::Read),
];

#[derive(Clone, Copy)]
enum Binding {
    /// The run's uniform, at a dynamic offset.
    Run,
    /// The jobs of a light, at a dynamic offset.
    Lights,
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
                Binding::Run => wgpu::BufferBindingType::Uniform,
                Binding::Lights | Binding::Read => wgpu::BufferBindingType::Storage { read_only: true },
                Binding::Write => wgpu::BufferBindingType::Storage { read_only: false },
            };
            let (dynamic, min_binding_size) = match kind {
                Binding::Run => (true, wgpu::BufferSize::new(RUN_BYTES)),
                Binding::Lights => (true, wgpu::BufferSize::new(JOB_BYTES)),
                Binding::Read | Binding::Write => (false, None),
            };
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

/// A stencil-only pipeline through vertex stage `entry` (every stage pulls its vertices), both faces
/// drawn.
fn draw_pipeline(
    cx: &WgpuContext,
    module: &wgpu::ShaderModule,
    layout: &wgpu::BindGroupLayout,
    entry: &str,
    front_face: wgpu::FrontFace,
    depth_stencil: wgpu::DepthStencilState,
) -> wgpu::RenderPipeline {
    let vertex = StencilVertex { module, entry, groups: &[&cx.shared.frame_layout, layout], buffers: &[] };
    stencil_pipeline(cx, &vertex, front_face, depth_stencil)
}
