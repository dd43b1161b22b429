//! The G-buffer targets: rendered by the pass, read by every shading kernel.

use ::gpu::{GpuError, transfer};

use crate::{
    ALBEDO_FORMAT, DEPTH_FORMAT, EMISSION_FORMAT, Frame, GBuffer, GBufferError, Image,
    LINEAR_DEPTH_FORMAT, MATERIAL_FORMAT, NORMAL_FORMAT,
};

/// The six G-buffer textures of one resolution (see the layout table in the crate docs).
#[derive(Clone)]
pub struct GBufferTargets {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Hardware depth.
    pub depth: wgpu::Texture,
    /// View-space depth.
    pub linear_depth: wgpu::Texture,
    /// Octahedral normal word.
    pub normal: wgpu::Texture,
    /// Albedo.
    pub albedo: wgpu::Texture,
    /// Material word.
    pub material: wgpu::Texture,
    /// Emission and occlusion.
    pub emission: wgpu::Texture,
}

impl GBufferTargets {
    /// Creates the targets; they can be rendered to, sampled, bound as storage (colour
    /// targets) and copied.
    pub fn new(device: &wgpu::Device, width: u32, height: u32) -> Result<Self, GpuError> {
        transfer::check_texture_size(device, "G-buffer", width, height)?;
        let make = |label: &str, format: wgpu::TextureFormat, storage: bool| {
            let mut usage = wgpu::TextureUsages::RENDER_ATTACHMENT
                | wgpu::TextureUsages::TEXTURE_BINDING
                | wgpu::TextureUsages::COPY_SRC;
            if storage {
                usage |= wgpu::TextureUsages::STORAGE_BINDING;
            }
            transfer::texture_2d(device, label, width, height, format, usage)
        };
        Ok(Self {
            width,
            height,
            depth: make("gbuffer depth", DEPTH_FORMAT, false),
            linear_depth: make("gbuffer linear depth", LINEAR_DEPTH_FORMAT, true),
            normal: make("gbuffer normal", NORMAL_FORMAT, true),
            albedo: make("gbuffer albedo", ALBEDO_FORMAT, true),
            material: make("gbuffer material", MATERIAL_FORMAT, true),
            emission: make("gbuffer emission", EMISSION_FORMAT, true),
        })
    }

    /// Total bytes of all targets (for bandwidth figures).
    pub fn bytes(&self) -> u64 {
        u64::from(self.width) * u64::from(self.height) * 28
    }

    /// Reads every target back into a CPU [`GBuffer`].
    pub fn read(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
    ) -> Result<GBuffer, GBufferError> {
        let read = |t: &wgpu::Texture, aspect| transfer::read_texture(device, queue, t, aspect);
        let all = wgpu::TextureAspect::All;
        let img = |bytes: Vec<u8>| -> Result<Image<u32>, GBufferError> {
            Image::from_vec(
                self.width,
                self.height,
                bytemuck::pod_collect_to_vec(&bytes),
            )
            .map_err(|e| GBufferError::Gpu(GpuError::Readback(e.to_string())))
        };
        let as_f32 = |i: Image<u32>| i.map(f32::from_bits);
        Ok(GBuffer {
            depth: as_f32(img(read(&self.depth, wgpu::TextureAspect::DepthOnly)?)?),
            linear_depth: as_f32(img(read(&self.linear_depth, all)?)?),
            normal: img(read(&self.normal, all)?)?,
            albedo: img(read(&self.albedo, all)?)?.map(u32::to_le_bytes),
            material: img(read(&self.material, all)?)?,
            emission: {
                let halves: Vec<half::f16> =
                    bytemuck::pod_collect_to_vec(&read(&self.emission, all)?);
                let texels = halves
                    .chunks_exact(4)
                    .map(|c| [0, 1, 2, 3].map(|k| c[k].to_f32()))
                    .collect();
                Image::from_vec(self.width, self.height, texels)
                    .map_err(|e| GBufferError::Gpu(GpuError::Readback(e.to_string())))?
            },
        })
    }
}

/// The G-buffer textures a screen-space pass reads (linear depth, normal, albedo, material),
/// borrowed from [`GBufferTargets`] or from an [`UploadedGBuffer`].
#[derive(Clone, Copy)]
pub struct GBufferTextures<'a> {
    /// `R32Float` view depth (0 where no surface).
    pub linear_depth: &'a wgpu::Texture,
    /// `R32Uint` octahedral normals.
    pub normal: &'a wgpu::Texture,
    /// `Rgba8Unorm` albedo.
    pub albedo: &'a wgpu::Texture,
    /// `R32Uint` material words.
    pub material: &'a wgpu::Texture,
}

impl<'a> From<&'a GBufferTargets> for GBufferTextures<'a> {
    fn from(t: &'a GBufferTargets) -> Self {
        Self {
            linear_depth: &t.linear_depth,
            normal: &t.normal,
            albedo: &t.albedo,
            material: &t.material,
        }
    }
}

/// A CPU [`GBuffer`]'s screen-space textures and its [`Frame`] uniform, uploaded as they are
/// (for running a pass on the same input as its CPU twin).
pub struct UploadedGBuffer {
    /// The frame uniform (`gbuffer/frame.wgsl`).
    pub frame: wgpu::Buffer,
    /// View depth.
    pub linear_depth: wgpu::Texture,
    /// Octahedral normal words.
    pub normal: wgpu::Texture,
    /// Albedo.
    pub albedo: wgpu::Texture,
    /// Material words.
    pub material: wgpu::Texture,
}

impl UploadedGBuffer {
    /// Uploads `frame` and `gb`'s linear depth, normal, albedo and material images (sampled
    /// and copied).
    pub fn new(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        gb: &GBuffer,
        frame: &Frame,
    ) -> Result<Self, GpuError> {
        let usage = wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_SRC;
        let upload = |label: &str, format, bytes: &[u8]| {
            transfer::texture_init(
                device,
                queue,
                label,
                gb.width(),
                gb.height(),
                format,
                usage,
                bytes,
            )
        };
        Ok(Self {
            frame: transfer::buffer_init(
                device,
                "frame",
                bytemuck::bytes_of(frame),
                wgpu::BufferUsages::UNIFORM,
            )?,
            linear_depth: upload(
                "linear depth",
                LINEAR_DEPTH_FORMAT,
                bytemuck::cast_slice(gb.linear_depth.pixels()),
            )?,
            normal: upload(
                "normal",
                NORMAL_FORMAT,
                bytemuck::cast_slice(gb.normal.pixels()),
            )?,
            albedo: upload(
                "albedo",
                ALBEDO_FORMAT,
                bytemuck::cast_slice(gb.albedo.pixels()),
            )?,
            material: upload(
                "material",
                MATERIAL_FORMAT,
                bytemuck::cast_slice(gb.material.pixels()),
            )?,
        })
    }

    /// The textures to bind.
    pub fn textures(&self) -> GBufferTextures<'_> {
        GBufferTextures {
            linear_depth: &self.linear_depth,
            normal: &self.normal,
            albedo: &self.albedo,
            material: &self.material,
        }
    }
}
