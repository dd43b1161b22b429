//! Interleaved shading of subsets of lights (Segovia 2006 §3.1, §4): `shade.wgsl`, on the
//! split G-buffer or fused with the split by strided addressing.

use ::gpu::kernel::{self, Binding, Layout};
use ::gpu::{transfer, wgpu};

use super::{IRRADIANCE_FORMAT, Passes, WRITE, compute_kernel, groups, pass, view};
use crate::cpu::SubsetLight;
use crate::{InterleaveError, Pattern, SplitLayout};

/// Lights per sub-buffer subset: `count / (n·m)`, which must be a whole number ≥ 1.
pub fn lights_per_subset(count: usize, pattern: Pattern) -> Result<u32, InterleaveError> {
    let subsets = pattern.count();
    if count == 0
        || !count.is_multiple_of(subsets as usize)
        || count / subsets as usize > u32::MAX as usize
    {
        return Err(InterleaveError::Lights { count, subsets });
    }
    Ok((count / subsets as usize) as u32)
}

/// The probe shader of [`crate::cpu::shade_subsets`] on the GPU, on the split G-buffer (then
/// gathered) or fused with the split by strided addressing (§3.1's indirection).
pub struct SubsetShading {
    layout: SplitLayout,
    split_pipeline: (wgpu::ComputePipeline, Layout),
    fused_pipeline: (wgpu::ComputePipeline, Layout),
    lights: wgpu::Buffer,
}

impl SubsetShading {
    /// Uploads `lights` (n·m equal subsets) and builds both pipelines.
    pub fn new(
        device: &wgpu::Device,
        layout: &SplitLayout,
        lights: &[SubsetLight],
    ) -> Result<Self, InterleaveError> {
        let per_subset = lights_per_subset(lights.len(), layout.pattern)?;
        let module = crate::SHADERS.module(device, "shade.wgsl")?;
        let bindings = [
            Binding::TextureUnfilterable,
            Binding::TextureUint,
            Binding::StorageRead,
            Binding::StorageTexture(IRRADIANCE_FORMAT),
        ];
        let constants = [
            ("width", f64::from(layout.width)),
            ("height", f64::from(layout.height)),
            ("n", f64::from(layout.pattern.n)),
            ("m", f64::from(layout.pattern.m)),
            ("sub_width", f64::from(layout.sub_width)),
            ("sub_height", f64::from(layout.sub_height)),
            ("per_subset", f64::from(per_subset)),
        ];
        let lights = transfer::buffer_init(
            device,
            "subset lights",
            bytemuck::cast_slice(lights),
            wgpu::BufferUsages::STORAGE,
        )?;
        Ok(Self {
            layout: *layout,
            split_pipeline: compute_kernel(device, &module, "shade_split", &bindings, &constants),
            fused_pipeline: compute_kernel(device, &module, "shade_fused", &bindings, &constants),
            lights,
        })
    }

    fn bind(
        &self,
        device: &wgpu::Device,
        name: &str,
        pipeline: &(wgpu::ComputePipeline, Layout),
        size: (u32, u32),
        textures: [&wgpu::Texture; 3],
    ) -> Result<Passes, InterleaveError> {
        let [depth, normals, irradiance] = textures;
        super::check_gbuffer(depth, normals, size)?;
        kernel::check_texture("irradiance", irradiance, size, IRRADIANCE_FORMAT, WRITE)?;
        let (d, nrm, out) = (view(depth), view(normals), view(irradiance));
        let l = &self.layout;
        Ok(pass(
            device,
            name,
            pipeline,
            &[
                wgpu::BindingResource::TextureView(&d),
                wgpu::BindingResource::TextureView(&nrm),
                self.lights.as_entire_binding(),
                wgpu::BindingResource::TextureView(&out),
            ],
            groups((l.split_width(), l.split_height()), 16),
        ))
    }

    /// Shades the split G-buffer (split size) into split irradiance.
    pub fn shade_split(
        &self,
        device: &wgpu::Device,
        split_depth: &wgpu::Texture,
        split_normals: &wgpu::Texture,
        split_irradiance: &wgpu::Texture,
    ) -> Result<Passes, InterleaveError> {
        let l = &self.layout;
        self.bind(
            device,
            "shade split",
            &self.split_pipeline,
            (l.split_width(), l.split_height()),
            [split_depth, split_normals, split_irradiance],
        )
    }

    /// Shades the interleaved G-buffer in sub-buffer order by strided addressing, writing the
    /// interleaved irradiance directly (no split, no gather).
    pub fn shade_fused(
        &self,
        device: &wgpu::Device,
        depth: &wgpu::Texture,
        normals: &wgpu::Texture,
        irradiance: &wgpu::Texture,
    ) -> Result<Passes, InterleaveError> {
        let l = &self.layout;
        self.bind(
            device,
            "shade fused",
            &self.fused_pipeline,
            (l.width, l.height),
            [depth, normals, irradiance],
        )
    }
}
