//! The supersampled G-buffer (`shaders/adaptive-ssaa/gbuffer.wgsl`): the G-buffer pass's vertex
//! stage and material with a fragment stage that writes texture coordinates and their
//! derivatives instead of albedo and emission.

use ::gbuffer::gpu::{GBufferPass, GpuScene, begin_scene_pass, scene_pipeline};
use ::gbuffer::{DEPTH_FORMAT, Image, LINEAR_DEPTH_FORMAT, MATERIAL_FORMAT, NORMAL_FORMAT};
use ::gpu::kernel;
use ::gpu::{GpuError, transfer};

use crate::cpu::SsGBuffer;
use crate::{TINT_FORMAT, UV_FORMAT, UV_GRAD_FORMAT};

/// The supersampled G-buffer's targets, `(m·w) × (m·h)` samples.
pub struct SsGBufferTargets {
    /// Width in samples.
    pub width: u32,
    /// Height in samples.
    pub height: u32,
    /// Hardware depth.
    pub depth: wgpu::Texture,
    /// View depth.
    pub linear_depth: wgpu::Texture,
    /// Octahedral normal words.
    pub normal: wgpu::Texture,
    /// Texture coordinates.
    pub uv: wgpu::Texture,
    /// Texture-coordinate derivatives.
    pub uv_grad: wgpu::Texture,
    /// Material words.
    pub material: wgpu::Texture,
    /// Vertex colour and occlusion words.
    pub tint: wgpu::Texture,
}

impl SsGBufferTargets {
    /// Creates the targets (rendered to, sampled, copied).
    pub fn new(device: &wgpu::Device, width: u32, height: u32) -> Result<Self, GpuError> {
        transfer::check_texture_size(device, "supersampled G-buffer", width, height)?;
        let make = |label: &str, format| {
            transfer::texture_2d(
                device,
                label,
                width,
                height,
                format,
                wgpu::TextureUsages::RENDER_ATTACHMENT
                    | wgpu::TextureUsages::TEXTURE_BINDING
                    | wgpu::TextureUsages::COPY_SRC,
            )
        };
        Ok(Self {
            width,
            height,
            depth: make("ss depth", DEPTH_FORMAT),
            linear_depth: make("ss linear depth", LINEAR_DEPTH_FORMAT),
            normal: make("ss normal", NORMAL_FORMAT),
            uv: make("ss uv", UV_FORMAT),
            uv_grad: make("ss uv grad", UV_GRAD_FORMAT),
            material: make("ss material", MATERIAL_FORMAT),
            tint: make("ss tint", TINT_FORMAT),
        })
    }

    /// Reads the targets back (derivatives widened from f16).
    pub fn read(&self, device: &wgpu::Device, queue: &wgpu::Queue) -> Result<SsGBuffer, GpuError> {
        let read =
            |t: &wgpu::Texture| transfer::read_texture(device, queue, t, wgpu::TextureAspect::All);
        fn image<T: Copy>(w: u32, h: u32, data: Vec<T>) -> Result<Image<T>, GpuError> {
            Image::from_vec(w, h, data).map_err(|e| GpuError::Readback(e.to_string()))
        }
        let (w, h) = (self.width, self.height);
        let words =
            |t| -> Result<Vec<u32>, GpuError> { Ok(bytemuck::cast_slice(&read(t)?).to_vec()) };
        let uv: Vec<f32> = bytemuck::cast_slice(&read(&self.uv)?).to_vec();
        let grad: Vec<half::f16> = bytemuck::cast_slice(&read(&self.uv_grad)?).to_vec();
        Ok(SsGBuffer {
            linear_depth: image(
                w,
                h,
                words(&self.linear_depth)?
                    .into_iter()
                    .map(f32::from_bits)
                    .collect(),
            )?,
            normal: image(w, h, words(&self.normal)?)?,
            uv: image(w, h, uv.chunks_exact(2).map(|c| [c[0], c[1]]).collect())?,
            uv_grad: image(
                w,
                h,
                grad.chunks_exact(4)
                    .map(|c| [c[0], c[1], c[2], c[3]].map(f32::from))
                    .collect(),
            )?,
            material: image(w, h, words(&self.material)?)?,
            tint: image(w, h, words(&self.tint)?)?,
        })
    }
}

/// The supersampled G-buffer pass: render pipelines on the G-buffer pass's layouts with the
/// `fs_texcoord` fragment stage, [two-sided, one-sided] (glTF `doubleSided`).
pub struct SsGBufferPass {
    pipelines: [wgpu::RenderPipeline; 2],
}

impl SsGBufferPass {
    /// Builds the pipeline for scenes uploaded with `gbuffer_pass`.
    pub fn new(device: &wgpu::Device, gbuffer_pass: &GBufferPass) -> Result<Self, GpuError> {
        let module = crate::SHADERS.module(device, "gbuffer.wgsl")?;
        let [frame, material] = gbuffer_pass.layouts();
        let layout = kernel::pipeline_layout(device, "ss gbuffer", &[frame, material]);
        let targets = [
            LINEAR_DEPTH_FORMAT,
            NORMAL_FORMAT,
            UV_FORMAT,
            MATERIAL_FORMAT,
            UV_GRAD_FORMAT,
            TINT_FORMAT,
        ];
        let stages = ("vs_main", Some(("fs_texcoord", &targets[..])));
        let depth = (wgpu::CompareFunction::Less, true);
        let pipelines = [false, true].map(|cull| {
            scene_pipeline(device, "ss gbuffer", &layout, &module, stages, depth, cull)
        });
        Ok(Self { pipelines })
    }

    /// Records the pass: clears every target and draws `scene` with the frame
    /// `gbuffer_pass` holds (write it at the sample resolution).
    pub fn encode(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        gbuffer_pass: &GBufferPass,
        scene: &GpuScene,
        targets: &SsGBufferTargets,
        timestamp_writes: Option<wgpu::RenderPassTimestampWrites<'_>>,
    ) {
        let colour = [
            (&targets.linear_depth, 0.0),
            (&targets.normal, 0.0),
            (&targets.uv, 0.0),
            (&targets.material, f64::from(::gbuffer::NO_MATERIAL)),
            (&targets.uv_grad, 0.0),
            (&targets.tint, 0.0),
        ];
        let depth = (&targets.depth, true);
        let mut pass = begin_scene_pass(encoder, "ss gbuffer", &colour, depth, timestamp_writes);
        let [two_sided, one_sided] = &self.pipelines;
        gbuffer_pass.draw_scene(&mut pass, [two_sided, one_sided], scene);
    }
}
