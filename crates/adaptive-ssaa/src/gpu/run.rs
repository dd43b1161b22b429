//! Convenience for tests and examples.

use ::gpu::Gpu;
use scene::{Camera, Scene};
use tiled_shading::GpuLight;

use super::SsaaRenderer;
use crate::cpu::Output;
use crate::{SsaaConfig, SsaaError};

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
