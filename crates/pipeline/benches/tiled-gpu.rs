//! `tiled-bench`: the light accumulation of Ishmukhametov 2013 on the GPU — brute force, tiled,
//! tiled with normal-cone back-face culling, tiled with slice masks, clustered, traditional deferred shading with
//! light volumes (§4.1, depth-tested against the G-buffer's depth), Forward+ and the light
//! pre-pass (§2.4.2, §2.1; with their geometry passes) — (1) on Sponza at 1920×1080 and
//! 3840×2160 with 256 to 65 536 scattered bounded point lights, (2) on the thesis's tests 1–4
//! (the wall scene with 0, 100, 500, 1000 lights behind the wall) with and without CPU
//! view-frustum culling, and along test 4's side wall at a grazing angle; whole frames too.
//! Every light-accumulation time is the GPU time of the method's own passes, brute force
//! measured in the same run as the baseline. Writes `tiled-shading-<adapter>-<date>` `.md` and
//! `.json` under `--out`; with `--transparency` only the transparency frames
//! (`tiled-transparency-…`).

mod common;

use anyhow::{Context, Result};
use bench::Stat;
use bench::per_frame_sum;
use clap::Parser;
use common::time_passes;
use gbuffer::gpu::BlendedSurfaces;
use gpu::Gpu;
use pipeline::{DEFAULT_AMBIENT, LightSearch, ShadingConfig, ShadingMethod, gpu::GpuRenderer};
use scene::{Camera, Light};
use serde::Serialize;

/// Benchmarks every light accumulation method.
#[derive(Parser, Debug)]
struct Args {
    #[command(flatten)]
    common: bench::SceneArgs,
    #[command(flatten)]
    quick: bench::Quick,
    /// Only the transparency frames (`tiled-transparency-<adapter>-<date>`): the material
    /// gallery with its blended sphere, dithered or drawn forward.
    #[arg(long)]
    transparency: bool,
    /// Only these light counts (comma-separated), at 1920×1080 from both views, without the
    /// thesis tests: a focused comparison.
    #[arg(long, value_delimiter = ',')]
    lights: Vec<usize>,
}

const SIZES: [(u32, u32); 2] = [(1920, 1080), (3840, 2160)];
const LIGHTS: [usize; 7] = [256, 1024, 4096, 16384, 65536, 262_144, 1_048_576];
/// Above this many lights only the culled compute methods run (brute force takes seconds).
const MOST_FOR_ALL: usize = 65536;

/// What is measured, by report name: every method, the tiled ones with both light searches
/// (`-flat`: every light per tile, as the thesis; without: through the light hierarchy).
const VARIANTS: [(&str, ShadingMethod, LightSearch); 11] = [
    ("brute", ShadingMethod::BruteForce, LightSearch::Flat),
    ("tiled-flat", ShadingMethod::Tiled, LightSearch::Flat),
    ("tiled", ShadingMethod::Tiled, LightSearch::Tree),
    (
        "tiled-cones-flat",
        ShadingMethod::TiledCones,
        LightSearch::Flat,
    ),
    ("tiled-cones", ShadingMethod::TiledCones, LightSearch::Tree),
    (
        "tiled-slices",
        ShadingMethod::TiledSlices,
        LightSearch::Tree,
    ),
    (
        "clustered-flat",
        ShadingMethod::Clustered,
        LightSearch::Flat,
    ),
    ("clustered", ShadingMethod::Clustered, LightSearch::Tree),
    ("volumes", ShadingMethod::LightVolumes, LightSearch::Flat),
    ("forward", ShadingMethod::ForwardPlus, LightSearch::Tree),
    (
        "light-prepass",
        ShadingMethod::LightPrePass,
        LightSearch::Tree,
    ),
];
/// Tiled with its lights set again before every frame (as when they move): the light hierarchy
/// is built on the GPU in every frame, so this minus `tiled` is the build's cost.
const MOVING: (&str, ShadingMethod, LightSearch) =
    ("tiled-moving", ShadingMethod::Tiled, LightSearch::Tree);
/// The passes that stand for a method's light accumulation besides its compute or volume pass:
/// Forward+'s geometry pass lighting the opaque surfaces, the light pre-pass's second geometry
/// pass applying the materials.
const LIGHTING_PASSES: [&str; 2] = ["forward+ opaque", "light pre-pass materials"];
const TESTS: [(u32, u32); 4] = [(1, 0), (2, 100), (3, 500), (4, 1000)];
/// A view down Sponza's side aisle (eye, target): pillars and arches near the eye against the
/// far end of the colonnade — depth discontinuities in most tiles, where clusters should pay.
const COLONNADE: ([f32; 3], [f32; 3]) = ([-14.0, 2.5, -4.5], [14.0, 3.0, -3.5]);
const COLONNADE_LIGHTS: [usize; 3] = [4096, 16384, 65536];
const TEST_SIZES: [(u32, u32); 2] = [(1280, 720), (1920, 1080)];
/// Test 4's walls seen at a grazing angle (eye, target): along the left side wall from near its
/// open end to the back wall — tiles over the side wall span tens of metres of depth.
const GRAZING: ([f32; 3], [f32; 3]) = ([-28.5, 3.0, -1.0], [-27.0, 3.5, -40.0]);

#[derive(Serialize)]
struct Row {
    /// `main` (the scene's camera) or `colonnade` ([`COLONNADE`]).
    view: &'static str,
    width: u32,
    height: u32,
    lights: usize,
    method: String,
    ms: Stat,
    /// The whole frame: every pass of the renderer (z-prepass, G-buffer, light accumulation,
    /// composition, output).
    frame_ms: Stat,
    /// Median brute-force ms / median ms (same run; none above [`MOST_FOR_ALL`] lights).
    speedup_vs_brute: Option<f64>,
    /// Mean list length over tiles with a surface (None for brute force).
    mean_list: Option<f64>,
    /// The brute-force median the speed-up divides, ms.
    #[serde(skip)]
    brute_ms: Option<f64>,
}

#[derive(Serialize)]
struct TestRow {
    /// `thesis` (the test's camera) or `grazing` ([`GRAZING`]).
    view: &'static str,
    test: u32,
    width: u32,
    height: u32,
    lights_total: usize,
    frustum_culling: bool,
    lights_sent: usize,
    method: String,
    ms: Stat,
    /// The whole frame, as [`Row::frame_ms`].
    frame_ms: Stat,
    mean_list: Option<f64>,
}

#[derive(Serialize)]
struct Report {
    header: bench::Header,
    frames: u32,
    scene: String,
    camera: String,
    colonnade: String,
    sweep: Vec<Row>,
    tests: Vec<TestRow>,
}

/// Times of the light accumulation pass and of the whole frame, and the mean list length of
/// non-empty tiles. With `moving`, those lights are set before every frame, as when they move:
/// the light hierarchy is then built in every frame's light accumulation pass.
fn measure(
    gpu: &Gpu,
    renderer: &mut GpuRenderer,
    camera: &Camera,
    (method, search): (ShadingMethod, LightSearch),
    frames: u32,
    moving: Option<&[Light]>,
) -> Result<(Stat, Stat, Option<f64>)> {
    renderer.set_shading(
        &gpu.device,
        &gpu.queue,
        &ShadingConfig {
            method,
            tile_size: 16,
            search,
        },
    )?;
    let name = renderer.shading().pass_name();
    let t = time_passes(gpu, renderer, camera, DEFAULT_AMBIENT, frames, moving)?;
    let mut lighting = vec![name.as_str()];
    lighting.extend(LIGHTING_PASSES);
    let ms = Stat::of(per_frame_sum(&t, &lighting));
    let every: Vec<&str> = t.iter().map(|(n, _)| n.as_str()).collect();
    let frame = Stat::of(per_frame_sum(&t, &every));
    let mean = renderer
        .light_counts(&gpu.device, &gpu.queue)?
        .map(|counts| {
            let lit: Vec<u32> = counts.into_iter().filter(|&c| c > 0).collect();
            lit.iter().map(|&c| f64::from(c)).sum::<f64>() / lit.len().max(1) as f64
        });
    Ok((ms, frame, mean))
}

fn main() -> Result<()> {
    let args = Args::parse_from(bench::args());
    let gpu = args.common.options.gpu()?;
    let frames = args.common.options.frames(10);
    if args.transparency {
        return transparency(&gpu, &args, frames);
    }
    let (path, scene, camera) = args.common.scene.load_viewed()?;
    println!(
        "scene: {} ({} triangles)",
        path.display(),
        scene.triangle_count()
    );
    let q = &args.quick;
    let (mut sizes, mut counts, mut tests) = (q.sweep(&SIZES), q.sweep(&LIGHTS), q.sweep(&TESTS));
    let mut colonnade_counts = if q.quick {
        &COLONNADE_LIGHTS[..1]
    } else {
        &COLONNADE_LIGHTS
    };
    if !args.lights.is_empty() {
        (sizes, counts, tests) = (&SIZES[..1], &args.lights, &[]);
        colonnade_counts = &args.lights;
    }

    let mut sweep = light_sweep(&gpu, &scene, &camera, "main", sizes, counts, frames)?;
    let colonnade = Camera {
        eye: COLONNADE.0.into(),
        target: COLONNADE.1.into(),
        ..camera
    };
    sweep.extend(light_sweep(
        &gpu,
        &scene,
        &colonnade,
        "colonnade",
        &SIZES[..1],
        colonnade_counts,
        frames,
    )?);

    let mut rows = Vec::new();
    for &(test, behind) in tests {
        let walls = scene::thesis_walls(behind);
        let cam = walls.camera.unwrap_or_else(|| walls.camera_or_framed());
        for size in TEST_SIZES {
            thesis_test(
                &gpu,
                (&walls, test),
                ("thesis", &cam),
                size,
                frames,
                &mut rows,
            )?;
        }
        if test == 4 {
            let grazing = Camera {
                eye: GRAZING.0.into(),
                target: GRAZING.1.into(),
                ..cam
            };
            let view = ("grazing", &grazing);
            thesis_test(&gpu, (&walls, test), view, SIZES[0], frames, &mut rows)?;
        }
    }

    let (_, colonnade) = bench::scene_labels(&path, &colonnade);
    let (scene, camera) = bench::scene_labels(&path, &camera);
    let report = Report {
        header: bench::Header::new(&gpu),
        frames,
        scene,
        camera,
        colonnade,
        sweep,
        tests: rows,
    };
    args.common.options.write_report(
        &report.header,
        "tiled-shading-",
        &report,
        &markdown(&report),
    )?;
    Ok(())
}

/// Every variant on thesis test `test`'s `walls` from `camera` (labelled `view`) at `size`,
/// with and without CPU view-frustum culling.
fn thesis_test(
    gpu: &Gpu,
    (walls, test): (&scene::Scene, u32),
    (view, cam): (&'static str, &Camera),
    size: (u32, u32),
    frames: u32,
    rows: &mut Vec<TestRow>,
) -> Result<()> {
    let (w, h) = bench::size(size);
    let mut renderer = GpuRenderer::new(&gpu.device, &gpu.queue, walls, &[], w, h)?;
    for frustum_culling in [true, false] {
        let all = pipeline::validate_lights(&walls.lights)?;
        let sent: Vec<Light> = if frustum_culling {
            tiled_shading::frustum_cull(cam, w as f32 / h as f32, &all)
                .into_iter()
                .map(|i| walls.lights[i as usize])
                .collect()
        } else {
            walls.lights.clone()
        };
        renderer.set_lights(&gpu.device, &gpu.queue, &sent)?;
        for (name, method, search) in VARIANTS {
            let (ms, frame_ms, mean_list) =
                measure(gpu, &mut renderer, cam, (method, search), frames, None)?;
            println!(
                "test {test} {view} {w}x{h} {:>4}/{} lights{} {name:<16} {:>8.3} ms",
                sent.len(),
                walls.lights.len(),
                if frustum_culling { " (VFC)" } else { "" },
                ms.median_ms
            );
            rows.push(TestRow {
                view,
                test,
                width: w,
                height: h,
                lights_total: walls.lights.len(),
                frustum_culling,
                lights_sent: sent.len(),
                method: name.to_string(),
                ms,
                frame_ms,
                mean_list,
            });
        }
    }
    Ok(())
}

/// Every variant at every size and light count (scattered over the scene's bounds) from
/// `camera`, labelled `view`.
fn light_sweep(
    gpu: &Gpu,
    scene: &scene::Scene,
    camera: &Camera,
    view: &'static str,
    sizes: &[(u32, u32)],
    counts: &[usize],
    frames: u32,
) -> Result<Vec<Row>> {
    let mut sweep = Vec::new();
    for (w, h) in sizes.iter().copied().map(bench::size) {
        let mut renderer = GpuRenderer::new(&gpu.device, &gpu.queue, scene, &[], w, h)?;
        let first_row = sweep.len();
        for &count in counts {
            let lights = scene::scatter_point_lights(scene.bounds(), count, 1);
            renderer.set_lights(&gpu.device, &gpu.queue, &lights)?;
            let mut brute = None;
            let moving = (MOVING.0, MOVING.1, MOVING.2, Some(&lights[..]));
            let variants = VARIANTS.iter().map(|&(n, m, s)| (n, m, s, None));
            for (name, method, search, moving) in variants.chain([moving]) {
                let slow = matches!(
                    method,
                    ShadingMethod::BruteForce | ShadingMethod::LightVolumes
                );
                if slow && count > MOST_FOR_ALL {
                    continue;
                }
                let (ms, frame_ms, mean_list) =
                    measure(gpu, &mut renderer, camera, (method, search), frames, moving)?;
                if method == ShadingMethod::BruteForce {
                    brute = Some(ms.median_ms);
                }
                let speedup = brute.map(|b| b / ms.median_ms);
                println!(
                    "{view} {w}x{h} {count:>7} lights {name:<16} {:>9.3} ms (frame {:>9.3})  ×{:<7.1} mean list {}",
                    ms.median_ms,
                    frame_ms.median_ms,
                    speedup.unwrap_or(f64::NAN),
                    mean_list.map_or("-".into(), |m| format!("{m:.1}"))
                );
                sweep.push(Row {
                    view,
                    width: w,
                    height: h,
                    lights: count,
                    method: name.to_string(),
                    ms,
                    frame_ms,
                    speedup_vs_brute: speedup,
                    mean_list,
                    brute_ms: brute,
                });
            }
        }
        // Along the light counts of each method at this size.
        bench::remeasure_outliers(
            &mut sweep[first_row..],
            |r: &Row| (r.method.clone(), r.lights as f64),
            |r| r.ms.median_ms,
            |r| format!("{view} {w}x{h} {} lights {}", r.lights, r.method),
            |r| -> Result<()> {
                let (_, method, search) = VARIANTS
                    .into_iter()
                    .chain([MOVING])
                    .find(|v| v.0 == r.method)
                    .context("the row's method")?;
                let lights = scene::scatter_point_lights(scene.bounds(), r.lights, 1);
                renderer.set_lights(&gpu.device, &gpu.queue, &lights)?;
                let moving = (r.method == MOVING.0).then_some(&lights[..]);
                (r.ms, r.frame_ms, r.mean_list) =
                    measure(gpu, &mut renderer, camera, (method, search), frames, moving)?;
                r.speedup_vs_brute = r.brute_ms.map(|b| b / r.ms.median_ms);
                Ok(())
            },
        )?;
    }
    Ok(sweep)
}

fn markdown(r: &Report) -> String {
    use std::fmt::Write;
    let mut s = r.header.markdown(
        "Tiled deferred shading with normal-cone culling (Ishmukhametov 2013)",
        r.frames,
    );
    let _ = writeln!(
        s,
        "Every time is the GPU time of the light accumulation alone (the G-buffer, composition \
         and CPU work excluded); 16×16 tiles; brute force (every light at every pixel) measured in \
         the same run is the baseline; `volumes` is the thesis's traditional deferred shading (§4.1: \
         instanced light volumes, back faces depth-tested against the scene, additive blending — \
         a render pass, timed like the others); `forward` is Forward+'s culling pass plus its \
         geometry pass lighting the opaque surfaces, `light-prepass` the light pre-pass's \
         lighting pass plus its second geometry pass. Lights: bounded point lights whose \
         attenuation is exactly zero at their radius, so every method renders the same image \
         (tested; the light pre-pass's monochrome specular approximates).\n\n\
         ## Light-count sweep: `{}`, {}\n\n\
         Lights scattered uniformly through the scene's bounds (`scatter_point_lights`, radius \
         0.6·diagonal/∛N). Cells: ms (speed-up over brute force); mean list = lights per \
         non-empty tile (for clustered: distinct lights over the tile's clusters); clustered vs \
         tiled = tiled ms / clustered ms, both through the hierarchy; hierarchy build = the tiled \
         ms with the lights set again before every frame (as when they move: the light hierarchy \
         is then built on the GPU in every frame) minus the tiled ms. Above 65 536 lights brute force and the volumes are not run (seconds \
         per frame). `-flat`: every light tested per tile, as the thesis; without: the tile finds \
         its lights through the light hierarchy (groups of 32 lights in Morton order under \
         bounding spheres) — the same lists.\n",
        r.scene, r.camera
    );
    sweep_table(&mut s, r, "main");
    let _ = writeln!(
        s,
        "\n## Depth discontinuities: Sponza's colonnade, {}\n\n\
         The same lights seen down the side aisle: pillars and arches near the eye against the \
         far end in most tiles.\n",
        r.colonnade
    );
    sweep_table(&mut s, r, "colonnade");
    let _ = writeln!(
        s,
        "\n## Whole frames\n\n\
         Every pass of the renderer (z-prepass, G-buffer, light accumulation, composition, \
         output), ms, 1920×1080.\n"
    );
    frame_table(&mut s, r);
    let _ = writeln!(
        s,
        "\n## Thesis tests 1–4 (§4.2): `scene::thesis_walls`\n\n\
         55 lights in view, 1445 outside the view frustum, and 0 / 100 / 500 / 1000 lights just \
         behind the back wall (cullable by normals). VFC = CPU view-frustum culling of lights \
         (§4.1) before upload. Cells: ms; cones vs tiled = tiled ms / tiled-cones ms, with the \
         thesis's flat search and with the light hierarchy; tiled vs volumes = volumes ms / \
         tiled-flat ms. The `grazing` view looks along test 4's left side wall to the back \
         wall: tiles over the side wall span tens of metres of depth (where clusters should \
         pay). `forward` = Forward+'s culling pass + its geometry pass lighting the opaque \
         surfaces; `light-prepass` = its lighting pass + its second geometry pass.\n\n\
         | test | view | size | lights | VFC | sent | brute | volumes | tiled-flat | tiled-cones-flat | tiled | tiled-cones | clustered | forward | light-prepass | cones vs tiled (flat) | cones vs tiled | tiled vs volumes | tiled list | cones list | clustered list |\n\
         |---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"
    );
    let mut keys: Vec<(u32, &str, u32, u32, bool)> = r
        .tests
        .iter()
        .map(|x| (x.test, x.view, x.width, x.height, x.frustum_culling))
        .collect();
    keys.dedup();
    for key in keys {
        let rows: Vec<&TestRow> = r
            .tests
            .iter()
            .filter(|x| (x.test, x.view, x.width, x.height, x.frustum_culling) == key)
            .collect();
        let get = |m: &str| rows.iter().find(|x| x.method == m);
        let ms = |m: &str| get(m).map_or(f64::NAN, |x| x.ms.median_ms);
        let list = |m: &str| {
            get(m)
                .and_then(|x| x.mean_list)
                .map_or("—".into(), |l| format!("{l:.1}"))
        };
        let first = rows[0];
        let _ = writeln!(
            s,
            "| {} | {} | {}×{} | {} | {} | {} | {:.3} | {:.3} | {:.3} | {:.3} | {:.3} | {:.3} | {:.3} | {:.3} | {:.3} | ×{:.2} | ×{:.2} | ×{:.1} | {} | {} | {} |",
            key.0,
            key.1,
            key.2,
            key.3,
            first.lights_total,
            if key.4 { "on" } else { "off" },
            first.lights_sent,
            ms("brute"),
            ms("volumes"),
            ms("tiled-flat"),
            ms("tiled-cones-flat"),
            ms("tiled"),
            ms("tiled-cones"),
            ms("clustered"),
            ms("forward"),
            ms("light-prepass"),
            ms("tiled-flat") / ms("tiled-cones-flat"),
            ms("tiled") / ms("tiled-cones"),
            ms("volumes") / ms("tiled-flat"),
            list("tiled"),
            list("tiled-cones"),
            list("clustered"),
        );
    }
    let _ = writeln!(
        s,
        "\nThesis (Radeon HD 5730, 1280×720, whole frame, VFC on): tiled-cones vs tiled 0.95× \
         (test 1), 1.17× (test 2), 1.50× (test 3), 1.66× (test 4); tiled vs traditional \
         deferred (volumes) 1.18×, 1.60×, 2.17×, 2.36×."
    );
    s
}

/// The light-count sweep of `view` as a table: light accumulation ms (× brute force).
fn sweep_table(s: &mut String, r: &Report, view: &str) {
    use std::fmt::Write;
    let methods: Vec<&str> = VARIANTS.iter().map(|v| v.0).collect();
    let _ = writeln!(
        s,
        "| size | lights | {} | clustered vs tiled | hierarchy build | tiled list | cones list | clustered list |\n|---|---|{}---|---|---|---|---|",
        methods.join(" | "),
        "---|".repeat(methods.len())
    );
    let rows: Vec<&Row> = r.sweep.iter().filter(|x| x.view == view).collect();
    let mut keys: Vec<(u32, u32, usize)> =
        rows.iter().map(|x| (x.width, x.height, x.lights)).collect();
    keys.dedup();
    for (w, h, n) in keys {
        let row = |m: &str| {
            rows.iter()
                .find(|x| (x.width, x.height, x.lights) == (w, h, n) && x.method == m)
        };
        let cells: Vec<String> = methods
            .iter()
            .map(|m| {
                row(m).map_or("—".into(), |x| match x.speedup_vs_brute {
                    Some(speedup) => format!("{:.3} (×{speedup:.1})", x.ms.median_ms),
                    None => format!("{:.3}", x.ms.median_ms),
                })
            })
            .collect();
        let list = |m: &str| {
            row(m)
                .and_then(|x| x.mean_list)
                .map_or("—".into(), |l| format!("{l:.1}"))
        };
        let ms = |m: &str| row(m).map_or(f64::NAN, |x| x.ms.median_ms);
        let _ = writeln!(
            s,
            "| {w}×{h} | {n} | {} | ×{:.2} | {:.3} | {} | {} | {} |",
            cells.join(" | "),
            ms("tiled") / ms("clustered"),
            ms(MOVING.0) - ms("tiled"),
            list("tiled"),
            list("tiled-cones"),
            list("clustered")
        );
    }
}

/// Whole-frame ms of every variant at 1920×1080: the sweep's views, and the thesis tests at
/// 1280×720 with CPU frustum culling (the thesis's whole-frame setting).
fn frame_table(s: &mut String, r: &Report) {
    use std::fmt::Write;
    let methods: Vec<&str> = VARIANTS.iter().map(|v| v.0).collect();
    let _ = writeln!(
        s,
        "| case | lights | {} |\n|---|---|{}",
        methods.join(" | "),
        "---|".repeat(methods.len())
    );
    let mut keys: Vec<(&str, usize)> = r
        .sweep
        .iter()
        .filter(|x| x.width == 1920)
        .map(|x| (x.view, x.lights))
        .collect();
    keys.dedup();
    for (view, n) in keys {
        let cells: Vec<String> = methods
            .iter()
            .map(|m| {
                r.sweep
                    .iter()
                    .find(|x| x.width == 1920 && x.view == view && x.lights == n && x.method == *m)
                    .map_or("—".into(), |x| format!("{:.3}", x.frame_ms.median_ms))
            })
            .collect();
        let _ = writeln!(s, "| Sponza {view} | {n} | {} |", cells.join(" | "));
    }
    // The thesis's setting, and the grazing view at 1920×1080.
    let whole = |x: &&TestRow| x.frustum_culling && (x.width == 1280) == (x.view == "thesis");
    let mut tests: Vec<(u32, &str, u32, u32, usize)> = r
        .tests
        .iter()
        .filter(whole)
        .map(|x| (x.test, x.view, x.width, x.height, x.lights_sent))
        .collect();
    tests.dedup();
    for (test, view, w, h, sent) in tests {
        let cells: Vec<String> = methods
            .iter()
            .map(|m| {
                r.tests
                    .iter()
                    .filter(whole)
                    .find(|x| x.test == test && x.view == view && x.method == *m)
                    .map_or("—".into(), |x| format!("{:.3}", x.frame_ms.median_ms))
            })
            .collect();
        let _ = writeln!(
            s,
            "| test {test} {view}, {w}×{h}, VFC | {sent} | {} |",
            cells.join(" | ")
        );
    }
}

/// How blended surfaces are drawn in [`transparency`]: (report name, light accumulation, how).
const BLENDS: [(&str, ShadingMethod, BlendedSurfaces); 4] = [
    (
        "tiled, dithered",
        ShadingMethod::Tiled,
        BlendedSurfaces::Dithered,
    ),
    (
        "tiled, blended forward",
        ShadingMethod::Tiled,
        BlendedSurfaces::Forward,
    ),
    (
        "forward+",
        ShadingMethod::ForwardPlus,
        BlendedSurfaces::Forward,
    ),
    (
        "light pre-pass, dithered",
        ShadingMethod::LightPrePass,
        BlendedSurfaces::Dithered,
    ),
];
/// The passes [`transparency`] reports one by one.
const TRANSPARENCY_PASSES: [&str; 6] = [
    "gbuffer",
    "light accumulation",
    "forward+ lists (blended)",
    "forward+ opaque",
    "light pre-pass materials",
    "forward+ blended",
];

#[derive(Serialize)]
struct TransparencyRow {
    method: &'static str,
    lights: usize,
    frame_ms: Stat,
    /// Median ms of each of [`TRANSPARENCY_PASSES`] that ran ("light accumulation" stands for
    /// the method's pass).
    passes: Vec<(String, f64)>,
}

#[derive(Serialize)]
struct TransparencyReport {
    header: bench::Header,
    frames: u32,
    scene: String,
    rows: Vec<TransparencyRow>,
}

/// Whole frames of the material gallery (one half-transparent sphere among opaque ones) at
/// 1920×1080 under its own lights and 4096 scattered ones, for each of [`BLENDS`].
fn transparency(gpu: &Gpu, args: &Args, frames: u32) -> Result<()> {
    let scene = scene::material_gallery();
    let camera = scene.camera_or_framed();
    let (w, h) = bench::size((1920, 1080));
    let mut rows = Vec::new();
    for count in [0, 4096] {
        let mut lights = scene.lights.clone();
        lights.extend(scene::scatter_point_lights(scene.bounds(), count, 1));
        let mut renderer = GpuRenderer::new(&gpu.device, &gpu.queue, &scene, &lights, w, h)?;
        for (method_name, method, blended) in BLENDS {
            renderer.set_blended(&gpu.device, &gpu.queue, BlendedSurfaces::Dithered)?;
            let config = ShadingConfig {
                method,
                ..Default::default()
            };
            renderer.set_shading(&gpu.device, &gpu.queue, &config)?;
            renderer.set_blended(&gpu.device, &gpu.queue, blended)?;
            let shading = renderer.shading().pass_name();
            let t = time_passes(gpu, &mut renderer, &camera, DEFAULT_AMBIENT, frames, None)?;
            let every: Vec<&str> = t.iter().map(|(n, _)| n.as_str()).collect();
            let frame_ms = Stat::of(per_frame_sum(&t, &every));
            let passes: Vec<(String, f64)> = TRANSPARENCY_PASSES
                .iter()
                .filter_map(|&p| {
                    let name = if p == "light accumulation" {
                        shading.as_str()
                    } else {
                        p
                    };
                    t.iter().any(|(n, _)| n == name).then(|| {
                        (
                            p.to_string(),
                            Stat::of(per_frame_sum(&t, &[name])).median_ms,
                        )
                    })
                })
                .collect();
            println!(
                "gallery {w}x{h} {:>5} lights {method_name:<26} frame {:>8.3} ms  {passes:?}",
                lights.len(),
                frame_ms.median_ms
            );
            rows.push(TransparencyRow {
                method: method_name,
                lights: lights.len(),
                frame_ms,
                passes,
            });
        }
    }
    let report = TransparencyReport {
        header: bench::Header::new(gpu),
        frames,
        scene: "scene::material_gallery".into(),
        rows,
    };
    args.common.options.write_report(
        &report.header,
        "tiled-transparency-",
        &report,
        &transparency_markdown(&report),
    )?;
    Ok(())
}

fn transparency_markdown(r: &TransparencyReport) -> String {
    use std::fmt::Write;
    let mut s = r.header.markdown(
        "Transparency: blended surfaces dithered or drawn forward (Forward+ lists)",
        r.frames,
    );
    let _ = writeln!(
        s,
        "`{}` at 1920×1080 (one alpha-BLEND sphere among opaque ones), whole frames and passes, \
         ms. `blended forward`: tiled deferred shading for the opaque surfaces, a Forward+ \
         culling pass for the blended ones' lists and their forward pass over the frame.\n\n\
         | lights | method | frame | {} |\n|---|---|---|{}",
        r.scene,
        TRANSPARENCY_PASSES.join(" | "),
        "---|".repeat(TRANSPARENCY_PASSES.len())
    );
    for row in &r.rows {
        let cells: Vec<String> = TRANSPARENCY_PASSES
            .iter()
            .map(|p| {
                row.passes
                    .iter()
                    .find(|(n, _)| n == p)
                    .map_or("—".into(), |(_, ms)| format!("{ms:.3}"))
            })
            .collect();
        let _ = writeln!(
            s,
            "| {} | {} | {:.3} | {} |",
            row.lights,
            row.method,
            row.frame_ms.median_ms,
            cells.join(" | ")
        );
    }
    s
}
