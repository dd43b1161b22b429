//! SMAA 1x beside adaptive supersampling: the `smaa` crate (Jimenez et al. 2012, its reference
//! shaders) on the same device, anti-aliasing `S`, the one-sample image the adaptive path shades
//! first. `S` is drawn into SMAA's colour target — the pass an application's scene pass would be
//! — and SMAA's three passes resolve it into an sRGB texture that is read back.
//!
//! The crate submits its passes itself (its frame's drop records and submits its own command
//! buffer), so its GPU time is bracketed: the end timestamp of the pass before its submission and
//! the begin timestamp of an empty pass after it. A full-supersampling pass recorded first keeps
//! the GPU busy while the CPU records and submits SMAA's work, so the bracket holds SMAA's passes
//! and the queue's gap between two submissions, not CPU time; [`Smaa::time`] with `smaa: false`
//! measures that bracket around an empty submission (the floor).

use adaptive_ssaa::gpu::Ssaa;
use anyhow::{Context, Result};
use gbuffer::Image;
use gpu::{Gpu, PassTimer};

/// The colour format of SMAA's targets: 8-bit sRGB, what the crate's example presents.
const FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8UnormSrgb;

/// Draws `S` (`w·h` RGBA32F, row-major) into a colour target, clamped to [0, 1].
const INPUT_WGSL: &str = r"
override width: u32;
@group(0) @binding(0) var<storage, read> first: array<vec4<f32>>;

@vertex
fn vs(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let corner = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4<f32>(corner * 2.0 - 1.0, 0.0, 1.0);
}

@fragment
fn fs(@builtin(position) p: vec4<f32>) -> @location(0) vec4<f32> {
    let s = first[u32(p.y) * width + u32(p.x)];
    return vec4<f32>(clamp(s.rgb, vec3<f32>(0.0), vec3<f32>(1.0)), 1.0);
}
";

/// The SMAA 1x baseline on one [`Ssaa`]'s `S`.
pub struct Smaa {
    target: smaa::SmaaTarget,
    input: wgpu::RenderPipeline,
    group: wgpu::BindGroup,
    output: wgpu::Texture,
    output_view: wgpu::TextureView,
}

impl Smaa {
    /// SMAA's targets at the size of `ssaa`, reading its `S`.
    pub fn new(gpu: &Gpu, ssaa: &Ssaa, width: u32, height: u32) -> Self {
        let device = &gpu.device;
        let target = smaa::SmaaTarget::new(
            device,
            &gpu.queue,
            width,
            height,
            FORMAT,
            smaa::SmaaMode::Smaa1X,
        );
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("smaa input"),
            source: wgpu::ShaderSource::Wgsl(INPUT_WGSL.into()),
        });
        let constants = [("width", f64::from(width))];
        let compilation_options = wgpu::PipelineCompilationOptions {
            constants: &constants,
            ..Default::default()
        };
        let input = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("smaa input"),
            layout: None,
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs"),
                compilation_options: compilation_options.clone(),
                buffers: &[],
            },
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("fs"),
                compilation_options,
                targets: &[Some(FORMAT.into())],
            }),
            primitive: Default::default(),
            depth_stencil: None,
            multisample: Default::default(),
            multiview_mask: None,
            cache: None,
        });
        let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("smaa input"),
            layout: &input.get_bind_group_layout(0),
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: ssaa.first().as_entire_binding(),
            }],
        });
        let output = gpu::transfer::texture_2d(
            device,
            "smaa output",
            width,
            height,
            FORMAT,
            wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
        );
        let output_view = output.create_view(&Default::default());
        Self {
            target,
            input,
            group,
            output,
            output_view,
        }
    }

    /// One frame: full supersampling (untimed, it keeps the GPU busy), `S` shaded (timed), `S`
    /// drawn into SMAA's colour target (timed), then — with `smaa` — SMAA's own submission,
    /// else an empty one (`S` drawn into the output instead), and an empty timed pass. Returns
    /// the ms of `S`'s shading plus the bracket from the end of the drawing of `S` to the begin
    /// of the empty pass.
    pub fn time(&mut self, gpu: &Gpu, ssaa: &Ssaa, timer: &PassTimer, smaa: bool) -> Result<f64> {
        let (device, queue) = (&gpu.device, &gpu.queue);
        let frame = smaa.then(|| self.target.start_frame(device, queue, &self.output_view));
        // Without SMAA, `S` goes straight to the output.
        let view: &wgpu::TextureView = frame.as_deref().unwrap_or(&self.output_view);
        let mut encoder = device.create_command_encoder(&Default::default());
        ssaa.encode_full(&mut encoder, None);
        ssaa.encode_first(&mut encoder, Some(timer));
        {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("smaa input"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view,
                    resolve_target: None,
                    depth_slice: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: None,
                timestamp_writes: timer.render_pass("smaa input"),
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(&self.input);
            pass.set_bind_group(0, &self.group, &[]);
            pass.draw(0..3, 0..1);
        }
        queue.submit([encoder.finish()]);
        match frame {
            Some(frame) => frame.resolve(),
            None => {
                queue.submit([]);
            }
        }
        let mut encoder = device.create_command_encoder(&Default::default());
        encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("after smaa"),
            timestamp_writes: timer.compute_pass("after smaa"),
        });
        timer.resolve(&mut encoder);
        queue.submit([encoder.finish()]);
        let times = timer.read(device, queue)?;
        let find = |name: &str| {
            times.iter().find(|t| t.name == name).with_context(|| {
                format!("no timestamp for {name} (the device lacks TIMESTAMP_QUERY?)")
            })
        };
        let first = find("shade first")?;
        let input = find("smaa input")?;
        let after = find("after smaa")?;
        Ok(first.ms + (after.start_ms - input.end_ms()))
    }

    /// The last SMAA output, as linear RGBA.
    pub fn read(&self, gpu: &Gpu) -> Result<Image<[f32; 4]>> {
        let bytes = gpu::transfer::read_texture(
            &gpu.device,
            &gpu.queue,
            &self.output,
            wgpu::TextureAspect::All,
        )?;
        let linear = |b: u8| scene::srgb_to_linear(f32::from(b) / 255.0);
        let texels = bytes
            .chunks_exact(4)
            .map(|p| [linear(p[0]), linear(p[1]), linear(p[2]), 1.0])
            .collect();
        let size = self.output.size();
        Ok(Image::from_vec(size.width, size.height, texels)?)
    }
}
