//! `progressive-gpu`: Segovia 2006 Table 5 on today's GPU — how long the progressive
//! physically based mode ([`pipeline::progressive`]: new VPLs, light samples and exact
//! rasterised VPL shadow maps every frame, averaged; or `--visibility rays`: a ray per pixel
//! and VPL instead of the maps) takes until its mean is within `--target`
//! RMS (1 %) of the path tracer, without and with interleaving, on the Cornell box, Dabrovic
//! Sponza and a larger scene (Sponza with the Stanford dragon and bunny). The truth is traced
//! through pixel centres (where the rasteriser samples) in two halves of `--spp` with other
//! seeds: their difference measures its own noise, which is taken off the measured RMS
//! (`rms² − noise²`, the mean-square error against the noiseless image). Writes
//! `progressive-<adapter>-<date>.{md,json}` (`progressive-rays-…` with `--visibility rays`,
//! `progressive-all-rays-…` with `--direct rays` too, `…-near-field-…` with `--near-field`)
//! under `--out`, again after every configuration.

use anyhow::Result;
use bench::{Header, Stat};
use clap::Parser;
use gbuffer::{Accuracy, Image};
use glam::{Mat4, Vec3};
use instant_radiosity::{Interleaving, shadows::VplShadows, vpl};
use interleave::Pattern;
use pipeline::progressive::{Progressive, ProgressiveConfig};
use scene::{Camera, Scene, reference::ReferenceConfig};
use serde::Serialize;

/// Time to a target RMS error of the progressive mode; writes docs/bench/progressive-*.
#[derive(Parser, Debug)]
#[command(version, about)]
struct Args {
    #[command(flatten)]
    options: bench::Options,
    /// Frame side (square frames).
    #[arg(long, default_value_t = 128)]
    side: u32,
    /// Path-tracer samples per pixel of the truth (two halves).
    #[arg(long, default_value_t = 4096)]
    spp: u32,
    /// RMS error (relative, noise of the truth taken off) to reach.
    #[arg(long, default_value_t = 0.01)]
    target: f64,
    /// Seconds of frames per configuration before giving up.
    #[arg(long, default_value_t = 60.0)]
    seconds: f64,
    /// Scenes: cornell, sponza, large (comma-separated).
    #[arg(long, default_value = "cornell,sponza,large", value_delimiter = ',')]
    scenes: Vec<String>,
    /// Interleaving patterns n (n×n; 1 = none), comma-separated; default: 1, 2, 4 on the
    /// Cornell box, 1, 2 elsewhere.
    #[arg(long, value_delimiter = ',')]
    patterns: Vec<u32>,
    /// The edge-aware 5×5 blur after interleaved shading (`--blur false`: the interleaved
    /// frame as it is, each pixel lit by its subset × the subset count, unbiased).
    #[arg(long, default_value_t = true, action = clap::ArgAction::Set)]
    blur: bool,
    /// Side of the VPLs' paraboloid tiles (hemicube faces are twice as wide).
    #[arg(long, default_value_t = ProgressiveConfig::new(&Scene::default()).vpl_maps.tile)]
    vpl_tile: u32,
    /// Factor on the progressive mode's VPL clamp distance (2 % of the scene diagonal; 0.25
    /// gives the 0.5 % of the runs before the near field).
    #[arg(long, default_value_t = 1.0)]
    clamp_scale: f32,
    /// The VPLs' visibility: the paper's rasterised maps, or rays through the scene's BVH.
    #[arg(long, value_enum, default_value_t = Visibility::Ssm)]
    visibility: Visibility,
    /// The direct lights' shadows: maps (1024², the renderer's default), or a ray per pixel
    /// and light.
    #[arg(long, value_enum, default_value_t = Direct::Maps)]
    direct: Direct,
    /// The VPLs' near field (the clamp's bias compensation, `ProgressiveConfig::near_field`):
    /// `--near-field false` leaves it out.
    #[arg(long, default_value_t = true, action = clap::ArgAction::Set)]
    near_field: bool,
    /// Folder that keeps the truths between runs ([`bench::path_traced_cached`]): trace them
    /// once on a machine with CPU time to spare, carry the folder to the GPU.
    #[arg(long)]
    truth_cache: Option<std::path::PathBuf>,
    /// Folder for each scene's truth and each configuration's final mean as linear EXR
    /// (`<scene>-truth.exr`, `<scene>-<n>x<n>.exr`) and the mean's error map
    /// (`<scene>-<n>x<n>-error.png`), to look at where the error lies.
    #[arg(long)]
    images: Option<std::path::PathBuf>,
}

/// `--visibility`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, Serialize)]
#[serde(rename_all = "lowercase")]
enum Visibility {
    /// Exact rasterised VPL maps (Segovia 2006's SSM).
    Ssm,
    /// A ray per pixel and VPL ([`VplShadows::Rays`]).
    Rays,
}

/// `--direct`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, Serialize)]
#[serde(rename_all = "lowercase")]
enum Direct {
    /// Shadow maps (`ProgressiveConfig::direct_maps`).
    Maps,
    /// A ray per pixel and light (`GpuRenderer::set_ray_shadows`).
    Rays,
}

/// Bounces of the VPL paths and of the truth.
const BOUNCES: u32 = 8;

#[derive(Serialize)]
struct Row {
    scene: String,
    triangles: usize,
    vpls_per_frame: usize,
    interleaving: String,
    reached: bool,
    frames: u32,
    gpu_ms_per_frame: Stat,
    ssm_ms_per_frame: f64,
    gpu_seconds: f64,
    wall_seconds: f64,
    rms: f64,
    rms_without_truth_noise: f64,
    error: f64,
    bias: f64,
    /// (frames, RMS without the truth's noise) at every evaluation.
    trajectory: Vec<(u32, f64)>,
}

#[derive(Serialize)]
struct Report<'a> {
    #[serde(flatten)]
    header: Header,
    size: (u32, u32),
    spp: u32,
    target: f64,
    seconds: f64,
    truth_noise: &'a [(String, f64)],
    vpl_tile: u32,
    clamp_scale: f32,
    visibility: Visibility,
    direct: Direct,
    near_field: bool,
    rows: &'a [Row],
}

/// Sponza with the Stanford dragon (100 k triangles) and bunny standing on its floor: a scene
/// of about 235 k triangles, like Segovia's conference room (228 k).
fn large_scene() -> Result<(Scene, Camera)> {
    let (mut scene, camera) = bench::fixture("sponza/dabrovic/sponza.gltf")?;
    let dir =
        scene::shared_fixtures().ok_or_else(|| anyhow::anyhow!("../shared/fixtures not found"))?;
    let bvh = scene::Bvh::build(&scene);
    let top = scene.bounds().center() + Vec3::Y * 5.0;
    let floor = bvh
        .closest_hit(top, Vec3::NEG_Y, 100.0)
        .map_or(scene.bounds().min.y, |h| h.position.y);
    for (file, height, at) in [
        ("stanford/dragon-100k.ply", 4.0, Vec3::new(-3.0, 0.0, 0.0)),
        ("stanford/stanford-bunny.obj", 3.0, Vec3::new(4.0, 0.0, 0.0)),
    ] {
        let model = Scene::load(dir.join(file))?;
        let b = model.bounds();
        let s = height / (b.max.y - b.min.y);
        let base = Vec3::new(b.center().x, b.min.y, b.center().z);
        let place = Mat4::from_translation(Vec3::new(at.x, floor, at.z))
            * Mat4::from_scale(Vec3::splat(s))
            * Mat4::from_translation(-base);
        let offset = scene.materials.len() as u32;
        scene.materials.extend(model.materials);
        for mut mesh in model.meshes {
            for p in &mut mesh.positions {
                *p = place.transform_point3(*p);
            }
            mesh.material += offset;
            scene.meshes.push(mesh);
        }
    }
    Ok((scene, camera))
}

fn main() -> Result<()> {
    let args = Args::parse_from(bench::args());
    let gpu = args.options.gpu()?;
    let (d, q) = (&gpu.device, &gpu.queue);
    let once = bench::run_once();
    let size = if once {
        (24, 24)
    } else {
        (args.side, args.side)
    };
    let spp = if once { 4 } else { args.spp };
    let mut rows = Vec::new();
    let mut noise_rows = Vec::new();
    for name in &args.scenes {
        // VPLs per frame: the exact maps rasterise every triangle five times per VPL.
        let ((scene, camera), vpls, label) = match name.as_str() {
            "cornell" => (
                bench::fixture("cornell/CornellBox-Original.obj")?,
                1024,
                "Cornell box (its ceiling lamp)",
            ),
            "sponza" => (
                bench::fixture("sponza/dabrovic/sponza.gltf")?,
                64,
                "Dabrovic Sponza (the default sun)",
            ),
            "large" => (
                large_scene()?,
                64,
                "Sponza + dragon + bunny (the default sun)",
            ),
            other => anyhow::bail!("unknown scene {other}: cornell, sponza or large"),
        };
        let vpls = if once { 16 } else { vpls };
        println!("{label}: {} triangles", scene.triangle_count());
        let (lights, emissive, _) = vpl::primary_lights(&scene);
        let photon_lights = vpl::photon_lights(&lights, emissive);
        let half = |seed: u64| {
            let config = ReferenceConfig {
                max_bounces: BOUNCES,
                seed,
                jitter: false,
                ..ReferenceConfig::default()
            };
            let cache = args.truth_cache.as_deref();
            bench::path_traced_cached(cache, &scene, photon_lights, camera, size, config, spp / 2)
        };
        let (a, b) = (half(1)?, half(2)?);
        let truth = Image::from_vec(
            size.0,
            size.1,
            a.pixels()
                .iter()
                .zip(b.pixels())
                .map(|(x, y)| std::array::from_fn(|k| 0.5 * (x[k] + y[k])))
                .collect(),
        )?;
        // Each half's relative RMS against the other is √2 × its noise; the mean of the two
        // halves has half that variance.
        let noise = gbuffer::accuracy(&a, &b, 10.0).rms / 2.0;
        println!("  truth noise {:.4} (relative RMS)", noise);
        if let Some(dir) = &args.images {
            std::fs::create_dir_all(dir)?;
            truth.write_exr(&dir.join(format!("{name}-truth.exr")))?;
        }
        noise_rows.push((label.to_owned(), noise));
        let patterns: &[u32] = match (&args.patterns[..], name.as_str()) {
            ([], "cornell") => &[1, 2, 4],
            ([], _) => &[1, 2],
            (chosen, _) => chosen,
        };
        for &n in patterns {
            let interleaving = match (n, args.blur) {
                (0..=1, _) => "none".to_owned(),
                (_, true) => format!("{n}×{n} + blur"),
                (_, false) => format!("{n}×{n}"),
            };
            let mut config = ProgressiveConfig::new(&scene);
            config.vpls = vpls;
            if n <= 1 {
                config.indirect.interleaving = Interleaving::Reference;
                config.indirect.blur = None;
            } else {
                config.indirect.pattern = Pattern { n, m: n };
                if !args.blur {
                    config.indirect.blur = None;
                }
            }
            config.vpl_maps.tile = args.vpl_tile;
            if args.visibility == Visibility::Rays {
                config.visibility = Some(VplShadows::Rays);
            }
            config.direct_rays = args.direct == Direct::Rays;
            config.near_field = args.near_field;
            config.indirect.clamp_distance *= args.clamp_scale;
            if once {
                config.vpl_maps.tile = 16;
                config.direct_maps.resolution = 128;
            }
            let mut p = Progressive::new(d, q, &scene, camera, size, &config)?;
            let (mut gpu_ms, mut ssm_ms, mut wall) = (Vec::new(), 0.0, 0.0);
            let mut trajectory = Vec::new();
            let mut last = (
                Accuracy {
                    error: 0.0,
                    bias: 0.0,
                    rms: f64::INFINITY,
                    pixels: 0,
                },
                f64::INFINITY,
            );
            let limit = if once { 2 } else { u32::MAX };
            while p.frames() < limit && wall < args.seconds {
                let start = std::time::Instant::now();
                let timings = p.frame(d, q)?;
                wall += start.elapsed().as_secs_f64();
                gpu_ms.push(timings.iter().map(|t| t.ms).sum::<f64>());
                ssm_ms += timings
                    .iter()
                    .filter(|t| t.name.starts_with("SSM"))
                    .map(|t| t.ms)
                    .sum::<f64>();
                let n = p.frames();
                // Evaluated every frame up to 16, then every 4th, 16th and 64th.
                let step = match n {
                    0..=16 => 1,
                    17..=64 => 4,
                    65..=256 => 16,
                    _ => 64,
                };
                if n % step == 0 {
                    let a = gbuffer::accuracy(&truth, &p.read(d, q)?, 10.0);
                    let clean = (a.rms * a.rms - noise * noise).max(0.0).sqrt();
                    trajectory.push((n, clean));
                    last = (a, clean);
                    if clean < args.target {
                        break;
                    }
                }
            }
            let (a, clean) = last;
            let frames = p.frames();
            if let Some(dir) = &args.images {
                let mean = p.read(d, q)?;
                mean.write_exr(&dir.join(format!("{name}-{n}x{n}.exr")))?;
                error_map(&truth, &mean)?
                    .write_png(&dir.join(format!("{name}-{n}x{n}-error.png")))?;
            }
            let row = Row {
                scene: label.to_owned(),
                triangles: scene.triangle_count(),
                vpls_per_frame: config.vpls,
                interleaving: interleaving.clone(),
                reached: clean < args.target,
                frames,
                gpu_seconds: gpu_ms.iter().sum::<f64>() / 1e3,
                gpu_ms_per_frame: Stat::of(gpu_ms),
                ssm_ms_per_frame: ssm_ms / f64::from(frames.max(1)),
                wall_seconds: wall,
                rms: a.rms,
                rms_without_truth_noise: clean,
                error: a.error,
                bias: a.bias,
                trajectory,
            };
            println!(
                "  {interleaving:<12} {} after {frames} frames ({:.1} s GPU, {:.1} s wall): RMS {:.4} ({:.4} without the truth's noise), error {:.4}, bias {:+.2} %",
                if row.reached {
                    "reached"
                } else {
                    "NOT reached"
                },
                row.gpu_seconds,
                row.wall_seconds,
                a.rms,
                clean,
                a.error,
                100.0 * a.bias
            );
            rows.push(row);
            // After every row: a run cut short keeps the rows it measured.
            let report = Report {
                header: Header::new(&gpu),
                size,
                spp,
                target: args.target,
                seconds: args.seconds,
                truth_noise: &noise_rows,
                vpl_tile: args.vpl_tile,
                clamp_scale: args.clamp_scale,
                visibility: args.visibility,
                direct: args.direct,
                near_field: args.near_field,
                rows: &rows,
            };
            let prefix = match (args.visibility, args.direct, args.near_field) {
                (Visibility::Ssm, Direct::Maps, false) => "progressive-",
                (Visibility::Rays, Direct::Maps, false) => "progressive-rays-",
                (_, Direct::Rays, false) => "progressive-all-rays-",
                (Visibility::Ssm, Direct::Maps, true) => "progressive-near-field-",
                (Visibility::Rays, Direct::Maps, true) => "progressive-rays-near-field-",
                (_, Direct::Rays, true) => "progressive-all-rays-near-field-",
            };
            args.options
                .write_report(&report.header, prefix, &report, &markdown(&report))?;
        }
    }
    Ok(())
}

/// Where `image` is off `truth`: per pixel the luminance error over the truth's mean
/// luminance, red too bright, blue too dark, full at ±50 %; 4× enlarged (nearest).
fn error_map(truth: &Image<[f32; 4]>, image: &Image<[f32; 4]>) -> Result<Image<[f32; 4]>> {
    const SCALE: u32 = 4;
    let lum = |p: &[f32; 4]| 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
    let mean = truth.pixels().iter().map(lum).sum::<f32>() / truth.pixels().len().max(1) as f32;
    let (w, h) = (truth.width(), truth.height());
    let pixels = (0..h * SCALE)
        .flat_map(|y| (0..w * SCALE).map(move |x| (x / SCALE, y / SCALE)))
        .map(|(x, y)| {
            let e = (lum(&image.get(x, y)) - lum(&truth.get(x, y))) / mean.max(1e-12);
            [
                (2.0 * e).clamp(0.0, 1.0),
                0.0,
                (-2.0 * e).clamp(0.0, 1.0),
                1.0,
            ]
        })
        .collect();
    Ok(Image::from_vec(w * SCALE, h * SCALE, pixels)?)
}

fn markdown(r: &Report) -> String {
    use std::fmt::Write;
    let mut s = r.header.markdown(
        "Progressive mode: time to < 1 % RMS against the path tracer",
        1,
    );
    let _ = writeln!(
        s,
        "{}×{}; truth: `scene::reference`, {BOUNCES} bounces, {} spp through pixel centres (two \
         halves of other seeds; its relative noise, taken off the RMS: {}); frames: \
         `pipeline::progressive` — per frame new VPLs ({BOUNCES} bounces, Russian roulette), 16 \
         new shadowed samples per emissive mesh, {v}, {direct}, VPL clamp \
         {c:.2} % of the diagonal{near}; stopped at RMS < {:.1} % or after {} s of frames. GPU time: the sum of the \
         frames' pass timestamps (ms per frame: the median); wall: the frames' \
         latency on the CPU (VPL tracing, encoding, submission, waiting), evaluation read-backs \
         excluded. The timing line above does not apply.\n",
        r.size.0,
        r.size.1,
        r.spp,
        r.truth_noise
            .iter()
            .map(|(scene, n)| format!("{scene} {:.2} %", 100.0 * n))
            .collect::<Vec<_>>()
            .join(", "),
        100.0 * r.target,
        r.seconds,
        v = match r.visibility {
            Visibility::Ssm => format!(
                "exact rasterised VPL maps ({t}×{t} paraboloid tiles from {f}² hemicube faces)",
                t = r.vpl_tile,
                f = 2 * r.vpl_tile
            ),
            Visibility::Rays => "VPL visibility by a ray per pixel and VPL (a BVH of the scene \
                                 traversed in the shading kernel, `VplShadows::Rays`)"
                .into(),
        },
        c = 2.0 * r.clamp_scale,
        direct = match r.direct {
            Direct::Maps => "direct shadow maps 1024²",
            Direct::Rays => "direct shadows by a ray per pixel and light",
        },
        near = if r.near_field {
            " with its near field (`instant_radiosity::near_field`: the clamp's bias \
             compensation, a ray of the clamp's length per pixel and frame)"
        } else {
            ""
        },
    );
    let mut table = bench::Table::new(&[
        "scene",
        "triangles",
        "VPLs/frame",
        "interleaving",
        "< 1 % RMS",
        "frames",
        "GPU ms/frame",
        "SSM ms/frame",
        "GPU s",
        "wall s",
        "RMS (noise off)",
        "RMS at 16 / 256 frames",
        "error",
        "bias",
    ]);
    for row in r.rows {
        table.row([
            row.scene.clone(),
            row.triangles.to_string(),
            row.vpls_per_frame.to_string(),
            row.interleaving.clone(),
            if row.reached { "yes" } else { "no" }.into(),
            row.frames.to_string(),
            format!("{:.2}", row.gpu_ms_per_frame.median_ms),
            match r.visibility {
                Visibility::Ssm => format!("{:.2}", row.ssm_ms_per_frame),
                Visibility::Rays => "–".into(),
            },
            format!("{:.2}", row.gpu_seconds),
            format!("{:.2}", row.wall_seconds),
            format!("{:.4} ({:.4})", row.rms, row.rms_without_truth_noise),
            [16, 256]
                .map(|f| {
                    row.trajectory
                        .iter()
                        .find(|t| t.0 == f)
                        .map_or("–".into(), |t| format!("{:.4}", t.1))
                })
                .join(" / "),
            format!("{:.4}", row.error),
            format!("{:+.2} %", 100.0 * row.bias),
        ]);
    }
    let _ = write!(s, "{table}");
    s
}
