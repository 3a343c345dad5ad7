//! hybrid's read-only tables for the caster masks' compute passes (the triangles, their setups, the
//! shafts and the shaft grid), laid out in textures of [`TABLE_ROW`] texels a row: lavapipe (Mesa 22.3)
//! loads from a storage buffer lane by lane and fetches a texel several times faster.

use wgpu::util::DeviceExt;

use shadow_wgpu::context::{WgpuContext, WgpuError};

/// Texels per row of the tables the compute passes read from textures (casters.wgsl's
/// `TABLE_ROW`).
pub(super) const TABLE_ROW: u32 = 4096;

/// A table of `n` texels as a texture of [`TABLE_ROW`] texels a row (at least one row), with `data`
/// (padded to whole rows), or to be copied into.
///
/// # Errors
/// [`WgpuError::BadSize`] for more rows than the device allows.
pub(super) fn table(
    cx: &WgpuContext,
    label: &'static str,
    format: wgpu::TextureFormat,
    n: u64,
    data: Option<&[u8]>,
) -> Result<wgpu::Texture, WgpuError> {
    let rows = n.div_ceil(u64::from(TABLE_ROW)).clamp(1, u64::from(u32::MAX)) as u32;
    let most = cx.device.limits().max_texture_dimension_2d;
    if rows > most {
        return Err(WgpuError::BadSize {
            what: label,
            width: u64::from(TABLE_ROW),
            height: u64::from(rows),
            why: format!("more rows than the device's {most}"),
        });
    }
    let size = wgpu::Extent3d { width: TABLE_ROW, height: rows, depth_or_array_layers: 1 };
    let desc = wgpu::TextureDescriptor {
        label: Some(label),
        size,
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    };
    Ok(match data {
        Some(bytes) => {
            let mut padded = bytes.to_vec();
            // Every format used has 32-bit components.
            padded.resize((u64::from(rows) * u64::from(TABLE_ROW) * 4 * format.components() as u64) as usize, 0);
            cx.device.create_texture_with_data(&cx.queue, &desc, wgpu::util::TextureDataOrder::LayerMajor, &padded)
        }
        None => cx.device.create_texture(&desc),
    })
}
