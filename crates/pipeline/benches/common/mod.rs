//! Timing of whole renderer frames, shared by this crate's GPU benchmark programs.

use glam::Vec3;
use gpu::Gpu;
use pipeline::{PassTiming, RenderError, gpu::GpuRenderer};
use scene::Camera;

/// Per pass name, the per-frame GPU milliseconds of `frames` frames of `renderer`
/// ([`bench::time_named`]: after the harness's warm-up).
pub fn time_passes(
    gpu: &Gpu,
    renderer: &mut GpuRenderer,
    camera: &Camera,
    ambient: Vec3,
    frames: u32,
) -> Result<Vec<(String, Vec<f64>)>, RenderError> {
    bench::time_named(frames, || {
        let timings: Vec<PassTiming> =
            renderer.time_frame(&gpu.device, &gpu.queue, camera, ambient)?;
        Ok(timings.into_iter().map(|t| (t.name, t.ms)).collect())
    })
}
