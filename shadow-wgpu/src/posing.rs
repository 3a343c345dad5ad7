//! Skinned and morphed meshes posed on the GPU (twin: shadow-core's `deform::pose` and
//! `Adjacency::posed`; `pose.wgsl`).
//!
//! A deformed mesh's rest data (skin weights, morph targets, and the weld and welded faces of its
//! adjacency) is uploaded once per mesh version, beside the rest mesh itself. Each node that draws it
//! posed has buffers of its own, made once: posed positions and normals, which the G-buffer and every
//! light pass draw in place of the rest mesh's, and posed welded positions and face planes, which the
//! extrusion reads in place of the rest adjacency's. Whenever a node's pose changes, its joint matrices
//! and morph weights (a few hundred bytes) are written and three dispatches pose it: once a frame, before
//! the first pass that reads it, however many passes do. Nodes share nothing they write, so two nodes
//! drawing one mesh in two poses both keep theirs.

use std::collections::HashMap;

use bytemuck::{Pod, Zeroable};
use shadow_core::deform::Deformers;
use shadow_core::scene::Pose;
use shadow_core::{Instance, MeshKey, NodeKey};

use crate::context::{WgpuContext, WgpuError};
use crate::passes::extrusion::groups;
use crate::shaders;

/// `Shape` in `pose.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable, PartialEq)]
struct Shape {
    /// Vertices, morph targets, joints (0 when not skinned), welded vertices.
    counts: [u32; 4],
    /// Faces.
    faces: [u32; 4],
}

/// A deformed mesh's rest data the pose reads (beside the rest mesh's positions and normals).
struct DeformGpu {
    version: u64,
    /// Per vertex its four joints and their weights (`SkinVertex`).
    skin: wgpu::Buffer,
    /// Per target and vertex its displacements of position and normal (`TargetVertex`), target-major.
    targets: wgpu::Buffer,
    target_count: u32,
    /// Per welded vertex, the last mesh vertex welded to it (whose posed position it takes, as the
    /// CPU's posed adjacency does).
    weld: wgpu::Buffer,
    /// Per face its welded corners (`vec4<u32>`).
    faces: wgpu::Buffer,
}

/// One node's posed mesh.
pub(crate) struct PosedGpu {
    /// The rest mesh it poses and that mesh's version.
    mesh: MeshKey,
    rest_version: u64,
    /// The pose it holds ([`Instance::mesh_version`]); `None` until the first is computed.
    version: Option<u64>,
    /// Posed positions (w = 1) and normals, `vec4<f32>` a vertex: vertex and storage buffers.
    pub positions: wgpu::Buffer,
    pub normals: wgpu::Buffer,
    /// Posed welded positions and face planes, as `AdjacencyGpu` has them.
    pub welded: wgpu::Buffer,
    pub planes: wgpu::Buffer,
    shape: Shape,
    /// Per frame turn, the pose's joint matrices and morph weights, and the group that binds them.
    pose: Vec<wgpu::Buffer>,
    pose_groups: Vec<wgpu::BindGroup>,
    weld_group: wgpu::BindGroup,
}

/// The pose's pipelines and the layouts of its two groups.
struct Pipelines {
    pose: wgpu::ComputePipeline,
    weld: wgpu::ComputePipeline,
    planes: wgpu::ComputePipeline,
    pose_layout: wgpu::BindGroupLayout,
    weld_layout: wgpu::BindGroupLayout,
}

/// Every deformed mesh's rest data and every posed node's buffers.
#[derive(Default)]
pub(crate) struct Posing {
    pipelines: Option<Pipelines>,
    deform: HashMap<MeshKey, DeformGpu>,
    posed: HashMap<NodeKey, PosedGpu>,
}

impl Posing {
    /// The buffers of `inst`'s pose, where it is posed and they are made.
    pub fn posed(&self, inst: &Instance) -> Option<&PosedGpu> {
        let pose = inst.pose.as_ref()?;
        self.posed.get(&inst.node).filter(|p| p.mesh == inst.mesh_key && p.rest_version == pose.rest_version)
    }

    /// Poses every posed instance of `instances` whose pose its buffers do not hold yet, recording the
    /// dispatches into the frame's encoder; `rest` gives each rest mesh's uploaded positions and normals.
    pub fn pose<'a>(
        &mut self,
        cx: &WgpuContext,
        instances: &[Instance],
        rest: impl Fn(MeshKey) -> Option<(&'a wgpu::Buffer, &'a wgpu::Buffer)>,
    ) {
        let stale: Vec<(&Instance, &Pose)> = instances
            .iter()
            .filter_map(|i| Some((i, i.pose.as_deref()?)))
            .filter(|(i, _)| self.posed(i).is_none_or(|p| p.version != Some(i.mesh_version)))
            .collect();
        if stale.is_empty() {
            return;
        }
        let pipelines = self.pipelines.get_or_insert_with(|| Pipelines::new(cx));
        let turn = cx.frame_turn();
        let mut jobs = Vec::with_capacity(stale.len());
        for (inst, pose) in stale {
            let Some(deformers) = pose.rest.deformers() else { continue };
            let Some((rest_positions, rest_normals)) = rest(inst.mesh_key) else { continue };
            if self.deform.get(&inst.mesh_key).is_none_or(|d| d.version != pose.rest_version) {
                self.deform.insert(inst.mesh_key, DeformGpu::upload(cx, pose, deformers));
            }
            let Some(deform) = self.deform.get(&inst.mesh_key) else { continue };
            let shape = Shape::of(pose, deform);
            let fits =
                |p: &PosedGpu| p.mesh == inst.mesh_key && p.rest_version == pose.rest_version && p.shape == shape;
            if !self.posed.get(&inst.node).is_some_and(fits) {
                let made = PosedGpu::new(cx, pipelines, inst.mesh_key, shape, deform, [rest_positions, rest_normals]);
                self.posed.insert(inst.node, made);
            }
            let Some(posed) = self.posed.get_mut(&inst.node) else { continue };
            cx.queue.write_buffer(&posed.pose[turn], 0, &pose_words(pose, shape));
            posed.version = Some(inst.mesh_version);
            jobs.push(inst.node);
        }
        let most = cx.device.limits().max_compute_workgroups_per_dimension;
        let mut enc = cx.encoder("posing");
        {
            let mut pass =
                enc.begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some("posing"), timestamp_writes: None });
            for node in jobs {
                let Some(posed) = self.posed.get(&node) else { continue };
                let [vertices, _, _, welded] = posed.shape.counts;
                pass.set_bind_group(0, &posed.pose_groups[turn], &[]);
                pass.set_pipeline(&pipelines.pose);
                let (x, y) = groups(vertices, most);
                pass.dispatch_workgroups(x, y, 1);
                pass.set_bind_group(1, &posed.weld_group, &[]);
                pass.set_pipeline(&pipelines.weld);
                let (x, y) = groups(welded, most);
                pass.dispatch_workgroups(x, y, 1);
                pass.set_pipeline(&pipelines.planes);
                let (x, y) = groups(posed.shape.faces[0], most);
                pass.dispatch_workgroups(x, y, 1);
            }
        }
        cx.submit(enc);
    }
}

/// What the GPU posed for one instance, read back: positions, normals, welded positions and face planes.
#[derive(Clone, Debug, PartialEq)]
pub struct PosedVertices {
    /// Posed positions, in the mesh's posed space (world space for a skinned mesh).
    pub positions: Vec<glam::Vec3>,
    /// Posed unit normals (zero where the pose collapses one).
    pub normals: Vec<glam::Vec3>,
    /// Posed welded positions, as the extrusion reads them.
    pub welded: Vec<glam::Vec3>,
    /// Face planes over the welded positions, as the extrusion reads them.
    pub planes: Vec<glam::Vec4>,
}

impl WgpuContext {
    /// Reads back what the GPU posed for `inst` (after [`WgpuContext::upload_meshes`] with its frame), to
    /// hold against the CPU's pose; `None` for an instance that is not posed.
    ///
    /// # Errors
    /// A GPU failure, or [`WgpuError::NotRecordable`] inside a frame recorded into a host's encoder.
    pub fn read_posed(&self, inst: &Instance) -> Result<Option<PosedVertices>, WgpuError> {
        let Some(posed) = self.cache.posing.posed(inst) else { return Ok(None) };
        let [vertices, _, _, welded] = posed.shape.counts;
        let read = |buffer: &wgpu::Buffer, n: u32| -> Result<Vec<glam::Vec4>, WgpuError> {
            let bytes = crate::readback::read_buffer(self, buffer, "reading a posed mesh back")?;
            let all: &[[f32; 4]] = bytemuck::cast_slice(&bytes);
            Ok(all.iter().take(n as usize).map(|&v| glam::Vec4::from_array(v)).collect())
        };
        let xyz = |v: Vec<glam::Vec4>| v.into_iter().map(glam::Vec4::truncate).collect();
        Ok(Some(PosedVertices {
            positions: xyz(read(&posed.positions, vertices)?),
            normals: xyz(read(&posed.normals, vertices)?),
            welded: xyz(read(&posed.welded, welded)?),
            planes: read(&posed.planes, posed.shape.faces[0])?,
        }))
    }
}

impl Shape {
    fn of(pose: &Pose, deform: &DeformGpu) -> Self {
        let joints = pose.joint_matrices.as_ref().map_or(0, Vec::len) as u32;
        let adjacency = &pose.rest_adjacency;
        Self {
            counts: [
                pose.rest.positions().len() as u32,
                deform.target_count,
                joints,
                adjacency.positions().len() as u32,
            ],
            faces: [adjacency.triangles().len() as u32, 0, 0, 0],
        }
    }
}

/// The pose's words: each joint matrix's columns, then the morph weights padded with zeros to a
/// whole `vec4` per four targets (a weight the node lacks counts as zero).
fn pose_words(pose: &Pose, shape: Shape) -> Vec<u8> {
    let [_, targets, joints, _] = shape.counts;
    let mut words: Vec<f32> = Vec::with_capacity(16 * joints as usize + targets.next_multiple_of(4) as usize);
    for m in pose.joint_matrices.iter().flatten() {
        words.extend(m.to_cols_array());
    }
    let weights = pose.weights.iter().copied().chain(std::iter::repeat(0.0));
    words.extend(weights.take(targets.next_multiple_of(4).max(4) as usize));
    bytemuck::cast_slice(&words).to_vec()
}

impl DeformGpu {
    fn upload(cx: &WgpuContext, pose: &Pose, deformers: &Deformers) -> Self {
        let vertices = pose.rest.positions().len();
        let skin: Vec<[u32; 8]> = match &deformers.skin {
            Some(s) => s
                .joints()
                .iter()
                .zip(s.weights())
                .map(|(j, w)| {
                    let [a, b, c, d] = j.map(u32::from);
                    let [x, y, z, u] = w.map(f32::to_bits);
                    [a, b, c, d, x, y, z, u]
                })
                .collect(),
            None => Vec::new(),
        };
        let mut targets: Vec<[f32; 8]> = Vec::with_capacity(deformers.morph_targets.len() * vertices);
        for t in &deformers.morph_targets {
            for (v, p) in t.positions.iter().enumerate() {
                let n = t.normals.as_ref().map_or(glam::Vec3::ZERO, |n| n[v]);
                targets.push([p.x, p.y, p.z, 0.0, n.x, n.y, n.z, 0.0]);
            }
        }
        let adjacency = &pose.rest_adjacency;
        let mut weld = vec![0u32; adjacency.positions().len()];
        for (v, &w) in adjacency.remap().iter().enumerate() {
            weld[w as usize] = v as u32;
        }
        let faces: Vec<[u32; 4]> = adjacency.triangles().iter().map(|&[a, b, c]| [a, b, c, 0]).collect();
        Self {
            version: pose.rest_version,
            skin: storage(cx, "skin weights", bytemuck::cast_slice(&skin)),
            targets: storage(cx, "morph targets", bytemuck::cast_slice(&targets)),
            target_count: deformers.morph_targets.len() as u32,
            weld: storage(cx, "weld", bytemuck::cast_slice(&weld)),
            faces: storage(cx, "welded faces", bytemuck::cast_slice(&faces)),
        }
    }
}

/// A read-only storage buffer of `contents` (where there are none, zeros enough for one element of the
/// largest array: bindings may not be smaller than one).
fn storage(cx: &WgpuContext, label: &str, contents: &[u8]) -> wgpu::Buffer {
    let padded = [0u8; 32];
    cx.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some(label),
        contents: if contents.is_empty() { &padded } else { contents },
        usage: wgpu::BufferUsages::STORAGE,
    })
}

impl PosedGpu {
    fn new(
        cx: &WgpuContext,
        pipelines: &Pipelines,
        mesh: MeshKey,
        shape: Shape,
        deform: &DeformGpu,
        [rest_positions, rest_normals]: [&wgpu::Buffer; 2],
    ) -> Self {
        let [vertices, targets, joints, welded] = shape.counts;
        let out = |label, items: u32, usage| {
            cx.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: 16 * u64::from(items.max(1)),
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC | usage,
                mapped_at_creation: false,
            })
        };
        let positions = out("posed positions", vertices, wgpu::BufferUsages::VERTEX);
        let normals = out("posed normals", vertices, wgpu::BufferUsages::VERTEX);
        let welded = out("posed welded positions", welded, wgpu::BufferUsages::empty());
        let planes = out("posed face planes", shape.faces[0], wgpu::BufferUsages::empty());
        let shape_buffer = cx.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("pose shape"),
            contents: bytemuck::bytes_of(&shape),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let pose_bytes = 4 * (16 * u64::from(joints) + u64::from(targets.next_multiple_of(4).max(4)));
        let pose_buffers: Vec<wgpu::Buffer> = (0..crate::resources::FRAMES)
            .map(|_| {
                cx.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("pose"),
                    size: pose_bytes,
                    usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
                    mapped_at_creation: false,
                })
            })
            .collect();
        let group = |label, layout, buffers: &[&wgpu::Buffer]| {
            let entries: Vec<wgpu::BindGroupEntry<'_>> = buffers
                .iter()
                .zip(0..)
                .map(|(b, binding)| wgpu::BindGroupEntry { binding, resource: b.as_entire_binding() })
                .collect();
            cx.device.create_bind_group(&wgpu::BindGroupDescriptor { label: Some(label), layout, entries: &entries })
        };
        let pose_groups = pose_buffers
            .iter()
            .map(|p| {
                let inputs = [&shape_buffer, rest_positions, rest_normals, &deform.skin, &deform.targets, p];
                let all: Vec<&wgpu::Buffer> = inputs.into_iter().chain([&positions, &normals]).collect();
                group("pose", &pipelines.pose_layout, &all)
            })
            .collect();
        let weld_group = group(
            "posed adjacency",
            &pipelines.weld_layout,
            &[&shape_buffer, &positions, &deform.weld, &deform.faces, &welded, &planes],
        );
        Self {
            mesh,
            rest_version: deform.version,
            version: None,
            positions,
            normals,
            welded,
            planes,
            shape,
            pose: pose_buffers,
            pose_groups,
            weld_group,
        }
    }
}

impl Pipelines {
    fn new(cx: &WgpuContext) -> Self {
        let module = cx.pipelines.module("pose", shaders::pose());
        let entry = |binding, ty| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Buffer { ty, has_dynamic_offset: false, min_binding_size: None },
            count: None,
        };
        let layout = |label, writes: u32, reads: u32| {
            let read = wgpu::BufferBindingType::Storage { read_only: true };
            let write = wgpu::BufferBindingType::Storage { read_only: false };
            let mut entries = vec![entry(0, wgpu::BufferBindingType::Uniform)];
            entries.extend((1..=reads).map(|b| entry(b, read)));
            entries.extend((reads + 1..=reads + writes).map(|b| entry(b, write)));
            cx.pipelines.group_layout(label, &entries)
        };
        let pose_layout = layout("pose", 2, 5);
        let weld_layout = layout("posed adjacency", 2, 3);
        let pipeline = |entry: &str, groups: &[Option<&wgpu::BindGroupLayout>]| {
            let layout = cx.pipelines.layout(entry, groups);
            cx.pipelines.compute(&wgpu::ComputePipelineDescriptor {
                label: Some(entry),
                layout: Some(&layout),
                module: &module,
                entry_point: Some(entry),
                compilation_options: Default::default(),
                cache: None,
            })
        };
        Self {
            pose: pipeline("cs_pose", &[Some(&pose_layout)]),
            weld: pipeline("cs_weld", &[None, Some(&weld_layout)]),
            planes: pipeline("cs_planes", &[None, Some(&weld_layout)]),
            pose_layout,
            weld_layout,
        }
    }
}
