//! The discontinuity buffer and the edge-aware blur of two images in one dispatch (Segovia 2006
//! §4.5): `discontinuity_blur.wgsl`.

use ::gpu::kernel::{self, Binding, Layout};
use ::gpu::shader::Specialisation;
use ::gpu::{transfer, wgpu};

use super::blur::{bilinear, blur_params};
use super::{
    DISCONTINUITY_FORMAT, DiscontinuityPass, IRRADIANCE_FORMAT, Passes, READ, WRITE,
    compute_kernel, groups, pass, view,
};
use crate::{Blur, BlurVariant, InterleaveError, Thresholds};

/// Pixels per side of the kernel's tile (`TILE` in `discontinuity_blur.wgsl`).
const TILE: u32 = 16;

/// `discontinuity_blur.wgsl`'s specialisation for `blur`: its radius and variant.
pub fn specialisation(blur: &Blur) -> Specialisation {
    Specialisation::default()
        .set("RADIUS", blur.radius())
        .set("FAST", blur.variant == BlurVariant::Fast)
}

/// [`DiscontinuityPass`] then [`BlurPass`] of two images (along one walk per pixel: it depends
/// on the discontinuity buffer alone) in one dispatch: each workgroup keeps the discontinuities and the horizontally blurred rows of its
/// tile in workgroup memory, so neither the scratch textures nor a read of the discontinuity
/// buffer is needed. The walks are the two-pass ones; in the vertical direction the fast
/// variant averages its tap pairs exactly (as the CPU twin does) instead of by the sampler.
pub struct DiscontinuityBlurPass {
    pipeline: (wgpu::ComputePipeline, Layout),
    thresholds: wgpu::Buffer,
    params: wgpu::Buffer,
    sampler: wgpu::Sampler,
}

impl DiscontinuityBlurPass {
    /// Builds the pipeline for `thresholds` and `blur`.
    pub fn new(
        device: &wgpu::Device,
        thresholds: &Thresholds,
        blur: &Blur,
    ) -> Result<Self, InterleaveError> {
        blur.validate()?;
        let module =
            crate::SHADERS.module_with(device, "discontinuity_blur.wgsl", &specialisation(blur))?;
        let irradiance = Binding::Texture;
        let output = Binding::StorageTexture(IRRADIANCE_FORMAT);
        let pipeline = compute_kernel(
            device,
            &module,
            "discontinuity_blur",
            &[
                Binding::TextureUnfilterable,
                Binding::TextureUint,
                Binding::StorageTexture(DISCONTINUITY_FORMAT),
                Binding::Uniform,
                Binding::Uniform,
                irradiance,
                irradiance,
                Binding::Sampler,
                output,
                output,
            ],
            &[],
        );
        let thresholds = transfer::buffer_init(
            device,
            "discontinuity thresholds",
            bytemuck::bytes_of(&DiscontinuityPass::uniform(thresholds)?),
            wgpu::BufferUsages::UNIFORM,
        )?;
        Ok(Self {
            pipeline,
            thresholds,
            params: blur_params(device, blur, [1, 0])?,
            sampler: bilinear(device),
        })
    }

    /// The pass writing `discontinuities` ([`DISCONTINUITY_FORMAT`]) from the G-buffer's linear
    /// depth and normal targets, and `irradiance[i]` blurred into `output[i]` (all
    /// [`IRRADIANCE_FORMAT`], the G-buffer's size).
    pub fn bind(
        &self,
        device: &wgpu::Device,
        (linear_depth, normals): (&wgpu::Texture, &wgpu::Texture),
        irradiance: [&wgpu::Texture; 2],
        discontinuities: &wgpu::Texture,
        output: [&wgpu::Texture; 2],
    ) -> Result<Passes, InterleaveError> {
        let size = super::discontinuity::check_targets(linear_depth, normals, discontinuities)?;
        for (irradiance, output) in irradiance.iter().zip(output) {
            kernel::check_texture("irradiance", irradiance, size, IRRADIANCE_FORMAT, READ)?;
            kernel::check_texture("blur output", output, size, IRRADIANCE_FORMAT, WRITE)?;
        }
        let views = [linear_depth, normals, discontinuities].map(view);
        let (images, outputs) = (irradiance.map(view), output.map(view));
        Ok(pass(
            device,
            "discontinuity buffer + blur",
            &self.pipeline,
            &[
                wgpu::BindingResource::TextureView(&views[0]),
                wgpu::BindingResource::TextureView(&views[1]),
                wgpu::BindingResource::TextureView(&views[2]),
                self.thresholds.as_entire_binding(),
                self.params.as_entire_binding(),
                wgpu::BindingResource::TextureView(&images[0]),
                wgpu::BindingResource::TextureView(&images[1]),
                wgpu::BindingResource::Sampler(&self.sampler),
                wgpu::BindingResource::TextureView(&outputs[0]),
                wgpu::BindingResource::TextureView(&outputs[1]),
            ],
            groups(size, TILE),
        ))
    }
}
