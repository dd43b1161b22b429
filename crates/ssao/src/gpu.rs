//! The estimators on the GPU (`shaders/ssao/estimators.wgsl`: `full`, `pass_1`, `pass_2`),
//! twins of [`crate::cpu`], over the caller's G-buffer textures (linear depth, normals) and
//! [`gbuffer::Frame`] uniform, writing the accessibility into the caller's buffer (one `f32` a
//! pixel, row-major; at half resolution `upsample` writes it from the grid's estimates).
//! [`SsaoKernels::new`] compiles the shader; [`SsaoKernels::bind`] binds one image, kernel and
//! estimator (building its pipelines on first use: the k × k kernels up to 21 pixels read their
//! samples from a workgroup tile); [`SsaoKernels::encode`] records.

use std::collections::HashMap;
use std::sync::{Arc, Mutex};

use ::gpu::kernel::{self, Binding, Layout, Passes, Workgroups};
use ::gpu::shader::Specialisation;
use ::gpu::{PassTimer, transfer};
use gbuffer::{Frame, GBuffer, Image};

use crate::cpu::{KernelConfig, frame_directions};
use crate::{Estimator, Method, SsaoError};

/// `common.wgsl`'s `Params`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct Params {
    width: u32,
    height: u32,
    size: u32,
    radius: f32,
    image_width: u32,
    image_height: u32,
    scale: u32,
    smoothing: u32,
}

/// `common.wgsl`'s bindings: frame, params; linear depth, normals; frame directions, pass 1,
/// accessibility, the half-resolution estimates.
const BINDINGS: [Binding; 8] = [
    Binding::Uniform,
    Binding::Uniform,
    Binding::TextureUnfilterable,
    Binding::TextureUint,
    Binding::StorageRead,
    Binding::Storage,
    Binding::Storage,
    Binding::Storage,
];

/// The widest kernel whose samples the workgroup tiles hold (`common.wgsl`'s APRON).
const TILED_KERNEL: u32 = 21;

/// One method's pipelines, tiled or not.
struct MethodPipelines {
    full: wgpu::ComputePipeline,
    pass_1: wgpu::ComputePipeline,
    pass_2: wgpu::ComputePipeline,
    smooth_x: wgpu::ComputePipeline,
    smooth_y: wgpu::ComputePipeline,
    upsample: wgpu::ComputePipeline,
}

/// The estimators' pipelines, built on first use of each method and kernel size.
pub struct SsaoKernels {
    layout: Layout,
    /// The shader with the workgroup tile (for the k × k kernels) and without (the rest).
    tiled: wgpu::ShaderModule,
    plain: wgpu::ShaderModule,
    pipelines: Mutex<HashMap<(Method, u32), Arc<MethodPipelines>>>,
}

/// [`SsaoKernels`] bound to one image, kernel and estimator.
pub struct BoundSsao {
    group: wgpu::BindGroup,
    /// The image's size and the estimator grid's.
    size: (u32, u32),
    grid: (u32, u32),
    estimator: Estimator,
    pipelines: Arc<MethodPipelines>,
}

impl SsaoKernels {
    /// Compiles the estimators' shader.
    pub fn new(device: &wgpu::Device) -> Result<Self, SsaoError> {
        Ok(Self {
            layout: Layout::compute(device, "ssao", &BINDINGS),
            tiled: crate::SHADERS.module(device, "estimators.wgsl")?,
            plain: crate::SHADERS.module_with(
                device,
                "estimators.wgsl",
                &Specialisation::default().set("TILE_CAPACITY", "1u"),
            )?,
            pipelines: Mutex::default(),
        })
    }

    /// The pipelines of `method` for kernels of side `k` (workgroup-tiled up to 21).
    fn pipelines(&self, device: &wgpu::Device, method: Method, k: u32) -> Arc<MethodPipelines> {
        let mut built = self.pipelines.lock().unwrap_or_else(|e| e.into_inner());
        let entry = built.entry((method, k)).or_insert_with(|| {
            let index = Method::ALL.iter().position(|&m| m == method).unwrap_or(0);
            let make = |entry: &str, tiled: bool| {
                let module = if tiled { &self.tiled } else { &self.plain };
                let constants = [
                    ("METHOD", index as f64),
                    ("TILED", f64::from(u8::from(tiled))),
                    ("APRON", f64::from(k.min(TILED_KERNEL) / 2)),
                ];
                kernel::pipeline(device, module, entry, &[&self.layout], &constants)
            };
            Arc::new(MethodPipelines {
                full: make("full", k <= TILED_KERNEL),
                pass_1: make("pass_1", false),
                pass_2: make("pass_2", false),
                smooth_x: make("smooth_x", false),
                smooth_y: make("smooth_y", false),
                upsample: make("upsample", false),
            })
        });
        entry.clone()
    }

    /// Binds `estimator` with `config` to `frame` (a [`Frame`] uniform), the G-buffer's
    /// `linear_depth` and `normal` textures and the caller's `output` (`STORAGE`, 4 bytes a
    /// pixel). Wrong formats, sizes or usages are an error here.
    pub fn bind(
        &self,
        device: &wgpu::Device,
        frame: &wgpu::Buffer,
        [linear_depth, normal]: [&wgpu::Texture; 2],
        output: &wgpu::Buffer,
        config: &KernelConfig,
        estimator: Estimator,
    ) -> Result<BoundSsao, SsaoError> {
        config.validate()?;
        let size = (linear_depth.width(), linear_depth.height());
        let input = wgpu::TextureUsages::TEXTURE_BINDING;
        kernel::check_texture(
            "linear depth",
            linear_depth,
            size,
            gbuffer::LINEAR_DEPTH_FORMAT,
            input,
        )?;
        kernel::check_texture("normals", normal, size, gbuffer::NORMAL_FORMAT, input)?;
        let pixels = u64::from(size.0) * u64::from(size.1);
        kernel::check_buffer(
            "accessibility",
            output,
            pixels * 4,
            wgpu::BufferUsages::STORAGE,
        )?;
        let scale = if estimator.half_resolution { 2 } else { 1 };
        let grid = (size.0.div_ceil(scale), size.1.div_ceil(scale));
        let points = u64::from(grid.0) * u64::from(grid.1);
        let params = transfer::buffer_init(
            device,
            "ssao params",
            bytemuck::bytes_of(&Params {
                width: grid.0,
                height: grid.1,
                size: config.size,
                radius: config.ao.radius,
                image_width: size.0,
                image_height: size.1,
                scale,
                smoothing: u32::from(estimator.separable && estimator.smoothing),
            }),
            wgpu::BufferUsages::UNIFORM,
        )?;
        let directions = transfer::buffer_init(
            device,
            "ssao frame directions",
            bytemuck::cast_slice(&frame_directions(config.size)),
            wgpu::BufferUsages::STORAGE,
        )?;
        let scratch = |label: &str, used: bool, bytes: u64| {
            let bytes = if used { bytes } else { 4 };
            transfer::buffer(device, label, bytes, wgpu::BufferUsages::STORAGE)
        };
        let first = scratch("ssao pass 1", estimator.separable, points * 12)?;
        let coarse = scratch("ssao half resolution", scale == 2, points * 4)?;
        let view = |t: &wgpu::Texture| t.create_view(&Default::default());
        let (depth_view, normal_view) = (view(linear_depth), view(normal));
        let group = self.layout.bind(
            device,
            &[
                frame.as_entire_binding(),
                params.as_entire_binding(),
                wgpu::BindingResource::TextureView(&depth_view),
                wgpu::BindingResource::TextureView(&normal_view),
                directions.as_entire_binding(),
                first.as_entire_binding(),
                output.as_entire_binding(),
                coarse.as_entire_binding(),
            ],
        );
        Ok(BoundSsao {
            group,
            size,
            grid,
            estimator,
            pipelines: self.pipelines(device, estimator.method, config.size),
        })
    }

    /// Records the estimator's passes (`ssao <estimator>`, or its `pass 1` and `pass 2`; then
    /// at half resolution its `upsample`).
    pub fn encode(
        &self,
        bound: &BoundSsao,
        encoder: &mut wgpu::CommandEncoder,
        timer: Option<&PassTimer>,
    ) {
        let pipelines = &bound.pipelines;
        let name = |pass: &str| format!("ssao {} {pass}", bound.estimator);
        let mut passes = if bound.estimator.separable {
            vec![
                (name("pass 1"), &pipelines.pass_1, bound.grid),
                (name("pass 2"), &pipelines.pass_2, bound.grid),
                (name("smooth x"), &pipelines.smooth_x, bound.grid),
                (name("smooth y"), &pipelines.smooth_y, bound.grid),
            ]
            .into_iter()
            .take(if bound.estimator.smoothing { 4 } else { 2 })
            .collect()
        } else {
            vec![(name("k×k"), &pipelines.full, bound.grid)]
        };
        if bound.estimator.half_resolution {
            passes.push((name("upsample"), &pipelines.upsample, bound.size));
        }
        for (name, pipeline, (w, h)) in passes {
            let workgroups = Workgroups::covering(w, h, 16);
            Passes::one(&name, pipeline, vec![bound.group.clone()], workgroups)
                .encode(encoder, timer);
        }
    }
}

/// Convenience for tests and examples: uploads `gbuffer` and `frame`, runs `estimator` and
/// reads the accessibility back.
pub fn run(
    gpu: &::gpu::Gpu,
    gbuffer: &GBuffer,
    frame: &Frame,
    config: &KernelConfig,
    estimator: Estimator,
) -> Result<Image<f32>, SsaoError> {
    crate::check_size(gbuffer, frame)?;
    let (d, q) = (&gpu.device, &gpu.queue);
    let uploaded = gbuffer::gpu::UploadedGBuffer::new(d, q, gbuffer, frame)?;
    let (w, h) = (gbuffer.linear_depth.width(), gbuffer.linear_depth.height());
    let output = transfer::buffer(
        d,
        "accessibility",
        u64::from(w) * u64::from(h) * 4,
        wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
    )?;
    let kernels = SsaoKernels::new(d)?;
    let textures = [&uploaded.linear_depth, &uploaded.normal];
    let bound = kernels.bind(d, &uploaded.frame, textures, &output, config, estimator)?;
    let mut encoder = d.create_command_encoder(&Default::default());
    kernels.encode(&bound, &mut encoder, None);
    q.submit([encoder.finish()]);
    let values: Vec<f32> = transfer::read_pod(d, q, &output)?;
    let mut image = Image::filled(w, h, 1.0);
    image
        .pixels_mut()
        .copy_from_slice(&values[..(w * h) as usize]);
    Ok(image)
}
