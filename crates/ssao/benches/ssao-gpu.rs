//! `ssao-bench`: Table 7.1 of Holländer 2013 (annex 7.2) on the lent GPU — every estimator
//! (eq. 7.1's filter, Crytek SSAO, volumetric obscurance, HBAO, and GTAO as the modern anchor),
//! over the k × k kernel and separably, at full and half resolution, at kernels 5, 11 and 21,
//! at 1024×768 (the paper's),
//! 1920×1080 and 3840×2160 on Sponza, timed with timestamp queries; the O(k) sweep of the filter
//! (k = 3…21 at 1920×1080, a plot); and each estimator's error against ray-traced ambient
//! occlusion (same radius, 64 rays a pixel: mean absolute error and FLIP) at 1024×768 on
//! Sponza, the Cornell box and the thesis walls, with a picture sheet per scene at k = 21.
//! Written to `docs/bench/ssao-<adapter>-<date>.{md,json,svg}` and
//! `ssao-<adapter>-<date>-<scene>.png`.

use std::fmt::Write as _;

use anyhow::{Context, Result, bail};
use bench::{Header, Stat};
use clap::Parser;
use gbuffer::gpu::UploadedGBuffer;
use gbuffer::{Frame, GBuffer, Image};
use gpu::{Gpu, PassTimer, transfer, wgpu};
use serde::Serialize;
use ssao::cpu::KernelConfig;
use ssao::gpu::SsaoKernels;
use ssao::{AoConfig, Estimator, Method};

/// GPU benchmark of the ssao crate.
#[derive(Parser, Debug)]
#[command(version, about)]
struct Args {
    #[command(flatten)]
    options: bench::Options,
}

const SIZES: [(u32, u32); 3] = [(1024, 768), (1920, 1080), (3840, 2160)];
const KERNELS: [u32; 3] = [5, 11, 21];
/// The O(k) sweep's kernels (all read workgroup tiles).
const SWEEP: [u32; 10] = [3, 5, 7, 9, 11, 13, 15, 17, 19, 21];
const REFERENCE_RAYS: u32 = 64;

#[derive(Serialize)]
struct Timing {
    size: String,
    kernel: u32,
    estimator: String,
    time: Stat,
}

#[derive(Serialize)]
struct Error {
    scene: String,
    radius: f32,
    kernel: u32,
    estimator: String,
    /// Mean absolute difference from ray-traced AO over the pixels with a surface.
    mae: f64,
    /// Mean FLIP of the accessibility shown as grey against the ray-traced image.
    flip: f64,
}

#[derive(Serialize)]
struct Report {
    #[serde(flatten)]
    header: Header,
    frames: u32,
    /// Sponza's radius in the timings.
    radius: f32,
    timings: Vec<Timing>,
    sweep: Vec<Timing>,
    errors: Vec<Error>,
}

/// Every method: k × k, separable and separable without the smoothing, at full then half
/// resolution (the last one at full resolution only).
fn estimators() -> Vec<Estimator> {
    Method::ALL
        .into_iter()
        .flat_map(|method| {
            let (full, separable) = (Estimator::new(method, false), Estimator::new(method, true));
            [
                full,
                full.at_half_resolution(),
                separable,
                separable.at_half_resolution(),
                separable.without_smoothing(),
            ]
        })
        .collect()
}

/// The radius that the k = 21 kernel's half (10 pixels) spans at the median surface depth:
/// the screen-space kernels then reach as far as the ray-traced reference looks.
fn radius_for(g: &GBuffer, frame: &Frame) -> f32 {
    let mut depths: Vec<f32> = g
        .linear_depth
        .pixels()
        .iter()
        .copied()
        .filter(|&d| d > 0.0)
        .collect();
    depths.sort_by(f32::total_cmp);
    let median = depths.get(depths.len() / 2).copied().unwrap_or(1.0);
    10.0 * 2.0 * frame.tan_half_fov.y * median / frame.viewport.y
}

/// The estimators bound to one uploaded G-buffer.
struct Target {
    uploaded: UploadedGBuffer,
    output: wgpu::Buffer,
    size: (u32, u32),
}

impl Target {
    fn new(gpu: &Gpu, g: &GBuffer, frame: &Frame) -> Result<Self> {
        let uploaded = UploadedGBuffer::new(&gpu.device, &gpu.queue, g, frame)?;
        let size = (g.linear_depth.width(), g.linear_depth.height());
        let output = transfer::buffer(
            &gpu.device,
            "accessibility",
            u64::from(size.0) * u64::from(size.1) * 4,
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        )?;
        Ok(Self {
            uploaded,
            output,
            size,
        })
    }

    fn bind(
        &self,
        gpu: &Gpu,
        kernels: &SsaoKernels,
        config: &KernelConfig,
        estimator: Estimator,
    ) -> Result<ssao::gpu::BoundSsao> {
        let textures = [&self.uploaded.linear_depth, &self.uploaded.normal];
        Ok(kernels.bind(
            &gpu.device,
            &self.uploaded.frame,
            textures,
            &self.output,
            config,
            estimator,
        )?)
    }

    /// Runs `estimator` once and reads the accessibility back.
    fn run(
        &self,
        gpu: &Gpu,
        kernels: &SsaoKernels,
        config: &KernelConfig,
        estimator: Estimator,
    ) -> Result<Image<f32>> {
        let bound = self.bind(gpu, kernels, config, estimator)?;
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        kernels.encode(&bound, &mut encoder, None);
        gpu.queue.submit([encoder.finish()]);
        let values: Vec<f32> = transfer::read_pod(&gpu.device, &gpu.queue, &self.output)?;
        let mut image = Image::filled(self.size.0, self.size.1, 1.0);
        image.pixels_mut().copy_from_slice(&values);
        Ok(image)
    }

    /// Times `estimator` over `frames` frames (from its first pass's start to its last's end).
    fn time(
        &self,
        gpu: &Gpu,
        kernels: &SsaoKernels,
        config: &KernelConfig,
        estimator: Estimator,
        frames: u32,
    ) -> Result<Stat> {
        let bound = self.bind(gpu, kernels, config, estimator)?;
        let timer = PassTimer::new(&gpu.device, 4);
        let runs = bench::warm_then_time(frames, || -> Result<f64> {
            let mut encoder = gpu.device.create_command_encoder(&Default::default());
            kernels.encode(&bound, &mut encoder, Some(&timer));
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
}

/// A as a grey image whose sRGB value is A.
fn grey(a: &Image<f32>) -> Image<[f32; 4]> {
    a.map(|v| {
        let c = gbuffer::srgb_to_linear(v.clamp(0.0, 1.0));
        [c, c, c, 1.0]
    })
}

/// 1 − 4·|a − truth| as grey (white: no difference, black: 0.25 or more).
fn difference(a: &Image<f32>, truth: &Image<f32>) -> Image<f32> {
    let mut d = Image::filled(a.width(), a.height(), 1.0);
    for ((o, x), t) in d
        .pixels_mut()
        .iter_mut()
        .zip(a.pixels())
        .zip(truth.pixels())
    {
        *o = 1.0 - (4.0 * (x - t).abs()).min(1.0);
    }
    d
}

/// The sheet of one scene: columns ray-traced, then each method; rows k × k, separable, and
/// their differences from ray-traced; every image reduced 4× (box filter).
fn sheet(truth: &Image<f32>, images: &[(Estimator, Image<f32>)]) -> Image<[f32; 4]> {
    const REDUCE: u32 = 4;
    let (w, h) = (truth.width() / REDUCE, truth.height() / REDUCE);
    let columns = 1 + Method::ALL.len() as u32;
    let mut out = Image::filled(w * columns, h * 4, [1.0, 1.0, 1.0, 1.0]);
    let mut put = |image: &Image<f32>, column: u32, row: u32| {
        for y in 0..h {
            for x in 0..w {
                let mut sum = 0.0;
                for dy in 0..REDUCE {
                    for dx in 0..REDUCE {
                        sum += image.get(x * REDUCE + dx, y * REDUCE + dy);
                    }
                }
                let c = gbuffer::srgb_to_linear(sum / (REDUCE * REDUCE) as f32);
                out.set(column * w + x, row * h + y, [c, c, c, 1.0]);
            }
        }
    };
    put(truth, 0, 0);
    for (estimator, image) in images {
        let column = 1 + Method::ALL
            .iter()
            .position(|&m| m == estimator.method)
            .unwrap_or(0) as u32;
        let row = u32::from(estimator.separable);
        put(image, column, row);
        put(&difference(image, truth), column, row + 2);
    }
    out
}

fn main() -> Result<()> {
    let args = Args::parse_from(bench::args());
    let gpu = args.options.gpu()?;
    let frames = args.options.frames(50);
    let out = bench::out_dir(&args.options.out);
    let header = Header::new(&gpu);
    let stem = header.file_stem("ssao-");
    let kernels = SsaoKernels::new(&gpu.device)?;
    let once = bench::run_once();
    let sizes = if once { &SIZES[..1] } else { &SIZES[..] };
    let sweep = if once { &SWEEP[..1] } else { &SWEEP[..] };

    // Timings on Sponza.
    let (sponza, camera) = bench::fixture("sponza/dabrovic/sponza.gltf")?;
    let first = bench::size(SIZES[0]);
    let g = gbuffer::cpu::rasterize(&sponza, &camera, first.0, first.1)?.gbuffer;
    let radius = radius_for(&g, &Frame::new(&camera, first.0, first.1));
    let mut timings = Vec::new();
    let mut swept = Vec::new();
    for &size in sizes {
        let size = bench::size(size);
        let g = gbuffer::cpu::rasterize(&sponza, &camera, size.0, size.1)?.gbuffer;
        let frame = Frame::new(&camera, size.0, size.1);
        let target = Target::new(&gpu, &g, &frame)?;
        for kernel in KERNELS {
            let config = KernelConfig {
                size: kernel,
                ao: AoConfig { radius },
            };
            for estimator in estimators() {
                let time = target.time(&gpu, &kernels, &config, estimator, frames)?;
                println!(
                    "{}×{} k {kernel} {estimator}: {:.3} ms",
                    size.0, size.1, time.median_ms
                );
                timings.push(Timing {
                    size: format!("{}x{}", size.0, size.1),
                    kernel,
                    estimator: estimator.to_string(),
                    time,
                });
            }
        }
        if size == bench::size(SIZES[1]) || once {
            for &kernel in sweep {
                let config = KernelConfig {
                    size: kernel,
                    ao: AoConfig { radius },
                };
                let separable = Estimator::new(Method::Filter, true);
                let variants = [
                    Estimator::new(Method::Filter, false),
                    separable,
                    separable.without_smoothing(),
                ];
                for estimator in variants {
                    let time = target.time(&gpu, &kernels, &config, estimator, frames)?;
                    swept.push(Timing {
                        size: format!("{}x{}", size.0, size.1),
                        kernel,
                        estimator: estimator.to_string(),
                        time,
                    });
                }
            }
        }
    }

    // Errors against ray-traced AO, and the picture sheets.
    let scenes: Vec<(&str, scene::Scene, scene::Camera)> = {
        let cornell = scene::cornell_box();
        let walls = scene::thesis_walls(0);
        let (cc, wc) = (cornell.camera_or_framed(), walls.camera_or_framed());
        vec![
            ("sponza", sponza, camera),
            ("cornell", cornell, cc),
            ("walls", walls, wc),
        ]
    };
    let scenes = if once { &scenes[..1] } else { &scenes[..] };
    let mut errors = Vec::new();
    std::fs::create_dir_all(&out).with_context(|| format!("cannot create {}", out.display()))?;
    for (name, scene, camera) in scenes {
        let size = bench::size(SIZES[0]);
        let g = gbuffer::cpu::rasterize(scene, camera, size.0, size.1)?.gbuffer;
        let frame = Frame::new(camera, size.0, size.1);
        let radius = radius_for(&g, &frame);
        let target = Target::new(&gpu, &g, &frame)?;
        let bvh = scene::Bvh::build(scene);
        let ao = AoConfig { radius };
        let truth = ssao::reference::ray_traced(&bvh, &g, &frame, &ao, REFERENCE_RAYS)?;
        let truth_grey = grey(&truth);
        let surfaces: Vec<bool> = g.linear_depth.pixels().iter().map(|&d| d > 0.0).collect();
        let count = surfaces.iter().filter(|&&s| s).count().max(1);
        for kernel in KERNELS {
            let config = KernelConfig { size: kernel, ao };
            let mut images = Vec::new();
            for estimator in estimators() {
                if estimator.half_resolution && !estimator.separable {
                    continue;
                }
                let a = target.run(&gpu, &kernels, &config, estimator)?;
                let mae = a
                    .pixels()
                    .iter()
                    .zip(truth.pixels())
                    .zip(&surfaces)
                    .filter(|(_, s)| **s)
                    .map(|((a, t), _)| f64::from((a - t).abs()))
                    .sum::<f64>()
                    / count as f64;
                let flip = bench::quality(&truth_grey, &grey(&a)).flip_mean;
                println!("{name} k {kernel} {estimator}: error {mae:.4}, FLIP {flip:.4}");
                errors.push(Error {
                    scene: (*name).into(),
                    radius,
                    kernel,
                    estimator: estimator.to_string(),
                    mae,
                    flip,
                });
                if !estimator.half_resolution {
                    images.push((estimator, a));
                }
            }
            if kernel == KERNELS[KERNELS.len() - 1] {
                sheet(&truth, &images).write_png(&out.join(format!("{stem}-{name}.png")))?;
            }
        }
    }

    let report = Report {
        header: header.clone(),
        frames,
        radius,
        timings,
        sweep: swept,
        errors,
    };
    std::fs::write(out.join(format!("{stem}.svg")), sweep_svg(&report))?;
    let md = markdown(&report, &stem, frames);
    args.options.write_report(&header, "ssao-", &report, &md)
}

/// The median time of `estimator` at `size` and `kernel`.
fn median(rows: &[Timing], size: &str, kernel: u32, estimator: &str) -> Option<f64> {
    rows.iter()
        .find(|t| t.size == size && t.kernel == kernel && t.estimator == estimator)
        .map(|t| t.time.median_ms)
}

fn markdown(r: &Report, stem: &str, frames: u32) -> String {
    let mut md = r
        .header
        .markdown("Screen-space ambient occlusion (Table 7.1)", frames);
    let _ = writeln!(
        md,
        "Timings on Sponza, radius {:.3} (the world size of 10 pixels at the median depth at 1024×768); median ms of the estimator's passes. Ratio: separable / k×k of the same method.\n",
        r.radius
    );
    let mut sizes: Vec<&str> = r.timings.iter().map(|t| t.size.as_str()).collect();
    sizes.dedup();
    for size in sizes {
        let _ = writeln!(
            md,
            "### {size}\n\n| k | method | k×k ms | separable ms | separable / k×k | separable unsmoothed ms | k×k half ms | separable half ms |\n|---:|---|---:|---:|---:|---:|---:|---:|"
        );
        for kernel in KERNELS {
            for method in Method::ALL {
                let time = |suffix: &str| {
                    let name = format!("{}{suffix}", method.name());
                    median(&r.timings, size, kernel, &name)
                };
                let times = [
                    "",
                    "-separable",
                    "-separable-unsmoothed",
                    "-half",
                    "-separable-half",
                ]
                .map(time);
                if let [
                    Some(full),
                    Some(separable),
                    Some(raw),
                    Some(full_half),
                    Some(half),
                ] = times
                {
                    let _ = writeln!(
                        md,
                        "| {kernel} | {} | {full:.3} | {separable:.3} | {:.2} | {raw:.3} | {full_half:.3} | {half:.3} |",
                        method.name(),
                        separable / full
                    );
                }
            }
        }
        md.push('\n');
    }
    let _ = writeln!(
        md,
        "### O(k): the filter at {}\n\n![time against k]({stem}.svg)\n\n| k | k×k ms | separable ms | separable unsmoothed ms |\n|---:|---:|---:|---:|",
        r.sweep.first().map_or("", |t| t.size.as_str())
    );
    for kernel in SWEEP {
        let size = r.sweep.first().map_or("", |t| t.size.as_str());
        let times = ["filter", "filter-separable", "filter-separable-unsmoothed"]
            .map(|e| median(&r.sweep, size, kernel, e));
        if let [Some(full), Some(separable), Some(raw)] = times {
            let _ = writeln!(md, "| {kernel} | {full:.3} | {separable:.3} | {raw:.3} |");
        }
    }
    let _ = writeln!(
        md,
        "\n### Error against ray-traced AO ({REFERENCE_RAYS} rays a pixel), 1024×768\n\nMean absolute error over the surface pixels / mean FLIP of A shown as grey. Radius: the world size of 10 pixels at the scene's median depth. Half resolution: the same k in steps of two pixels (twice the reach).\n\n| scene | k | method | k×k | separable | separable / k×k (MAE) | separable unsmoothed | separable half |\n|---|---:|---|---:|---:|---:|---:|---:|"
    );
    let plain = r
        .errors
        .iter()
        .filter(|e| Method::ALL.iter().any(|m| m.name() == e.estimator));
    for e in plain {
        let find = |suffix: &str| {
            r.errors.iter().find(|s| {
                s.scene == e.scene
                    && s.kernel == e.kernel
                    && s.estimator == format!("{}{suffix}", e.estimator)
            })
        };
        let found = [
            find("-separable"),
            find("-separable-unsmoothed"),
            find("-separable-half"),
        ];
        if let [Some(s), Some(u), Some(h)] = found {
            let _ = writeln!(
                md,
                "| {} (r {:.3}) | {} | {} | {:.4} / {:.4} | {:.4} / {:.4} | {:.2} | {:.4} / {:.4} | {:.4} / {:.4} |",
                e.scene,
                e.radius,
                e.kernel,
                e.estimator,
                e.mae,
                e.flip,
                s.mae,
                s.flip,
                s.mae / e.mae,
                u.mae,
                u.flip,
                h.mae,
                h.flip
            );
        }
    }
    let _ = writeln!(
        md,
        "\nPicture sheets at k = 21 (columns: ray-traced, filter, Crytek, VO, HBAO, GTAO; rows: k×k, separable, then 1 − 4·|difference from ray-traced| of each): {}",
        ["sponza", "cornell", "walls"]
            .map(|s| format!("[{s}]({stem}-{s}.png)"))
            .join(", ")
    );
    md
}

/// Time against kernel size, k × k and separable: the paper's O(k²) against O(k).
fn sweep_svg(r: &Report) -> String {
    let series = [
        ("filter", "k×k"),
        ("filter-separable", "separable"),
        ("filter-separable-unsmoothed", "unsmoothed"),
    ]
    .into_iter()
    .map(|(estimator, name)| bench::chart::Series {
        name: name.into(),
        points: r
            .sweep
            .iter()
            .filter(|t| t.estimator == estimator)
            .map(|t| (f64::from(t.kernel), t.time.median_ms))
            .collect(),
    })
    .collect();
    bench::chart::LineChart {
        title: format!(
            "Eq. 7.1's filter, {} ({}): time against kernel side k",
            r.sweep.first().map_or("", |t| t.size.as_str()),
            r.header.adapter
        ),
        x_label: "k (pixels)".into(),
        y_label: "ms".into(),
        x_ticks: SWEEP.map(|k| (f64::from(k), k.to_string())).to_vec(),
        series,
    }
    .svg()
}
