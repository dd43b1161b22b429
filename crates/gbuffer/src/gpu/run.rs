//! Convenience for tests and examples.

use ::gpu::Gpu;
use ::scene::{Camera, Scene};

use super::{GBufferPass, GBufferTargets, GpuScene};
use crate::{Frame, GBuffer, GBufferError, TextureOptions};

/// Convenience for tests and examples: uploads `scene`, renders its G-buffer on `gpu` and
/// reads it back.
pub fn run(
    gpu: &Gpu,
    scene: &Scene,
    camera: &Camera,
    width: u32,
    height: u32,
) -> Result<GBuffer, GBufferError> {
    run_with(
        gpu,
        scene,
        camera,
        (width, height),
        false,
        &TextureOptions::default(),
    )
}

/// Like [`run`] at `(width, height)` with textures filtered as `options` say; with
/// `prepass`, through [`GBufferPass::encode_with_prepass`].
pub fn run_with(
    gpu: &Gpu,
    scene: &Scene,
    camera: &Camera,
    (width, height): (u32, u32),
    prepass: bool,
    options: &TextureOptions,
) -> Result<GBuffer, GBufferError> {
    crate::validate_size(width, height)?;
    crate::validate_camera(camera)?;
    let pass = GBufferPass::new(&gpu.device)?;
    let gpu_scene = GpuScene::upload_with(&gpu.device, &gpu.queue, scene, &pass, options)?;
    let targets = GBufferTargets::new(&gpu.device, width, height)?;
    pass.write_frame(&gpu.queue, &Frame::new(camera, width, height));
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    if prepass {
        pass.encode_with_prepass(&mut encoder, &gpu_scene, &targets, None, None);
    } else {
        pass.encode(&mut encoder, &gpu_scene, &targets, None);
    }
    gpu.queue.submit([encoder.finish()]);
    targets.read(&gpu.device, &gpu.queue)
}

/// Like [`run_with`] through the visibility buffer ([`super::visibility`]): the compute
/// rasteriser, then the resolve; the read-back G-buffer's depth is the visibility buffer's
/// (z/w, 1 where no triangle is). Meshes whose material discards by alpha are left out.
pub fn run_visibility(
    gpu: &Gpu,
    scene: &Scene,
    camera: &Camera,
    (width, height): (u32, u32),
    options: &TextureOptions,
) -> Result<GBuffer, GBufferError> {
    use super::visibility::{NO_TRIANGLE, ResolvePass, VisibilityPass};
    crate::validate_size(width, height)?;
    crate::validate_camera(camera)?;
    let device = &gpu.device;
    let pass = GBufferPass::new(device)?;
    let gpu_scene = GpuScene::upload_with(device, &gpu.queue, scene, &pass, options)?;
    let targets = GBufferTargets::new(device, width, height)?;
    pass.write_frame(&gpu.queue, &Frame::new(camera, width, height));
    let buffer = VisibilityPass::buffer(device, width, height)?;
    let frame = pass.frame_buffer();
    let vis = VisibilityPass::new(device)?.bind(
        device,
        (&gpu_scene, scene),
        frame,
        (width, height),
        &buffer,
    )?;
    let resolve = ResolvePass::new(device, &pass)?.bind(
        device,
        (&gpu_scene, scene),
        frame,
        &buffer,
        &targets,
    )?;
    let mut encoder = device.create_command_encoder(&Default::default());
    vis.passes.then(resolve).encode(&mut encoder, None);
    let words =
        ::gpu::transfer::read_after(device, &gpu.queue, encoder, &buffer, 0..buffer.size())?;
    let mut gb = targets.read(device, &gpu.queue)?;
    for (d, w) in gb
        .depth
        .pixels_mut()
        .iter_mut()
        .zip(bytemuck::pod_collect_to_vec::<u8, u64>(&words))
    {
        *d = if w as u32 == NO_TRIANGLE {
            1.0
        } else {
            f32::from_bits((w >> 32) as u32)
        };
    }
    Ok(gb)
}
