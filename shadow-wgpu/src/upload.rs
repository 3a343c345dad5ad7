//! Scene upload, cached: vertex and index buffers per [`MeshKey`] (refreshed when the mesh's version
//! changes), the adjacency the GPU's shadow-volume extrusion reads (per mesh, on first use), the
//! materials' textures ([`crate::textures`]), and the per-instance data of a frame (rewritten in place
//! when an instance changes, made anew only when their number does).

use std::collections::HashMap;

use bytemuck::{Pod, Zeroable};
use glam::Mat4;
use shadow_core::geometry::adjacency::{Adjacency, FaceUse};
use shadow_core::{FrameInputs, MeshKey};

use crate::context::{WgpuContext, WgpuError};
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
    fn of(inst: &shadow_core::Instance) -> Self {
        let n = Mat4::from_mat3(shadow_core::affine::normal_matrix(inst.world_from_local));
        let texel = read_texture(inst).and_then(|_| TexelRuleRaw::of(&inst.material)).unwrap_or_default();
        Self {
            world_from_local: inst.world_from_local.to_cols_array_2d(),
            normal_from_local: n.to_cols_array_2d(),
            color: inst.base_color.extend(if inst.two_sided { 1.0 } else { 0.0 }).to_array(),
            flags: [u32::from(inst.receives_shadow), u32::from(inst.mirrored), 0, 0],
            texel,
        }
    }
}

/// A mesh's adjacency on the GPU, as the shadow-volume extrusion reads it (twin: shadow-core's
/// `Adjacency`).
pub struct AdjacencyGpu {
    version: u64,
    /// Welded positions, `vec4<f32>` with w = 1.
    pub welded: wgpu::Buffer,
    /// Per face, its plane `(n, d)` as the adjacency scaled it (`vec4<f32>`).
    pub planes: wgpu::Buffer,
    /// Per edge `(a, b, first use, uses)`, `vec4<u32>`: its welded vertices (a < b) and its run of
    /// [`Self::uses`]. Manifold edges first, then boundary edges, then the rest, as the CPU's silhouette
    /// reads them.
    pub edges: wgpu::Buffer,
    /// The faces' uses of the edges, `face << 1 | reversed` (shadow-core's `FaceUse`).
    pub uses: wgpu::Buffer,
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
    fn upload(cx: &WgpuContext, adj: &Adjacency, version: u64) -> Self {
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
        // Storage bindings may not be empty: a mesh without edges still binds one word.
        let storage = |label, contents: &[u8]| {
            let padded = [0u8; 16];
            cx.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents: if contents.is_empty() { &padded } else { contents },
                usage: wgpu::BufferUsages::STORAGE,
            })
        };
        Self {
            version,
            welded: storage("welded positions", bytemuck::cast_slice(&welded)),
            planes: storage("face planes", bytemuck::cast_slice(&planes)),
            edges: storage("edges", bytemuck::cast_slice(&edges)),
            uses: storage("face uses", bytemuck::cast_slice(&uses)),
            faces: planes.len() as u32,
            edge_count: edges.len() as u32,
            use_count: uses.len() as u32,
            closed: adj.closed(),
        }
    }
}

/// What the backend keeps uploaded between frames.
#[derive(Default)]
pub struct SceneCache {
    meshes: HashMap<MeshKey, MeshGpu>,
    adjacency: HashMap<MeshKey, AdjacencyGpu>,
    /// The instance buffers, one per frame that may be in flight, each with what it holds.
    instances: Vec<(Vec<InstanceRaw>, wgpu::Buffer)>,
    /// The materials' textures.
    pub textures: DeviceTextures,
}

impl SceneCache {
    /// Uploads every instance's mesh that is missing or stale.
    pub fn upload_meshes(&mut self, cx: &WgpuContext, frame: &FrameInputs) {
        for inst in &frame.instances {
            if self.meshes.get(&inst.mesh_key).is_some_and(|m| m.version == inst.mesh_version) {
                continue;
            }
            let m = &inst.mesh;
            let positions: Vec<[f32; 4]> = m.positions().iter().map(|p| p.extend(1.0).to_array()).collect();
            let normals: Vec<[f32; 4]> = m.normals().iter().map(|n| n.extend(0.0).to_array()).collect();
            let indices: Vec<u32> = m.triangles().iter().flatten().copied().collect();
            let make = |label, contents: &[u8], usage| {
                cx.create_buffer_init(&wgpu::util::BufferInitDescriptor { label: Some(label), contents, usage })
            };
            self.meshes.insert(
                inst.mesh_key,
                MeshGpu {
                    version: inst.mesh_version,
                    positions: make("positions", bytemuck::cast_slice(&positions), wgpu::BufferUsages::VERTEX),
                    normals: make("normals", bytemuck::cast_slice(&normals), wgpu::BufferUsages::VERTEX),
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
    }

    /// The mesh of an instance (after [`SceneCache::upload_meshes`]).
    #[must_use]
    pub fn mesh(&self, key: MeshKey) -> Option<&MeshGpu> {
        self.meshes.get(&key)
    }

    /// Uploads the adjacency of every casting instance's mesh that is missing or stale.
    pub fn upload_adjacency(&mut self, cx: &WgpuContext, frame: &FrameInputs) {
        for inst in frame.instances.iter().filter(|i| i.casts_shadow) {
            if self.adjacency.get(&inst.mesh_key).is_some_and(|a| a.version == inst.mesh_version) {
                continue;
            }
            self.adjacency.insert(inst.mesh_key, AdjacencyGpu::upload(cx, &inst.adjacency, inst.mesh_version));
        }
    }

    /// The adjacency of an instance's mesh (after [`SceneCache::upload_adjacency`]).
    #[must_use]
    pub fn adjacency(&self, key: MeshKey) -> Option<&AdjacencyGpu> {
        self.adjacency.get(&key)
    }

    /// The frame's instance data, in the buffer of this frame's turn (a few are used in turn, as the
    /// transient buffers are, so a frame's writes never wait for a frame in flight that reads): the
    /// instances that changed since that buffer's last frame are written in place. The buffers are made
    /// anew only when the number of instances changes.
    pub fn instances(&mut self, cx: &WgpuContext, frame: &FrameInputs) -> &wgpu::Buffer {
        let raw: Vec<InstanceRaw> = frame.instances.iter().map(InstanceRaw::of).collect();
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
