//! The discontinuity buffer (Segovia 2006 §4.5): `discontinuity.wgsl`.

use ::gpu::kernel::{self, Binding, Layout};
use ::gpu::{transfer, wgpu};
use bytemuck::Pod;

use super::{DISCONTINUITY_FORMAT, Passes, WRITE, compute_kernel, groups, pass, view};
use crate::{InterleaveError, Thresholds};

/// Uniform block of `discontinuity.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Pod, bytemuck::Zeroable)]
pub(super) struct ThresholdsUniform {
    cos_squared: f32,
    cos_positive: u32,
    depth_factor: f32,
    _pad: u32,
}

/// The discontinuity buffer kernel (§4.5).
pub struct DiscontinuityPass {
    pipeline: (wgpu::ComputePipeline, Layout),
    thresholds: wgpu::Buffer,
}

impl DiscontinuityPass {
    /// Builds the pipeline with `thresholds` (change them with [`Self::set_thresholds`]).
    pub fn new(device: &wgpu::Device, thresholds: &Thresholds) -> Result<Self, InterleaveError> {
        let module = crate::SHADERS.module(device, "discontinuity.wgsl")?;
        let pipeline = compute_kernel(
            device,
            &module,
            "discontinuity",
            &[
                Binding::TextureUnfilterable,
                Binding::TextureUint,
                Binding::StorageTexture(DISCONTINUITY_FORMAT),
                Binding::Uniform,
            ],
            &[],
        );
        let thresholds = transfer::buffer_init(
            device,
            "discontinuity thresholds",
            bytemuck::bytes_of(&Self::uniform(thresholds)?),
            wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        )?;
        Ok(Self {
            pipeline,
            thresholds,
        })
    }

    pub(super) fn uniform(t: &Thresholds) -> Result<ThresholdsUniform, InterleaveError> {
        t.validate()?;
        let (cos_squared, positive) = t.cos_squared();
        Ok(ThresholdsUniform {
            cos_squared,
            cos_positive: u32::from(positive),
            depth_factor: t.depth_factor(),
            _pad: 0,
        })
    }

    /// New thresholds for the following submissions.
    pub fn set_thresholds(
        &self,
        queue: &wgpu::Queue,
        t: &Thresholds,
    ) -> Result<(), InterleaveError> {
        queue.write_buffer(&self.thresholds, 0, bytemuck::bytes_of(&Self::uniform(t)?));
        Ok(())
    }

    /// The pass writing `discontinuities` ([`DISCONTINUITY_FORMAT`]) from the G-buffer's linear
    /// depth and normal targets.
    pub fn bind(
        &self,
        device: &wgpu::Device,
        linear_depth: &wgpu::Texture,
        normals: &wgpu::Texture,
        discontinuities: &wgpu::Texture,
    ) -> Result<Passes, InterleaveError> {
        let size = check_targets(linear_depth, normals, discontinuities)?;
        let (d, nrm, out) = (view(linear_depth), view(normals), view(discontinuities));
        Ok(pass(
            device,
            "discontinuity buffer",
            &self.pipeline,
            &[
                wgpu::BindingResource::TextureView(&d),
                wgpu::BindingResource::TextureView(&nrm),
                wgpu::BindingResource::TextureView(&out),
                self.thresholds.as_entire_binding(),
            ],
            groups(size, 16),
        ))
    }
}

/// Checks the G-buffer's linear depth and normal targets and the discontinuity buffer written
/// from them (same size); returns the size.
pub(super) fn check_targets(
    linear_depth: &wgpu::Texture,
    normals: &wgpu::Texture,
    discontinuities: &wgpu::Texture,
) -> Result<(u32, u32), InterleaveError> {
    let size = (linear_depth.width(), linear_depth.height());
    super::check_gbuffer(linear_depth, normals, size)?;
    kernel::check_texture(
        "discontinuity buffer",
        discontinuities,
        size,
        DISCONTINUITY_FORMAT,
        WRITE,
    )?;
    Ok(size)
}
