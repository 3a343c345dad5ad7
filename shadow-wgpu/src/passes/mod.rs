//! The passes every technique on the wgpu backend builds from (DESIGN 5), named by what they do:
//!
//! - [`maps`]: render light depth maps (and object-ID maps), look them up over the G-buffer with each
//!   filter, or with a technique's own fragment entry;
//! - [`volumes`]: upload shadow volumes, count them in the stencil either way, resolve the stencil,
//!   count what a pass rasterizes;
//! - [`extrusion`]: find and extrude shadow volumes on the GPU and count them in the stencil.
//!
//! [`full_screen`] runs a technique's full-screen pass into a visibility target, [`full_screen_to`] over
//! what it holds too; [`answer`] the pass that writes a light's visibility, over the pixels of its reach
//! only.

mod cutout_maps;
pub mod extrusion;
pub mod maps;
pub mod volumes;

use shadow_core::light::PixelRect;

use crate::frame::GpuVisibility;

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
    full_screen_to(cx, (label, target, LIT), pipeline, groups, depth_stencil);
}

/// [`full_screen`] into `target` loaded as `load` says: cleared to a colour, or kept
/// (`wgpu::LoadOp::Load`: the fragments the pipeline writes replace its values, the others keep them).
pub fn full_screen_to(
    cx: &crate::WgpuContext,
    target: (&str, &wgpu::TextureView, wgpu::LoadOp<wgpu::Color>),
    pipeline: &wgpu::RenderPipeline,
    groups: &[&wgpu::BindGroup],
    depth_stencil: Option<(&wgpu::TextureView, u32)>,
) {
    draw_full_screen(cx, target, None, pipeline, groups, depth_stencil);
}

/// Clears a visibility to 1: lit.
pub const LIT: wgpu::LoadOp<wgpu::Color> = wgpu::LoadOp::Clear(wgpu::Color::WHITE);

/// [`full_screen_to`] into a light's visibility `out`, cleared to 1 ([`LIT`]) or kept
/// (`wgpu::LoadOp::Load`), its fragments scissored to the light's reach ([`GpuVisibility::rect`]): a pixel
/// outside keeps what it had, 1 when cleared.
pub fn answer(
    cx: &crate::WgpuContext,
    (label, out, load): (&str, &GpuVisibility, wgpu::LoadOp<wgpu::Color>),
    pipeline: &wgpu::RenderPipeline,
    groups: &[&wgpu::BindGroup],
    depth_stencil: Option<(&wgpu::TextureView, u32)>,
) {
    draw_full_screen(cx, (label, &out.view, load), Some(out.rect), pipeline, groups, depth_stencil);
}

/// The full-screen triangle, its fragments within `scissor` where one is given (nothing drawn for an
/// empty one).
fn draw_full_screen(
    cx: &crate::WgpuContext,
    (label, target, load): (&str, &wgpu::TextureView, wgpu::LoadOp<wgpu::Color>),
    scissor: Option<PixelRect>,
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
        if let Some(r) = scissor {
            pass.set_scissor_rect(r.x0, r.y0, r.x1.saturating_sub(r.x0), r.y1.saturating_sub(r.y0));
        }
        if !scissor.is_some_and(|r| r.is_empty()) {
            pass.draw(0..3, 0..1);
        }
        pass.pop_debug_group();
    }
    cx.submit(enc);
}
