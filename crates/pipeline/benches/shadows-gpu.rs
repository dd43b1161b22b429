//! `shadows-gpu`: the cost of the direct lights' shadow maps (`docs/shadows.md`) in the
//! renderer's frame on Sponza at 1920×1080 — a sun with 4 cascades, 1 to 256 shadowed spot
//! lights (one view each), 1 to 42 shadowed point lights (six cube faces each, up to the 256
//! layers of `wgpu::Limits::default()`) — as the GPU time of the `shadow maps` pass (every view
//! rasterised) and of the light accumulation with the lookup, against the same light
//! accumulation without shadows measured in the same run. Then the same lights (16 to 256
//! spots, 8 to 256 points) with ManyLoD shadows instead (Holländer 2013 §3.6: one paraboloid
//! tile per spot, two per point light, 32² and 64², cut and splatted from 2^20 surfels each
//! frame): the crossover against rasterised maps. Writes `shadows-<adapter>-<date>` `.md` and
//! `.json` under `--out`.

mod common;

use anyhow::Result;
use bench::{Stat, per_frame_sum};
use clap::Parser;
use common::time_passes;
use glam::Vec3;
use pipeline::{DEFAULT_AMBIENT, gpu::GpuRenderer};
use scene::Light;
use serde::Serialize;
use tiled_shading::shadows::ShadowMapConfig;

/// Benchmarks shadow maps of suns, spot and point lights.
#[derive(Parser, Debug)]
struct Args {
    #[command(flatten)]
    common: bench::SceneArgs,
    /// Texels across every shadow view.
    #[arg(long, default_value_t = 1024)]
    resolution: u32,
}

const SIZE: (u32, u32) = (1920, 1080);
const SPOTS: [usize; 4] = [1, 16, 64, 256];
const POINTS: [usize; 3] = [1, 8, 42];
/// The ManyLoD rows: light kind and count.
const MANYLOD: [(&str, usize); 6] = [
    ("spot", 16),
    ("spot", 64),
    ("spot", 256),
    ("point", 8),
    ("point", 42),
    ("point", 256),
];
/// Tile sizes of the ManyLoD rows.
const TILES: [u32; 2] = [32, 64];

#[derive(Serialize)]
struct Row {
    lights: String,
    count: usize,
    /// `rasterised` (depth views of `--resolution`²) or `ManyLoD <tile>²`.
    method: String,
    views: usize,
    shadow_maps: Stat,
    shading_shadowed: Stat,
    shading_unshadowed: Stat,
    /// Triangles rasterised per second into the maps (views × scene triangles / time).
    triangles_per_s: Option<f64>,
}

#[derive(Serialize)]
struct Report {
    header: bench::Header,
    frames: u32,
    scene: String,
    width: u32,
    height: u32,
    resolution: u32,
    triangles: u64,
    rows: Vec<Row>,
}

/// `count` lights of `kind` through `bounds` (the scene's scattered point lights; spots
/// point down with a 40° cone).
fn lights(kind: &str, count: usize, bounds: scene::Aabb) -> Vec<Light> {
    if kind == "sun" {
        return vec!["dir:0.3,-1,0.25,1,0.95,0.85,3".parse().expect("sun")];
    }
    scene::scatter_point_lights(bounds, count, 7)
        .into_iter()
        .map(|l| match l {
            Light::Point {
                position,
                color,
                intensity,
                radius,
            } if kind == "spot" => Light::Spot {
                position,
                direction: Vec3::NEG_Y,
                color,
                intensity,
                radius,
                inner_angle: 30f32.to_radians(),
                outer_angle: 40f32.to_radians(),
            },
            other => other,
        })
        .collect()
}

fn main() -> Result<()> {
    let args = Args::parse_from(bench::args());
    let gpu = args.common.options.gpu()?;
    let frames = args.common.options.frames(10);
    let (path, scene, camera) = args.common.scene.load_viewed()?;
    let (w, h) = bench::size(SIZE);
    let resolution = if bench::run_once() {
        64
    } else {
        args.resolution
    };
    let config = ShadowMapConfig {
        resolution,
        ..ShadowMapConfig::default()
    };
    let once = bench::run_once();
    let mut configs = vec![("sun", 1)];
    configs.extend(
        SPOTS
            .iter()
            .take(if once { 1 } else { 4 })
            .map(|&n| ("spot", n)),
    );
    configs.extend(
        POINTS
            .iter()
            .take(if once { 1 } else { 3 })
            .map(|&n| ("point", n)),
    );
    println!(
        "scene: {} ({} triangles), {w}×{h}, shadow views {resolution}²",
        path.display(),
        scene.triangle_count()
    );
    let (d, q) = (&gpu.device, &gpu.queue);
    let mut rows = Vec::new();
    let mut runs: Vec<(&str, usize, Option<u32>)> =
        configs.into_iter().map(|(k, n)| (k, n, None)).collect();
    for tile in TILES.iter().take(if once { 1 } else { 2 }) {
        runs.extend(
            MANYLOD
                .iter()
                .take(if once { 1 } else { MANYLOD.len() })
                .map(|&(k, n)| (k, n, Some(*tile))),
        );
    }
    for (kind, count, tile) in runs {
        let set = lights(kind, count, scene.bounds());
        let mut renderer = GpuRenderer::new(d, q, &scene, &set, w, h)?;
        let shading = renderer.shading().pass_name();
        let plain = time_passes(&gpu, &mut renderer, &camera, DEFAULT_AMBIENT, frames, None)?;
        let (method, views, passes) = match tile {
            None => {
                renderer.set_shadows(d, q, Some(&config))?;
                let views = renderer.shadow_view_count();
                ("rasterised".to_string(), views, &["shadow maps"][..])
            }
            Some(tile) => {
                let manylod = instant_radiosity::shadows::ShadowConfig {
                    tile,
                    ..Default::default()
                };
                renderer.set_manylod_shadows(d, q, &scene, Some(&manylod))?;
                let per_light = if kind == "point" { 2 } else { 1 };
                (
                    format!("ManyLoD {tile}²"),
                    per_light * count,
                    &["cut", "splat"][..],
                )
            }
        };
        let shadowed = time_passes(&gpu, &mut renderer, &camera, DEFAULT_AMBIENT, frames, None)?;
        let maps = Stat::of(per_frame_sum(&shadowed, passes));
        let row = Row {
            lights: kind.into(),
            count,
            views,
            triangles_per_s: tile
                .is_none()
                .then(|| views as f64 * scene.triangle_count() as f64 / (maps.median_ms * 1e-3)),
            shadow_maps: maps,
            shading_shadowed: Stat::of(per_frame_sum(&shadowed, &[shading.as_str()])),
            shading_unshadowed: Stat::of(per_frame_sum(&plain, &[shading.as_str()])),
            method,
        };
        println!(
            "{count:>4} {kind:<5} {:<12} ({views:>3} views): shadow maps {:.3} ms, light accumulation {:.3} ms (unshadowed {:.3} ms)",
            row.method,
            row.shadow_maps.median_ms,
            row.shading_shadowed.median_ms,
            row.shading_unshadowed.median_ms
        );
        rows.push(row);
    }
    let report = Report {
        header: bench::Header::new(&gpu),
        frames,
        scene: path.display().to_string(),
        width: w,
        height: h,
        resolution,
        triangles: scene.triangle_count() as u64,
        rows,
    };
    args.common
        .options
        .write_report(&report.header, "shadows-", &report, &markdown(&report))?;
    Ok(())
}

fn markdown(r: &Report) -> String {
    let mut table = bench::Table::new(&[
        "lights",
        "method",
        "views",
        "shadow maps ms",
        "G scene triangles/s",
        "light accumulation ms, shadowed",
        "unshadowed",
        "shadows + shading ms",
    ]);
    for row in &r.rows {
        let (maps, shaded) = (&row.shadow_maps, &row.shading_shadowed);
        table.row([
            format!("{} {}", row.count, row.lights),
            row.method.clone(),
            row.views.to_string(),
            maps.to_string(),
            row.triangles_per_s
                .map_or("—".into(), |t| format!("{:.2}", t / 1e9)),
            shaded.to_string(),
            format!("{:.3}", row.shading_unshadowed.median_ms),
            format!("{:.3}", maps.median_ms + shaded.median_ms),
        ]);
    }
    format!(
        "{}\nScene `{}` ({} triangles), {}×{}, tiled light accumulation (16×16), rasterised views \
         {}² texels. `shadow maps` = the GPU time of rendering every view (rasterised: one depth \
         pass per view, the whole scene each, `G scene triangles/s` = views × scene triangles / \
         time; ManyLoD: the incremental cut and the splat of 2^20 surfels into paraboloid tiles, \
         ε 2 px, one tile per spot, two per point light); the light accumulation with the \
         lookup against the same pass without shadows in the same run. Medians (minimum) of \
         GPU timestamps.\n\n{table}",
        r.header.markdown(
            "Shadow maps of the direct lights (docs/shadows.md)",
            r.frames
        ),
        r.scene,
        r.triangles,
        r.width,
        r.height,
        r.resolution
    )
}
