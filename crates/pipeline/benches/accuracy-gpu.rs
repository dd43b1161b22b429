//! `accuracy-gpu`: how far the renderer's frames are from the path-traced ground truth
//! (`scene::reference`, issue 21's measure): per configuration, the relative mean absolute
//! luminance error and bias (emitters excluded, [`gbuffer::accuracy`]) and FLIP / PSNR against
//! the path tracer at `--spp` samples — direct light only (truth: no bounce), then direct light
//! plus 1024 VPLs without visibility, with ISM and with ManyLoD visibility (truth: one bounce).
//! Accuracy does not depend on the adapter (the GPU only renders the frame), so the report of
//! any adapter is valid; writes `accuracy-<adapter>-<date>.{md,json}` under `--out`.

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
use scene::{
    Camera, Scene,
    reference::{PathTracer, ReferenceConfig},
};
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
}

#[derive(Serialize)]
struct Row {
    configuration: String,
    truth: String,
    error: f64,
    bias: f64,
    pixels: usize,
    quality: Quality,
}

#[derive(Serialize)]
struct Report {
    #[serde(flatten)]
    header: Header,
    scene: String,
    size: (u32, u32),
    spp: u32,
    vpls: usize,
    rows: Vec<Row>,
}

/// The Cornell box of `../shared/fixtures/cornell` from its view in `scene`'s views.json
/// (the issue's: eye (0, 1, 3.9), target (0, 1, 0), fov 39.3°).
fn cornell() -> Result<(Scene, Camera)> {
    let dir =
        scene::shared_fixtures().ok_or_else(|| anyhow::anyhow!("../shared/fixtures not found"))?;
    let path = dir.join("cornell/CornellBox-Original.obj");
    let scene = Scene::load(&path)?;
    let camera = scene::preset_view(&path, &scene)
        .ok_or_else(|| anyhow::anyhow!("no view of {} in views.json", path.display()))?;
    Ok((scene, camera))
}

fn truth(
    scene: &Scene,
    camera: Camera,
    (w, h): (u32, u32),
    bounces: u32,
    spp: u32,
) -> Result<Image<[f32; 4]>> {
    let config = ReferenceConfig {
        max_bounces: bounces,
        ..ReferenceConfig::default()
    };
    let mut pt = PathTracer::new(scene, camera, w, h, &scene.lights, config);
    pt.add_samples(spp);
    Ok(Image::from_vec(
        w,
        h,
        pt.image().iter().map(|c| [c.x, c.y, c.z, 1.0]).collect(),
    )?)
}

fn main() -> Result<()> {
    let args = Args::parse_from(bench::args());
    let gpu = args.options.gpu()?;
    let (d, q) = (&gpu.device, &gpu.queue);
    let (scene, camera) = cornell()?;
    let size = if bench::run_once() {
        (32, 32)
    } else {
        (256, 256)
    };
    let spp = if bench::run_once() { 4 } else { args.spp };
    let vpls = if bench::run_once() { 64 } else { args.vpls };
    let (w, h) = size;
    let direct_truth = truth(&scene, camera, size, 0, spp)?;
    let bounce_truth = truth(&scene, camera, size, 1, spp)?;
    let (lights, _, _) = vpl::primary_lights(&scene);
    let config = IndirectConfig::new(scene.bounds());
    let bvh = scene::Bvh::build(&scene);
    let set = vpl::generate_from_primary(&scene, &bvh, vpls, config.subsets(), 1)?;
    let mut rows = Vec::new();
    // `shadowed`: the emitter as that many shadowed hemispherical samples (else one
    // unshadowed point at its centroid).
    let mut measure = |name: &str,
                       shadowed: Option<u32>,
                       visibility: Option<Option<VplShadows>>|
     -> Result<()> {
        let mut r = match shadowed {
            Some(samples) => {
                let (sampled, _, _) = vpl::primary_lights_sampled(&scene, samples);
                let mut r = GpuRenderer::new(d, q, &scene, &sampled, w, h)?;
                r.set_shadows(d, q, Some(&ShadowMapConfig::default()))?;
                r
            }
            None => GpuRenderer::new(d, q, &scene, &lights, w, h)?,
        };
        match visibility {
            None => {}
            Some(None) => r.set_indirect(d, &config, &set)?,
            Some(Some(mode)) => {
                r.set_vpl_shadows(d, &scene, mode, &ShadowConfig::default(), &config, &set)?
            }
        }
        let image = r.render(d, q, &camera, Vec3::ZERO)?.image;
        let (truth, truth_name) = match visibility {
            None => (&direct_truth, "direct light"),
            Some(_) => (&bounce_truth, "one bounce"),
        };
        let Accuracy {
            error,
            bias,
            pixels,
        } = gbuffer::accuracy(truth, &image, 10.0);
        let quality = bench::quality(truth, &image);
        println!(
            "{name:<40} vs {truth_name:<12}: error {error:.3}, bias {:+.1} %, FLIP {:.4}, PSNR {:.1} dB",
            100.0 * bias,
            quality.flip_mean,
            quality.psnr
        );
        rows.push(Row {
            configuration: name.into(),
            truth: truth_name.into(),
            error,
            bias,
            pixels,
            quality,
        });
        Ok(())
    };
    measure("direct light (one point, no shadows)", None, None)?;
    measure("direct light (one point, shadow maps)", Some(1), None)?;
    measure("direct light (16 samples, shadow maps)", Some(16), None)?;
    measure("+ VPLs, no visibility", None, Some(None))?;
    measure("+ VPLs, ISM visibility", None, Some(Some(VplShadows::Ism)))?;
    measure(
        "+ VPLs, ManyLoD visibility",
        None,
        Some(Some(VplShadows::ManyLod)),
    )?;
    measure(
        "16 shadowed samples + VPLs, ManyLoD",
        Some(16),
        Some(Some(VplShadows::ManyLod)),
    )?;
    let report = Report {
        header: Header::new(&gpu),
        scene: "cornell/CornellBox-Original.obj, eye (0, 1, 3.9), target (0, 1, 0), fov 39.3°"
            .into(),
        size,
        spp,
        vpls: set.vpls.len(),
        rows,
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
        "Scene {}, {}×{}; truth: `scene::reference` at {} spp (direct light only, or one bounce), \
         the lamp an area light; frames: the GPU renderer, tiled shading, no ambient, {} VPLs 4×4 \
         fused with the 5×5 blur. Error: relative mean absolute luminance error over the pixels \
         the truth lights, the emitter (luminance > 10) excluded; bias: mean luminance ratio − 1. \
         The timing line above does not apply: nothing here is timed.\n\n\
         | configuration | truth | error | bias | FLIP | PSNR dB |\n|---|---|---|---|---|---|",
        r.scene, r.size.0, r.size.1, r.spp, r.vpls
    );
    for row in &r.rows {
        let _ = writeln!(
            s,
            "| {} | {} | {:.3} | {:+.1} % | {:.4} | {:.1} |",
            row.configuration,
            row.truth,
            row.error,
            100.0 * row.bias,
            row.quality.flip_mean,
            row.quality.psnr
        );
    }
    s
}
