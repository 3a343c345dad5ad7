//! Copies of GPU textures back into [`Image`]s (rows padded to 256 bytes on the GPU side, as
//! `copy_texture_to_buffer` requires).

use shadow_core::Image;
use shadow_core::image::Rgb8;

use crate::context::{WgpuContext, WgpuError};

/// Reads one layer of a texture whose texels are `texel_bytes` bytes, as raw rows without padding.
fn read_layer(
    cx: &WgpuContext,
    tex: &wgpu::Texture,
    layer: u32,
    texel_bytes: u32,
    aspect: wgpu::TextureAspect,
) -> Result<Vec<u8>, WgpuError> {
    let (w, h) = (tex.width(), tex.height());
    let row = w * texel_bytes;
    let padded = row.div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT) * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
    let buffer = cx.create_buffer(&wgpu::BufferDescriptor {
        label: Some("readback"),
        size: u64::from(padded) * u64::from(h),
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    });
    let mut enc = cx.encoder("readback");
    enc.copy_texture_to_buffer(
        wgpu::TexelCopyTextureInfo {
            texture: tex,
            mip_level: 0,
            origin: wgpu::Origin3d { x: 0, y: 0, z: layer },
            aspect,
        },
        wgpu::TexelCopyBufferInfo {
            buffer: &buffer,
            layout: wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(padded), rows_per_image: Some(h) },
        },
        wgpu::Extent3d { width: w, height: h, depth_or_array_layers: 1 },
    );
    cx.submit(enc);
    let data = map_read(cx, &buffer, "readback")?;
    let mut out = Vec::with_capacity((row * h) as usize);
    for y in 0..h as usize {
        out.extend_from_slice(&data[y * padded as usize..y * padded as usize + row as usize]);
    }
    Ok(out)
}

/// Maps a MAP_READ buffer (its copies already submitted) and returns its bytes.
///
/// # Errors
/// A GPU failure, or [`WgpuError::NotRecordable`] inside a frame recorded into a host's encoder.
pub fn map_read(cx: &WgpuContext, buffer: &wgpu::Buffer, during: &str) -> Result<Vec<u8>, WgpuError> {
    cx.may_wait(during)?;
    let slice = buffer.slice(..);
    let (tx, rx) = std::sync::mpsc::channel();
    slice.map_async(wgpu::MapMode::Read, move |r| {
        let _ = tx.send(r);
    });
    cx.wait()?;
    let gpu = |m: String| WgpuError::Gpu { during: during.into(), message: m };
    rx.recv().map_err(|_| gpu("the map callback never ran".into()))?.map_err(|e| gpu(e.to_string()))?;
    let bytes = slice.get_mapped_range().map_err(|e| gpu(e.to_string()))?.to_vec();
    buffer.unmap();
    Ok(bytes)
}

/// A buffer's bytes (its usage must include COPY_SRC).
///
/// # Errors
/// A GPU failure, or [`WgpuError::NotRecordable`] inside a frame recorded into a host's encoder.
pub fn read_buffer(cx: &WgpuContext, buffer: &wgpu::Buffer, during: &str) -> Result<Vec<u8>, WgpuError> {
    cx.may_wait(during)?;
    let staging = cx.create_buffer(&wgpu::BufferDescriptor {
        label: Some("readback"),
        size: buffer.size(),
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    });
    let mut enc = cx.encoder("readback");
    enc.copy_buffer_to_buffer(buffer, 0, &staging, 0, buffer.size());
    cx.submit(enc);
    map_read(cx, &staging, during)
}

/// A single-channel f32 texture (R32Float or Depth32Float) as an image.
///
/// # Errors
/// A GPU failure.
pub fn read_f32(
    cx: &WgpuContext,
    tex: &wgpu::Texture,
    layer: u32,
    aspect: wgpu::TextureAspect,
) -> Result<Image<f32>, WgpuError> {
    let bytes = read_layer(cx, tex, layer, 4, aspect)?;
    let data = bytes.chunks_exact(4).map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]])).collect();
    Image::from_vec(tex.width(), tex.height(), data)
        .ok_or_else(|| WgpuError::Gpu { during: "readback".into(), message: "size mismatch".into() })
}

/// One layer of an R32Uint texture as an image.
///
/// # Errors
/// A GPU failure.
pub fn read_u32(cx: &WgpuContext, tex: &wgpu::Texture, layer: u32) -> Result<Image<u32>, WgpuError> {
    let bytes = read_layer(cx, tex, layer, 4, wgpu::TextureAspect::All)?;
    let data = bytes.chunks_exact(4).map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]])).collect();
    Image::from_vec(tex.width(), tex.height(), data)
        .ok_or_else(|| WgpuError::Gpu { during: "readback".into(), message: "size mismatch".into() })
}

/// The stencil aspect of a depth-stencil texture as an image.
///
/// # Errors
/// A GPU failure.
pub fn read_stencil(cx: &WgpuContext, tex: &wgpu::Texture) -> Result<Image<u8>, WgpuError> {
    let bytes = read_layer(cx, tex, 0, 1, wgpu::TextureAspect::StencilOnly)?;
    Image::from_vec(tex.width(), tex.height(), bytes)
        .ok_or_else(|| WgpuError::Gpu { during: "readback".into(), message: "size mismatch".into() })
}

/// An Rgba8 texture as an RGB image.
///
/// # Errors
/// A GPU failure.
pub fn read_rgb8(cx: &WgpuContext, tex: &wgpu::Texture) -> Result<Image<Rgb8>, WgpuError> {
    let bytes = read_layer(cx, tex, 0, 4, wgpu::TextureAspect::All)?;
    let data = bytes.chunks_exact(4).map(|c| [c[0], c[1], c[2]]).collect();
    Image::from_vec(tex.width(), tex.height(), data)
        .ok_or_else(|| WgpuError::Gpu { during: "readback".into(), message: "size mismatch".into() })
}

/// One layer of an Rg32Float texture as an image of pairs.
///
/// # Errors
/// A GPU failure.
pub fn read_rg32(cx: &WgpuContext, tex: &wgpu::Texture, layer: u32) -> Result<Image<[f32; 2]>, WgpuError> {
    let bytes = read_layer(cx, tex, layer, 8, wgpu::TextureAspect::All)?;
    let f = |c: &[u8]| f32::from_le_bytes([c[0], c[1], c[2], c[3]]);
    let data = bytes.chunks_exact(8).map(|c| [f(&c[..4]), f(&c[4..])]).collect();
    Image::from_vec(tex.width(), tex.height(), data)
        .ok_or_else(|| WgpuError::Gpu { during: "readback".into(), message: "size mismatch".into() })
}

/// An Rgba32Float texture as an image of quadruples.
///
/// # Errors
/// A GPU failure.
pub fn read_rgba32(cx: &WgpuContext, tex: &wgpu::Texture) -> Result<Image<[f32; 4]>, WgpuError> {
    let bytes = read_layer(cx, tex, 0, 16, wgpu::TextureAspect::All)?;
    let f = |c: &[u8]| f32::from_le_bytes([c[0], c[1], c[2], c[3]]);
    let data = bytes.chunks_exact(16).map(|c| [f(&c[..4]), f(&c[4..8]), f(&c[8..12]), f(&c[12..])]).collect();
    Image::from_vec(tex.width(), tex.height(), data)
        .ok_or_else(|| WgpuError::Gpu { during: "readback".into(), message: "size mismatch".into() })
}
