//! `ssao-bench`: Table 7.1 of Holländer 2013 (annex 7.2) on the lent GPU — eq. 7.1's k × k
//! kernel against its separable approximation at kernels 5, 11 and 21, at 1024×768 (the
//! paper's), 1920×1080 and 3840×2160, timed with timestamp queries — with each estimator's mean
//! absolute error against ray-traced ambient occlusion (same radius, 64 rays a pixel) at
//! 1024×768, on Sponza. Written to `docs/bench/ssao-<adapter>-<date>.{md,json}`.

use std::fmt::Write as _;

use anyhow::{Result, bail};
use bench::{Header, Stat};
use clap::Parser;
use gbuffer::gpu::UploadedGBuffer;
use gpu::{Gpu, PassTimer, transfer, wgpu};
use serde::Serialize;
use ssao::AoConfig;
use ssao::cpu::KernelConfig;
use ssao::gpu::{Estimator, SsaoKernels};

/// GPU benchmark of the ssao crate.
#[derive(Parser, Debug)]
#[command(version, about)]
struct Args {
    #[command(flatten)]
    options: bench::Options,
}

const SIZES: [(u32, u32); 3] = [(1024, 768), (1920, 1080), (3840, 2160)];
const KERNELS: [u32; 3] = [5, 11, 21];
const REFERENCE_RAYS: u32 = 64;

#[derive(Serialize)]
struct Row {
    size: String,
    kernel: u32,
    estimator: String,
    time: Stat,
    /// Mean absolute error against ray-traced AO (at the first size only).
    error: Option<f64>,
}

#[derive(Serialize)]
struct Report {
    #[serde(flatten)]
    header: Header,
    frames: u32,
    radius: f32,
    rows: Vec<Row>,
}

/// Times the estimator's passes over `frames` frames (from the first pass's start to the last's
/// end).
fn time(
    gpu: &Gpu,
    frames: u32,
    record: impl Fn(&mut wgpu::CommandEncoder, &PassTimer),
) -> Result<Stat> {
    let timer = PassTimer::new(&gpu.device, 4);
    let runs = bench::warm_then_time(frames, || -> Result<f64> {
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        record(&mut encoder, &timer);
        timer.resolve(&mut encoder);
        gpu.queue.submit([encoder.finish()]);
        let times = timer.read(&gpu.device, &gpu.queue)?;
        let (Some(first), Some(last)) = (times.first(), times.last()) else {
            bail!("the adapter has no timestamp queries");
        };
        Ok(last.end_ms() - first.start_ms)
    })?;
    Ok(Stat::of(runs))
}

fn main() -> Result<()> {
    let args = Args::parse_from(bench::args());
    let gpu = args.options.gpu()?;
    let frames = args.options.frames(50);
    let (scene, camera) = bench::fixture("sponza/dabrovic/sponza.gltf")?;
    let radius = 0.02 * scene.bounds().diagonal();
    let kernels = SsaoKernels::new(&gpu.device)?;
    let bvh = scene::Bvh::build(&scene);
    let mut rows = Vec::new();
    for (i, size) in SIZES.map(bench::size).into_iter().enumerate() {
        let g = gbuffer::cpu::rasterize(&scene, &camera, size.0, size.1)?.gbuffer;
        let frame = gbuffer::Frame::new(&camera, size.0, size.1);
        let uploaded = UploadedGBuffer::new(&gpu.device, &gpu.queue, &g, &frame)?;
        let pixels = u64::from(size.0) * u64::from(size.1);
        let output = transfer::buffer(
            &gpu.device,
            "accessibility",
            pixels * 4,
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        )?;
        let truth = (i == 0)
            .then(|| {
                ssao::reference::ray_traced(&bvh, &g, &frame, &AoConfig { radius }, REFERENCE_RAYS)
            })
            .transpose()?;
        for kernel in KERNELS {
            let config = KernelConfig {
                size: kernel,
                ao: AoConfig { radius },
            };
            for estimator in [Estimator::Kernel2d, Estimator::Separable] {
                let textures = [&uploaded.linear_depth, &uploaded.normal];
                let bound = kernels.bind(
                    &gpu.device,
                    &uploaded.frame,
                    textures,
                    &output,
                    &config,
                    estimator,
                )?;
                let stat = time(&gpu, frames, |e, t| kernels.encode(&bound, e, Some(t)))?;
                let error = match &truth {
                    Some(truth) => {
                        let a: Vec<f32> = transfer::read_pod(&gpu.device, &gpu.queue, &output)?;
                        let surfaces: Vec<(f32, f32)> = a
                            .iter()
                            .zip(truth.pixels())
                            .zip(g.linear_depth.pixels())
                            .filter(|(_, d)| **d > 0.0)
                            .map(|((a, t), _)| (*a, *t))
                            .collect();
                        let sum: f64 = surfaces.iter().map(|(a, t)| f64::from((a - t).abs())).sum();
                        Some(sum / surfaces.len().max(1) as f64)
                    }
                    None => None,
                };
                println!(
                    "{}×{} k {kernel} {estimator:?}: {:.3} ms{}",
                    size.0,
                    size.1,
                    stat.median_ms,
                    error.map_or(String::new(), |e| format!(", error {e:.4}"))
                );
                rows.push(Row {
                    size: format!("{}x{}", size.0, size.1),
                    kernel,
                    estimator: format!("{estimator:?}"),
                    time: stat,
                    error,
                });
            }
        }
    }
    let header = Header::new(&gpu);
    let mut md = header.markdown("Screen-space ambient occlusion (Table 7.1)", frames);
    let _ = writeln!(
        md,
        "Sponza, radius {radius:.3} (2 % of the scene's diagonal); error: mean absolute difference from ray-traced AO ({REFERENCE_RAYS} rays a pixel) over the pixels with a surface.\n\n| size | k | eq. 7.1 (k×k) ms | separable (2 passes) ms | separable / k×k | error k×k | error separable |\n|---|---:|---:|---:|---:|---:|---:|"
    );
    for pair in rows.chunks(2) {
        let (full, sep) = (&pair[0], &pair[1]);
        let e = |r: &Row| r.error.map_or("—".into(), |e| format!("{e:.4}"));
        let _ = writeln!(
            md,
            "| {} | {} | {:.3} | {:.3} | {:.2} | {} | {} |",
            full.size,
            full.kernel,
            full.time.median_ms,
            sep.time.median_ms,
            sep.time.median_ms / full.time.median_ms,
            e(full),
            e(sep)
        );
    }
    let report = Report {
        header: header.clone(),
        frames,
        radius,
        rows,
    };
    args.options.write_report(&header, "ssao-", &report, &md)
}
