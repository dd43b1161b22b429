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

/// Like [`run_with`] through the visibility buffer ([`super::visibility`]) with pixels merged
/// as `atomics` says: the compute rasteriser (alpha-tested meshes by the hardware draw into
/// it), the resolve along `path` and the depth target drawn from the visibility buffer. An
/// error where the device cannot take `path` (for [`ResolvePath::OneDispatch`]: see
/// [`super::visibility::bindless_needs`]).
///
/// [`ResolvePath::OneDispatch`]: super::visibility::ResolvePath::OneDispatch
pub fn run_visibility(
    gpu: &Gpu,
    scene: &Scene,
    camera: &Camera,
    (width, height): (u32, u32),
    options: &TextureOptions,
    (atomics, path): (super::visibility::Atomics, super::visibility::ResolvePath),
) -> Result<GBuffer, GBufferError> {
    use super::visibility::{Capacity, ResolvePass, VisibilityPass};
    crate::validate_size(width, height)?;
    crate::validate_camera(camera)?;
    let device = &gpu.device;
    let pass = GBufferPass::new(device)?;
    let gpu_scene = GpuScene::upload_with(device, &gpu.queue, scene, &pass, options)?;
    let targets = GBufferTargets::new(device, width, height)?;
    pass.write_frame(&gpu.queue, &Frame::new(camera, width, height));
    let buffer = VisibilityPass::buffer(device, width, height)?;
    let frame = pass.frame_buffer();
    let vis = VisibilityPass::with(device, &pass, Capacity::default(), atomics)?.bind(
        device,
        &gpu_scene,
        frame,
        (width, height),
        &buffer,
    )?;
    let resolve_pass = ResolvePass::with(device, &pass, path)?;
    let resolve = resolve_pass.bind(device, &gpu_scene, frame, &vis, &targets)?;
    if resolve.path != path {
        return Err(GBufferError::InvalidOptions(format!(
            "the resolve along {path:?} needs binding arrays of the scene's {} textures (features {:?}); the device resolves along {:?}",
            gpu_scene.textures.all().len(),
            super::visibility::BINDLESS_FEATURES,
            resolve.path
        )));
    }
    let mut encoder = device.create_command_encoder(&Default::default());
    vis.encode(&mut encoder, Some(&targets.depth), None)?;
    resolve.passes.encode(&mut encoder, None);
    resolve_pass.encode_depth(&resolve, &mut encoder, &targets.depth, None);
    gpu.queue.submit([encoder.finish()]);
    targets.read(device, &gpu.queue)
}
