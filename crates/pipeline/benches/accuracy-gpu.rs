//! `accuracy-gpu`: how far the renderer's frames are from the path-traced ground truth
//! (`scene::reference`, issue 21's measure) on the Cornell box (its ceiling lamp) and
//! Dabrovic Sponza (the default sun): per configuration, the relative mean absolute luminance
//! error and bias (emitters excluded, [`gbuffer::accuracy`]) and FLIP / PSNR against the path
//! tracer at `--spp` samples — direct light without and with shadow maps or ray shadows
//! (truth: no bounce), then shadowed direct light plus `--vpls` VPLs without visibility, with
//! ISM, with ManyLoD, with exact rasterised (SSM) visibility and with rays (truth: one
//! bounce), multi-bounce VPLs (photons
//! continue by Russian roulette; truth: 8 bounces), and the progressive mode's mean after
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

/// The row of configuration `name`'s `image` against `truth` (named).
fn row(name: &str, (truth_name, truth): (&str, &Image<[f32; 4]>), image: &Image<[f32; 4]>) -> Row {
    let Accuracy {
        error,
        bias,
        rms,
        pixels,
    } = gbuffer::accuracy(truth, image, 10.0);
    let quality = bench::quality(truth, image);
    println!(
        "{name:<48} vs {truth_name:<12}: error {error:.3}, bias {:+.1} %, FLIP {:.4}, PSNR {:.1} dB",
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
    let mut measure = |name: &str,
                       shadowed: Option<(u32, Direct)>,
                       visibility: Option<Option<(VplShadows, u32)>>,
                       bounces: u32|
     -> Result<()> {
        let set = if bounces > 1 { &many_set } else { &set };
        let mut r = match shadowed {
            Some((samples, direct)) => {
                let (sampled, _, _) = vpl::primary_lights_sampled(scene, samples);
                let mut r = GpuRenderer::new(d, q, scene, &sampled, w, h)?;
                match direct {
                    Direct::Maps => r.set_shadows(d, q, Some(&ShadowMapConfig::default()))?,
                    Direct::Rays => r.set_ray_shadows(d, q, Some(scene))?,
                }
                r
            }
            None => GpuRenderer::new(d, q, scene, &lights, w, h)?,
        };
        match visibility {
            None => {}
            Some(None) => r.set_indirect(d, &config, set)?,
            Some(Some((mode, tile))) => {
                let maps = ShadowConfig {
                    tile,
                    ..ShadowConfig::for_mode(mode)
                };
                r.set_vpl_shadows(d, scene, mode, &maps, &config, set)?
            }
        }
        let image = r.render(d, q, &camera, Vec3::ZERO)?.image;
        let truth_name = match (visibility, bounces) {
            (None, _) => "direct light",
            (Some(_), 1) => "one bounce",
            (Some(_), _) => "8 bounces",
        };
        let truth = match truth_name {
            "direct light" => &direct_truth,
            "one bounce" => &bounce_truth,
            _ => &many_truth,
        };
        rows.push(row(name, (truth_name, truth), &image));
        if PICTURE.contains(&name) {
            pictures.push(image);
        }
        Ok(())
    };
    measure("direct light (no shadows)", None, None, 0)?;
    measure(
        "direct light (shadow maps)",
        Some((1, Direct::Maps)),
        None,
        0,
    )?;
    // Emitters as area lights: 16 shadowed samples each (punctual lights are one sample).
    let samples = if emissive { 16 } else { 1 };
    if emissive {
        measure(PICTURE[0], Some((samples, Direct::Maps)), None, 0)?;
    }
    let rays = Some((samples, Direct::Rays));
    measure("direct light (shadows by rays)", rays, None, 0)?;
    let samples = Some((samples, Direct::Maps));
    let (ism, manylod) = (VplShadows::Ism, VplShadows::ManyLod);
    let bounce = |visibility: &str| format!("shadowed direct light + VPLs, {visibility}");
    measure(&bounce("no visibility"), samples, Some(None), 1)?;
    measure(&bounce("ISM"), samples, Some(Some((ism, 32))), 1)?;
    measure(&bounce("ManyLoD"), samples, Some(Some((manylod, 32))), 1)?;
    let maps64 = Some(Some((manylod, 64)));
    measure(&bounce("ManyLoD 64×64 maps"), samples, maps64, 1)?;
    let many = |visibility: &str| format!("shadowed direct light + 8-bounce VPLs, {visibility}");
    measure(&many("no visibility"), samples, Some(None), MANY_BOUNCES)?;
    measure(&many("ManyLoD 64×64 maps"), samples, maps64, MANY_BOUNCES)?;
    let ssm = Some(Some((VplShadows::Rasterised, 64)));
    measure(&bounce("exact SSM 64×64 maps"), samples, ssm, 1)?;
    measure(&many("exact SSM 64×64 maps"), samples, ssm, MANY_BOUNCES)?;
    let vpl_rays = Some(Some((VplShadows::Rays, 0)));
    measure(&bounce("rays"), samples, vpl_rays, 1)?;
    measure(&many("rays"), samples, vpl_rays, MANY_BOUNCES)?;
    let all_rays = |v: &str| format!("direct light by rays + 8-bounce VPLs, {v}");
    measure(&all_rays("rays"), rays, vpl_rays, MANY_BOUNCES)?;
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
        &image,
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
        .markdown("Accuracy against the path-traced ground truth", 1);
    let _ = writeln!(
        s,
        "{}×{}; truth: `scene::reference` at {} spp (direct light only, one bounce, or 8), emitters \
         as area lights; frames: the GPU renderer, tiled shading, no ambient, {} VPLs 4×4 fused \
         with the 5×5 blur, VPL visibility maps 32×32 unless said, direct shadow maps 1024² \
         (an emitter as 16 shadowed samples, a punctual light as itself). Error: relative mean \
         absolute luminance error over the pixels the truth lights, emitters (luminance > 10) \
         and their neighbours excluded; bias: mean luminance ratio − 1; RMS: relative \
         root-mean-square luminance error. The timing line above \
         does not apply: nothing here is timed.\n",
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
            ]);
        }
        let _ = write!(s, "## {}\n\n{table}", scene.scene);
    }
    s
}
