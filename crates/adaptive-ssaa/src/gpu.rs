//! Adaptive supersampling on the GPU: the supersampled G-buffer is one render pass
//! (`shaders/adaptive-ssaa/gbuffer.wgsl`, the G-buffer's vertex stage with a texture-coordinate
//! fragment stage); the rest are compute passes of `shaders/adaptive-ssaa/ssaa.wgsl`:
//! `shade_first` → `evaluate` → `shade_adaptive` (or the sorted resolve `sort_count` →
//! `sort_scan` → `sort_scatter` → `shade_sorted`), and the baselines `shade_full` and `fxaa`.
//! Pipelines, buffers and bind groups are built once per image size; nothing is read back
//! between passes (the sorted resolve sizes its last dispatch indirectly).

use ::gpu::kernel::{self, Binding, Layout, Passes, Workgroups};
use ::gpu::{Gpu, GpuError, PassTimer, transfer};
use gbuffer::gpu::{GBufferPass, GpuScene};
use gbuffer::{DEPTH_FORMAT, Frame, Image, LINEAR_DEPTH_FORMAT, MATERIAL_FORMAT, NORMAL_FORMAT};
use scene::{Camera, Scene};
use tiled_shading::GpuLight;

use crate::cpu::{Output, SsGBuffer};
use crate::{
    Resolve, SsaaConfig, SsaaError, SsaaMaterial, TextureArray, UV_FORMAT, UV_GRAD_FORMAT,
    dither_order,
};

/// Side of the largest texture-array layer [`run`] builds.
pub const TEXTURE_SIZE: u32 = 1024;

/// Uniform block of `ssaa.wgsl` (`Params`).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct SsaaParams {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Window side.
    pub m: u32,
    /// Samples per window.
    pub n: u32,
    /// 0 none, 1 MM, 2 NC, 3 DV, 4 NV, 5 ND.
    pub metric: u32,
    /// 1 when the shading metric is on.
    pub shading_on: u32,
    /// [`SsaaConfig::min_samples`].
    pub min_samples: u32,
    /// [`SsaaConfig::stall`].
    pub stall: u32,
    /// Constants c of MM, NC, DV, NV.
    pub c: [f32; 4],
    /// Shading metric c.
    pub c_shading: f32,
    /// Shading metric absolute threshold.
    pub min_threshold: f32,
    /// Shading metric relative threshold.
    pub edge_threshold: f32,
    /// Far plane distance.
    pub far: f32,
    /// Ambient radiance.
    pub ambient: [f32; 3],
    /// Lights in the light buffer.
    pub light_count: u32,
    /// Background radiance.
    pub background: [f32; 3],
    /// Always 0 (see the shader).
    pub zero: f32,
    /// Dither order, `x | y << 8` per sample.
    pub order: [u32; 64],
}

impl SsaaParams {
    fn new(config: &SsaaConfig, width: u32, height: u32, far: f32, light_count: u32) -> Self {
        let mut order = [0u32; 64];
        for (o, c) in order.iter_mut().zip(dither_order(config.m)) {
            *o = c[0] | (c[1] << 8);
        }
        let shading = config.shading.unwrap_or_default();
        let c = config.constants;
        Self {
            width,
            height,
            m: config.m,
            n: config.samples(),
            metric: config.metric.map_or(0, |m| m.code()),
            shading_on: u32::from(config.shading.is_some()),
            min_samples: config.min_samples,
            stall: config.stall,
            c: [c.mm, c.nc, c.dv, c.nv],
            c_shading: shading.c,
            min_threshold: shading.min_threshold,
            edge_threshold: shading.edge_threshold,
            far,
            ambient: config.ambient.to_array(),
            light_count,
            background: config.background.to_array(),
            zero: 0.0,
            order,
        }
    }
}

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
        })
    }
}

/// The supersampled G-buffer pass: a render pipeline on the G-buffer pass's layouts with the
/// `fs_texcoord` fragment stage.
pub struct SsGBufferPass {
    pipeline: wgpu::RenderPipeline,
}

impl SsGBufferPass {
    /// Builds the pipeline for scenes uploaded with `gbuffer_pass`.
    pub fn new(device: &wgpu::Device, gbuffer_pass: &GBufferPass) -> Result<Self, GpuError> {
        let module = crate::SHADERS.module(device, "gbuffer.wgsl")?;
        let [frame, material] = gbuffer_pass.layouts();
        let layout = kernel::pipeline_layout(device, "ss gbuffer", &[frame, material]);
        let attributes = GBufferPass::vertex_attributes();
        let target = |format| {
            Some(wgpu::ColorTargetState {
                format,
                blend: None,
                write_mask: wgpu::ColorWrites::ALL,
            })
        };
        let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("ss gbuffer"),
            layout: Some(&layout),
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs_main"),
                compilation_options: Default::default(),
                buffers: &[Some(wgpu::VertexBufferLayout {
                    array_stride: size_of::<gbuffer::gpu::GpuVertex>() as u64,
                    step_mode: wgpu::VertexStepMode::Vertex,
                    attributes: &attributes,
                })],
            },
            primitive: wgpu::PrimitiveState {
                cull_mode: None,
                ..Default::default()
            },
            depth_stencil: Some(wgpu::DepthStencilState {
                format: DEPTH_FORMAT,
                depth_write_enabled: Some(true),
                depth_compare: Some(wgpu::CompareFunction::Less),
                stencil: Default::default(),
                bias: Default::default(),
            }),
            multisample: Default::default(),
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("fs_texcoord"),
                compilation_options: Default::default(),
                targets: &[
                    target(LINEAR_DEPTH_FORMAT),
                    target(NORMAL_FORMAT),
                    target(UV_FORMAT),
                    target(MATERIAL_FORMAT),
                    target(UV_GRAD_FORMAT),
                ],
            }),
            multiview_mask: None,
            cache: None,
        });
        Ok(Self { pipeline })
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
        let views = [
            (&targets.linear_depth, 0.0),
            (&targets.normal, 0.0),
            (&targets.uv, 0.0),
            (&targets.material, f64::from(gbuffer::NO_MATERIAL)),
            (&targets.uv_grad, 0.0),
        ]
        .map(|(t, clear)| (t.create_view(&Default::default()), clear));
        let attachments: Vec<_> = views
            .iter()
            .map(|(view, clear)| {
                Some(wgpu::RenderPassColorAttachment {
                    view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color {
                            r: *clear,
                            g: 0.0,
                            b: 0.0,
                            a: 0.0,
                        }),
                        store: wgpu::StoreOp::Store,
                    },
                })
            })
            .collect();
        let depth_view = targets.depth.create_view(&Default::default());
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("ss gbuffer"),
            color_attachments: &attachments,
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &depth_view,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(1.0),
                    store: wgpu::StoreOp::Store,
                }),
                stencil_ops: None,
            }),
            timestamp_writes,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        gbuffer_pass.draw_scene(&mut pass, &self.pipeline, scene);
    }
}

/// The [`TextureArray`] on the GPU (`Rgba8UnormSrgb`, all mips) and its anisotropic sampler.
pub struct GpuTextures {
    view: wgpu::TextureView,
    sampler: wgpu::Sampler,
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

/// Compute pipelines of `ssaa.wgsl`.
struct Pipelines {
    first: wgpu::ComputePipeline,
    evaluate: wgpu::ComputePipeline,
    adaptive: wgpu::ComputePipeline,
    full: wgpu::ComputePipeline,
    sort_count: wgpu::ComputePipeline,
    sort_scan: wgpu::ComputePipeline,
    sort_scatter: wgpu::ComputePipeline,
    shade_sorted: wgpu::ComputePipeline,
    fxaa: wgpu::ComputePipeline,
}

/// Adaptive supersampling of one image size and window side, bound to one supersampled
/// G-buffer, texture array and material table.
pub struct Ssaa {
    config: SsaaConfig,
    params: SsaaParams,
    params_buffer: wgpu::Buffer,
    pipelines: Pipelines,
    group: wgpu::BindGroup,
    args_group: wgpu::BindGroup,
    args: wgpu::Buffer,
    lights: wgpu::Buffer,
    light_capacity: usize,
    /// `S` (`w·h` RGBA32F).
    first: wgpu::Buffer,
    counts: wgpu::Buffer,
    output: wgpu::Buffer,
    sort: wgpu::Buffer,
}

fn storage(
    device: &wgpu::Device,
    label: &str,
    size: u64,
    extra: wgpu::BufferUsages,
) -> Result<wgpu::Buffer, GpuError> {
    transfer::check_buffer_size(device, label, size, wgpu::BufferUsages::STORAGE)?;
    Ok(device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: size.max(4),
        usage: wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::COPY_SRC
            | wgpu::BufferUsages::COPY_DST
            | extra,
        mapped_at_creation: false,
    }))
}

/// Inputs [`Ssaa::new`] binds.
pub struct SsaaInputs<'a> {
    /// The frame uniform at sample resolution (e.g. [`GBufferPass::frame_buffer`]).
    pub frame: &'a wgpu::Buffer,
    /// The supersampled G-buffer.
    pub targets: &'a SsGBufferTargets,
    /// The texture array.
    pub textures: &'a GpuTextures,
    /// The materials ([`SsaaMaterial`] by id).
    pub materials: &'a wgpu::Buffer,
}

impl Ssaa {
    /// Builds the passes for a `width × height` image (the targets must be `m` times larger)
    /// and up to `light_capacity` lights.
    pub fn new(
        device: &wgpu::Device,
        inputs: &SsaaInputs,
        config: &SsaaConfig,
        width: u32,
        height: u32,
        light_capacity: usize,
    ) -> Result<Self, SsaaError> {
        config.validate()?;
        let m = config.m;
        if width == 0
            || height == 0
            || inputs.targets.width != width * m
            || inputs.targets.height != height * m
        {
            return Err(SsaaError::InvalidSize { width, height, m });
        }
        let module = crate::SHADERS.module(device, "ssaa.wgsl")?;
        let group_layout = Layout::compute(device, "ssaa", &SSAA_BINDINGS);
        let args_layout = Layout::compute(device, "ssaa dispatch args", &[Binding::Storage]);
        let make = |entry: &str| kernel::pipeline(device, &module, entry, &[&group_layout], &[]);
        let pipelines = Pipelines {
            first: make("shade_first"),
            evaluate: make("evaluate"),
            adaptive: make("shade_adaptive"),
            full: make("shade_full"),
            sort_count: make("sort_count"),
            sort_scan: kernel::pipeline(
                device,
                &module,
                "sort_scan",
                &[&group_layout, &args_layout],
                &[],
            ),
            sort_scatter: make("sort_scatter"),
            shade_sorted: make("shade_sorted"),
            fxaa: make("fxaa"),
        };
        let pixels = u64::from(width) * u64::from(height);
        let params = SsaaParams::new(config, width, height, 1.0, 0);
        let params_buffer = transfer::buffer_init(
            device,
            "ssaa params",
            bytemuck::bytes_of(&params),
            wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        )?;
        let light_capacity = light_capacity.max(1);
        let lights = storage(
            device,
            "ssaa lights",
            (light_capacity * size_of::<GpuLight>()) as u64,
            wgpu::BufferUsages::empty(),
        )?;
        let first = storage(
            device,
            "ssaa first sample",
            pixels * 16,
            wgpu::BufferUsages::empty(),
        )?;
        let counts = storage(
            device,
            "ssaa sample counts",
            pixels * 4,
            wgpu::BufferUsages::empty(),
        )?;
        let output = storage(
            device,
            "ssaa output",
            pixels * 16,
            wgpu::BufferUsages::empty(),
        )?;
        let sort = storage(device, "ssaa sort", 131 * 4, wgpu::BufferUsages::empty())?;
        let list = storage(
            device,
            "ssaa pixel list",
            pixels * 4,
            wgpu::BufferUsages::empty(),
        )?;
        let args = storage(
            device,
            "ssaa dispatch args",
            12,
            wgpu::BufferUsages::INDIRECT,
        )?;
        let t = inputs.targets;
        let views = [&t.linear_depth, &t.normal, &t.uv, &t.uv_grad, &t.material]
            .map(|t| t.create_view(&Default::default()));
        let view = wgpu::BindingResource::TextureView;
        let mut resources = vec![
            inputs.frame.as_entire_binding(),
            params_buffer.as_entire_binding(),
        ];
        resources.extend(views.iter().map(view));
        resources.extend([
            view(&inputs.textures.view),
            wgpu::BindingResource::Sampler(&inputs.textures.sampler),
        ]);
        resources.extend(
            [
                inputs.materials,
                &lights,
                &first,
                &counts,
                &output,
                &sort,
                &list,
            ]
            .map(|b| b.as_entire_binding()),
        );
        let group = group_layout.bind(device, &resources);
        let args_group = args_layout.bind_buffers(device, &[&args]);
        Ok(Self {
            config: *config,
            params,
            params_buffer,
            pipelines,
            group,
            args_group,
            args,
            lights,
            light_capacity,
            first,
            counts,
            output,
            sort,
        })
    }

    /// The configuration in use.
    pub fn config(&self) -> &SsaaConfig {
        &self.config
    }

    /// Changes metric, constants, thresholds, resolve, stall, ambient or background (the
    /// window side and the anisotropy are fixed at creation).
    pub fn set_config(
        &mut self,
        queue: &wgpu::Queue,
        config: &SsaaConfig,
    ) -> Result<(), SsaaError> {
        config.validate()?;
        if config.m != self.config.m {
            return Err(SsaaError::WindowSize(config.m));
        }
        if config.anisotropy != self.config.anisotropy {
            return Err(SsaaError::Anisotropy(config.anisotropy));
        }
        self.config = *config;
        self.params = SsaaParams::new(
            config,
            self.params.width,
            self.params.height,
            self.params.far,
            self.params.light_count,
        );
        queue.write_buffer(&self.params_buffer, 0, bytemuck::bytes_of(&self.params));
        Ok(())
    }

    /// Sets the camera's far distance (the depth metrics use view depth / far).
    pub fn set_far(&mut self, queue: &wgpu::Queue, far: f32) {
        self.params.far = far;
        queue.write_buffer(&self.params_buffer, 0, bytemuck::bytes_of(&self.params));
    }

    /// Replaces the lights.
    pub fn set_lights(
        &mut self,
        queue: &wgpu::Queue,
        lights: &[GpuLight],
    ) -> Result<(), SsaaError> {
        if lights.len() > self.light_capacity {
            return Err(SsaaError::Gpu(GpuError::DataSize(format!(
                "{} lights do not fit the light buffer made for {}",
                lights.len(),
                self.light_capacity
            ))));
        }
        queue.write_buffer(&self.lights, 0, bytemuck::cast_slice(lights));
        self.params.light_count = lights.len() as u32;
        queue.write_buffer(&self.params_buffer, 0, bytemuck::bytes_of(&self.params));
        Ok(())
    }

    fn dispatch(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        pipeline: &wgpu::ComputePipeline,
        timer: Option<&PassTimer>,
        name: &str,
    ) {
        let workgroups = Workgroups::covering(self.params.width, self.params.height, 8);
        Passes::one(name, pipeline, vec![self.group.clone()], workgroups).encode(encoder, timer);
    }

    /// Shades the first sample per pixel into `S`.
    pub fn encode_first(&self, encoder: &mut wgpu::CommandEncoder, timer: Option<&PassTimer>) {
        self.dispatch(encoder, &self.pipelines.first, timer, "shade first");
    }

    /// Evaluates the metrics into the sample counts (needs `S`).
    pub fn encode_evaluate(&self, encoder: &mut wgpu::CommandEncoder, timer: Option<&PassTimer>) {
        self.dispatch(encoder, &self.pipelines.evaluate, timer, "evaluate");
    }

    /// Shades the remaining samples into the output with the configured [`Resolve`].
    pub fn encode_resolve(&self, encoder: &mut wgpu::CommandEncoder, timer: Option<&PassTimer>) {
        match self.config.resolve {
            Resolve::Loop => {
                self.dispatch(encoder, &self.pipelines.adaptive, timer, "shade adaptive")
            }
            Resolve::Sorted => {
                encoder.clear_buffer(&self.sort, 0, None);
                self.dispatch(encoder, &self.pipelines.sort_count, timer, "sort count");
                let groups = vec![self.group.clone(), self.args_group.clone()];
                let scan = Workgroups::Direct([1, 1, 1]);
                Passes::one("sort scan", &self.pipelines.sort_scan, groups, scan)
                    .encode(encoder, timer);
                self.dispatch(encoder, &self.pipelines.sort_scatter, timer, "sort scatter");
                let sorted = Workgroups::Indirect(self.args.clone(), 0);
                Passes::one(
                    "shade sorted",
                    &self.pipelines.shade_sorted,
                    vec![self.group.clone()],
                    sorted,
                )
                .encode(encoder, timer);
            }
        }
    }

    /// Listing 4.1 after the G-buffer: first sample, evaluation, adaptive shading.
    pub fn encode(&self, encoder: &mut wgpu::CommandEncoder, timer: Option<&PassTimer>) {
        self.encode_first(encoder, timer);
        self.encode_evaluate(encoder, timer);
        self.encode_resolve(encoder, timer);
    }

    /// Full supersampling into the output (the reference).
    pub fn encode_full(&self, encoder: &mut wgpu::CommandEncoder, timer: Option<&PassTimer>) {
        self.dispatch(encoder, &self.pipelines.full, timer, "shade full");
    }

    /// FXAA on `S` into the output (needs `S`).
    pub fn encode_fxaa(&self, encoder: &mut wgpu::CommandEncoder, timer: Option<&PassTimer>) {
        self.dispatch(encoder, &self.pipelines.fxaa, timer, "fxaa");
    }

    /// The output buffer (`w·h` RGBA32F, row-major), e.g. to copy into a texture.
    pub fn output(&self) -> &wgpu::Buffer {
        &self.output
    }

    fn read_rgba(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        buffer: &wgpu::Buffer,
    ) -> Result<Image<[f32; 4]>, SsaaError> {
        let bytes = transfer::read_buffer(device, queue, buffer)?;
        let texels: Vec<[f32; 4]> = bytemuck::cast_slice::<u8, f32>(&bytes)
            .chunks_exact(4)
            .map(|c| [c[0], c[1], c[2], c[3]])
            .collect();
        Image::from_vec(self.params.width, self.params.height, texels)
            .map_err(|e| SsaaError::Gpu(GpuError::Readback(e.to_string())))
    }

    /// Reads the output back.
    pub fn read_output(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
    ) -> Result<Image<[f32; 4]>, SsaaError> {
        self.read_rgba(device, queue, &self.output)
    }

    /// Reads `S` back.
    pub fn read_first(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
    ) -> Result<Image<[f32; 4]>, SsaaError> {
        self.read_rgba(device, queue, &self.first)
    }

    /// Reads the sample counts back.
    pub fn read_counts(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
    ) -> Result<Image<u32>, SsaaError> {
        let bytes = transfer::read_buffer(device, queue, &self.counts)?;
        Image::from_vec(
            self.params.width,
            self.params.height,
            bytemuck::cast_slice(&bytes).to_vec(),
        )
        .map_err(|e| SsaaError::Gpu(GpuError::Readback(e.to_string())))
    }
}

/// Group 0 of `ssaa.wgsl`: frame, params; linear depth, normal, uv, uv gradient, material
/// targets; texture array and sampler; materials, lights; first sample, counts, output, sort
/// histogram, pixel list.
const SSAA_BINDINGS: [Binding; 16] = {
    use Binding::{
        Sampler, Storage, StorageRead, TextureArray, TextureUint, TextureUnfilterable, Uniform,
    };
    [
        Uniform,
        Uniform,
        TextureUnfilterable,
        TextureUint,
        TextureUnfilterable,
        TextureUnfilterable,
        TextureUint,
        TextureArray,
        Sampler,
        StorageRead,
        StorageRead,
        Storage,
        Storage,
        Storage,
        Storage,
        Storage,
    ]
};

/// A scene set up for adaptive supersampling at one size: G-buffer passes, uploaded scene,
/// texture array, materials, targets and the [`Ssaa`] passes.
pub struct SsaaRenderer {
    gbuffer_pass: GBufferPass,
    ss_pass: SsGBufferPass,
    scene: GpuScene,
    /// The supersampled G-buffer.
    pub targets: SsGBufferTargets,
    /// The adaptive supersampling passes.
    pub ssaa: Ssaa,
    width: u32,
    height: u32,
}

impl SsaaRenderer {
    /// Uploads `scene` (textures resampled to at most [`TEXTURE_SIZE`]) and builds every pass
    /// for a `width × height` image.
    pub fn new(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        scene: &Scene,
        lights: &[GpuLight],
        width: u32,
        height: u32,
        config: &SsaaConfig,
    ) -> Result<Self, SsaaError> {
        config.validate()?;
        let (sw, sh) = (width.checked_mul(config.m), height.checked_mul(config.m));
        let (Some(sw), Some(sh)) = (sw, sh) else {
            return Err(SsaaError::InvalidSize {
                width,
                height,
                m: config.m,
            });
        };
        if width == 0 || height == 0 || sw > gbuffer::MAX_SIZE || sh > gbuffer::MAX_SIZE {
            return Err(SsaaError::InvalidSize {
                width,
                height,
                m: config.m,
            });
        }
        let gbuffer_pass = GBufferPass::new(device)?;
        let ss_pass = SsGBufferPass::new(device, &gbuffer_pass)?;
        let gpu_scene = GpuScene::upload(device, queue, scene, &gbuffer_pass)?;
        let textures = GpuTextures::new(
            device,
            queue,
            &TextureArray::new(scene, TEXTURE_SIZE),
            config.anisotropy,
        )?;
        let materials = transfer::buffer_init(
            device,
            "ssaa materials",
            bytemuck::cast_slice(&SsaaMaterial::of_scene(scene)),
            wgpu::BufferUsages::STORAGE,
        )?;
        let targets = SsGBufferTargets::new(device, sw, sh)?;
        let inputs = SsaaInputs {
            frame: gbuffer_pass.frame_buffer(),
            targets: &targets,
            textures: &textures,
            materials: &materials,
        };
        let mut ssaa = Ssaa::new(device, &inputs, config, width, height, lights.len())?;
        ssaa.set_lights(queue, lights)?;
        Ok(Self {
            gbuffer_pass,
            ss_pass,
            scene: gpu_scene,
            targets,
            ssaa,
            width,
            height,
        })
    }

    /// Writes the camera (frame at the sample resolution, far distance).
    pub fn set_camera(&mut self, queue: &wgpu::Queue, camera: &Camera) -> Result<(), SsaaError> {
        gbuffer::validate_camera(camera)?;
        let m = self.ssaa.config().m;
        self.gbuffer_pass
            .write_frame(queue, &Frame::new(camera, self.width * m, self.height * m));
        self.ssaa.set_far(queue, camera.far);
        Ok(())
    }

    /// Records the supersampled G-buffer pass.
    pub fn encode_gbuffer(&self, encoder: &mut wgpu::CommandEncoder, timer: Option<&PassTimer>) {
        self.ss_pass.encode(
            encoder,
            &self.gbuffer_pass,
            &self.scene,
            &self.targets,
            timer.and_then(|t| t.render_pass("ss gbuffer")),
        );
    }
}

/// Convenience for tests and examples: renders `scene` from `camera` with adaptive
/// supersampling and reads the image, `S` and the sample counts back.
pub fn run(
    gpu: &Gpu,
    scene: &Scene,
    camera: &Camera,
    lights: &[GpuLight],
    width: u32,
    height: u32,
    config: &SsaaConfig,
) -> Result<Output, SsaaError> {
    let mut renderer = SsaaRenderer::new(
        &gpu.device,
        &gpu.queue,
        scene,
        lights,
        width,
        height,
        config,
    )?;
    renderer.set_camera(&gpu.queue, camera)?;
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    renderer.encode_gbuffer(&mut encoder, None);
    renderer.ssaa.encode(&mut encoder, None);
    gpu.queue.submit([encoder.finish()]);
    Ok(Output {
        image: renderer.ssaa.read_output(&gpu.device, &gpu.queue)?,
        first: renderer.ssaa.read_first(&gpu.device, &gpu.queue)?,
        counts: renderer.ssaa.read_counts(&gpu.device, &gpu.queue)?,
    })
}
