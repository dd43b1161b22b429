//! Timing of whole renderer frames, shared by this crate's GPU benchmark programs.

use glam::Vec3;
use gpu::Gpu;
use pipeline::{PassTiming, RenderError, gpu::GpuRenderer};
use scene::{Camera, Light};

/// Per pass name, the per-frame GPU milliseconds of `frames` frames of `renderer`
/// ([`bench::time_named`]: after the harness's warm-up). With `relight`, those lights are set
/// before every frame, as when they move, so per-frame light uploads and builds are timed too.
pub fn time_passes(
    gpu: &Gpu,
    renderer: &mut GpuRenderer,
    camera: &Camera,
    ambient: Vec3,
    frames: u32,
    relight: Option<&[Light]>,
) -> Result<Vec<(String, Vec<f64>)>, RenderError> {
    bench::time_named(frames, || {
        if let Some(lights) = relight {
            renderer.set_lights(&gpu.device, &gpu.queue, lights)?;
        }
        let timings: Vec<PassTiming> =
            renderer.time_frame(&gpu.device, &gpu.queue, camera, ambient)?;
        Ok(timings.into_iter().map(|t| (t.name, t.ms)).collect())
    })
}
