//! The scene's texture array on the GPU, drawn from its texture store and sampled with the
//! stored derivatives.

use ::gbuffer::gpu::MaterialTextures;
use ::gpu::{GpuError, transfer};
use scene::ColorSpace;

use crate::{ArrayLayers, TextureArray};

/// The [`TextureArray`] on the GPU (`Rgba8UnormSrgb`, all mips), drawn from the scene's
/// texture store, and its anisotropic sampler.
pub struct GpuTextures {
    texture: wgpu::Texture,
    pub(super) view: wgpu::TextureView,
    pub(super) sampler: wgpu::Sampler,
}

impl GpuTextures {
    /// Draws the array of `layers` from `store`, `size` texels on a side
    /// ([`MaterialTextures::array`]); the sampler repeats and filters with anisotropy up to
    /// `anisotropy` (1..=16).
    pub fn new(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        store: &MaterialTextures,
        layers: &ArrayLayers,
        size: u32,
        anisotropy: u32,
    ) -> Result<Self, GpuError> {
        let texture = store.array(device, queue, &layers.sources, ColorSpace::Srgb, size)?;
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
        Ok(Self {
            texture,
            view,
            sampler,
        })
    }

    /// A one-layer white 1×1 array for passes that bind the array but never sample it
    /// ([`super::Ssaa::evaluation`]).
    pub fn placeholder(device: &wgpu::Device) -> Self {
        let texture = transfer::texture_2d(
            device,
            "texture array placeholder",
            1,
            1,
            wgpu::TextureFormat::Rgba8UnormSrgb,
            wgpu::TextureUsages::TEXTURE_BINDING,
        );
        let view = texture.create_view(&wgpu::TextureViewDescriptor {
            dimension: Some(wgpu::TextureViewDimension::D2Array),
            ..Default::default()
        });
        let sampler = device.create_sampler(&Default::default());
        Self {
            texture,
            view,
            sampler,
        }
    }

    /// Reads every level and layer back: the array the GPU samples, for the CPU twin of the
    /// shading.
    pub fn read(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
    ) -> Result<TextureArray, GpuError> {
        let size = self.texture.width();
        let layers = self.texture.depth_or_array_layers() as usize;
        let mips = (0..self.texture.mip_level_count())
            .map(|level| {
                let all = transfer::read_texture_level(
                    device,
                    queue,
                    &self.texture,
                    wgpu::TextureAspect::All,
                    level,
                )?;
                let layer_bytes = all.len() / layers;
                Ok(all.chunks_exact(layer_bytes).map(<[u8]>::to_vec).collect())
            })
            .collect::<Result<_, GpuError>>()?;
        Ok(TextureArray::from_texels(size, mips))
    }
}
