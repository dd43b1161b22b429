//! The light pre-pass ([`Method::LightPrePass`], thesis §2.1 after Engel 2008) as a comparator:
//! its lighting pass is `tiled.wgsl`'s culling with `METHOD_PREPASS`, bound by the caller with
//! a light buffer ([`LightPrePass::light_buffer`]) as its first output; `light_prepass.wgsl`
//! then draws the scene a second time after the depth pre-pass, applying each fragment's
//! material to the light buffer, into the light accumulation ([`LightPrePass::encode`]).
//!
//! ```no_run
//! use tiled_shading::{Method, ShadingConfig, gpu::{LightShading, light_prepass::LightPrePass}};
//! # fn frame(device: &wgpu::Device, gbuffer: &gbuffer::gpu::GBufferPass,
//! #     scene: &gbuffer::gpu::GpuScene, targets: &gbuffer::gpu::GBufferTargets,
//! #     outputs: [&wgpu::Texture; 2]) -> Result<(), tiled_shading::ShadingError> {
//! let config = ShadingConfig { method: Method::LightPrePass, ..Default::default() };
//! let lighting = LightShading::new(device, &config)?;
//! let light_buffer = LightPrePass::light_buffer(device, targets.width, targets.height);
//! let bound = lighting.bind(device, gbuffer.frame_buffer(), targets.into(),
//!     [&light_buffer, outputs[1]], 1024, false)?;
//! let materials = LightPrePass::new(device, gbuffer)?;
//! let applied = materials.bind(device, &light_buffer)?;
//! let mut encoder = device.create_command_encoder(&Default::default());
//! // … the z-prepass and G-buffer pass into `targets`, then:
//! lighting.encode(&bound, &mut encoder, None);
//! materials.encode(&applied, &mut encoder, (gbuffer, scene), &targets.depth, outputs, None);
//! # Ok(()) }
//! ```

use ::gpu::kernel::{self, Binding, Layout};
use ::gpu::{PassTimer, transfer};
use gbuffer::gpu::{GBufferPass, GpuScene, scene_pipelines};

use super::ACCUMULATION_FORMAT;
use crate::ShadingError;

/// The light pre-pass's second geometry pass, built once on a [`GBufferPass`]'s layouts.
pub struct LightPrePass {
    /// [two-sided, one-sided] pipelines of `fs_light_prepass`.
    pipelines: [wgpu::RenderPipeline; 2],
    layout: Layout,
}

/// A [`LightPrePass`] bound to a light buffer.
pub struct BoundLightPrePass {
    group: wgpu::BindGroup,
}

impl LightPrePass {
    /// Builds the pipelines on `gbuffer`'s frame and material layouts.
    pub fn new(device: &wgpu::Device, gbuffer: &GBufferPass) -> Result<Self, ShadingError> {
        let module = crate::SHADERS.module(device, "light_prepass.wgsl")?;
        let layout = Layout::new(
            device,
            "light buffer",
            wgpu::ShaderStages::FRAGMENT,
            &[Binding::TextureUnfilterable],
        );
        let [frame, material] = gbuffer.layouts();
        let pipeline_layout =
            kernel::pipeline_layout(device, "light pre-pass", &[frame, material, &layout]);
        let target = Some(wgpu::ColorTargetState::from(ACCUMULATION_FORMAT));
        let pipelines = scene_pipelines(
            device,
            "light pre-pass materials",
            &pipeline_layout,
            &module,
            (
                "vs_main",
                Some(("fs_light_prepass", &[target.clone(), target])),
            ),
            (wgpu::CompareFunction::Equal, false),
        );
        Ok(Self { pipelines, layout })
    }

    /// A light buffer of `width × height` ([`ACCUMULATION_FORMAT`]: diffuse light rgb,
    /// monochrome specular a; storage and sampled).
    pub fn light_buffer(device: &wgpu::Device, width: u32, height: u32) -> wgpu::Texture {
        transfer::texture_2d(
            device,
            "light buffer",
            width,
            height,
            ACCUMULATION_FORMAT,
            transfer::STORAGE_OUTPUT,
        )
    }

    /// Binds the pass to `light_buffer` (a [`LightPrePass::light_buffer`]).
    pub fn bind(
        &self,
        device: &wgpu::Device,
        light_buffer: &wgpu::Texture,
    ) -> Result<BoundLightPrePass, ShadingError> {
        let size = (light_buffer.width(), light_buffer.height());
        let usage = wgpu::TextureUsages::TEXTURE_BINDING;
        kernel::check_texture(
            "light buffer",
            light_buffer,
            size,
            ACCUMULATION_FORMAT,
            usage,
        )?;
        let view = light_buffer.create_view(&Default::default());
        let group = self
            .layout
            .bind(device, &[wgpu::BindingResource::TextureView(&view)]);
        Ok(BoundLightPrePass { group })
    }

    /// Records the second geometry pass: `outputs` (the light accumulation's diffuse and
    /// specular, render attachments of [`ACCUMULATION_FORMAT`], the light buffer's size)
    /// cleared, then `scene` drawn with the camera of `gbuffer`'s frame against `depth`, the
    /// depth pre-pass's buffer (loaded, `Equal`), timed as `light pre-pass materials`.
    pub fn encode(
        &self,
        bound: &BoundLightPrePass,
        encoder: &mut wgpu::CommandEncoder,
        (gbuffer, scene): (&GBufferPass, &GpuScene),
        depth: &wgpu::Texture,
        outputs: [&wgpu::Texture; 2],
        timer: Option<&PassTimer>,
    ) {
        super::draw_into_accumulation(
            encoder,
            "light pre-pass materials",
            (gbuffer, scene),
            depth,
            outputs,
            &[&bound.group],
            &self.pipelines,
            timer,
        );
    }
}
