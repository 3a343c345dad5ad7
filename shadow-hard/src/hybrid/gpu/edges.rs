//! hybrid's `edge_texels=paired` on the GPU: the edge cells the CPU makes from the casters' silhouette
//! edges, uploaded a layer per light projection (the test that reads them is edges_paired.wgsl's
//! `near_edge`).

use crate::hybrid::edge_map::edge_cells;
use glam::Vec3;
use shadow_core::light::LightView;

use shadow_wgpu::context::WgpuContext;

/// The edge cells of a light (`edge_texels=paired`): per projection, `edge_cells` of the casters'
/// silhouette edges, made on the CPU and uploaded as a layer of an
/// `(res + 1)` square float array (twin: the CPU hybrid's build; read by edges_paired.wgsl's
/// `near_edge`), into `kept` (this light's last) when it has that size.
pub(super) fn edge_cell_maps(
    cx: &WgpuContext,
    segments: &[[Vec3; 2]],
    light: &LightView,
    res: u32,
    kept: Option<wgpu::Texture>,
) -> wgpu::Texture {
    let mut cells = Vec::with_capacity(((res + 1) * (res + 1)) as usize * light.projections.len());
    for p in &light.projections {
        cells.extend_from_slice(edge_cells(segments, p, res, None).data());
    }
    let size =
        wgpu::Extent3d { width: res + 1, height: res + 1, depth_or_array_layers: light.projections.len() as u32 };
    let texture = match kept {
        Some(t) if t.size() == size => t,
        _ => cx.create_texture(&wgpu::TextureDescriptor {
            label: Some("hybrid edge cells"),
            size,
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::R32Float,
            usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
            view_formats: &[],
        }),
    };
    let layout =
        wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(4 * (res + 1)), rows_per_image: Some(res + 1) };
    cx.queue.write_texture(texture.as_image_copy(), bytemuck::cast_slice(&cells), layout, size);
    texture
}
