//! The scene's texture array on the GPU, sampled with the stored derivatives.

use ::gpu::{GpuError, transfer};

use crate::TextureArray;

/// The [`TextureArray`] on the GPU (`Rgba8UnormSrgb`, all mips) and its anisotropic sampler.
pub struct GpuTextures {
    pub(super) view: wgpu::TextureView,
    pub(super) sampler: wgpu::Sampler,
}

impl GpuTextures {
    /// Uploads `array`; the sampler filters with anisotropy up to `anisotropy` (1..=16).
    pub fn new(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        array: &TextureArray,
        anisotropy: u32,
    ) -> Result<Self, GpuError> {
        transfer::check_texture_size(device, "texture array", array.size, array.size)?;
        let texture = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("texture array"),
            size: wgpu::Extent3d {
                width: array.size,
                height: array.size,
                depth_or_array_layers: array.layers,
            },
            mip_level_count: array.levels(),
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::Rgba8UnormSrgb,
            usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
            view_formats: &[],
        });
        for (level, layers) in array.mips.iter().enumerate() {
            let side = array.size >> level;
            for (layer, texels) in layers.iter().enumerate() {
                queue.write_texture(
                    wgpu::TexelCopyTextureInfo {
                        texture: &texture,
                        mip_level: level as u32,
                        origin: wgpu::Origin3d {
                            x: 0,
                            y: 0,
                            z: layer as u32,
                        },
                        aspect: wgpu::TextureAspect::All,
                    },
                    texels,
                    wgpu::TexelCopyBufferLayout {
                        offset: 0,
                        bytes_per_row: Some(side * 4),
                        rows_per_image: Some(side),
                    },
                    wgpu::Extent3d {
                        width: side,
                        height: side,
                        depth_or_array_layers: 1,
                    },
                );
            }
        }
        let view = texture.create_view(&wgpu::TextureViewDescriptor {
            dimension: Some(wgpu::TextureViewDimension::D2Array),
            ..Default::default()
        });
        let sampler = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("anisotropic"),
            address_mode_u: wgpu::AddressMode::Repeat,
            address_mode_v: wgpu::AddressMode::Repeat,
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            mipmap_filter: wgpu::MipmapFilterMode::Linear,
            anisotropy_clamp: anisotropy.clamp(1, crate::MAX_ANISOTROPY) as u16,
            ..Default::default()
        });
        Ok(Self { view, sampler })
    }
}
