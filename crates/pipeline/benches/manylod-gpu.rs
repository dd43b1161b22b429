//! `manylod-bench`: many-view LoD cuts (Holländer 2013 Tables 3.1/3.2) on Sponza. The scene is
//! sampled into 2^20 and 2^21 surfels (the paper: 1.3 M points); 1024 VPLs (32×32 paraboloid
//! micro-views, a 1024×1024 atlas) come from a spot light orbiting 10° per frame. The CPU
//! build and the GPU refit; per threshold ε = 4, 2, 1 px, over the animation, the cut (basic
//! with one to four tree levels per pass, incremental with one to three, lazy with q = 2) and
//! the splat of each, the in-place variant, and at ε = 1 the ISM baseline (8 k random points per
//! view, Table 3.1) measured in the same run; then 4096 views at ε = 4 and 1. `--quick`: 2^20
//! points, ε = 4.
//! Writes `manylod-<adapter>-<date>.{md,json}`.

use anyhow::{Context, Result};
use bench::Stat;
use clap::Parser;
use gpu::{Gpu, PassTimer};
use instant_radiosity::{
    shadows::{scene_mesh, vpl_atlas, vpl_views},
    vpl,
};
use manylod::{
    Bsh, ManyLodError, View,
    gpu::{Compaction, CutKind, GpuIsm, GpuManyLod, GpuRefit},
    splat, surfels,
};
use scene::{Bvh, Scene};
use serde::Serialize;

/// Benchmarks ManyLoDs cuts and splats.
#[derive(Parser, Debug)]
struct Args {
    #[command(flatten)]
    common: bench::SceneArgs,
    /// With `--quick`: 2^20 points at ε = 4 px only (issue 28's rows).
    #[command(flatten)]
    quick: bench::Quick,
}

const TILE: u32 = 32;
/// Frames of the animation: the sun turns 10° per frame.
const CYCLE: usize = 36;

#[derive(Serialize)]
struct Row {
    points: usize,
    views: usize,
    epsilon: f32,
    variant: String,
    cut: Option<Stat>,
    splat: Option<Stat>,
    total: Stat,
    /// Node-views in the last frame's cut and processed to find it.
    cut_size: u64,
    /// Of those, culled (kept for the next frame, not drawn).
    culled: u64,
    processed: u64,
    iterations: u32,
}

#[derive(Serialize)]
struct Setup {
    points: usize,
    build_cpu_ms: f64,
    refit: Stat,
}

#[derive(Serialize)]
struct Report {
    header: bench::Header,
    frames: u32,
    /// Mean VPL move per frame, fraction of the scene's diagonal.
    vpl_move: f32,
    scene: String,
    triangles: usize,
    setups: Vec<Setup>,
    rows: Vec<Row>,
}

/// The VPL views of every frame of the animation, and the VPLs' mean move per frame as a
/// fraction of the scene's diagonal: VPLs of a spot light high in the scene, pointing down,
/// orbiting the vertical axis through the scene's centre by 10° per frame. The photons leave
/// in the same directions every frame and all of them land (the spot reaches past the scene),
/// so VPL `j` of consecutive frames comes from the same photon: the coherent set-up of the
/// paper's moving area light.
fn animation(scene: &Scene, bvh: &Bvh, count: usize) -> Result<(Vec<Vec<View>>, f32)> {
    let bounds = scene.bounds();
    let diagonal = bounds.diagonal();
    let lift = 1e-3 * diagonal;
    let sets = (0..CYCLE)
        .map(|f| {
            let spot = bench::orbiting_spot(&bounds, (f as f32 * 10.0).to_radians());
            Ok(vpl::generate(
                scene,
                bvh,
                &[spot],
                &vpl::VplConfig {
                    count,
                    subsets: 1,
                    seed: 1,
                    emissive: false,
                    bounces: 1,
                },
            )?)
        })
        .collect::<Result<Vec<_>>>()?;
    let moved: f32 = sets
        .windows(2)
        .flat_map(|w| {
            w[0].vpls
                .iter()
                .zip(&w[1].vpls)
                .map(|(a, b)| a.position.distance(b.position))
        })
        .sum::<f32>()
        / ((sets.len() - 1) * count) as f32;
    let views = sets.iter().map(|set| vpl_views(set, TILE, lift)).collect();
    Ok((views, moved / diagonal))
}

/// Records one frame's passes.
type Record<'a> =
    dyn Fn(&mut GpuManyLod, &mut wgpu::CommandEncoder, &PassTimer) -> Result<(), ManyLodError> + 'a;

/// Per-frame GPU times of the passes `record` encodes for each frame of `views` in turn
/// (the views of frame `f` uploaded first; `bench::time_named`).
fn time_animation(
    gpu: &Gpu,
    timer: &PassTimer,
    frames: u32,
    views: &[Vec<View>],
    m: &mut GpuManyLod,
    record: &Record<'_>,
) -> Result<Vec<(String, Vec<f64>)>> {
    let mut frame = 0usize;
    bench::time_named(frames, || -> Result<Vec<(String, f64)>> {
        m.set_views(&gpu.queue, &views[frame % views.len()])?;
        frame += 1;
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        record(m, &mut encoder, timer)?;
        timer.resolve(&mut encoder);
        gpu.queue.submit([encoder.finish()]);
        Ok(timer
            .read(&gpu.device, &gpu.queue)?
            .into_iter()
            .map(|t| (t.name, t.ms))
            .collect())
    })
}

/// A GPU set-up whose lists hold the largest cuts of the run: starts at 4 node-views per
/// micro-view pixel and doubles (up to the device's largest list) while a basic cut or the
/// incremental cuts of the next frames overflow.
fn gpu_manylod(
    gpu: &Gpu,
    bsh: &Bsh,
    views: &[Vec<View>],
    epsilon: f32,
    diagonal: f32,
) -> Result<GpuManyLod> {
    let largest = manylod::gpu::largest_capacity(&gpu.device);
    let mut capacity = views[0].len() * (TILE * TILE) as usize * 4;
    loop {
        let layout = vpl_atlas(views[0].len(), TILE, diagonal);
        let mut m = GpuManyLod::new(&gpu.device, bsh, &views[0], epsilon, layout, capacity, None)?;
        let mut overflowed = false;
        for (f, v) in views.iter().take(4).enumerate() {
            m.set_views(&gpu.queue, v)?;
            let mut encoder = gpu.device.create_command_encoder(&Default::default());
            let kind = if f == 0 {
                CutKind::Basic
            } else {
                CutKind::Incremental
            };
            m.encode_cut(&mut encoder, kind, None);
            gpu.queue.submit([encoder.finish()]);
            match m.read_cut(&gpu.device, &gpu.queue) {
                Err(ManyLodError::Capacity { .. }) => {
                    overflowed = true;
                    // The next frame cannot start from an overflowed cut.
                    break;
                }
                r => drop(r?),
            }
        }
        if !overflowed {
            return Ok(m);
        }
        drop(m);
        if capacity >= largest {
            anyhow::bail!("the cuts need more than the device's {largest} node-views per list");
        }
        capacity = (2 * capacity).min(largest);
    }
}

/// What a row measures: a list-based cut (with its tree levels per pass) and its splat, or
/// the in-place variant.
#[derive(Clone, Copy)]
enum Variant {
    Cut(CutKind, u32),
    InPlace(Compaction),
}

/// The variants measured at a set-up: basic cuts of one to four tree levels per pass,
/// incremental cuts of one to three and (with `lazy`) lazy cuts, and the in-place variant with each compaction the
/// device runs.
fn variants(m: &GpuManyLod, lazy: bool) -> Vec<(&'static str, Variant)> {
    let mut v = vec![
        ("basic", Variant::Cut(CutKind::Basic, 1)),
        ("basic, 2 levels/pass", Variant::Cut(CutKind::Basic, 2)),
        ("basic, 3 levels/pass", Variant::Cut(CutKind::Basic, 3)),
        ("basic, 4 levels/pass", Variant::Cut(CutKind::Basic, 4)),
        ("incremental", Variant::Cut(CutKind::Incremental, 1)),
        (
            "incremental, 2 levels/pass",
            Variant::Cut(CutKind::Incremental, 2),
        ),
        (
            "incremental, 3 levels/pass",
            Variant::Cut(CutKind::Incremental, 3),
        ),
    ];
    if lazy {
        v.push(("lazy q=2", Variant::Cut(CutKind::Lazy(2), 1)));
    }
    for c in m.compactions() {
        v.push(match c {
            Compaction::Atomic => ("in-place (basic, atomic)", Variant::InPlace(c)),
            Compaction::Ballot => ("in-place (basic, ballot)", Variant::InPlace(c)),
        });
    }
    v
}

#[allow(clippy::too_many_arguments)]
fn variant_row(
    gpu: &Gpu,
    timer: &PassTimer,
    frames: u32,
    views: &[Vec<View>],
    m: &mut GpuManyLod,
    points: usize,
    epsilon: f32,
    (name, variant): (&str, Variant),
) -> Result<Row> {
    if let Variant::Cut(_, levels) = variant {
        m.set_levels_per_pass(&gpu.queue, levels)?;
    }
    let by_name = time_animation(gpu, timer, frames, views, m, &|m, e, t| match variant {
        Variant::Cut(k, _) => {
            m.encode_cut(e, k, Some(t));
            m.encode_splat(e, Some(t));
            Ok(())
        }
        Variant::InPlace(c) => m.encode_inplace(e, c, Some(t)),
    })?;
    let total = Stat::of(bench::per_frame_sum(
        &by_name,
        &["cut", "splat", "in-place"],
    ));
    let (cut_size, culled, processed, iterations) = match variant {
        Variant::Cut(..) => {
            let c = m.read_cut(&gpu.device, &gpu.queue)?;
            (
                c.node_views.len() as u64,
                c.culled,
                c.processed,
                c.iterations,
            )
        }
        Variant::InPlace(_) => {
            m.read_atlas(&gpu.device, &gpu.queue)?;
            (0, 0, 0, 0)
        }
    };
    println!(
        "{points} points, {} views, ε {epsilon}: {name} {:.3} ms ({cut_size} node-views, {processed} processed)",
        views[0].len(),
        total.median_ms
    );
    Ok(Row {
        points,
        views: views[0].len(),
        epsilon,
        variant: name.into(),
        cut: bench::pass_stat(&by_name, "cut"),
        splat: bench::pass_stat(&by_name, "splat"),
        total,
        cut_size,
        culled,
        processed,
        iterations,
    })
}

fn main() -> Result<()> {
    let args = Args::parse_from(bench::args());
    let gpu = args.common.options.gpu()?;
    let frames = args.common.options.frames(36);
    let (path, scene) = args.common.scene.load()?;
    let bvh = Bvh::build(&scene);
    let diagonal = scene.bounds().diagonal();
    let (positions, indices) = scene_mesh(&scene);
    // Run-once mode (a test, not a measurement) shrinks views and points 16-fold.
    let shrink = if bench::run_once() { 16 } else { 1 };
    let (views_1k, moved) = animation(&scene, &bvh, 1024 / shrink)?;
    let (views_4k, _) = animation(&scene, &bvh, 4096 / shrink)?;
    println!("VPLs move {:.2} % of the diagonal per frame", 100.0 * moved);
    let timer = PassTimer::new(&gpu.device, 8);
    let mut setups = Vec::new();
    let mut rows = Vec::new();
    for &points in args
        .quick
        .sweep(&[1usize << 20, 1 << 21].map(|p| p / shrink))
    {
        let start = std::time::Instant::now();
        let s = surfels::sample(&positions, &indices, points, 1)?;
        let (p, n) = surfels::evaluate(&s, &positions, &indices);
        let bsh = Bsh::build(&p, &n, surfels::disc_radius(&positions, &indices, points))?;
        let build_cpu_ms = start.elapsed().as_secs_f64() * 1e3;
        let first_row = rows.len();
        let epsilons = args.quick.sweep(&[4.0f32, 2.0, 1.0]);
        for &epsilon in epsilons {
            let mut m = gpu_manylod(&gpu, &bsh, &views_1k, epsilon, diagonal)?;
            if epsilon == epsilons[0] {
                let refit = GpuRefit::new(&gpu.device, &m, &bsh, &s, &positions, &indices)?;
                let refit_stat = bench::time_encoded(&gpu, &timer, frames, false, &|e, t| {
                    refit.encode(e, Some(t));
                })?;
                println!(
                    "{points} points: build {build_cpu_ms:.0} ms (CPU), refit {:.3} ms",
                    refit_stat.median_ms
                );
                setups.push(Setup {
                    points,
                    build_cpu_ms,
                    refit: refit_stat,
                });
            }
            for variant in variants(&m, true) {
                rows.push(variant_row(
                    &gpu, &timer, frames, &views_1k, &mut m, points, epsilon, variant,
                )?);
            }
            if Some(&epsilon) == epsilons.last() {
                let n = bsh.leaf_count();
                let (ism_points, list) =
                    splat::ism(&bsh.nodes[n - 1..], views_1k[0].len(), 8192, 3)?;
                let ism = GpuIsm::new(&gpu.device, &m, &ism_points, &list)?;
                let by_name =
                    time_animation(&gpu, &timer, frames, &views_1k, &mut m, &|m, e, t| {
                        ism.encode(e, m, Some(t));
                        Ok(())
                    })?;
                let total = bench::pass_stat(&by_name, "ism").unwrap_or(Stat::of(Vec::new()));
                println!(
                    "{points} points: ISM 8 k points/view {:.3} ms",
                    total.median_ms
                );
                rows.push(Row {
                    points,
                    views: views_1k[0].len(),
                    epsilon,
                    variant: "ISM 8 k points/view".into(),
                    cut: None,
                    splat: Some(total),
                    total,
                    cut_size: list.len() as u64,
                    culled: 0,
                    processed: 0,
                    iterations: 0,
                });
            }
        }
        // Along ε for each variant with the 1024 views (64 in run-once mode).
        bench::remeasure_outliers(
            &mut rows[first_row..],
            |r: &Row| (r.variant.clone(), f64::from(r.epsilon)),
            |r| r.total.median_ms,
            |r| {
                format!(
                    "{points} points, {} views, ε {}: {}",
                    r.views, r.epsilon, r.variant
                )
            },
            |r| -> Result<()> {
                let mut m = gpu_manylod(&gpu, &bsh, &views_1k, r.epsilon, diagonal)?;
                let variant = variants(&m, true)
                    .into_iter()
                    .find(|(name, _)| *name == r.variant)
                    .context("the row's variant")?;
                *r = variant_row(
                    &gpu, &timer, frames, &views_1k, &mut m, points, r.epsilon, variant,
                )?;
                Ok(())
            },
        )?;
        for &epsilon in args.quick.sweep(&[4.0f32, 1.0]) {
            let mut m = gpu_manylod(&gpu, &bsh, &views_4k, epsilon, diagonal)?;
            for variant in variants(&m, false) {
                rows.push(variant_row(
                    &gpu, &timer, frames, &views_4k, &mut m, points, epsilon, variant,
                )?);
            }
        }
    }

    let header = bench::Header::new(&gpu);
    let mut md = header.markdown(
        "Many-view LoD cuts, ManyLoDs (Holländer 2013 §3.5–3.7)",
        frames,
    );
    md.push_str(&format!(
        "\nScene: {} ({} triangles). VPLs from a spot light pointing down from high in the scene and \
         orbiting its vertical axis by 10° per frame over a {CYCLE}-frame cycle (the same photons \
         every frame: VPLs move {:.2} % of the scene's diagonal per frame on average); each VPL is a 32×32 paraboloid micro-view (1024 views: a 1024×1024 atlas, 4096: \
         2048×2048). GPU times (timestamp queries, median of {} frames of the animation): `cut` \
         = all iterations of the many-view cut (indirect dispatch, no read-back), `splat` = \
         atlas clear + disc splats with atomic-min FreePipe depth; in-place = cut and splat in one \
         kernel (one workgroup per view). Incremental and lazy frames start from the previous \
         frame's cut. The paper (GTX 480, Table 3.1, Grog 1.3 M points, 1024 VPLs): \
         non-incremental 55 ms, incremental 5.3 ms, lazy 2.9 ms, ISM 8 k points 120 ms; Table 3.2 \
         (Sponza 1.3 M points): cut 3.4 / 1.6 / 3.8 ms at c = 1 / 2 / 4 px, update 15 ms.\n\n\
         | points | build (CPU) ms | refit ms |\n|---|---|---|\n",
        path.file_name()
            .map_or_else(String::new, |f| f.to_string_lossy().into_owned()),
        scene.triangle_count(),
        100.0 * moved,
        frames
    ));
    for s in &setups {
        md.push_str(&format!(
            "| {} | {:.0} | {:.3} |\n",
            s.points, s.build_cpu_ms, s.refit.median_ms
        ));
    }
    md.push_str(
        "\n| points | views | ε px | variant | cut ms | splat ms | total ms | ÷ basic | cut node-views | culled | processed | iterations |\n\
         |---|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    let ms = |s: &Option<Stat>| s.map_or("–".into(), |s| format!("{:.3}", s.median_ms));
    for r in &rows {
        let basic = rows
            .iter()
            .find(|b| {
                b.points == r.points
                    && b.views == r.views
                    && b.epsilon == r.epsilon
                    && b.variant == "basic"
            })
            .map_or(f64::NAN, |b| b.total.median_ms);
        md.push_str(&format!(
            "| {} | {} | {} | {} | {} | {} | {:.3} | {:.2} | {} | {} | {} | {} |\n",
            r.points,
            r.views,
            r.epsilon,
            r.variant,
            ms(&r.cut),
            ms(&r.splat),
            r.total.median_ms,
            r.total.median_ms / basic,
            r.cut_size,
            r.culled,
            r.processed,
            r.iterations
        ));
    }
    let report = Report {
        header,
        frames: frames,
        vpl_move: moved,
        scene: path.display().to_string(),
        triangles: scene.triangle_count(),
        setups,
        rows,
    };
    args.common
        .options
        .write_report(&report.header, "manylod-", &report, &md)
}
