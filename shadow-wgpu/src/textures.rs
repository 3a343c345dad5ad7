//! Materials' textures on the device, read by the texel rule of `texel.wgsl` (twin: shadow-core's
//! `material::sampler`).
//!
//! Each texture a frame's materials read is uploaded once, with shadow-core's mip chain level for level
//! (Rgba8UnormSrgb: the same bytes the CPU samples), and kept while frames keep reading it: a texture
//! that many materials or instances share is one texture on the device, as it is one on the CPU. Shaders
//! read the texels by index and filter them themselves, so the two backends pick the same levels and
//! texels where a hardware sampler's level selection and weights would vary between drivers. How a
//! material reads its texture (sampler, transform, alpha) travels as a [`TexelRuleRaw`].

use std::collections::HashMap;
use std::sync::Arc;

use bytemuck::{Pod, Zeroable};
use shadow_core::FrameInputs;
use shadow_core::frame::Coverage;
use shadow_core::material::{AlphaMode, Filter, Material, Sampler, Texture, TextureRef, Wrap};

use crate::context::{WgpuContext, WgpuError};

/// The format of every material texture: sRGB colour decoded to linear light by a load, alpha linear.
pub const TEXTURE_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8UnormSrgb;

/// GPU twin of `TexelRule` in texel.wgsl: how a material reads its texture.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct TexelRuleRaw {
    row_u: [f32; 4],
    row_v: [f32; 4],
    sampler: [u32; 4],
    alpha: [f32; 4],
}

impl TexelRuleRaw {
    /// The rule of `texture`'s reads with the alpha `factor`, and the alpha test's `cutoff` (`None`: the
    /// surface is everywhere, whatever its alpha).
    #[must_use]
    pub fn new(texture: &TextureRef, factor: f32, cutoff: Option<f32>) -> Self {
        let m = texture.transform.matrix();
        let Sampler { mag, min, mipmap, wrap_u, wrap_v } = texture.sampler;
        let filter = |f: Filter| match f {
            Filter::Nearest => 0,
            Filter::Linear => 1,
        };
        let mip = match mipmap {
            None => 0,
            Some(Filter::Nearest) => 1,
            Some(Filter::Linear) => 2,
        };
        let wrap = |w: Wrap| match w {
            Wrap::Repeat => 0,
            Wrap::ClampToEdge => 1,
            Wrap::MirroredRepeat => 2,
        };
        Self {
            row_u: [m.x_axis.x, m.y_axis.x, m.z_axis.x, 0.0],
            row_v: [m.x_axis.y, m.y_axis.y, m.z_axis.y, 0.0],
            sampler: [filter(mag), filter(min), mip, wrap(wrap_u) | wrap(wrap_v) << 4],
            // A cutoff no alpha in [0, 1] fails where the surface is everywhere.
            alpha: [factor, cutoff.unwrap_or(-1.0), 0.0, 0.0],
        }
    }

    /// The rule of `material`'s base-colour texture, where it has one: its alpha test where it is masked.
    #[must_use]
    pub fn of(material: &Material) -> Option<Self> {
        let cutoff = match material.alpha_mode {
            AlphaMode::Mask { cutoff } => Some(cutoff),
            AlphaMode::Opaque | AlphaMode::Blend => None,
        };
        material.base_color_texture.as_ref().map(|t| Self::new(t, material.alpha, cutoff))
    }
}

/// A texture on the device, with the texture it was made from (held, so its address names it while it
/// is kept).
pub struct TextureGpu {
    source: Arc<Texture>,
    /// The mip chain, level 0 first.
    pub texture: wgpu::Texture,
    /// A view of every level.
    pub view: wgpu::TextureView,
    /// The view bound as the passes that read a material's texture bind it (`Shared::material_layout`).
    pub group: wgpu::BindGroup,
}

impl TextureGpu {
    /// Uploads `source` with its mip chain.
    ///
    /// # Errors
    /// [`WgpuError::TextureTooLarge`] for a side over the device's limit.
    pub fn upload(cx: &WgpuContext, source: &Arc<Texture>) -> Result<Self, WgpuError> {
        let (width, height) = (source.width(), source.height());
        let most = cx.device.limits().max_texture_dimension_2d;
        if width > most || height > most {
            return Err(WgpuError::TextureTooLarge { texture: source.name().to_string(), width, height, most });
        }
        let levels = source.levels();
        let texture = cx.create_texture(&wgpu::TextureDescriptor {
            label: Some(source.name()),
            size: wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
            mip_level_count: levels.len() as u32,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: TEXTURE_FORMAT,
            usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
            view_formats: &[],
        });
        for (k, level) in levels.iter().enumerate() {
            cx.queue.write_texture(
                wgpu::TexelCopyTextureInfo {
                    texture: &texture,
                    mip_level: k as u32,
                    origin: wgpu::Origin3d::ZERO,
                    aspect: wgpu::TextureAspect::All,
                },
                bytemuck::cast_slice(level.data()),
                wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(4 * level.width()),
                    rows_per_image: Some(level.height()),
                },
                wgpu::Extent3d { width: level.width(), height: level.height(), depth_or_array_layers: 1 },
            );
        }
        let view = texture.create_view(&wgpu::TextureViewDescriptor::default());
        let group = cx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some(source.name()),
            layout: &cx.shared.material_layout,
            entries: &[wgpu::BindGroupEntry { binding: 0, resource: wgpu::BindingResource::TextureView(&view) }],
        });
        Ok(Self { source: source.clone(), texture, view, group })
    }

    /// The texture it was made from.
    #[must_use]
    pub fn source(&self) -> &Arc<Texture> {
        &self.source
    }
}

/// The textures on the device, by the address of the texture each was made from.
#[derive(Default)]
pub struct DeviceTextures {
    textures: HashMap<usize, TextureGpu>,
}

/// The key of a texture: its address, which names it while the cache holds it.
fn key(texture: &Arc<Texture>) -> usize {
    Arc::as_ptr(texture) as usize
}

impl DeviceTextures {
    /// Uploads the textures `frame`'s instances read that are not on the device yet, and lets go of
    /// those it reads no more (a frame of another scene).
    ///
    /// # Errors
    /// A texture over the device's limit.
    pub fn upload(&mut self, cx: &WgpuContext, frame: &FrameInputs) -> Result<(), WgpuError> {
        let read: HashMap<usize, &Arc<Texture>> =
            frame.instances.iter().filter_map(read_texture).map(|t| (key(t), t)).collect();
        self.textures.retain(|k, _| read.contains_key(k));
        for texture in read.into_values() {
            if let std::collections::hash_map::Entry::Vacant(slot) = self.textures.entry(key(texture)) {
                slot.insert(TextureGpu::upload(cx, texture)?);
            }
        }
        Ok(())
    }

    /// The texture on the device made from `texture` (after [`Self::upload`] of a frame that reads it).
    #[must_use]
    pub fn get(&self, texture: &Arc<Texture>) -> Option<&TextureGpu> {
        self.textures.get(&key(texture))
    }

    /// How many textures are on the device.
    #[must_use]
    pub fn len(&self) -> usize {
        self.textures.len()
    }

    /// True when no texture is on the device.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.textures.is_empty()
    }
}

/// The texture an instance's surface reads: its material's base-colour texture, where the mesh has the
/// coordinates to read it at and the surface is there at all.
#[must_use]
pub fn read_texture(instance: &shadow_core::Instance) -> Option<&Arc<Texture>> {
    let readable = instance.material.base_color_texture.is_some() && instance.mesh.uvs().is_some();
    (readable && instance.coverage() != Coverage::Absent).then_some(instance.base_color_texture.as_ref()).flatten()
}
