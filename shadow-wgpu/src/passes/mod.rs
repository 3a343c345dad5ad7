//! The passes every technique on the wgpu backend builds from (DESIGN 5), named by what they do:
//!
//! - [`maps`]: render light depth maps (and object-ID maps), look them up over the G-buffer with each
//!   filter, or with a technique's own fragment entry;
//! - [`volumes`]: upload shadow volumes, count them in the stencil either way, resolve the stencil,
//!   count what a pass rasterizes;
//! - [`extrusion`]: find and extrude shadow volumes on the GPU and count them in the stencil.
//!
//! [`full_screen`] runs a technique's full-screen pass into a visibility target, [`full_screen_to`] over
//! what it holds too.

pub mod extrusion;
pub mod maps;
pub mod volumes;

/// Runs a full-screen pipeline into `target` (cleared to 1: lit), with an optional depth-stencil
/// attachment whose contents are kept.
pub fn full_screen(
    cx: &crate::WgpuContext,
    label: &str,
    target: &wgpu::TextureView,
    pipeline: &wgpu::RenderPipeline,
    groups: &[&wgpu::BindGroup],
    depth_stencil: Option<(&wgpu::TextureView, u32)>,
) {
    let clear = wgpu::LoadOp::Clear(wgpu::Color::WHITE);
    full_screen_to(cx, (label, target, clear), pipeline, groups, depth_stencil);
}

/// [`full_screen`] into `target` loaded as `load` says: cleared to a colour, or kept
/// (`wgpu::LoadOp::Load`: the fragments the pipeline writes replace its values, the others keep them).
pub fn full_screen_to(
    cx: &crate::WgpuContext,
    (label, target, load): (&str, &wgpu::TextureView, wgpu::LoadOp<wgpu::Color>),
    pipeline: &wgpu::RenderPipeline,
    groups: &[&wgpu::BindGroup],
    depth_stencil: Option<(&wgpu::TextureView, u32)>,
) {
    let mut enc = cx.encoder(label);
    {
        let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some(label),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: target,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations { load, store: wgpu::StoreOp::Store },
            })],
            depth_stencil_attachment: depth_stencil.map(|(view, _)| wgpu::RenderPassDepthStencilAttachment {
                view,
                depth_ops: Some(wgpu::Operations { load: wgpu::LoadOp::Load, store: wgpu::StoreOp::Store }),
                stencil_ops: Some(wgpu::Operations { load: wgpu::LoadOp::Load, store: wgpu::StoreOp::Store }),
            }),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.push_debug_group(label);
        pass.set_pipeline(pipeline);
        for (i, g) in groups.iter().enumerate() {
            pass.set_bind_group(i as u32, *g, &[]);
        }
        if let Some((_, reference)) = depth_stencil {
            pass.set_stencil_reference(reference);
        }
        pass.draw(0..3, 0..1);
        pass.pop_debug_group();
    }
    cx.submit(enc);
}
