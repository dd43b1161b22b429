//! `ssao` inside an application that owns its wgpu device: the separable ambient occlusion of
//! a G-buffer on the GPU, in the application's own encoder, checked against the CPU twin.

use gbuffer::gpu::UploadedGBuffer;
use ssao::cpu::KernelConfig;
use ssao::gpu::SsaoKernels;
use ssao::{Estimator, Method};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let adapter =
        pollster::block_on(wgpu::Instance::default().request_adapter(&Default::default()))?;
    let (device, queue) =
        pollster::block_on(adapter.request_device(&ssao::device_needs().descriptor()))?;

    // The application's G-buffer: here the CPU rasteriser's, uploaded.
    let scene = scene::cornell_box();
    let camera = scene.camera_or_framed();
    let (w, h) = (160, 120);
    let gbuffer = gbuffer::cpu::rasterize(&scene, &camera, w, h)?.gbuffer;
    let frame = gbuffer::Frame::new(&camera, w, h);
    let uploaded = UploadedGBuffer::new(&device, &queue, &gbuffer, &frame)?;
    let output = gpu::transfer::buffer(
        &device,
        "ao",
        u64::from(w * h) * 4,
        wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
    )?;

    // new: pipelines once; bind: the caller's textures and buffer; encode: only records.
    let config = KernelConfig {
        size: 11,
        ao: ssao::AoConfig {
            radius: 0.1 * scene.bounds().diagonal(),
        },
    };
    // The paper's estimator: eq. 7.1 in two 1D passes (`deferred --ssao filter-separable`).
    let estimator = Estimator::new(Method::Filter, true);
    let kernels = SsaoKernels::new(&device)?;
    let textures = [&uploaded.linear_depth, &uploaded.normal];
    let bound = kernels.bind(
        &device,
        &uploaded.frame,
        textures,
        &output,
        &config,
        estimator,
    )?;
    let mut encoder = device.create_command_encoder(&Default::default());
    kernels.encode(&bound, &mut encoder, None);
    queue.submit([encoder.finish()]);

    let gpu: Vec<f32> = gpu::transfer::read_pod(&device, &queue, &output)?;
    let cpu = ssao::cpu::estimate(&gbuffer, &frame, &config, estimator)?;
    let worst = gpu
        .iter()
        .zip(cpu.pixels())
        .map(|(a, b)| (a - b).abs())
        .fold(0.0f32, f32::max);
    assert!(worst < 1e-4, "GPU and CPU differ by {worst}");
    println!(
        "{estimator} AO of {w}×{h} on {}: equal to the CPU twin (within {worst:.1e})",
        adapter.get_info().name
    );
    Ok(())
}
