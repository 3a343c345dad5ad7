//! A depth target as a minimum blend, on the wgpu backend: a pass writes a value as fragment depth and
//! the depth test "less" keeps the smallest at every texel, at full float precision, where blending a
//! float colour target is an optional feature. Smoothies keep their buffer's depth and alpha this way,
//! the penumbra map its values.

use shadow_wgpu::frame::layer_view;
use shadow_wgpu::pipelines::{buffer_entry, depth_array_entry, depth_pass, min_depth_pipeline};
use shadow_wgpu::{Transient, TransientRing, WgpuContext};

/// A pipeline drawing `vertices` through `vertex` and `fragment` of `module`, whose fragment depth is the
/// value kept (shadow-wgpu's `min_depth_pipeline` with a fragment stage).
#[must_use]
pub fn pipeline(
    cx: &WgpuContext,
    label: &str,
    module: &wgpu::ShaderModule,
    layout: &wgpu::BindGroupLayout,
    vertex: (&str, wgpu::VertexBufferLayout<'_>),
    fragment: &str,
) -> wgpu::RenderPipeline {
    min_depth_pipeline(&cx.pipelines, label, module, &[layout], vertex, Some(fragment))
}

/// Records a pass that clears layer 0 of `target` to 1 (nothing drawn) and, given vertices, draws them
/// with `pipeline` and `group`.
pub fn draw(
    enc: &mut wgpu::CommandEncoder,
    target: &wgpu::Texture,
    pipeline: &wgpu::RenderPipeline,
    group: &wgpu::BindGroup,
    vertices: Option<&(Transient, u32)>,
) {
    let view = layer_view(target, 0);
    let mut pass = depth_pass(enc, &view, "minimum target");
    if let Some((buffer, count)) = vertices {
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, group, &[]);
        pass.set_vertex_buffer(0, buffer.slice());
        pass.draw(0..*count, 0..1);
    }
}

/// The bindings of a pass over the blockers' maps: a uniform at 0, the maps (a depth array) at 1.
#[must_use]
pub fn layout(cx: &WgpuContext, label: &str) -> wgpu::BindGroupLayout {
    cx.pipelines.group_layout(
        label,
        &[buffer_entry(0, wgpu::BufferBindingType::Uniform, wgpu::ShaderStages::VERTEX_FRAGMENT), depth_array_entry(1)],
    )
}

/// A group of [`layout`]: `params` as the uniform (in the frame's transient buffer), and `maps`.
#[must_use]
pub fn bind(
    cx: &WgpuContext,
    layout: &wgpu::BindGroupLayout,
    label: &str,
    params: &impl bytemuck::Pod,
    maps: &wgpu::Texture,
) -> wgpu::BindGroup {
    let uniform = cx.transient(bytemuck::bytes_of(params));
    let maps_view = maps.create_view(&wgpu::TextureViewDescriptor {
        dimension: Some(wgpu::TextureViewDimension::D2Array),
        ..Default::default()
    });
    cx.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some(label),
        layout,
        entries: &[
            wgpu::BindGroupEntry { binding: 0, resource: uniform.binding() },
            wgpu::BindGroupEntry { binding: 1, resource: wgpu::BindingResource::TextureView(&maps_view) },
        ],
    })
}

/// `vertices` in this frame's buffer of `ring` (the pass's own: their number follows the casters'
/// silhouettes), with their count; `None` when there are none (a pass then only clears).
#[must_use]
pub fn vertex_buffer<V: bytemuck::Pod>(
    cx: &WgpuContext,
    ring: &mut TransientRing,
    vertices: &[V],
) -> Option<(Transient, u32)> {
    (!vertices.is_empty()).then(|| {
        let [slice] = ring.write(cx, [bytemuck::cast_slice(vertices)]);
        (slice, vertices.len() as u32)
    })
}
