//! hybrid's `edge_texels=all` on the GPU: the casters' silhouette edges drawn as texel-covering quads into
//! edge maps, a layer per light projection holding the nearest edge's depth per texel (twin: the CPU
//! hybrid's build; the test that reads them is edges_all.wgsl's `near_edge`).

use crate::hybrid::edge_map::{edge_cells, edge_texel_quads};
use glam::Vec3;
use shadow_core::light::LightView;
use wgpu::util::DeviceExt;

use shadow_wgpu::context::WgpuContext;
use shadow_wgpu::frame::{layer_view, layered};
use shadow_wgpu::pipelines::{MAP_DEPTH, depth_pass, min_depth_pipeline};
use shadow_wgpu::shaders;

/// Clip-space positions, for the edge pass.
const CLIP_LAYOUT: wgpu::VertexBufferLayout<'static> = wgpu::VertexBufferLayout {
    array_stride: 16,
    step_mode: wgpu::VertexStepMode::Vertex,
    attributes: &wgpu::vertex_attr_array![0 => Float32x4],
};

/// The edge pass (`edge_texels=on`): clip-space quads into a map depth target, the depth test keeping the
/// nearest edge per texel.
pub(super) fn edge_pass(cx: &WgpuContext) -> wgpu::RenderPipeline {
    let module = shaders::module(&cx.device, "hybrid edge pass", super::shaders::EDGE_PASS.to_string());
    min_depth_pipeline(&cx.device, "hybrid edge pass", &module, &[], ("vs_edge", CLIP_LAYOUT), None)
}

/// The edge maps of a light: per projection, the casters' silhouette edges drawn as
/// `edge_texel_quads` into a layer cleared to 1 (twin: the CPU hybrid's build).
pub(super) fn edge_maps(
    cx: &WgpuContext,
    pass: &wgpu::RenderPipeline,
    segments: &[[Vec3; 2]],
    light: &LightView,
    res: u32,
) -> wgpu::Texture {
    let maps = layered(cx, "hybrid edge maps", res, res, light.projections.len() as u32, MAP_DEPTH);
    let mut enc = cx.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("edge maps") });
    for (k, p) in light.projections.iter().enumerate() {
        let quads: Vec<[f32; 4]> =
            edge_texel_quads(segments, p, res).iter().flat_map(|t| t.map(|v| v.to_array())).collect();
        let view = layer_view(&maps, k as u32);
        let mut rp = depth_pass(&mut enc, &view, "edge map");
        if !quads.is_empty() {
            let vb = cx.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("edge quads"),
                contents: bytemuck::cast_slice(&quads),
                usage: wgpu::BufferUsages::VERTEX,
            });
            rp.set_pipeline(pass);
            rp.set_vertex_buffer(0, vb.slice(..));
            rp.draw(0..quads.len() as u32, 0..1);
        }
    }
    cx.queue.submit([enc.finish()]);
    maps
}

/// The edge cells of a light (`edge_texels=paired`): per projection, shadow-core's `edge_cells` of the
/// casters' silhouette edges, made on the CPU as the edge quads are and uploaded as a layer of an
/// `(res + 1)` square float array (twin: the CPU hybrid's build; read by edges_paired.wgsl's
/// `near_edge`).
pub(super) fn edge_cell_maps(cx: &WgpuContext, segments: &[[Vec3; 2]], light: &LightView, res: u32) -> wgpu::Texture {
    let mut cells = Vec::with_capacity(((res + 1) * (res + 1)) as usize * light.projections.len());
    for p in &light.projections {
        cells.extend_from_slice(edge_cells(segments, p, res, None).data());
    }
    let desc = wgpu::TextureDescriptor {
        label: Some("hybrid edge cells"),
        size: wgpu::Extent3d { width: res + 1, height: res + 1, depth_or_array_layers: light.projections.len() as u32 },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::R32Float,
        usage: wgpu::TextureUsages::TEXTURE_BINDING,
        view_formats: &[],
    };
    cx.device.create_texture_with_data(
        &cx.queue,
        &desc,
        wgpu::util::TextureDataOrder::LayerMajor,
        bytemuck::cast_slice(&cells),
    )
}
