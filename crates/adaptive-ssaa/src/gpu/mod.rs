//! Adaptive supersampling on the GPU: the supersampled G-buffer is one render pass
//! (`shaders/adaptive-ssaa/gbuffer.wgsl`, the G-buffer's vertex stage with a texture-coordinate
//! fragment stage, [`gbuffer`]); the rest are compute passes over one bind group
//! (`common.wgsl`), one module per stage with the stem of its WGSL file and CPU twin:
//! `shade_first` ([`shade`]) → `evaluate` ([`evaluate`]) → `shade_adaptive` (or `shade_tiles`, or the sorted
//! resolve `sort_count` → `sort_scan` → `sort_scatter` → `shade_sorted`, [`sort`]), and the
//! baselines `shade_full` and `fxaa` ([`fxaa`]). Pipelines, buffers and bind groups are built
//! once per image size; nothing is read back between passes (the sorted resolve sizes its last
//! dispatch indirectly).

pub mod evaluate;
pub mod fxaa;
pub mod gbuffer;
pub mod renderer;
pub mod run;
pub mod shade;
pub mod sort;
pub mod textures;

pub use gbuffer::{SsGBufferPass, SsGBufferTargets};
pub use renderer::SsaaRenderer;
pub use run::run;
pub use textures::GpuTextures;

use ::gbuffer::Image;
use ::gpu::kernel::{self, Binding, Layout, Passes, Workgroups};
use ::gpu::{GpuError, PassTimer, transfer};
use tiled_shading::GpuLight;

use crate::{SsaaConfig, SsaaError, dither_order};

/// Side of the largest texture-array layer [`run`] builds.
pub const TEXTURE_SIZE: u32 = 1024;

/// Uniform block of `common.wgsl` (`Params`).
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

/// Compute pipelines of the stages (`shade.wgsl`, `evaluate.wgsl`, `sort.wgsl`, `fxaa.wgsl`).
struct Pipelines {
    first: wgpu::ComputePipeline,
    evaluate: wgpu::ComputePipeline,
    adaptive: wgpu::ComputePipeline,
    tiles: wgpu::ComputePipeline,
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
    use wgpu::BufferUsages as U;
    transfer::buffer(
        device,
        label,
        size,
        U::STORAGE | U::COPY_SRC | U::COPY_DST | extra,
    )
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
    /// The caller's output buffer (`w·h` RGBA32F, row-major, `STORAGE`), e.g. one its
    /// presentation pass reads; `None` allocates one ([`Ssaa::output`]).
    pub output: Option<&'a wgpu::Buffer>,
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
        let t = inputs.targets;
        let samples = [
            &t.linear_depth,
            &t.normal,
            &t.uv,
            &t.uv_grad,
            &t.material,
            &t.tint,
        ];
        let bound = (samples, inputs.textures, inputs.materials);
        let size = (width, height);
        Self::build(
            device,
            inputs.frame,
            bound,
            inputs.output,
            config,
            size,
            light_capacity,
        )
    }

    /// Only the sample-count evaluation (§4.3.3, [`Ssaa::encode_evaluate`]) for a caller that
    /// shades the samples itself: `geometry` = the linear depth, normal and material targets of
    /// its supersampled G-buffer (`m` times `width × height`, the `gbuffer` formats), `frame`
    /// its frame uniform. The caller writes `S` into [`Ssaa::first`] before the evaluation and
    /// reads [`Ssaa::counts`] after it; the shading passes of this value read placeholders.
    pub fn evaluation(
        device: &wgpu::Device,
        frame: &wgpu::Buffer,
        geometry: [&wgpu::Texture; 3],
        config: &SsaaConfig,
        (width, height): (u32, u32),
    ) -> Result<Self, SsaaError> {
        config.validate()?;
        let m = config.m;
        let [linear_depth, normal, material] = geometry;
        let size = (width.saturating_mul(m), height.saturating_mul(m));
        if width == 0 || height == 0 {
            return Err(SsaaError::InvalidSize { width, height, m });
        }
        let input = wgpu::TextureUsages::TEXTURE_BINDING;
        for (what, texture, format) in [
            ("linear depth", linear_depth, ::gbuffer::LINEAR_DEPTH_FORMAT),
            ("normals", normal, ::gbuffer::NORMAL_FORMAT),
            ("material", material, ::gbuffer::MATERIAL_FORMAT),
        ] {
            kernel::check_texture(what, texture, size, format, input)?;
        }
        let placeholder =
            |label: &str, format| transfer::texture_2d(device, label, 1, 1, format, input);
        let uv = placeholder("ssaa uv placeholder", crate::UV_FORMAT);
        let uv_grad = placeholder("ssaa uv grad placeholder", crate::UV_GRAD_FORMAT);
        let tint = placeholder("ssaa tint placeholder", crate::TINT_FORMAT);
        let textures = GpuTextures::placeholder(device);
        let materials = storage(
            device,
            "ssaa materials placeholder",
            size_of::<crate::SsaaMaterial>() as u64,
            wgpu::BufferUsages::empty(),
        )?;
        let samples = [linear_depth, normal, &uv, &uv_grad, material, &tint];
        let bound = (samples, &textures, &materials);
        Self::build(device, frame, bound, None, config, (width, height), 1)
    }

    /// The passes over the sample textures (linear depth, normal, uv, uv gradient, material,
    /// tint), the texture array and the materials, for up to `light_capacity` lights.
    fn build(
        device: &wgpu::Device,
        frame: &wgpu::Buffer,
        (samples, textures, materials): ([&wgpu::Texture; 6], &GpuTextures, &wgpu::Buffer),
        output: Option<&wgpu::Buffer>,
        config: &SsaaConfig,
        (width, height): (u32, u32),
        light_capacity: usize,
    ) -> Result<Self, SsaaError> {
        let [shade, evaluate, sort, fxaa] = ["shade", "evaluate", "sort", "fxaa"]
            .map(|stage| crate::SHADERS.module(device, &format!("{stage}.wgsl")));
        let (shade, evaluate, sort) = (shade?, evaluate?, sort?);
        let group_layout = Layout::compute(device, "ssaa", &SSAA_BINDINGS);
        let args_layout = Layout::compute(device, "ssaa dispatch args", &[Binding::Storage]);
        let make = |module: &wgpu::ShaderModule, entry: &str| {
            kernel::pipeline(device, module, entry, &[&group_layout], &[])
        };
        let pipelines = Pipelines {
            first: make(&shade, "shade_first"),
            evaluate: make(&evaluate, "evaluate"),
            adaptive: make(&shade, "shade_adaptive"),
            tiles: make(&shade, "shade_tiles"),
            full: make(&shade, "shade_full"),
            sort_count: make(&sort, "sort_count"),
            sort_scan: kernel::pipeline(
                device,
                &sort,
                "sort_scan",
                &[&group_layout, &args_layout],
                &[],
            ),
            sort_scatter: make(&sort, "sort_scatter"),
            shade_sorted: make(&sort, "shade_sorted"),
            fxaa: make(&fxaa?, "fxaa"),
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
        let none = wgpu::BufferUsages::empty();
        let [first, counts, sort, list] = [
            ("ssaa first sample", pixels * 16),
            ("ssaa sample counts", pixels * 4),
            ("ssaa sort", 131 * 4),
            ("ssaa pixel list", pixels * 4),
        ]
        .map(|(label, size)| storage(device, label, size, none));
        let [first, counts, sort, list] = [first?, counts?, sort?, list?];
        let output = match output {
            Some(output) => {
                let usage = wgpu::BufferUsages::STORAGE;
                kernel::check_buffer("SSAA output", output, pixels * 16, usage)?;
                output.clone()
            }
            None => storage(device, "ssaa output", pixels * 16, none)?,
        };
        let args = storage(
            device,
            "ssaa dispatch args",
            12,
            wgpu::BufferUsages::INDIRECT,
        )?;
        let views = samples.map(|t| t.create_view(&Default::default()));
        let view = wgpu::BindingResource::TextureView;
        let mut resources = vec![frame.as_entire_binding(), params_buffer.as_entire_binding()];
        resources.extend(views[..5].iter().map(view));
        resources.extend([
            view(&textures.view),
            wgpu::BindingResource::Sampler(&textures.sampler),
        ]);
        resources.extend(
            [materials, &lights, &first, &counts, &output, &sort, &list]
                .map(|b| b.as_entire_binding()),
        );
        resources.push(view(&views[5]));
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

    /// Listing 4.1 after the G-buffer: first sample, evaluation, adaptive shading.
    pub fn encode(&self, encoder: &mut wgpu::CommandEncoder, timer: Option<&PassTimer>) {
        self.encode_first(encoder, timer);
        self.encode_evaluate(encoder, timer);
        self.encode_resolve(encoder, timer);
    }

    /// `S`, the first sample's radiance per pixel (`w·h` RGBA32F, row-major), which the
    /// shading metric of [`Ssaa::encode_evaluate`] reads.
    pub fn first(&self) -> &wgpu::Buffer {
        &self.first
    }

    /// The samples per pixel [`Ssaa::encode_evaluate`] chose (`w·h` u32, row-major; the
    /// shading clamps them to `1..=m²`).
    pub fn counts(&self) -> &wgpu::Buffer {
        &self.counts
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
        let texels: Vec<[f32; 4]> = transfer::read_pod(device, queue, buffer)?;
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
        let counts: Vec<u32> = transfer::read_pod(device, queue, &self.counts)?;
        Image::from_vec(self.params.width, self.params.height, counts)
            .map_err(|e| SsaaError::Gpu(GpuError::Readback(e.to_string())))
    }
}

/// Group 0 of `common.wgsl`: frame, params; linear depth, normal, uv, uv gradient, material
/// targets; texture array and sampler; materials, lights; first sample, counts, output, sort
/// histogram, pixel list; tint target.
const SSAA_BINDINGS: [Binding; 17] = {
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
        TextureUint,
    ]
};
