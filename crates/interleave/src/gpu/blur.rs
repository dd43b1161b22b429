//! The edge-aware separable Gaussian blur (Segovia 2006 §4.5): `blur.wgsl`.

use ::gpu::kernel::{self, Binding, Layout};
use ::gpu::{transfer, wgpu};
use bytemuck::Pod;

use super::{
    DISCONTINUITY_FORMAT, IRRADIANCE_FORMAT, Passes, READ, USAGE, WRITE, compute_kernel, groups,
    pass, view,
};
use crate::{Blur, BlurVariant, InterleaveError};

/// Uniform block of `blur_params.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Pod, bytemuck::Zeroable)]
struct BlurUniform {
    direction: [i32; 2],
    radius: i32,
    _pad: i32,
    weights: [f32; 12],
}

/// `blur`'s uniform buffer for `direction` ((1, 0) horizontal, (0, 1) vertical).
pub(super) fn blur_params(
    device: &wgpu::Device,
    blur: &Blur,
    direction: [i32; 2],
) -> Result<wgpu::Buffer, ::gpu::GpuError> {
    let mut weights = [0.0; 12];
    for (w, v) in weights.iter_mut().zip(blur.weights()) {
        *w = v;
    }
    transfer::buffer_init(
        device,
        "blur params",
        bytemuck::bytes_of(&BlurUniform {
            direction,
            radius: blur.radius() as i32,
            _pad: 0,
            weights,
        }),
        wgpu::BufferUsages::UNIFORM,
    )
}

/// The blur's bilinear sampler (the fast variant's paired taps).
pub(super) fn bilinear(device: &wgpu::Device) -> wgpu::Sampler {
    device.create_sampler(&wgpu::SamplerDescriptor {
        label: Some("blur bilinear"),
        mag_filter: wgpu::FilterMode::Linear,
        min_filter: wgpu::FilterMode::Linear,
        ..Default::default()
    })
}

/// The edge-aware separable Gaussian blur (§4.5): a horizontal and a vertical pass.
pub struct BlurPass {
    blur: Blur,
    pipeline: (wgpu::ComputePipeline, Layout),
    params: [wgpu::Buffer; 2],
    sampler: wgpu::Sampler,
}

impl BlurPass {
    /// Builds the pipeline of `blur`'s variant.
    pub fn new(device: &wgpu::Device, blur: &Blur) -> Result<Self, InterleaveError> {
        blur.validate()?;
        let module = crate::SHADERS.module(device, "blur.wgsl")?;
        let (texture, entry) = match blur.variant {
            BlurVariant::Plain => (Binding::TextureUnfilterable, "blur_plain"),
            BlurVariant::Fast => (Binding::Texture, "blur_fast"),
        };
        // irradiance, discontinuities, blurred, params, bilinear (the fast kernel's only).
        let bindings = [
            texture,
            texture,
            Binding::StorageTexture(IRRADIANCE_FORMAT),
            Binding::Uniform,
            Binding::Sampler,
        ];
        let bindings = match blur.variant {
            BlurVariant::Plain => &bindings[..4],
            BlurVariant::Fast => &bindings[..],
        };
        let pipeline = compute_kernel(device, &module, entry, bindings, &[]);
        let [h, v] = [[1, 0], [0, 1]].map(|direction| blur_params(device, blur, direction));
        let sampler = bilinear(device);
        Ok(Self {
            blur: *blur,
            pipeline,
            params: [h?, v?],
            sampler,
        })
    }

    /// An [`IRRADIANCE_FORMAT`] texture of `width × height` (blur input, scratch or output).
    pub fn irradiance_texture(
        device: &wgpu::Device,
        label: &str,
        width: u32,
        height: u32,
    ) -> wgpu::Texture {
        transfer::texture_2d(device, label, width, height, IRRADIANCE_FORMAT, USAGE)
    }

    /// Passes blurring `irradiance` into `output` through `scratch` (all [`IRRADIANCE_FORMAT`],
    /// same size), guided by `discontinuities`.
    pub fn bind(
        &self,
        device: &wgpu::Device,
        irradiance: &wgpu::Texture,
        discontinuities: &wgpu::Texture,
        scratch: &wgpu::Texture,
        output: &wgpu::Texture,
    ) -> Result<Passes, InterleaveError> {
        let size = (irradiance.width(), irradiance.height());
        kernel::check_texture("irradiance", irradiance, size, IRRADIANCE_FORMAT, READ)?;
        kernel::check_texture("blur scratch", scratch, size, IRRADIANCE_FORMAT, READ)?;
        kernel::check_texture("blur scratch", scratch, size, IRRADIANCE_FORMAT, WRITE)?;
        kernel::check_texture("blur output", output, size, IRRADIANCE_FORMAT, WRITE)?;
        kernel::check_texture(
            "discontinuity buffer",
            discontinuities,
            size,
            DISCONTINUITY_FORMAT,
            READ,
        )?;
        let disc = view(discontinuities);
        let [h, v] = &self.params;
        let one = |name: &str, from: &wgpu::Texture, to: &wgpu::Texture, params: &wgpu::Buffer| {
            let (from, to) = (view(from), view(to));
            let mut resources = vec![
                wgpu::BindingResource::TextureView(&from),
                wgpu::BindingResource::TextureView(&disc),
                wgpu::BindingResource::TextureView(&to),
                params.as_entire_binding(),
            ];
            if self.blur.variant == BlurVariant::Fast {
                resources.push(wgpu::BindingResource::Sampler(&self.sampler));
            }
            pass(device, name, &self.pipeline, &resources, groups(size, 16))
        };
        Ok(one("blur horizontal", irradiance, scratch, h).then(one(
            "blur vertical",
            scratch,
            output,
            v,
        )))
    }
}
