//! `pbgi-bench`: point-based GI's gather through many-view cuts (Holländer 2013 §3.6.1,
//! Fig. 3.18: 4096 indirect-lighting views over 1 M points at 1024×1024 in 29 ms on a GTX 480)
//! on Sponza lit by a low sun. The receivers are the pixels of a 1024×1024 G-buffer on a
//! regular grid (32×32 or 64×64 of them: 1024 or 4096 views); the 2^20 surfels are lit on the
//! GPU every frame (shadow rays through the scene's BVH, then the nodes' means). Per
//! configuration (views, tile, ε): the lighting, the GPU cut, the splat with nearest nodes and
//! the convolution (`instant_radiosity::pbgi::GpuGather`), and their sum. Not measured here:
//! receivers from the GPU G-buffer and the upsampling (both per pixel or per receiver, timed
//! in the frame). Writes `pbgi-<adapter>-<date>.{md,json}`.

use anyhow::Result;
use bench::Stat;
use clap::Parser;
use glam::Vec3;
use gpu::PassTimer;
use instant_radiosity::pbgi::{GpuGather, LitPoints, PbgiConfig};
use serde::Serialize;
use tiled_shading::GpuLight;

/// Benchmarks point-based GI's gather.
#[derive(Parser, Debug)]
struct Args {
    #[command(flatten)]
    common: bench::SceneArgs,
}

#[derive(Serialize)]
struct Row {
    points: usize,
    views: usize,
    tile: u32,
    epsilon: f32,
    lighting: Option<Stat>,
    cut: Option<Stat>,
    splat: Option<Stat>,
    convolve: Option<Stat>,
    total: Stat,
    /// Node-views per list the cut needed (the capacity it ran with).
    capacity: usize,
}

#[derive(Serialize)]
struct Report {
    header: bench::Header,
    frames: u32,
    scene: String,
    triangles: usize,
    size: (u32, u32),
    lighting_cpu_ms: f64,
    rows: Vec<Row>,
}

/// Receivers of a `grid × grid` lattice of the G-buffer's pixels that show a surface.
fn receivers(
    gb: &gbuffer::GBuffer,
    frame: &gbuffer::Frame,
    (w, h): (u32, u32),
    grid: u32,
) -> Vec<(Vec3, Vec3)> {
    let mut out = Vec::new();
    for j in 0..grid {
        for i in 0..grid {
            let (x, y) = ((2 * i + 1) * w / (2 * grid), (2 * j + 1) * h / (2 * grid));
            let depth = gb.linear_depth.get(x, y);
            if depth > 0.0 {
                out.push((
                    gbuffer::position::from_view_ray(frame, x, y, depth),
                    gbuffer::normal::unpack_octahedral(gb.normal.get(x, y)),
                ));
            }
        }
    }
    out
}

/// A gather that holds its cut: the capacity doubled from one node-view per texel until the
/// cut fits (or the device's largest list).
fn gather(
    gpu: &gpu::Gpu,
    (scene, lights): (&scene::Scene, &[GpuLight]),
    lit: &LitPoints,
    points: &[(Vec3, Vec3)],
) -> Result<(GpuGather, usize)> {
    let largest = manylod::gpu::largest_capacity(&gpu.device);
    let tile = lit.config().tile as usize;
    let mut capacity = (points.len() * tile * tile).min(largest);
    loop {
        let mut g = GpuGather::new(&gpu.device, lit, points, capacity)?;
        g.light_on_gpu(&gpu.device, scene, lit, lights)?;
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        g.encode(&mut encoder, None);
        gpu.queue.submit([encoder.finish()]);
        match g.read_irradiance(&gpu.device, &gpu.queue) {
            Err(instant_radiosity::IndirectError::ManyLod(manylod::ManyLodError::Capacity {
                ..
            })) if capacity < largest => capacity = (2 * capacity).min(largest),
            r => {
                r?;
                return Ok((g, capacity));
            }
        }
    }
}

fn main() -> Result<()> {
    let args = Args::parse_from(bench::args());
    let gpu = args.common.options.gpu()?;
    let frames = args.common.options.frames(20);
    let (path, scene, camera) = args.common.scene.load_viewed()?;
    let size = bench::size((1024, 1024));
    let shrink = if bench::run_once() { 64 } else { 1 };
    let points = (1usize << 20) / shrink;
    let sun = scene::Light::Directional {
        direction: Vec3::new(0.4, -1.0, 0.3).normalize(),
        color: Vec3::new(1.0, 0.95, 0.85),
        intensity: 4.0,
    };
    let lights = [GpuLight::from(&sun)];
    let start = std::time::Instant::now();
    let lit = LitPoints::new(
        &scene,
        &lights,
        &PbgiConfig {
            points_log2: points.ilog2(),
            ..PbgiConfig::default()
        },
    )?;
    let lighting_cpu_ms = start.elapsed().as_secs_f64() * 1e3;
    println!("{points} surfels lit on the CPU in {lighting_cpu_ms:.0} ms");
    let gb = gbuffer::cpu::rasterize(&scene, &camera, size.0, size.1)?.gbuffer;
    let frame = gbuffer::Frame::new(&camera, size.0, size.1);
    let timer = PassTimer::new(&gpu.device, 8);
    let mut rows = Vec::new();
    let grids: &[u32] = if bench::run_once() { &[8] } else { &[32, 64] };
    for &grid in grids {
        let points_of_views = receivers(&gb, &frame, size, grid);
        for (tile, epsilon) in [(32u32, 1.0f32), (16, 2.0), (16, 4.0)] {
            let config = PbgiConfig {
                tile,
                epsilon,
                points_log2: points.ilog2(),
            };
            let lit = lit.reconfigured(config)?;
            let (mut g, capacity) = gather(&gpu, (&scene, &lights), &lit, &points_of_views)?;
            let by_name = bench::time_recorded(&gpu, &timer, frames, |e, t| g.encode(e, Some(t)))?;
            let total = Stat::of(bench::per_frame_sum(
                &by_name,
                &["pbgi lighting", "cut", "splat", "pbgi convolve"],
            ));
            println!(
                "{} views, tile {tile}, ε {epsilon}: {:.3} ms",
                points_of_views.len(),
                total.median_ms
            );
            rows.push(Row {
                points,
                views: points_of_views.len(),
                tile,
                epsilon,
                lighting: bench::pass_stat(&by_name, "pbgi lighting"),
                cut: bench::pass_stat(&by_name, "cut"),
                splat: bench::pass_stat(&by_name, "splat"),
                convolve: bench::pass_stat(&by_name, "pbgi convolve"),
                total,
                capacity,
            });
        }
    }

    let header = bench::Header::new(&gpu);
    let mut md = header.markdown(
        "Point-based GI's gather through many-view cuts (Holländer 2013 §3.6.1)",
        frames,
    );
    md.push_str(&format!(
        "\nScene: {} ({} triangles), {}×{} G-buffer, receivers on a regular grid of its \
         pixels; {points} surfels lit by a low sun on the GPU every frame (shadow rays through \
         the scene's BVH, then the nodes' means; the CPU reference took {lighting_cpu_ms:.0} ms). \
         Each receiver: a paraboloid view of `tile`² texels, the basic cut at ε texels, the splat \
         with nearest nodes, the convolution. Paper (Fig. 3.18, GTX 480): 4096 views, 1 M points, \
         29 ms; target here: ≤ 5 ms.\n\n\
         | views | tile | ε | lighting ms | cut ms | splat ms | convolve ms | total ms (median) |\n\
         |---:|---:|---:|---:|---:|---:|---:|---:|\n",
        path.display(),
        scene.triangle_count(),
        size.0,
        size.1
    ));
    let ms = |s: &Option<Stat>| {
        s.as_ref()
            .map_or("–".into(), |s| format!("{:.3}", s.median_ms))
    };
    for r in &rows {
        md.push_str(&format!(
            "| {} | {} | {} | {} | {} | {} | {} | {:.3} |\n",
            r.views,
            r.tile,
            r.epsilon,
            ms(&r.lighting),
            ms(&r.cut),
            ms(&r.splat),
            ms(&r.convolve),
            r.total.median_ms
        ));
    }
    let report = Report {
        header: header.clone(),
        frames,
        scene: path.display().to_string(),
        triangles: scene.triangle_count(),
        size,
        lighting_cpu_ms,
        rows,
    };
    args.common
        .options
        .write_report(&header, "pbgi-", &report, &md)
}
