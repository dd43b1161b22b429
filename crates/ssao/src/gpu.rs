//! The estimators on the GPU (`shaders/ssao/`): `kernel_2d.wgsl` (eq. 7.1) and
//! `separable.wgsl` (`pass_1d`, `pass_2`), twins of [`crate::cpu`], over the caller's G-buffer
//! textures (linear depth, normals) and [`gbuffer::Frame`] uniform, writing the accessibility
//! into the caller's buffer (one `f32` a pixel, row-major). Pipelines are built once
//! ([`SsaoKernels::new`]); [`SsaoKernels::bind`] binds one image and kernel;
//! [`SsaoKernels::encode`] records.

use ::gpu::kernel::{self, Binding, Layout, Passes, Workgroups};
use ::gpu::{PassTimer, transfer};
use gbuffer::{Frame, GBuffer, Image};

use crate::SsaoError;
use crate::cpu::{KernelConfig, frame_directions};

/// Which estimator runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Estimator {
    /// Eq. 7.1, k² − 1 samples a pixel.
    Kernel2d,
    /// The separable approximation, 2k − 1 samples a pixel in two passes.
    Separable,
}

/// `common.wgsl`'s `Params`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct Params {
    width: u32,
    height: u32,
    size: u32,
    radius: f32,
}

/// `common.wgsl`'s bindings: frame, params; linear depth, normals; frame directions, pass 1,
/// accessibility.
const BINDINGS: [Binding; 7] = [
    Binding::Uniform,
    Binding::Uniform,
    Binding::TextureUnfilterable,
    Binding::TextureUint,
    Binding::StorageRead,
    Binding::Storage,
    Binding::Storage,
];

/// The estimators' pipelines.
pub struct SsaoKernels {
    layout: Layout,
    kernel_2d: wgpu::ComputePipeline,
    pass_1d: wgpu::ComputePipeline,
    pass_2: wgpu::ComputePipeline,
}

/// [`SsaoKernels`] bound to one image, kernel and estimator.
pub struct BoundSsao {
    group: wgpu::BindGroup,
    size: (u32, u32),
    estimator: Estimator,
}

impl SsaoKernels {
    /// Builds the pipelines.
    pub fn new(device: &wgpu::Device) -> Result<Self, SsaoError> {
        let layout = Layout::compute(device, "ssao", &BINDINGS);
        let make = |file: &str, entry: &str| -> Result<_, SsaoError> {
            let module = crate::SHADERS.module(device, file)?;
            Ok(kernel::pipeline(device, &module, entry, &[&layout], &[]))
        };
        Ok(Self {
            kernel_2d: make("kernel_2d.wgsl", "kernel_2d")?,
            pass_1d: make("separable.wgsl", "pass_1d")?,
            pass_2: make("separable.wgsl", "pass_2")?,
            layout,
        })
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
        let params = transfer::buffer_init(
            device,
            "ssao params",
            bytemuck::bytes_of(&Params {
                width: size.0,
                height: size.1,
                size: config.size,
                radius: config.ao.radius,
            }),
            wgpu::BufferUsages::UNIFORM,
        )?;
        let directions = transfer::buffer_init(
            device,
            "ssao frame directions",
            bytemuck::cast_slice(&frame_directions(config.size)),
            wgpu::BufferUsages::STORAGE,
        )?;
        let first_bytes = match estimator {
            Estimator::Separable => pixels * 4,
            Estimator::Kernel2d => 4,
        };
        let first = transfer::buffer(
            device,
            "ssao pass 1",
            first_bytes,
            wgpu::BufferUsages::STORAGE,
        )?;
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
            ],
        );
        Ok(BoundSsao {
            group,
            size,
            estimator,
        })
    }

    /// Records the estimator's passes (`ssao 2d`, or `ssao pass 1` and `ssao pass 2`).
    pub fn encode(
        &self,
        bound: &BoundSsao,
        encoder: &mut wgpu::CommandEncoder,
        timer: Option<&PassTimer>,
    ) {
        let passes: &[(&str, &wgpu::ComputePipeline)] = match bound.estimator {
            Estimator::Kernel2d => &[("ssao 2d", &self.kernel_2d)],
            Estimator::Separable => &[
                ("ssao pass 1", &self.pass_1d),
                ("ssao pass 2", &self.pass_2),
            ],
        };
        for (name, pipeline) in passes {
            let workgroups = Workgroups::covering(bound.size.0, bound.size.1, 8);
            Passes::one(name, pipeline, vec![bound.group.clone()], workgroups)
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
