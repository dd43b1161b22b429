//! `reflections-bench`: reflection maps through many-view cuts (Holländer 2013 §3.6.1,
//! Fig. 3.19: 400 reflecting objects, 2 M polygons, 2 M points, every object's map in 40 ms on
//! a GTX 480). `scene::mirror_spheres(400)` — 400 mirror and glass spheres in the Cornell box — sampled
//! into 2^21 surfels lit by the room's light; every sphere's dual-paraboloid map (two views of
//! `tile²` texels) by the probes' cut, the splat with nearest nodes and the maps' resolve
//! (`instant_radiosity::reflections::GpuReflections`), per tile and ε. Baseline in the same
//! run: rasterising the whole scene into every sphere's cube map (6 faces of 64², the
//! G-buffer pass after a z-prepass, near plane past the sphere) — what the maps replace.
//! Writes `reflections-<adapter>-<date>.{md,json}`.

use anyhow::Result;
use bench::Stat;
use clap::Parser;
use gbuffer::{
    Frame,
    gpu::{GBufferPass, GBufferTargets, GpuScene},
};
use glam::Vec3;
use gpu::{Gpu, PassTimer};
use instant_radiosity::pbgi::{LitPoints, PbgiConfig};
use instant_radiosity::reflections::{GpuReflections, Probes};
use scene::{Camera, Scene};
use serde::Serialize;
use tiled_shading::GpuLight;

/// Benchmarks reflection maps.
#[derive(Parser, Debug)]
struct Args {
    #[command(flatten)]
    options: bench::Options,
}

#[derive(Serialize)]
struct Row {
    tile: u32,
    epsilon: f32,
    cut: Stat,
    splat: Stat,
    resolve: Stat,
    total: Stat,
    /// Node-views per cut list the maps needed.
    capacity: usize,
}

#[derive(Serialize)]
struct Report {
    header: bench::Header,
    frames: u32,
    objects: usize,
    triangles: usize,
    points: usize,
    lighting_cpu_ms: f64,
    /// Rasterising the scene into every object's cube map (6 faces of 64²), scaled from
    /// `raster_measured_objects`' maps.
    raster_cube_maps: Stat,
    raster_measured_objects: usize,
    rows: Vec<Row>,
}

/// The maps with lists that hold their cut: the capacity doubled from one node-view per
/// texel until it fits (or the device's largest list).
fn reflections(
    gpu: &Gpu,
    lit: &LitPoints,
    radiance: &wgpu::Buffer,
    probes: &Probes,
    tile: u32,
) -> Result<(GpuReflections, usize)> {
    let largest = manylod::gpu::largest_capacity(&gpu.device);
    let mut capacity = (probes.len() * 2 * (tile * tile) as usize).min(largest);
    loop {
        let mut r = GpuReflections::new(&gpu.device, lit, radiance, (probes, tile), capacity)?;
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        r.encode(&mut encoder, None);
        gpu.queue.submit([encoder.finish()]);
        match r.check(&gpu.device, &gpu.queue) {
            Err(instant_radiosity::IndirectError::ManyLod(manylod::ManyLodError::Capacity {
                ..
            })) if capacity < largest => capacity = (2 * capacity).min(largest),
            c => {
                c?;
                return Ok((r, capacity));
            }
        }
    }
}

/// The six 90° cameras of a cube map at `center`, the near plane just past `radius`.
fn cube_faces(center: Vec3, radius: f32, far: f32) -> [Camera; 6] {
    [
        (Vec3::X, Vec3::NEG_Y),
        (Vec3::NEG_X, Vec3::NEG_Y),
        (Vec3::Y, Vec3::Z),
        (Vec3::NEG_Y, Vec3::NEG_Z),
        (Vec3::Z, Vec3::NEG_Y),
        (Vec3::NEG_Z, Vec3::NEG_Y),
    ]
    .map(|(dir, up)| Camera {
        eye: center,
        target: center + dir,
        up,
        fov_y: 90f32.to_radians(),
        near: radius * 1.01,
        far,
    })
}

/// GPU ms of rasterising `scene` into every probe's cube map (the G-buffer pass after a
/// z-prepass per face, one 64² target), from the first face's begin to the last one's end.
fn raster_cube_maps(gpu: &Gpu, scene: &Scene, probes: &[(Vec3, f32)], frames: u32) -> Result<Stat> {
    let pass = GBufferPass::new(&gpu.device)?;
    let gpu_scene = GpuScene::upload(&gpu.device, &gpu.queue, scene, &pass)?;
    let targets = GBufferTargets::new(&gpu.device, 64, 64)?;
    let far = scene.bounds().diagonal();
    let faces: Vec<_> = probes
        .iter()
        .flat_map(|&(c, r)| cube_faces(c, r, far))
        .map(|camera| {
            let uniform = pass.frame_uniform(&gpu.device);
            uniform.write(&gpu.queue, &Frame::new(&camera, 64, 64));
            uniform
        })
        .collect();
    let timer = PassTimer::new(&gpu.device, 2);
    Ok(bench::time_encoded(gpu, &timer, frames, true, &|e, t| {
        drop(e.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("cube maps begin"),
            timestamp_writes: t.compute_pass("cube maps begin"),
        }));
        for f in &faces {
            pass.encode_with_prepass_at(e, f, &gpu_scene, &targets, (None, None));
        }
        drop(e.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("cube maps end"),
            timestamp_writes: t.compute_pass("cube maps end"),
        }));
    })?)
}

/// The statistics of pass `name`, which must have run.
fn stat(by_name: &[(String, Vec<f64>)], name: &str) -> Result<Stat> {
    bench::pass_stat(by_name, name).ok_or_else(|| anyhow::anyhow!("no timings of {name}"))
}

fn main() -> Result<()> {
    let args = Args::parse_from(bench::args());
    let gpu = args.options.gpu()?;
    let frames = args.options.frames(10);
    let once = bench::run_once();
    let objects = if once { 8 } else { 400 };
    let scene = scene::mirror_spheres(objects);
    let points_log2 = if once { 14 } else { 21 };
    let (lights, _, _) = instant_radiosity::vpl::primary_lights_sampled(&scene, 16);
    let lights: Vec<GpuLight> = lights.iter().map(GpuLight::from).collect();
    let start = std::time::Instant::now();
    let config = PbgiConfig {
        points_log2,
        tile: 64,
        epsilon: 1.0,
    };
    let lit = LitPoints::new(&scene, &lights, &config)?;
    let lighting_cpu_ms = start.elapsed().as_secs_f64() * 1e3;
    let probes = Probes::of_scene(&scene);
    println!(
        "{} objects, {} triangles, 2^{points_log2} surfels lit in {lighting_cpu_ms:.0} ms (CPU)",
        probes.len(),
        scene.triangle_count()
    );
    let radiance: Vec<[f32; 4]> = lit
        .radiance
        .iter()
        .map(|r| r.extend(0.0).to_array())
        .collect();
    let radiance = gpu::transfer::buffer_init(
        &gpu.device,
        "radiance",
        bytemuck::cast_slice(&radiance),
        wgpu::BufferUsages::STORAGE,
    )?;
    let timer = PassTimer::new(&gpu.device, 4);
    let mut rows = Vec::new();
    for (tile, epsilon) in [(64u32, 1.0f32), (64, 2.0), (32, 1.0)] {
        let lit = lit.reconfigured(PbgiConfig {
            tile,
            epsilon,
            points_log2,
        })?;
        let (mut r, capacity) = reflections(&gpu, &lit, &radiance, &probes, tile)?;
        let by_name = bench::time_recorded(&gpu, &timer, frames, |e, t| r.encode(e, Some(t)))?;
        let total = Stat::of(bench::per_frame_sum(
            &by_name,
            &["cut", "splat", "reflection maps"],
        ));
        println!(
            "{} maps of 2×{tile}², ε {epsilon}: {:.3} ms",
            probes.len(),
            total.median_ms
        );
        rows.push(Row {
            tile,
            epsilon,
            cut: stat(&by_name, "cut")?,
            splat: stat(&by_name, "splat")?,
            resolve: stat(&by_name, "reflection maps")?,
            total,
            capacity,
        });
    }
    let spheres: Vec<(Vec3, f32)> = probes
        .centers
        .iter()
        .map(|&c| {
            let radius = scene
                .meshes
                .iter()
                .filter(|m| m.name.starts_with("sphere"))
                .filter_map(|m| m.positions.first())
                .map(|p| p.distance(c))
                .fold(f32::INFINITY, f32::min);
            (c, radius)
        })
        .collect();
    // Every probe's faces are passes of their own, so the cost is linear in the probes: a
    // tenth of them is measured and the time scaled (a frame of all 2400 faces takes seconds).
    let measured = spheres.len().div_ceil(10);
    let tenth = raster_cube_maps(&gpu, &scene, &spheres[..measured], frames)?;
    let scale = spheres.len() as f64 / measured as f64;
    let raster = Stat {
        median_ms: tenth.median_ms * scale,
        min_ms: tenth.min_ms * scale,
    };
    println!(
        "rasterising the scene into {measured} cube maps of 6 × 64²: {:.3} ms, ×{scale} = {:.3} ms",
        tenth.median_ms, raster.median_ms
    );

    let header = bench::Header::new(&gpu);
    let mut md = header.markdown(
        "Reflection maps through many-view cuts (Holländer 2013 §3.6.1, Fig. 3.19)",
        frames,
    );
    md.push_str(&format!(
        "\n`scene::mirror_spheres({objects})`: {} mirror and glass spheres in the Cornell box ({} \
         triangles), 2^{points_log2} surfels lit by the room's light (on the CPU, \
         {lighting_cpu_ms:.0} ms; not timed). Per sphere a dual-paraboloid map (two views of \
         tile² texels): the probes' basic cut, the splat with nearest nodes, the maps' resolve. \
         Baseline: the G-buffer pass after a z-prepass of the whole scene into every sphere's \
         cube map (6 faces of 64²): **{:.3} ms** (measured for {measured} spheres, {:.3} ms, \
         and scaled: each face is a pass of its own). Paper (GTX 480): 400 objects, 2 M points, \
         40 ms; target here ≤ 5 ms for 400 maps of 64².\n\n\
         | tile | ε | cut ms | splat ms | resolve ms | total ms | × cube-map raster |\n\
         |---:|---:|---:|---:|---:|---:|---:|\n",
        probes.len(),
        scene.triangle_count(),
        raster.median_ms,
        tenth.median_ms
    ));
    for r in &rows {
        md.push_str(&format!(
            "| 2×{}² | {} | {:.3} | {:.3} | {:.3} | {:.3} | {:.1} |\n",
            r.tile,
            r.epsilon,
            r.cut.median_ms,
            r.splat.median_ms,
            r.resolve.median_ms,
            r.total.median_ms,
            raster.median_ms / r.total.median_ms
        ));
    }
    let report = Report {
        header: header.clone(),
        frames,
        objects: probes.len(),
        triangles: scene.triangle_count(),
        points: 1 << points_log2,
        lighting_cpu_ms,
        raster_cube_maps: raster,
        raster_measured_objects: measured,
        rows,
    };
    args.options
        .write_report(&header, "reflections-", &report, &md)
}
