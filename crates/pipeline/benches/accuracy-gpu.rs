//! `accuracy-gpu`: how far the renderer's frames are from the path-traced ground truth
//! (`scene::reference`, issue 21's measure) on the Cornell box (its ceiling lamp) and
//! Dabrovic Sponza (the default sun): per configuration, the relative mean absolute luminance
//! error and bias (emitters excluded, [`gbuffer::accuracy`]) and FLIP / PSNR against the path
//! tracer at `--spp` samples — direct light without and with shadow maps or ray shadows
//! (truth: no bounce), then shadowed direct light plus `--vpls` VPLs without visibility, with
//! ISM, with ManyLoD, with exact rasterised (SSM) visibility and with rays (truth: one
//! bounce), multi-bounce VPLs (photons
//! continue by Russian roulette; truth: 8 bounces), point-based GI in place of the VPLs (a
//! receiver every 2, 4 or 8 pixels; truth: one bounce), and the progressive mode's mean after
//! `--progressive-frames` frames (`pipeline::progressive`; a quarter of the VPLs per frame on
//! Sponza). Accuracy does not depend on the adapter (the GPU only
//! renders the frame), so the report of any adapter is valid; writes
//! `accuracy-<adapter>-<date>.{md,json}` under `--out`.

use anyhow::Result;
use bench::{Header, Quality};
use clap::Parser;
use gbuffer::{Accuracy, Image};
use glam::Vec3;
use instant_radiosity::{
    IndirectConfig,
    shadows::{ShadowConfig, VplShadows},
    vpl,
};
use pipeline::gpu::GpuRenderer;
use pipeline::progressive::{Progressive, ProgressiveConfig};
use scene::{Camera, Scene, reference::ReferenceConfig};
use serde::Serialize;
use tiled_shading::shadows::ShadowMapConfig;

/// Accuracy of the renderer against the path tracer; writes docs/bench/accuracy-*.
#[derive(Parser, Debug)]
#[command(version, about)]
struct Args {
    #[command(flatten)]
    options: bench::Options,
    /// Path-tracer samples per pixel of the ground truth.
    #[arg(long, default_value_t = 4096)]
    spp: u32,
    /// VPLs of the indirect configurations.
    #[arg(long, default_value_t = 1024)]
    vpls: usize,
    /// Frames of the progressive row.
    #[arg(long, default_value_t = 64)]
    progressive_frames: u32,
    /// Also write the docs' picture (PNG): the truth and the renderer side by side — direct
    /// light, then one bounce without and with ManyLoD visibility, on the Cornell box.
    #[arg(long)]
    picture: Option<std::path::PathBuf>,
}

/// Bounces of the multi-bounce VPLs and of their truth.
const MANY_BOUNCES: u32 = 8;

/// The configurations of the docs' picture, left to right after the truth of each half.
const PICTURE: [&str; 3] = [
    "direct light (16 samples, shadow maps)",
    "shadowed direct light + VPLs, no visibility",
    "shadowed direct light + VPLs, ManyLoD",
];

/// `images` side by side with a 4-pixel black gap (all of one size).
fn side_by_side(images: &[&Image<[f32; 4]>]) -> Result<Image<[f32; 4]>> {
    let (w, h) = (images[0].width(), images[0].height());
    let gap = 4;
    let width = images.len() as u32 * (w + gap) - gap;
    let mut out = Image::filled(width, h, [0.0, 0.0, 0.0, 1.0]);
    for (k, image) in images.iter().enumerate() {
        anyhow::ensure!(
            image.width() == w && image.height() == h,
            "picture sizes differ"
        );
        for y in 0..h {
            for x in 0..w {
                out.set(k as u32 * (w + gap) + x, y, image.get(x, y));
            }
        }
    }
    Ok(out)
}

#[derive(Serialize)]
struct Row {
    configuration: String,
    truth: String,
    error: f64,
    bias: f64,
    rms: f64,
    pixels: usize,
    quality: Quality,
    /// GPU milliseconds of the frame (all passes; the median of 10 frames after a warm-up),
    /// for equal-time comparisons on a hardware adapter.
    frame_ms: f64,
}

#[derive(Serialize)]
struct SceneRows {
    scene: String,
    rows: Vec<Row>,
}

#[derive(Serialize)]
struct Report {
    #[serde(flatten)]
    header: Header,
    size: (u32, u32),
    spp: u32,
    vpls: usize,
    scenes: Vec<SceneRows>,
}

fn truth(
    scene: &Scene,
    lights: &[scene::Light],
    camera: Camera,
    size: (u32, u32),
    bounces: u32,
    spp: u32,
) -> Result<Image<[f32; 4]>> {
    let config = ReferenceConfig {
        max_bounces: bounces,
        ..ReferenceConfig::default()
    };
    bench::path_traced(scene, lights, camera, size, config, spp)
}

/// The row of configuration `name`'s `image` (its frame took `frame_ms`) against `truth`
/// (named).
fn row(
    name: &str,
    (truth_name, truth): (&str, &Image<[f32; 4]>),
    (image, frame_ms): (&Image<[f32; 4]>, f64),
) -> Row {
    let Accuracy {
        error,
        bias,
        rms,
        pixels,
    } = gbuffer::accuracy(truth, image, 10.0);
    let quality = bench::quality(truth, image);
    println!(
        "{name:<48} vs {truth_name:<12}: error {error:.3}, bias {:+.1} %, FLIP {:.4}, PSNR {:.1} dB, {frame_ms:.3} ms",
        100.0 * bias,
        quality.flip_mean,
        quality.psnr
    );
    Row {
        configuration: name.into(),
        truth: truth_name.into(),
        error,
        bias,
        rms,
        pixels,
        quality,
        frame_ms,
    }
}

/// What one scene's rows are measured with.
#[derive(Clone, Copy)]
struct Setup<'a> {
    gpu: &'a gpu::Gpu,
    size: (u32, u32),
    spp: u32,
    vpls: usize,
    progressive_vpls: usize,
    progressive_frames: u32,
}

/// How a measured frame shadows its direct lights.
#[derive(Clone, Copy)]
enum Direct {
    /// Shadow maps (`ShadowMapConfig::default()`).
    Maps,
    /// A ray per pixel and light (`GpuRenderer::set_ray_shadows`).
    Rays,
}

/// The one-bounce light a measured frame adds.
#[derive(Clone, Copy)]
enum Bounce {
    /// None: direct light only.
    None,
    /// VPLs with a visibility (mode, map tile), or none.
    Vpls(Option<(VplShadows, u32)>),
    /// Point-based GI: a receiver every `stride` pixels, `tile`² texels, ε.
    Pbgi {
        stride: u32,
        tile: u32,
        epsilon: f32,
    },
}

/// Surfels of point-based GI's rows (fewer in run-once mode).
const PBGI_POINTS_LOG2: u32 = 18;

/// A scene's rows and the pictures of [`PICTURE`].
type Measured = (Vec<Row>, Vec<Image<[f32; 4]>>);

/// The rows of `scene` from `camera`, and the frames of [`PICTURE`] with both truths.
fn measure_scene(setup: &Setup<'_>, scene: &Scene, camera: Camera) -> Result<Measured> {
    let (d, q) = (&setup.gpu.device, &setup.gpu.queue);
    let (w, h) = setup.size;
    let (lights, emissive, lit_by) = vpl::primary_lights(scene);
    println!("{} triangles, lit by {lit_by}", scene.triangle_count());
    // The truth sees the emissive triangles themselves, not their stand-ins.
    let true_lights = vpl::photon_lights(&lights, emissive);
    let direct_truth = truth(scene, true_lights, camera, setup.size, 0, setup.spp)?;
    let bounce_truth = truth(scene, true_lights, camera, setup.size, 1, setup.spp)?;
    let many_truth = truth(
        scene,
        true_lights,
        camera,
        setup.size,
        MANY_BOUNCES,
        setup.spp,
    )?;
    let config = IndirectConfig::new(scene.bounds());
    let bvh = scene::Bvh::build(scene);
    let set = vpl::generate_from_primary(scene, &bvh, setup.vpls, config.subsets(), 1)?;
    let many_set = vpl::generate(
        scene,
        &bvh,
        true_lights,
        &vpl::VplConfig {
            count: set.vpls.len(),
            subsets: config.subsets(),
            seed: 1,
            emissive,
            bounces: MANY_BOUNCES,
        },
    )?;
    let mut rows = Vec::new();
    let mut pictures = Vec::new();
    // `shadowed`: the lights with shadow maps (`Direct::Maps`) or rays, an emitter as that
    // many hemispherical samples (else unshadowed, an emitter one point at its centroid).
    // `bounces`: the VPLs' bounces (the truth's), with `visibility` (`None`: no VPLs).
    let points_log2 = if bench::run_once() {
        12
    } else {
        PBGI_POINTS_LOG2
    };
    let mut measure =
        |name: &str, shadowed: Option<(u32, Direct)>, bounce: Bounce, bounces: u32| -> Result<()> {
            let set = if bounces > 1 { &many_set } else { &set };
            let (frame_lights, mut r) = match shadowed {
                Some((samples, direct)) => {
                    let (sampled, _, _) = vpl::primary_lights_sampled(scene, samples);
                    let mut r = GpuRenderer::new(d, q, scene, &sampled, w, h)?;
                    match direct {
                        Direct::Maps => r.set_shadows(d, q, Some(&ShadowMapConfig::default()))?,
                        Direct::Rays => r.set_ray_shadows(d, q, Some(scene))?,
                    }
                    (sampled, r)
                }
                None => (
                    lights.clone(),
                    GpuRenderer::new(d, q, scene, &lights, w, h)?,
                ),
            };
            match bounce {
                Bounce::None => {}
                Bounce::Vpls(None) => r.set_indirect(d, &config, set)?,
                Bounce::Vpls(Some((mode, tile))) => {
                    let maps = ShadowConfig {
                        tile,
                        ..ShadowConfig::for_mode(mode)
                    };
                    r.set_vpl_shadows(d, scene, mode, &maps, &config, set)?
                }
                Bounce::Pbgi {
                    stride,
                    tile,
                    epsilon,
                } => {
                    let config = instant_radiosity::pbgi::PbgiConfig {
                        tile,
                        epsilon,
                        points_log2,
                    };
                    let gpu_lights = pipeline::validate_lights(&frame_lights)?;
                    let lit = instant_radiosity::pbgi::LitPoints::new(scene, &gpu_lights, &config)?;
                    r.set_pbgi(d, Some((&lit, stride, scene)))?;
                }
            }
            // The frame's GPU time: the median of 10 frames after the clock has risen.
            let mut frames = bench::warm_then_time(10, || r.time_frame(d, q, &camera, Vec3::ZERO))?;
            // Point-based GI's cut lists grow to the cut they must hold; then time again.
            while r.check_pbgi(d, q)? {
                frames = bench::warm_then_time(10, || r.time_frame(d, q, &camera, Vec3::ZERO))?;
            }
            let totals: Vec<f64> = frames
                .iter()
                .map(|passes| passes.iter().map(|t| t.ms).sum())
                .collect();
            let frame_ms = bench::Stat::of(totals).median_ms;
            let image = r.render(d, q, &camera, Vec3::ZERO)?.image;
            let truth_name = match (bounce, bounces) {
                (Bounce::None, _) => "direct light",
                (_, 1) => "one bounce",
                (_, _) => "8 bounces",
            };
            let truth = match truth_name {
                "direct light" => &direct_truth,
                "one bounce" => &bounce_truth,
                _ => &many_truth,
            };
            rows.push(row(name, (truth_name, truth), (&image, frame_ms)));
            if PICTURE.contains(&name) {
                pictures.push(image);
            }
            Ok(())
        };
    measure("direct light (no shadows)", None, Bounce::None, 0)?;
    measure(
        "direct light (shadow maps)",
        Some((1, Direct::Maps)),
        Bounce::None,
        0,
    )?;
    // Emitters as area lights: 16 shadowed samples each (punctual lights are one sample).
    let samples = if emissive { 16 } else { 1 };
    if emissive {
        measure(PICTURE[0], Some((samples, Direct::Maps)), Bounce::None, 0)?;
    }
    let rays = Some((samples, Direct::Rays));
    measure("direct light (shadows by rays)", rays, Bounce::None, 0)?;
    let samples = Some((samples, Direct::Maps));
    let (ism, manylod) = (VplShadows::Ism, VplShadows::ManyLod);
    let bounce = |visibility: &str| format!("shadowed direct light + VPLs, {visibility}");
    measure(&bounce("no visibility"), samples, Bounce::Vpls(None), 1)?;
    measure(&bounce("ISM"), samples, Bounce::Vpls(Some((ism, 32))), 1)?;
    measure(
        &bounce("ManyLoD"),
        samples,
        Bounce::Vpls(Some((manylod, 32))),
        1,
    )?;
    let maps64 = Bounce::Vpls(Some((manylod, 64)));
    measure(&bounce("ManyLoD 64×64 maps"), samples, maps64, 1)?;
    let many = |visibility: &str| format!("shadowed direct light + 8-bounce VPLs, {visibility}");
    measure(
        &many("no visibility"),
        samples,
        Bounce::Vpls(None),
        MANY_BOUNCES,
    )?;
    measure(&many("ManyLoD 64×64 maps"), samples, maps64, MANY_BOUNCES)?;
    let ssm = Bounce::Vpls(Some((VplShadows::Rasterised, 64)));
    measure(&bounce("exact SSM 64×64 maps"), samples, ssm, 1)?;
    measure(&many("exact SSM 64×64 maps"), samples, ssm, MANY_BOUNCES)?;
    let vpl_rays = Bounce::Vpls(Some((VplShadows::Rays, 0)));
    measure(&bounce("rays"), samples, vpl_rays, 1)?;
    measure(&many("rays"), samples, vpl_rays, MANY_BOUNCES)?;
    let all_rays = |v: &str| format!("direct light by rays + 8-bounce VPLs, {v}");
    measure(&all_rays("rays"), rays, vpl_rays, MANY_BOUNCES)?;
    // Point-based GI (Holländer 2013 §3.6.1) in place of the VPLs: receiver stride, texels, ε.
    for (stride, tile, epsilon) in [(8, 16, 2.0), (4, 16, 2.0), (2, 16, 2.0), (4, 32, 1.0)] {
        let name = format!(
            "shadowed direct light + PBGI, a receiver every {stride} px, {tile}² texels, ε {epsilon}"
        );
        let pbgi = Bounce::Pbgi {
            stride,
            tile,
            epsilon,
        };
        measure(&name, samples, pbgi, 1)?;
    }
    // The progressive mode: its own lights, VPLs and maps every frame, averaged.
    let mut config = ProgressiveConfig::new(scene);
    config.vpls = setup.progressive_vpls;
    let mut progressive = Progressive::new(d, q, scene, camera, setup.size, &config)?;
    for _ in 0..setup.progressive_frames {
        progressive.frame(d, q)?;
    }
    let image = progressive.read(d, q)?;
    rows.push(row(
        &format!(
            "progressive (exact SSM, 2×2 + blur, {} VPLs/frame), {} frames",
            config.vpls, setup.progressive_frames
        ),
        ("8 bounces", &many_truth),
        (&image, f64::NAN),
    ));
    if pictures.len() == PICTURE.len() {
        pictures.splice(0..0, [direct_truth.clone()]);
        pictures.insert(2, bounce_truth);
    }
    Ok((rows, pictures))
}

fn main() -> Result<()> {
    let args = Args::parse_from(bench::args());
    let gpu = args.options.gpu()?;
    let once = bench::run_once();
    let setup = Setup {
        gpu: &gpu,
        size: if once { (32, 32) } else { (256, 256) },
        spp: if once { 4 } else { args.spp },
        vpls: if once { 64 } else { args.vpls },
        progressive_vpls: 0,
        progressive_frames: if once { 2 } else { args.progressive_frames },
    };
    let mut scenes = Vec::new();
    for (file, label) in [
        (
            "cornell/CornellBox-Original.obj",
            "Cornell box (cornell/CornellBox-Original.obj), its ceiling lamp",
        ),
        (
            "sponza/dabrovic/sponza.gltf",
            "Dabrovic Sponza (sponza/dabrovic/sponza.gltf), the default sun",
        ),
    ] {
        println!("{label}");
        let (scene, camera) = bench::fixture(file)?;
        // The exact maps rasterise every triangle five times per VPL: fewer VPLs per frame on
        // the larger scene.
        let per_frame = if file.starts_with("cornell") {
            setup.vpls
        } else {
            setup.vpls / 4
        };
        let setup = Setup {
            progressive_vpls: per_frame.max(16),
            ..setup
        };
        let (rows, pictures) = measure_scene(&setup, &scene, camera)?;
        if let (Some(path), true) = (&args.picture, file.starts_with("cornell")) {
            let strip: Vec<&Image<[f32; 4]>> = pictures.iter().collect();
            anyhow::ensure!(
                strip.len() == 5,
                "the picture's configurations were not all measured"
            );
            side_by_side(&strip)?.write_png(path)?;
            println!("wrote {}", path.display());
        }
        scenes.push(SceneRows {
            scene: format!(
                "{label}, {}",
                bench::scene_labels(std::path::Path::new(file), &camera).1
            ),
            rows,
        });
    }
    let report = Report {
        header: Header::new(&gpu),
        size: setup.size,
        spp: setup.spp,
        vpls: setup.vpls,
        scenes,
    };
    args.options
        .write_report(&report.header, "accuracy-", &report, &markdown(&report))
}

fn markdown(r: &Report) -> String {
    use std::fmt::Write;
    let mut s = r
        .header
        .markdown("Accuracy against the path-traced ground truth", 10);
    let _ = writeln!(
        s,
        "{}×{}; truth: `scene::reference` at {} spp (direct light only, one bounce, or 8), emitters \
         as area lights; frames: the GPU renderer, tiled shading, no ambient, {} VPLs 4×4 fused \
         with the 5×5 blur, VPL visibility maps 32×32 unless said, direct shadow maps 1024² \
         (an emitter as 16 shadowed samples, a punctual light as itself). Error: relative mean \
         absolute luminance error over the pixels the truth lights, emitters (luminance > 10) \
         and their neighbours excluded; bias: mean luminance ratio − 1; RMS: relative \
         root-mean-square luminance error. Frame ms: the GPU time of the frame's passes (the \
         median of 10 frames after a warm-up; the progressive row is not timed), for \
         equal-time comparisons; the timing line above applies to it only. PBGI: 2^18 surfels \
         lit on the GPU, receivers on a grid of the frame.\n",
        r.size.0, r.size.1, r.spp, r.vpls
    );
    for scene in &r.scenes {
        let mut table = bench::Table::new(&[
            "configuration",
            "truth",
            "error",
            "bias",
            "RMS",
            "FLIP",
            "PSNR dB",
            "frame ms",
        ]);
        for row in &scene.rows {
            table.row([
                row.configuration.clone(),
                row.truth.clone(),
                format!("{:.3}", row.error),
                format!("{:+.1} %", 100.0 * row.bias),
                format!("{:.3}", row.rms),
                format!("{:.4}", row.quality.flip_mean),
                format!("{:.1}", row.quality.psnr),
                if row.frame_ms.is_finite() {
                    format!("{:.3}", row.frame_ms)
                } else {
                    "–".into()
                },
            ]);
        }
        let _ = write!(s, "## {}\n\n{table}", scene.scene);
    }
    s
}
