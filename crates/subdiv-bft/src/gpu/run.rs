//! Convenience for tests and examples: upload, run, read back.

use ::gpu::Gpu;
use glam::Vec3;

use super::GpuSubdivider;
use crate::{BftSet, Refined, SubdivError, Subdivider};

/// Uploads, runs both steps at `level` and reads the mesh back.
pub fn run(
    gpu: &Gpu,
    sub: &Subdivider,
    bft: &BftSet,
    m0_positions: &[Vec3],
    level: u32,
) -> Result<Refined, SubdivError> {
    let g = GpuSubdivider::new(&gpu.device, sub, bft)?;
    let out = g.level(&gpu.device, sub, level)?;
    g.set_positions(&gpu.queue, m0_positions)?;
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    g.encode(&mut encoder, &out, None);
    gpu.queue.submit([encoder.finish()]);
    g.read_level(&gpu.device, &gpu.queue, &out)
}

/// Uploads, computes screen-space factors for `view` on the GPU, runs the adaptive
/// tessellation up to `max_level` and reads back the mesh (the whole vertex layout, triangles
/// in append order) and the factors.
pub fn run_adaptive(
    gpu: &Gpu,
    sub: &Subdivider,
    bft: &BftSet,
    m0_positions: &[Vec3],
    max_level: u32,
    view: &crate::adaptive::ScreenView,
) -> Result<(Refined, Vec<f32>), SubdivError> {
    let g = GpuSubdivider::new(&gpu.device, sub, bft)?;
    let a = g.adaptive(&gpu.device, sub, max_level)?;
    g.set_positions(&gpu.queue, m0_positions)?;
    a.set_view(&gpu.queue, view)?;
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    g.encode_initial(&mut encoder, None);
    g.encode_screen_factors(&mut encoder, &a, None);
    g.encode_adaptive(&mut encoder, &a, None);
    gpu.queue.submit([encoder.finish()]);
    Ok((
        g.read_adaptive(&gpu.device, &gpu.queue, &a)?,
        g.read_factors(&gpu.device, &gpu.queue, &a)?,
    ))
}
