//! hybrid's read-only tables for the caster masks' compute passes (the triangles, their setups, the
//! shafts and the shaft grid), laid out in textures of [`TABLE_ROW`] texels a row: lavapipe (Mesa 22.3)
//! loads from a storage buffer lane by lane and fetches a texel several times faster.

use shadow_wgpu::context::{WgpuContext, WgpuError};

/// Texels per row of the tables the compute passes read from textures (casters.wgsl's
/// `TABLE_ROW`).
pub(super) const TABLE_ROW: u32 = 4096;

/// A table of `n` texels as a texture of [`TABLE_ROW`] texels a row (at least one row), with `data`
/// written into its first rows (padded to whole rows), or to be copied into. `kept`, the same table
/// of this light's last build, is reused when it has as many rows; a table made anew gets rows to the
/// next power of two, so the builds under a moving light reuse it. The passes read a table's first `n`
/// texels only.
///
/// # Errors
/// [`WgpuError::BadSize`] for more rows than the device allows.
pub(super) fn table(
    cx: &WgpuContext,
    label: &'static str,
    format: wgpu::TextureFormat,
    (n, data): (u64, Option<&[u8]>),
    kept: Option<wgpu::Texture>,
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
    let texture = match kept {
        Some(t) if t.format() == format && t.height() >= rows => t,
        _ => cx.create_texture(&wgpu::TextureDescriptor {
            label: Some(label),
            size: wgpu::Extent3d {
                width: TABLE_ROW,
                height: rows.next_power_of_two().min(most),
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
            view_formats: &[],
        }),
    };
    if let Some(bytes) = data {
        // Every format used has 32-bit components.
        let row_bytes = TABLE_ROW * 4 * format.components() as u32;
        let mut padded = bytes.to_vec();
        padded.resize((u64::from(rows) * u64::from(row_bytes)) as usize, 0);
        cx.queue.write_texture(
            texture.as_image_copy(),
            &padded,
            wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(row_bytes), rows_per_image: None },
            wgpu::Extent3d { width: TABLE_ROW, height: rows, depth_or_array_layers: 1 },
        );
    }
    Ok(texture)
}
