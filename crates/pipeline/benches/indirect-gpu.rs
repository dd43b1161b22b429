//! `indirect-bench`: instant radiosity with interleaved deferred shading on Sponza (Segovia
//! 2006 Tables 3 and 4): for each size, VPL count and pattern, the GPU time of every pass of
//! the indirect-only frame (BC → BS → SNSM → BG → DB → B → composition), the reference frame
//! where every pixel shades every VPL measured in the same run, the speed-up of the indirect
//! passes over the reference shading, and the quality of the interleaved image against the
//! reference (RMSE, PSNR, FLIP mean; blur on and off). Writes `indirect-<adapter>-<date>.md`
//! and `.json` under `--out`.

mod common;

use anyhow::Result;
use bench::Stat;
use bench::{Quality, per_frame_sum, quality};
use clap::Parser;
use common::time_passes;
use glam::Vec3;
use instant_radiosity::{IndirectConfig, Interleaving, vpl};
use interleave::{Blur, BlurVariant, Pattern, SplitVariant};
use pipeline::gpu::GpuRenderer;
use scene::Bvh;
use serde::Serialize;

/// Benchmarks the interleaved indirect pipeline against the non-interleaved reference.
#[derive(Parser, Debug)]
struct Args {
    #[command(flatten)]
    common: bench::SceneArgs,
    #[command(flatten)]
    quick: bench::Quick,
    /// Only 1920×1080 and these VPL counts (comma-separated): a focused comparison.
    #[arg(long, value_delimiter = ',')]
    vpls: Vec<usize>,
}

const SIZES: [(u32, u32); 3] = [(1024, 768), (1920, 1080), (3840, 2160)];
const VPLS: [usize; 4] = [256, 480, 1024, 4096];
const PATTERNS: [(u32, u32); 3] = [(4, 4), (8, 6), (8, 8)];
/// The passes of the indirect stage whose sum the targets compare with the reference shading.
const INDIRECT: [&str; 4] = ["BS", "SNSM", "BG", "DB + B"];

#[derive(Serialize)]
struct Row {
    width: u32,
    height: u32,
    vpls: usize,
    pattern: String,
    interleaving: String,
    /// Median ms per pass name (passes of one name summed per frame).
    passes: Vec<(String, Stat)>,
    /// Median of the per-frame sum of BS+SNSM+BG+DB+B.
    indirect: Stat,
    /// Median of the reference frame's shading pass (same VPLs, same run).
    reference_shading: Stat,
    speedup: f64,
    /// n·m: the speed-up of the shading alone if nothing else cost anything.
    ideal: u32,
    /// What the row measured, to measure it again: the VPL count asked for, the pattern
    /// and the interleaving.
    #[serde(skip)]
    setup: (usize, Pattern, Interleaving),
}

#[derive(Serialize)]
struct QualityRow {
    width: u32,
    height: u32,
    vpls: usize,
    pattern: String,
    blurred: Quality,
    unfiltered: Quality,
}

#[derive(Serialize)]
struct Report {
    header: bench::Header,
    frames: u32,
    scene: String,
    camera: String,
    rows: Vec<Row>,
    quality: Vec<QualityRow>,
}

fn config(
    bounds: scene::Aabb,
    pattern: Pattern,
    interleaving: Interleaving,
    blur: bool,
) -> IndirectConfig {
    IndirectConfig {
        pattern,
        interleaving,
        blur: blur.then_some(Blur {
            kernel: 5,
            variant: BlurVariant::Fast,
        }),
        ..IndirectConfig::new(bounds)
    }
}

/// The indirect frame's passes (per name, per-frame ms) with `interleaving` of `pattern`, blur
/// on, lit by `set`.
fn time_indirect(
    gpu: &gpu::Gpu,
    renderer: &mut GpuRenderer,
    camera: &scene::Camera,
    bounds: scene::Aabb,
    (pattern, interleaving): (Pattern, Interleaving),
    set: &vpl::VplSet,
    frames: u32,
) -> Result<Vec<(String, Vec<f64>)>> {
    let c = config(bounds, pattern, interleaving, true);
    renderer.set_indirect(&gpu.device, &c, set)?;
    Ok(time_passes(
        gpu,
        renderer,
        camera,
        Vec3::ZERO,
        frames,
        None,
    )?)
}

fn main() -> Result<()> {
    let args = Args::parse_from(bench::args());
    let gpu = args.common.options.gpu()?;
    let frames = args.common.options.frames(10);
    let (path, scene, camera) = args.common.scene.load_viewed()?;
    let (_, _, lit_by) = vpl::primary_lights(&scene);
    println!(
        "scene: {} ({} triangles), VPLs from {lit_by}",
        path.display(),
        scene.triangle_count()
    );
    let bvh = Bvh::build(&scene);
    let bounds = scene.bounds();

    let q = &args.quick;
    let (mut sizes, mut counts, patterns) = (q.sweep(&SIZES), q.sweep(&VPLS), q.sweep(&PATTERNS));
    if !args.vpls.is_empty() {
        (sizes, counts) = (&SIZES[1..2], &args.vpls);
    }
    let time = |renderer: &mut GpuRenderer, setup, set: &vpl::VplSet| {
        time_indirect(&gpu, renderer, &camera, bounds, setup, set, frames)
    };
    let mut rows = Vec::new();
    let mut qualities = Vec::new();
    for (w, h) in sizes.iter().copied().map(bench::size) {
        // Indirect light only: no direct lights, no ambient (the direct sun would hide errors).
        let mut renderer = GpuRenderer::new(&gpu.device, &gpu.queue, &scene, &[], w, h)?;
        for &count in counts {
            let mut reference_ms: Option<Vec<f64>> = None;
            for &(n, m) in patterns {
                let pattern = Pattern::new(n, m)?;
                let subsets = pattern.count();
                let set = vpl::generate_from_primary(&scene, &bvh, count, subsets, 1)?;
                let total = set.vpls.len();
                let reference = config(bounds, pattern, Interleaving::Reference, false);
                renderer.set_indirect(&gpu.device, &reference, &set)?;
                let reference_image = renderer
                    .render(&gpu.device, &gpu.queue, &camera, Vec3::ZERO)?
                    .image;
                // The reference cost depends on the VPL count only: time it once per count.
                let reference_ms = match &reference_ms {
                    Some(v) => v.clone(),
                    None => {
                        let t =
                            time_passes(&gpu, &mut renderer, &camera, Vec3::ZERO, frames, None)?;
                        let v = per_frame_sum(&t, &["shading (reference)"]);
                        reference_ms = Some(v.clone());
                        v
                    }
                };
                let mut images = Vec::new();
                for blur in [true, false] {
                    let c = config(bounds, pattern, Interleaving::Fused, blur);
                    renderer.set_indirect(&gpu.device, &c, &set)?;
                    images.push(
                        renderer
                            .render(&gpu.device, &gpu.queue, &camera, Vec3::ZERO)?
                            .image,
                    );
                }
                let q = QualityRow {
                    width: w,
                    height: h,
                    vpls: total,
                    pattern: pattern.to_string(),
                    blurred: quality(&reference_image, &images[0]),
                    unfiltered: quality(&reference_image, &images[1]),
                };
                println!(
                    "{w}x{h} {total:>5} VPLs {pattern}: FLIP {:.4} (unfiltered {:.4}), PSNR {:.1} dB",
                    q.blurred.flip_mean, q.unfiltered.flip_mean, q.blurred.psnr
                );
                qualities.push(q);
                for interleaving in [
                    Interleaving::Fused,
                    Interleaving::Split(SplitVariant::Tiled),
                ] {
                    let t = time(&mut renderer, (pattern, interleaving), &set)?;
                    let indirect = Stat::of(per_frame_sum(&t, &INDIRECT));
                    let reference_shading = Stat::of(reference_ms.clone());
                    let speedup = reference_shading.median_ms / indirect.median_ms;
                    let name = match interleaving {
                        Interleaving::Fused => "fused".to_string(),
                        Interleaving::Split(v) => format!("split {}", v.name()),
                        Interleaving::Reference => "reference".into(),
                    };
                    println!(
                        "{w}x{h} {total:>5} VPLs {pattern} {name:<12}: indirect {:.3} ms, reference {:.3} ms, ×{speedup:.1} of ×{subsets}",
                        indirect.median_ms, reference_shading.median_ms
                    );
                    rows.push(Row {
                        width: w,
                        height: h,
                        vpls: total,
                        pattern: pattern.to_string(),
                        interleaving: name,
                        passes: t.into_iter().map(|(n, v)| (n, Stat::of(v))).collect(),
                        indirect,
                        reference_shading,
                        speedup,
                        ideal: subsets,
                        setup: (count, pattern, interleaving),
                    });
                }
            }
        }
    }
    // Along the VPL counts of each size, pattern and interleaving.
    bench::remeasure_outliers(
        &mut rows,
        |r| {
            (
                (r.width, r.height, r.pattern.clone(), r.interleaving.clone()),
                r.vpls as f64,
            )
        },
        |r| r.indirect.median_ms,
        |r| {
            format!(
                "{}×{} {} VPLs {} {}",
                r.width, r.height, r.vpls, r.pattern, r.interleaving
            )
        },
        |r| -> Result<()> {
            let (count, pattern, interleaving) = r.setup;
            let set = vpl::generate_from_primary(&scene, &bvh, count, pattern.count(), 1)?;
            let mut renderer =
                GpuRenderer::new(&gpu.device, &gpu.queue, &scene, &[], r.width, r.height)?;
            let t = time(&mut renderer, (pattern, interleaving), &set)?;
            r.indirect = Stat::of(per_frame_sum(&t, &INDIRECT));
            r.speedup = r.reference_shading.median_ms / r.indirect.median_ms;
            r.passes = t.into_iter().map(|(n, v)| (n, Stat::of(v))).collect();
            Ok(())
        },
    )?;
    let (scene, camera) = bench::scene_labels(&path, &camera);
    let report = Report {
        header: bench::Header::new(&gpu),
        frames: frames,
        scene,
        camera,
        rows,
        quality: qualities,
    };
    args.common
        .options
        .write_report(&report.header, "indirect-", &report, &markdown(&report))?;
    Ok(())
}

fn markdown(r: &Report) -> String {
    let mut passes = bench::Table::new(&[
        "size",
        "VPLs",
        "interleaving",
        "BC",
        "BS",
        "SNSM",
        "BG",
        "DB + B",
        "composition",
    ]);
    for row in r.rows.iter().filter(|x| x.pattern == "4x4") {
        let mfrag = f64::from(row.width) * f64::from(row.height) / 1e6;
        let cell = |names: &[&str]| {
            let ms: f64 = row
                .passes
                .iter()
                .filter(|(n, _)| names.contains(&n.as_str()))
                .map(|(_, st)| st.median_ms)
                .sum();
            if ms == 0.0 {
                "—".to_string()
            } else {
                format!("{ms:.3} ({:.3})", ms / mfrag)
            }
        };
        let mut cells = vec![
            format!("{}×{}", row.width, row.height),
            row.vpls.to_string(),
            row.interleaving.clone(),
            cell(&["z-prepass", "gbuffer"]),
        ];
        cells.extend(["BS", "SNSM", "BG", "DB + B", "composition"].map(|p| cell(&[p])));
        passes.row(cells);
    }
    let mut speedups = bench::Table::new(&[
        "size",
        "VPLs",
        "pattern",
        "interleaving",
        "indirect ms",
        "reference ms",
        "speed-up",
        "ideal",
        "% of ideal",
    ]);
    // The first cells of both tables: size, VPLs, pattern.
    let configuration = |width: u32, height: u32, vpls: usize, pattern: &str| {
        [
            format!("{width}×{height}"),
            vpls.to_string(),
            pattern.to_owned(),
        ]
    };
    for row in &r.rows {
        let cells = [
            row.interleaving.clone(),
            format!("{:.3}", row.indirect.median_ms),
            format!("{:.3}", row.reference_shading.median_ms),
            format!("×{:.1}", row.speedup),
            format!("×{}", row.ideal),
            format!("{:.0} %", 100.0 * row.speedup / f64::from(row.ideal)),
        ];
        speedups.row(
            configuration(row.width, row.height, row.vpls, &row.pattern)
                .into_iter()
                .chain(cells),
        );
    }
    let mut quality = bench::Table::new(&[
        "size",
        "VPLs",
        "pattern",
        "FLIP mean",
        "PSNR dB",
        "RMSE",
        "FLIP unfiltered",
        "PSNR unfiltered",
    ]);
    for q in &r.quality {
        let cells = [
            format!("{:.4}", q.blurred.flip_mean),
            format!("{:.1}", q.blurred.psnr),
            format!("{:.4}", q.blurred.rmse),
            format!("{:.4}", q.unfiltered.flip_mean),
            format!("{:.1}", q.unfiltered.psnr),
        ];
        quality.row(
            configuration(q.width, q.height, q.vpls, &q.pattern)
                .into_iter()
                .chain(cells),
        );
    }
    format!(
        "{}\nScene `{}`, {}; primary light: the default sun; indirect light only (no direct \
         light, no ambient), one bounce, no VPL visibility (SNSM). Blur 5×5 fast unless said. \
         Times are medians of GPU timestamps; the reference (every pixel shades every VPL) is \
         measured in the same run.\n\n## Table 3: ms per pass and per million fragments (4×4)\n\n\
         {passes}Cells: ms (ms per million fragments). BC = z-prepass + G-buffer (raster); \
         DB + B = the discontinuity buffer and both blur directions in one dispatch.\n\n\
         ## Speed-up of the indirect passes over the reference shading\n\nIndirect = BS + SNSM + \
         BG + DB + B (fused: SNSM + DB + B). Ideal = n·m.\n\n{speedups}\
         ## Quality against the reference (indirect-only image, sRGB)\n\n{quality}",
        r.header.markdown(
            "Instant radiosity with interleaved deferred shading (Segovia 2006)",
            r.frames
        ),
        r.scene,
        r.camera
    )
}
