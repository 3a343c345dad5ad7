//! Scene upload, cached: vertex and index buffers per [`MeshKey`] (refreshed when the mesh's version
//! changes), and the per-instance data of a frame (refreshed when any instance changes).

use std::collections::HashMap;

use bytemuck::{Pod, Zeroable};
use glam::Mat4;
use shadow_core::{FrameInputs, MeshKey};
use wgpu::util::DeviceExt;

/// A mesh on the GPU.
pub struct MeshGpu {
    version: u64,
    /// Homogeneous positions (w = 1), one `vec4<f32>` per vertex.
    pub positions: wgpu::Buffer,
    /// Normals, one `vec4<f32>` per vertex.
    pub normals: wgpu::Buffer,
    /// Triangle indices.
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
}

impl InstanceRaw {
    fn of(inst: &shadow_core::Instance) -> Self {
        let n = Mat4::from_mat3(shadow_core::affine::normal_matrix(inst.world_from_local));
        Self {
            world_from_local: inst.world_from_local.to_cols_array_2d(),
            normal_from_local: n.to_cols_array_2d(),
            color: inst.base_color.extend(if inst.two_sided { 1.0 } else { 0.0 }).to_array(),
            flags: [u32::from(inst.receives_shadow), u32::from(inst.mirrored), 0, 0],
        }
    }
}

/// What the backend keeps uploaded between frames.
#[derive(Default)]
pub struct SceneCache {
    meshes: HashMap<MeshKey, MeshGpu>,
    instances: Option<(Vec<InstanceRaw>, wgpu::Buffer)>,
}

impl SceneCache {
    /// Uploads every instance's mesh that is missing or stale.
    pub fn upload_meshes(&mut self, device: &wgpu::Device, frame: &FrameInputs) {
        for inst in &frame.instances {
            if self.meshes.get(&inst.mesh_key).is_some_and(|m| m.version == inst.mesh_version) {
                continue;
            }
            let m = &inst.mesh;
            let positions: Vec<[f32; 4]> = m.positions().iter().map(|p| p.extend(1.0).to_array()).collect();
            let normals: Vec<[f32; 4]> = m.normals().iter().map(|n| n.extend(0.0).to_array()).collect();
            let indices: Vec<u32> = m.triangles().iter().flatten().copied().collect();
            let make = |label, contents: &[u8], usage| {
                device.create_buffer_init(&wgpu::util::BufferInitDescriptor { label: Some(label), contents, usage })
            };
            self.meshes.insert(
                inst.mesh_key,
                MeshGpu {
                    version: inst.mesh_version,
                    positions: make("positions", bytemuck::cast_slice(&positions), wgpu::BufferUsages::VERTEX),
                    normals: make("normals", bytemuck::cast_slice(&normals), wgpu::BufferUsages::VERTEX),
                    indices: make("indices", bytemuck::cast_slice(&indices), wgpu::BufferUsages::INDEX),
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

    /// The frame's instance data, uploaded when it changed.
    pub fn instances(&mut self, device: &wgpu::Device, frame: &FrameInputs) -> &wgpu::Buffer {
        let raw: Vec<InstanceRaw> = frame.instances.iter().map(InstanceRaw::of).collect();
        let stale = self
            .instances
            .as_ref()
            .is_none_or(|(old, _)| bytemuck::cast_slice::<_, u8>(old) != bytemuck::cast_slice::<_, u8>(&raw));
        if stale {
            let buf = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("instances"),
                contents: bytemuck::cast_slice(&raw),
                usage: wgpu::BufferUsages::STORAGE,
            });
            self.instances = Some((raw, buf));
        }
        match &self.instances {
            Some((_, b)) => b,
            None => unreachable!("just uploaded"),
        }
    }
}
