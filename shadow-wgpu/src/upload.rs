//! Scene upload, cached: vertex and index buffers per [`MeshKey`] (refreshed when the mesh's version
//! changes), the adjacency the GPU's shadow-volume extrusion reads (per mesh, on first use, the meshes
//! that arrive together sharing buffers: see [`SceneCache::upload_adjacency`]), skinned and
//! morphed meshes posed per node ([`crate::posing`]), the materials' textures ([`crate::textures`]), and
//! the per-instance data of a frame (rewritten in place when an instance changes, made anew only when
//! their number does).
//!
//! Passes reach an instance's buffers through [`SceneCache::mesh`] and [`SceneCache::adjacency`], which
//! hand a posed instance its node's posed positions, normals, welded positions and planes beside its
//! rest mesh's indices, texture coordinates and topology.

use std::collections::HashMap;

use bytemuck::{Pod, Zeroable};
use glam::Mat4;
use shadow_core::geometry::adjacency::{Adjacency, FaceUse};
use shadow_core::{FrameInputs, Instance, MeshKey, NodeKey};

use crate::context::{WgpuContext, WgpuError};
use crate::draw_order::DrawOrder;
use crate::posing::Posing;
use crate::textures::{DeviceTextures, TexelRuleRaw, read_texture};

/// A mesh on the GPU.
pub struct MeshGpu {
    version: u64,
    /// Homogeneous positions (w = 1), one `vec4<f32>` per vertex.
    pub positions: wgpu::Buffer,
    /// Normals, one `vec4<f32>` per vertex.
    pub normals: wgpu::Buffer,
    /// Texture coordinates, one `vec2<f32>` per vertex, where the mesh has them.
    pub uvs: Option<wgpu::Buffer>,
    /// Triangle indices (also bound as storage: the extrusion copies casting faces' indices into its cap
    /// lists).
    pub indices: wgpu::Buffer,
    /// Number of indices.
    pub index_count: u32,
}

/// An instance's mesh as the passes draw it: its positions and normals (its node's posed ones for a
/// posed instance), texture coordinates and indices.
#[derive(Clone, Copy)]
pub struct MeshView<'a> {
    /// Homogeneous positions (w = 1), one `vec4<f32>` per vertex.
    pub positions: &'a wgpu::Buffer,
    /// Normals, one `vec4<f32>` per vertex.
    pub normals: &'a wgpu::Buffer,
    /// Texture coordinates, one `vec2<f32>` per vertex, where the mesh has them.
    pub uvs: Option<&'a wgpu::Buffer>,
    /// Triangle indices (index and storage usage).
    pub indices: &'a wgpu::Buffer,
    /// Number of indices.
    pub index_count: u32,
}

/// An instance's adjacency as the extrusion reads it: the welded positions and face planes (its node's
/// posed ones for a posed instance) and the mesh's topology ([`AdjacencyGpu`]).
#[derive(Clone, Copy)]
pub struct AdjacencyView<'a> {
    /// Welded positions, `vec4<f32>` with w = 1.
    pub welded: BufferRange<'a>,
    /// Per face, its plane `(n, d)` (`vec4<f32>`).
    pub planes: BufferRange<'a>,
    /// The rest of it: edges, uses and counts.
    pub topology: &'a AdjacencyGpu,
}

/// What identifies the buffers an instance is drawn from: its mesh and that mesh's version, and for a
/// posed instance its node (whose posed buffers it reads) with its rest mesh's version. Equal keys, equal
/// buffers: a pass that binds them may keep its bind groups while the key holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct BuffersKey {
    mesh: MeshKey,
    version: u64,
    posed: Option<NodeKey>,
}

impl BuffersKey {
    /// The key of `inst`'s buffers.
    #[must_use]
    pub fn of(inst: &Instance) -> Self {
        match &inst.pose {
            Some(pose) => Self { mesh: inst.mesh_key, version: pose.rest_version, posed: Some(inst.node) },
            None => Self { mesh: inst.mesh_key, version: inst.mesh_version, posed: None },
        }
    }
}

/// GPU twin of `Instance` in common.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub struct InstanceRaw {
    world_from_local: [[f32; 4]; 4],
    normal_from_local: [[f32; 4]; 4],
    color: [f32; 4],
    flags: [u32; 4],
    texel: TexelRuleRaw,
}

impl InstanceRaw {
    /// The instance `index` of its frame.
    fn of(inst: &shadow_core::Instance, index: usize) -> Self {
        let n = Mat4::from_mat3(shadow_core::affine::normal_matrix(inst.world_from_local));
        let texel = read_texture(inst).and_then(|_| TexelRuleRaw::of(&inst.material)).unwrap_or_default();
        Self {
            world_from_local: inst.world_from_local.to_cols_array_2d(),
            normal_from_local: n.to_cols_array_2d(),
            color: inst.base_color.extend(if inst.two_sided { 1.0 } else { 0.0 }).to_array(),
            flags: [u32::from(inst.receives_shadow), u32::from(inst.mirrored), index as u32, 0],
            texel,
        }
    }
}

/// A range of a buffer, to bind as storage: an array of one mesh in a buffer that many share, or the
/// whole of a buffer of its own.
#[derive(Clone, Copy, Debug)]
pub struct BufferRange<'a> {
    /// The buffer.
    pub buffer: &'a wgpu::Buffer,
    /// Where the range starts (a multiple of the device's storage offset alignment).
    pub offset: u64,
    /// Its length in bytes.
    pub size: u64,
}

impl<'a> BufferRange<'a> {
    /// All of `buffer`.
    #[must_use]
    pub fn whole(buffer: &'a wgpu::Buffer) -> Self {
        Self { buffer, offset: 0, size: buffer.size() }
    }

    /// The range as a binding.
    #[must_use]
    pub fn binding(self) -> wgpu::BindingResource<'a> {
        wgpu::BindingResource::Buffer(wgpu::BufferBinding {
            buffer: self.buffer,
            offset: self.offset,
            size: wgpu::BufferSize::new(self.size),
        })
    }
}

/// One array of a mesh's adjacency: where it lies in a buffer the meshes uploaded with it share.
struct Shared {
    buffer: wgpu::Buffer,
    offset: u64,
    size: u64,
}

impl Shared {
    fn range(&self) -> BufferRange<'_> {
        BufferRange { buffer: &self.buffer, offset: self.offset, size: self.size }
    }
}

/// A mesh's adjacency on the GPU, as the shadow-volume extrusion reads it (twin: shadow-core's
/// `Adjacency`).
pub struct AdjacencyGpu {
    version: u64,
    /// Welded positions, `vec4<f32>` with w = 1; per face, its plane `(n, d)` as the adjacency scaled it
    /// (`vec4<f32>`); per edge `(a, b, first use, uses)`, `vec4<u32>`: its welded vertices (a < b) and
    /// its run of uses (manifold edges first, then boundary edges, then the rest, as the CPU's
    /// silhouette reads them); the faces' uses of the edges, `face << 1 | reversed` (shadow-core's
    /// `FaceUse`).
    arrays: [Shared; 4],
    /// Number of faces.
    pub faces: u32,
    /// Number of edges.
    pub edge_count: u32,
    /// Number of uses: the most side quads one light can make of the mesh (an edge's weight is at most
    /// its number of uses).
    pub use_count: u32,
    /// Whether the mesh is closed: only lit faces cast, or else every face turned to the light (Bergeron).
    pub closed: bool,
}

impl AdjacencyGpu {
    /// Per face, its plane.
    #[must_use]
    pub fn planes(&self) -> BufferRange<'_> {
        self.arrays[1].range()
    }

    /// Per edge, its welded vertices and its run of uses.
    #[must_use]
    pub fn edges(&self) -> BufferRange<'_> {
        self.arrays[2].range()
    }

    /// The faces' uses of the edges.
    #[must_use]
    pub fn uses(&self) -> BufferRange<'_> {
        self.arrays[3].range()
    }
}

/// A mesh's adjacency as the GPU reads it, on its way to a shared buffer: its four arrays (welded
/// positions, planes, edges, uses), its counts and whether it is closed.
struct Arrays {
    key: MeshKey,
    version: u64,
    arrays: [Vec<u8>; 4],
    counts: [u32; 3],
    closed: bool,
}

impl Arrays {
    fn of(key: MeshKey, version: u64, adj: &Adjacency) -> Self {
        let welded: Vec<[f32; 4]> = adj.positions().iter().map(|p| p.extend(1.0).to_array()).collect();
        let planes: Vec<[f32; 4]> = adj.planes().iter().map(|p| p.to_array()).collect();
        let mut edges: Vec<[u32; 4]> = Vec::with_capacity(adj.edge_count());
        let mut uses: Vec<u32> = Vec::with_capacity(2 * adj.edge_count());
        let mut push = |v: [u32; 2], faces: &mut dyn Iterator<Item = FaceUse>| {
            let first = uses.len() as u32;
            uses.extend(faces.map(|u| u.face() << 1 | u32::from(u.reversed())));
            edges.push([v[0], v[1], first, uses.len() as u32 - first]);
        };
        for (e, &[fwd, rev]) in adj.manifold_edges().iter().zip(adj.manifold_faces()) {
            push(e.v, &mut [FaceUse::new(fwd, false), FaceUse::new(rev, true)].into_iter());
        }
        for (e, &u) in adj.boundary_edges().iter().zip(adj.boundary_faces()) {
            push(e.v, &mut std::iter::once(u));
        }
        for e in adj.complex_edges() {
            push(e.v, &mut e.uses.iter().copied());
        }
        let counts = [planes.len() as u32, edges.len() as u32, uses.len() as u32];
        let bytes = |words: &[u8]| words.to_vec();
        let arrays = [
            bytes(bytemuck::cast_slice(&welded)),
            bytes(bytemuck::cast_slice(&planes)),
            bytes(bytemuck::cast_slice(&edges)),
            bytes(bytemuck::cast_slice(&uses)),
        ];
        Self { key, version, arrays, counts, closed: adj.closed() }
    }

    /// An array's length as bound: storage bindings may not be empty, so an empty array (a mesh
    /// without edges) still takes four words.
    fn bound(array: &[u8]) -> u64 {
        (array.len() as u64).max(16)
    }

    /// The bytes its arrays take in a shared buffer, each at an offset a multiple of `align`.
    fn bytes(&self, align: u64) -> u64 {
        self.arrays.iter().map(|a| Self::bound(a).next_multiple_of(align)).sum()
    }

    /// Its arrays each in a buffer of its own (a large mesh's, each as large as a binding may be).
    fn upload_alone(self, cx: &WgpuContext) -> AdjacencyGpu {
        let arrays = self.arrays.map(|array| {
            let size = Self::bound(&array);
            let mut contents = array;
            contents.resize(size as usize, 0);
            let buffer = cx.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("adjacency"),
                contents: &contents,
                usage: wgpu::BufferUsages::STORAGE,
            });
            Shared { buffer, offset: 0, size }
        });
        let [faces, edge_count, use_count] = self.counts;
        AdjacencyGpu { version: self.version, arrays, faces, edge_count, use_count, closed: self.closed }
    }

    /// `group`'s arrays in one buffer of `bytes`, one after another at offsets a multiple of `align`.
    fn upload(cx: &WgpuContext, group: Vec<Self>, bytes: u64, align: u64) -> Vec<(MeshKey, AdjacencyGpu)> {
        let mut contents = vec![0u8; bytes as usize];
        let mut at = 0u64;
        let placed: Vec<_> = group
            .into_iter()
            .map(|a| {
                let ranges = a.arrays.each_ref().map(|array| {
                    let offset = at;
                    contents[offset as usize..][..array.len()].copy_from_slice(array);
                    at = (offset + Self::bound(array)).next_multiple_of(align);
                    (offset, Self::bound(array))
                });
                (a, ranges)
            })
            .collect();
        let buffer = cx.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("adjacency"),
            contents: &contents,
            usage: wgpu::BufferUsages::STORAGE,
        });
        placed
            .into_iter()
            .map(|(a, ranges)| {
                let arrays = ranges.map(|(offset, size)| Shared { buffer: buffer.clone(), offset, size });
                let [faces, edge_count, use_count] = a.counts;
                (a.key, AdjacencyGpu { version: a.version, arrays, faces, edge_count, use_count, closed: a.closed })
            })
            .collect()
    }
}

/// The most bytes of adjacency the meshes uploaded together put in one shared buffer (a mesh's own
/// past it get a buffer per array).
const SHARED_ADJACENCY: u64 = 64 << 20;

/// What the backend keeps uploaded between frames.
#[derive(Default)]
pub struct SceneCache {
    meshes: HashMap<MeshKey, MeshGpu>,
    adjacency: HashMap<MeshKey, AdjacencyGpu>,
    /// The instance buffers, one per frame that may be in flight, each with what it holds.
    instances: Vec<(Vec<InstanceRaw>, wgpu::Buffer)>,
    /// The slot of each of the last frame's instances in its instance buffer.
    order: DrawOrder,
    /// Deformed meshes' rest data and posed nodes' buffers.
    pub(crate) posing: Posing,
    /// The materials' textures.
    pub textures: DeviceTextures,
}

/// The mesh an instance is drawn from at rest, and that mesh's version: a posed instance's rest mesh.
fn rest_mesh(inst: &Instance) -> (&shadow_core::Mesh, u64) {
    match &inst.pose {
        Some(pose) => (&pose.rest, pose.rest_version),
        None => (&inst.mesh, inst.mesh_version),
    }
}

impl SceneCache {
    /// Uploads every instance's mesh that is missing or stale (a posed instance's rest mesh), and poses
    /// the posed instances whose pose changed ([`crate::posing`]).
    pub fn upload_meshes(&mut self, cx: &WgpuContext, frame: &FrameInputs) {
        for inst in &frame.instances {
            let (m, version) = rest_mesh(inst);
            if self.meshes.get(&inst.mesh_key).is_some_and(|m| m.version == version) {
                continue;
            }
            // The pose reads a deformed mesh's rest positions and normals as storage; the extrusion reads
            // every mesh's positions and indices so.
            let posable =
                if m.deformers().is_some() { wgpu::BufferUsages::STORAGE } else { wgpu::BufferUsages::empty() };
            let positions: Vec<[f32; 4]> = m.positions().iter().map(|p| p.extend(1.0).to_array()).collect();
            let normals: Vec<[f32; 4]> = m.normals().iter().map(|n| n.extend(0.0).to_array()).collect();
            let indices: Vec<u32> = m.triangles().iter().flatten().copied().collect();
            let make = |label, contents: &[u8], usage| {
                cx.create_buffer_init(&wgpu::util::BufferInitDescriptor { label: Some(label), contents, usage })
            };
            self.meshes.insert(
                inst.mesh_key,
                MeshGpu {
                    version,
                    positions: make(
                        "positions",
                        bytemuck::cast_slice(&positions),
                        wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::STORAGE,
                    ),
                    normals: make("normals", bytemuck::cast_slice(&normals), wgpu::BufferUsages::VERTEX | posable),
                    uvs: m.uvs().map(|uvs| make("uvs", bytemuck::cast_slice(uvs), wgpu::BufferUsages::VERTEX)),
                    indices: make(
                        "indices",
                        bytemuck::cast_slice(&indices),
                        wgpu::BufferUsages::INDEX | wgpu::BufferUsages::STORAGE,
                    ),
                    index_count: indices.len() as u32,
                },
            );
        }
        let meshes = &self.meshes;
        self.posing.pose(cx, &frame.instances, |key| meshes.get(&key).map(|m| (&m.positions, &m.normals)));
    }

    /// The mesh an instance is drawn from (after [`SceneCache::upload_meshes`]): a posed instance's
    /// positions and normals are its node's posed ones.
    #[must_use]
    pub fn mesh(&self, inst: &Instance) -> Option<MeshView<'_>> {
        let m = self.meshes.get(&inst.mesh_key)?;
        let (positions, normals) = match &inst.pose {
            Some(_) => self.posing.posed(inst).map(|p| (&p.positions, &p.normals))?,
            None => (&m.positions, &m.normals),
        };
        Some(MeshView { positions, normals, uvs: m.uvs.as_ref(), indices: &m.indices, index_count: m.index_count })
    }

    /// Uploads the adjacency of every casting instance's mesh that is missing or stale (a posed
    /// instance's rest adjacency: its pose gives the welded positions and planes).
    ///
    /// The meshes uploaded together share buffers, each array of each mesh at an offset of its own: a
    /// scene of many small meshes makes a few buffers, not four per mesh (a device allocator's cost per
    /// buffer grows with the buffers it holds). A shared buffer is let go when every mesh in it has
    /// been replaced or dropped.
    pub fn upload_adjacency(&mut self, cx: &WgpuContext, frame: &FrameInputs) {
        let mut missing: Vec<(MeshKey, &Adjacency, u64)> = Vec::new();
        let mut listed = std::collections::HashSet::new();
        for inst in frame.instances.iter().filter(|i| i.casts_shadow) {
            let (adjacency, version) = match &inst.pose {
                Some(pose) => (&pose.rest_adjacency, pose.rest_version),
                None => (&inst.adjacency, inst.mesh_version),
            };
            let stale = self.adjacency.get(&inst.mesh_key).is_none_or(|a| a.version != version);
            if stale && listed.insert(inst.mesh_key) {
                missing.push((inst.mesh_key, adjacency, version));
            }
        }
        let align = u64::from(cx.device.limits().min_storage_buffer_offset_alignment);
        let mut group: Vec<Arrays> = Vec::new();
        let mut bytes = 0u64;
        for (key, adjacency, version) in missing {
            let arrays = Arrays::of(key, version, adjacency);
            let own = arrays.bytes(align);
            if own > SHARED_ADJACENCY {
                self.adjacency.insert(key, arrays.upload_alone(cx));
                continue;
            }
            if bytes > 0 && bytes + own > SHARED_ADJACENCY {
                self.adjacency.extend(Arrays::upload(cx, std::mem::take(&mut group), bytes, align));
                bytes = 0;
            }
            group.push(arrays);
            bytes += own;
        }
        if bytes > 0 {
            self.adjacency.extend(Arrays::upload(cx, group, bytes, align));
        }
    }

    /// The adjacency an instance's extrusion reads (after [`SceneCache::upload_adjacency`] and
    /// [`SceneCache::upload_meshes`]): a posed instance's welded positions and planes are its node's
    /// posed ones.
    #[must_use]
    pub fn adjacency(&self, inst: &Instance) -> Option<AdjacencyView<'_>> {
        let topology = self.adjacency.get(&inst.mesh_key)?;
        let (welded, planes) = match &inst.pose {
            Some(_) => {
                self.posing.posed(inst).map(|p| (BufferRange::whole(&p.welded), BufferRange::whole(&p.planes)))?
            }
            None => (topology.arrays[0].range(), topology.arrays[1].range()),
        };
        Some(AdjacencyView { welded, planes, topology })
    }

    /// The frame's instance data, in the buffer of this frame's turn (a few are used in turn, as the
    /// transient buffers are, so a frame's writes never wait for a frame in flight that reads): the
    /// instances that changed since that buffer's last frame are written in place. The buffers are made
    /// anew only when the number of instances changes. The instances are laid out in their
    /// [`DrawOrder`], which [`SceneCache::order`] then gives.
    pub fn instances(&mut self, cx: &WgpuContext, frame: &FrameInputs) -> &wgpu::Buffer {
        self.order = DrawOrder::of(frame);
        let raw: Vec<InstanceRaw> = self.order.instances().map(|i| InstanceRaw::of(&frame.instances[i], i)).collect();
        if self.instances.first().is_none_or(|(old, _)| old.len() != raw.len()) {
            let desc = wgpu::util::BufferInitDescriptor {
                label: Some("instances"),
                contents: bytemuck::cast_slice(&raw),
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            };
            self.instances =
                (0..crate::resources::FRAMES).map(|_| (raw.clone(), cx.create_buffer_init(&desc))).collect();
        }
        let (old, buf) = &mut self.instances[cx.frame_turn()];
        let size = std::mem::size_of::<InstanceRaw>();
        for (i, (was, now)) in old.iter_mut().zip(&raw).enumerate() {
            if bytemuck::bytes_of(was) != bytemuck::bytes_of(now) {
                cx.queue.write_buffer(buf, (i * size) as u64, bytemuck::bytes_of(now));
                *was = *now;
            }
        }
        buf
    }

    /// Where the instances of the frame last given to [`SceneCache::instances`] sit in its buffer.
    #[must_use]
    pub fn order(&self) -> &DrawOrder {
        &self.order
    }
}

impl WgpuContext {
    /// Uploads every instance's mesh of `frame` that is missing or stale ([`SceneCache::upload_meshes`]).
    pub fn upload_meshes(&mut self, frame: &FrameInputs) {
        let mut cache = std::mem::take(&mut self.cache);
        cache.upload_meshes(self, frame);
        self.cache = cache;
    }

    /// Uploads the adjacency of every casting instance's mesh that is missing or stale
    /// ([`SceneCache::upload_adjacency`]).
    pub fn upload_adjacency(&mut self, frame: &FrameInputs) {
        let mut cache = std::mem::take(&mut self.cache);
        cache.upload_adjacency(self, frame);
        self.cache = cache;
    }

    /// Uploads the textures `frame`'s materials read that are not on the device yet, and lets go of those
    /// it reads no more ([`DeviceTextures::upload`]).
    ///
    /// # Errors
    /// A texture over the device's limit.
    pub fn upload_textures(&mut self, frame: &FrameInputs) -> Result<(), WgpuError> {
        let mut cache = std::mem::take(&mut self.cache);
        let done = cache.textures.upload(self, frame);
        self.cache = cache;
        done
    }

    /// The frame's instance data, written where it changed ([`SceneCache::instances`]).
    pub fn instances(&mut self, frame: &FrameInputs) -> wgpu::Buffer {
        let mut cache = std::mem::take(&mut self.cache);
        let buffer = cache.instances(self, frame).clone();
        self.cache = cache;
        buffer
    }
}
