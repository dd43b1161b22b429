//! `ssaa-bench`: adaptive supersampling (Holländer 2013 §4.3) against full supersampling
//! measured in the same run — the set-ups of Tables 4.1 and 4.2: Sponza (with the built-in
//! checker texture on its untextured materials) and the textured DamagedHelmet, 1024×768 and
//! 1920×1080, m = 2, 3, 4, every geometric metric alone and ND + shading metric (loop and
//! sorted resolve), plus one sample per pixel, FXAA and SMAA 1x (the `smaa` crate, same device
//! and frame: [`smaa`]). Times are GPU times of the shading
//! passes after the shared supersampled G-buffer (reported apart), with the light loop run once
//! ("real-time") and 32 times per sample ("stalled"). MSE/PSNR (sRGB, [0, 1]) and FLIP are
//! measured against full supersampling. Writes `adaptive-ssaa-<adapter>-<date>.{md,json}`.

use std::path::{Path, PathBuf};

use adaptive_ssaa::gpu::SsaaRenderer;
use adaptive_ssaa::{GeometricMetric, Resolve, SsaaConfig};
use anyhow::{Context, Result};
use bench::Stat;
use clap::Parser;
use gbuffer::Image;
use glam::Vec3;
use gpu::{Gpu, PassTimer};
use scene::{Light, Scene};
use serde::Serialize;

mod smaa;

/// Benchmarks adaptive supersampling against full supersampling, one sample and FXAA.
#[derive(Parser, Debug)]
struct Args {
    #[command(flatten)]
    options: bench::Options,
    /// Sponza at 1024×768, m = 4, no stall, ND + shading and the sweep only (a tuning run).
    #[arg(long)]
    quick: bool,
    /// Scales of the ND + shading constants swept at 1024×768 (and in --quick), without stall.
    #[arg(long, value_delimiter = ',', default_value = "0.25,0.5,2,4")]
    sweep: Vec<f32>,
    /// Also write the pictures of the docs (Sponza 1024×768, m = 4) into this folder; at the
    /// docs' size in run-once mode too (one frame per measurement: pictures on a software
    /// adapter).
    #[arg(long)]
    images: Option<PathBuf>,
}

/// A method of the table: its name, geometric metric, shading metric on or off, resolve and
/// the scale of its constants.
type Method = (String, Option<GeometricMetric>, bool, Resolve, f32);

/// Light loop repetitions of the "stalled" column.
const STALL: u32 = 32;

#[derive(Serialize, Clone)]
struct Row {
    scene: String,
    width: u32,
    height: u32,
    m: u32,
    method: String,
    stall: u32,
    ms: Stat,
    /// Median full-supersampling ms / median ms (same stall).
    speedup_vs_full: f64,
    /// Samples as a fraction of m² per pixel.
    samples: f64,
    /// Shading evaluations as a fraction of full supersampling's.
    shaded: f64,
    mse: f64,
    psnr: f64,
    flip_mean: f64,
}

#[derive(Serialize)]
struct Report {
    header: bench::Header,
    frames: u32,
    stall: u32,
    gbuffer: Vec<(String, u32, u32, u32, Stat)>,
    /// Per scene, size and m: the bracket of [`smaa::Smaa::time`] around an empty submission,
    /// with the one-sample shading (the floor under the SMAA rows).
    smaa_floor: Vec<(String, u32, u32, u32, Stat)>,
    rows: Vec<Row>,
}

/// The adapted scenes: Sponza with the checker on untextured materials, and DamagedHelmet.
fn scenes(quick: bool) -> Result<Vec<(String, Scene, scene::Camera)>> {
    let fixtures = scene::shared_fixtures().context("../shared/fixtures not found")?;
    let sponza_path = fixtures.join("sponza/dabrovic/sponza.gltf");
    let mut sponza = Scene::load(&sponza_path)?;
    let checker = sponza.textures.len() as u32;
    sponza.textures.push(scene::checker_texture());
    for m in &mut sponza.materials {
        m.base_color_texture
            .get_or_insert(scene::TextureRef::new(checker));
    }
    let camera =
        scene::preset_view(&sponza_path, &sponza).unwrap_or_else(|| sponza.camera_or_framed());
    let mut out = vec![("sponza".to_string(), sponza, camera)];
    if !quick {
        let helmet = Scene::load(&fixtures.join("gltf/DamagedHelmet/DamagedHelmet.glb"))?;
        let camera = helmet.camera_or_framed();
        out.push(("damaged-helmet".to_string(), helmet, camera));
    }
    Ok(out)
}

/// A sun and 16 scattered bounded point lights (seeded).
fn lights(scene: &Scene) -> Result<Vec<tiled_shading::GpuLight>> {
    let mut lights = vec![Light::Directional {
        direction: Vec3::new(-0.3, -1.0, -0.4).normalize(),
        color: Vec3::new(1.0, 0.95, 0.85),
        intensity: 2.5,
    }];
    lights.extend(scene::scatter_point_lights(scene.bounds(), 16, 11));
    Ok(tiled_shading::gpu_lights(&lights)?)
}

fn time(
    gpu: &Gpu,
    timer: &PassTimer,
    frames: u32,
    record: &dyn Fn(&mut wgpu::CommandEncoder, &PassTimer),
) -> Result<Stat> {
    Ok(bench::time_encoded(gpu, timer, frames, false, record)?)
}

/// Heat colour of the absolute error (max over channels of sRGB values), full scale at `max`.
fn error_heatmap(a: &Image<[f32; 4]>, b: &Image<[f32; 4]>, max: f32) -> Result<Image<[f32; 4]>> {
    let srgb = |v: f32| gbuffer::linear_to_srgb(v.clamp(0.0, 1.0));
    let data = a
        .pixels()
        .iter()
        .zip(b.pixels())
        .map(|(p, q)| {
            let e = (0..3)
                .map(|c| (srgb(p[c]) - srgb(q[c])).abs())
                .fold(0.0f32, f32::max);
            tiled_shading::heat_color((e / max).min(1.0))
        })
        .collect();
    Ok(Image::from_vec(a.width(), a.height(), data)?)
}

fn main() -> Result<()> {
    let args = Args::parse_from(bench::args());
    let gpu = args.options.gpu()?;
    let frames = args.options.frames(10);
    let timer = PassTimer::new(&gpu.device, 16);
    let quick = args.quick || bench::run_once();
    let sizes: &[(u32, u32)] = if quick {
        &[(1024, 768)]
    } else {
        &[(1024, 768), (1920, 1080)]
    };
    let ms_list: &[u32] = if quick { &[4] } else { &[2, 3, 4] };
    let stalls: &[u32] = if quick { &[1] } else { &[1, STALL] };
    let nd = Some(GeometricMetric::NormalDepth);
    let mut methods: Vec<Method> = vec![
        ("ND+shading".into(), nd, true, Resolve::Loop, 1.0),
        ("ND+shading tiles".into(), nd, true, Resolve::Tiles, 1.0),
    ];
    if !quick {
        methods.push(("ND+shading sorted".into(), nd, true, Resolve::Sorted, 1.0));
        methods.extend(
            GeometricMetric::ALL
                .map(|g| (g.name().to_string(), Some(g), false, Resolve::Loop, 1.0)),
        );
        methods.push(("shading".into(), None, true, Resolve::Loop, 1.0));
    }
    methods.extend(
        args.sweep
            .iter()
            .map(|&s| (format!("ND+shading c×{s}"), nd, true, Resolve::Loop, s)),
    );
    let mut rows = Vec::new();
    let mut gbuffer_times = Vec::new();
    let mut smaa_floor = Vec::new();
    for (name, scene, camera) in scenes(quick)? {
        let lights = lights(&scene)?;
        let size = |s| {
            if args.images.is_some() {
                s
            } else {
                bench::size(s)
            }
        };
        for (w, h) in sizes.iter().copied().map(size) {
            for &m in ms_list {
                let base = SsaaConfig {
                    m,
                    ..Default::default()
                };
                let mut r =
                    SsaaRenderer::new(&gpu.device, &gpu.queue, &scene, &lights, w, h, &base)?;
                r.set_camera(&gpu.queue, &camera)?;
                let g = time(&gpu, &timer, frames, &|e, t| r.encode_gbuffer(e, Some(t)))?;
                println!(
                    "{name} {w}×{h} m={m}: supersampled G-buffer {:.3} ms",
                    g.median_ms
                );
                gbuffer_times.push((name.clone(), w, h, m, g));
                // The G-buffer stays; every configuration below shades it.
                let mut encoder = gpu.device.create_command_encoder(&Default::default());
                r.encode_gbuffer(&mut encoder, None);
                gpu.queue.submit([encoder.finish()]);
                for &stall in stalls {
                    let config = SsaaConfig { stall, ..base };
                    r.ssaa.set_config(&gpu.queue, &config)?;
                    let full_ms =
                        time(&gpu, &timer, frames, &|e, t| r.ssaa.encode_full(e, Some(t)))?;
                    let full = r.ssaa.read_output(&gpu.device, &gpu.queue)?;
                    let row = |method: &str,
                               ms: Stat,
                               image: &Image<[f32; 4]>,
                               samples: f64,
                               shaded: f64| {
                        let q = bench::quality(&full, image);
                        let row = Row {
                            scene: name.clone(),
                            width: w,
                            height: h,
                            m,
                            method: method.into(),
                            stall,
                            speedup_vs_full: full_ms.median_ms / ms.median_ms,
                            ms,
                            samples,
                            shaded,
                            mse: q.rmse * q.rmse,
                            psnr: q.psnr,
                            flip_mean: q.flip_mean,
                        };
                        println!(
                            "{name} {w}×{h} m={m} stall {stall} {method:<18} {:>8.3} ms ×{:<5.2} samples {:>5.1} % MSE {:.2e} PSNR {:.1} FLIP {:.4}",
                            row.ms.median_ms,
                            row.speedup_vs_full,
                            100.0 * samples,
                            row.mse,
                            row.psnr,
                            row.flip_mean
                        );
                        row
                    };
                    rows.push(row("full SSAA", full_ms, &full, 1.0, 1.0));
                    let one = f64::from(m * m).recip();
                    let first_ms = time(&gpu, &timer, frames, &|e, t| {
                        r.ssaa.encode_first(e, Some(t))
                    })?;
                    let first = r.ssaa.read_first(&gpu.device, &gpu.queue)?;
                    rows.push(row("1 sample", first_ms, &first, one, one));
                    let fxaa_ms = time(&gpu, &timer, frames, &|e, t| {
                        r.ssaa.encode_first(e, Some(t));
                        r.ssaa.encode_fxaa(e, Some(t));
                    })?;
                    rows.push(row(
                        "FXAA",
                        fxaa_ms,
                        &r.ssaa.read_output(&gpu.device, &gpu.queue)?,
                        one,
                        one,
                    ));
                    let mut smaa = smaa::Smaa::new(&gpu, &r.ssaa, w, h);
                    let mut smaa_time = |on: bool| -> Result<Stat> {
                        Ok(Stat::of(bench::warm_then_time(frames, || {
                            smaa.time(&gpu, &r.ssaa, &timer, on)
                        })?))
                    };
                    if stall == 1 {
                        smaa_floor.push((name.clone(), w, h, m, smaa_time(false)?));
                    }
                    // Last, so that the output holds SMAA's image.
                    let smaa_ms = smaa_time(true)?;
                    let smaa_image = smaa.read(&gpu)?;
                    rows.push(row("SMAA 1x", smaa_ms, &smaa_image, one, one));
                    // The configuration of a method: its metrics, constants scaled.
                    let method_config = |(_, metric, shading, resolve, scale): &Method| {
                        let c = config.constants;
                        let sm = adaptive_ssaa::ShadingMetric::default();
                        SsaaConfig {
                            metric: *metric,
                            constants: adaptive_ssaa::Constants {
                                mm: c.mm * scale,
                                nc: c.nc * scale,
                                dv: c.dv * scale,
                                nv: c.nv * scale,
                            },
                            shading: shading.then_some(adaptive_ssaa::ShadingMetric {
                                c: sm.c * scale,
                                ..sm
                            }),
                            resolve: *resolve,
                            ..config
                        }
                    };
                    let first_method = rows.len();
                    for method in &methods {
                        let (label, _, _, _, scale) = method;
                        let swept = *scale != 1.0;
                        if swept && (stall != 1 || w != sizes[0].0) {
                            continue;
                        }
                        r.ssaa.set_config(&gpu.queue, &method_config(method))?;
                        let ms = time(&gpu, &timer, frames, &|e, t| r.ssaa.encode(e, Some(t)))?;
                        let out = adaptive_ssaa::cpu::Output {
                            image: r.ssaa.read_output(&gpu.device, &gpu.queue)?,
                            first: r.ssaa.read_first(&gpu.device, &gpu.queue)?,
                            counts: r.ssaa.read_counts(&gpu.device, &gpu.queue)?,
                        };
                        rows.push(row(
                            label,
                            ms,
                            &out.image,
                            out.sample_fraction(m),
                            out.shaded(m),
                        ));
                        let pictures = (name == "sponza"
                            && w == 1024
                            && m == 4
                            && stall == 1
                            && label == "ND+shading")
                            || (quick && label == "ND+shading");
                        if let (Some(dir), true) = (&args.images, pictures) {
                            write_pictures(dir, &name, m, &full, &out, &smaa_image)?;
                        }
                    }
                    // Along the scales of the constants of each method.
                    let method_of = |row: &Row| methods.iter().find(|m| m.0 == row.method);
                    bench::remeasure_outliers(
                        &mut rows[first_method..],
                        |row| {
                            let family = row.method.split(" c×").next().unwrap_or_default();
                            (
                                family.to_owned(),
                                method_of(row).map_or(1.0, |m| f64::from(m.4)),
                            )
                        },
                        |row| row.ms.median_ms,
                        |row| format!("{name} {w}×{h} m={m} stall {stall} {}", row.method),
                        |row| -> Result<()> {
                            let method = method_of(row).context("the row's method")?;
                            r.ssaa.set_config(&gpu.queue, &method_config(method))?;
                            row.ms = time(&gpu, &timer, frames, &|e, t| r.ssaa.encode(e, Some(t)))?;
                            row.speedup_vs_full = full_ms.median_ms / row.ms.median_ms;
                            Ok(())
                        },
                    )?;
                    // What the resolve costs: ND + shading without it (S and the evaluation).
                    r.ssaa.set_config(&gpu.queue, &method_config(&methods[0]))?;
                    let metrics_ms = time(&gpu, &timer, frames, &|e, t| {
                        r.ssaa.encode_first(e, Some(t));
                        r.ssaa.encode_evaluate(e, Some(t));
                    })?;
                    rows.push(row("ND+shading, no resolve", metrics_ms, &first, one, one));
                    r.ssaa.set_config(&gpu.queue, &base)?;
                }
            }
        }
    }
    let header = bench::Header::new(&gpu);
    let mut md = header.markdown("Adaptive supersampling (Holländer 2013 §4.3)", frames);
    md.push_str(&format!(
        "\nGPU time of the shading passes after the shared supersampled G-buffer (median of {} frames); \
         'stalled' runs the light loop {STALL}× per sample. Speed-up, MSE/PSNR (sRGB in [0, 1]) and FLIP \
         against full supersampling of the same run. Samples: Σk / (m²·pixels); shaded: shading \
         evaluations / full SSAA's (S plus k for every pixel with k > 1).\n\n",
        frames
    ));
    md.push_str("## Supersampled G-buffer\n\n| scene | size | m | ms |\n|---|---|---|---|\n");
    for (s, w, h, m, g) in &gbuffer_times {
        md.push_str(&format!("| {s} | {w}×{h} | {m} | {:.3} |\n", g.median_ms));
    }
    md.push_str(
        "\nSMAA 1x: the `smaa` crate 0.21 on `S` (8-bit sRGB targets); it submits its own passes, so \
         its time is bracketed by timestamps in the submissions before and after it, a full \
         supersampling pass keeping the GPU busy meanwhile. The same bracket around an empty \
         submission (with the one-sample shading, as in the SMAA rows):\n\n\
         | scene | size | m | ms |\n|---|---|---|---|\n",
    );
    for (s, w, h, m, f) in &smaa_floor {
        md.push_str(&format!("| {s} | {w}×{h} | {m} | {:.3} |\n", f.median_ms));
    }
    md.push_str("\n## Shading\n\n| scene | size | m | method | ms | ×full | stalled ms | ×full | MSE ×1e-4 | PSNR dB | FLIP | samples % | shaded % |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    for r in rows.iter().filter(|r| r.stall == 1) {
        let stalled = rows.iter().find(|s| {
            s.stall != 1
                && s.scene == r.scene
                && s.width == r.width
                && s.m == r.m
                && s.method == r.method
        });
        let (sms, sx) = stalled.map_or(("–".into(), "–".into()), |s| {
            (
                format!("{:.3}", s.ms.median_ms),
                format!("{:.2}", s.speedup_vs_full),
            )
        });
        md.push_str(&format!(
            "| {} | {}×{} | {} | {} | {:.3} | {:.2} | {sms} | {sx} | {:.2} | {:.1} | {:.4} | {:.1} | {:.1} |\n",
            r.scene, r.width, r.height, r.m, r.method, r.ms.median_ms, r.speedup_vs_full,
            r.mse * 1e4, r.psnr, r.flip_mean, 100.0 * r.samples, 100.0 * r.shaded
        ));
    }
    let report = Report {
        header,
        frames: frames,
        stall: STALL,
        gbuffer: gbuffer_times,
        smaa_floor,
        rows,
    };
    args.options
        .write_report(&report.header, "adaptive-ssaa-", &report, &md)
}

fn write_pictures(
    dir: &Path,
    name: &str,
    m: u32,
    full: &Image<[f32; 4]>,
    out: &adaptive_ssaa::cpu::Output,
    smaa: &Image<[f32; 4]>,
) -> Result<()> {
    std::fs::create_dir_all(dir)?;
    let p = |what: &str| dir.join(format!("ssaa-{name}-{what}.png"));
    full.write_png(&p("full"))?;
    out.image.write_png(&p("adaptive"))?;
    out.first.write_png(&p("one-sample"))?;
    adaptive_ssaa::cpu::sample_heatmap(&out.counts, m * m).write_png(&p("samples"))?;
    error_heatmap(&out.image, full, 0.25)?.write_png(&p("error-adaptive"))?;
    error_heatmap(&out.first, full, 0.25)?.write_png(&p("error-one-sample"))?;
    smaa.write_png(&p("smaa"))?;
    error_heatmap(smaa, full, 0.25)?.write_png(&p("error-smaa"))?;
    println!("wrote pictures to {}", dir.display());
    Ok(())
}
