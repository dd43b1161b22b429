//! `deferred-bench`: GPU benchmarks of the toolkit, timed with timestamp queries, written as
//! Markdown + JSON reports named by adapter and date.
//!
//! Benchmark 1, G-buffer creation (Ishmukhametov 2013 §1.3 step 2): the MRT pass on a scene
//! (default: Dabrovic Sponza from ../shared/fixtures) at 1920×1080 and 3840×2160. Baselines
//! measured in the same run: a pass that only clears and stores the same six targets (the
//! pass's unavoidable write traffic), and a buffer-to-buffer copy of as many bytes.

use anyhow::{Context, Result, bail};
use bench::{Header, Stat};
use clap::Parser;
use gbuffer::{
    Frame,
    gpu::{GBufferPass, GBufferTargets, GpuScene},
};
use glam::Vec3;
use gpu::{Gpu, PassTimer};
use scene::{Camera, Scene};
use serde::Serialize;

/// GPU benchmarks; writes docs/bench/<adapter>-<date>.{md,json}.
#[derive(Parser, Debug)]
#[command(version, about)]
struct Args {
    #[command(flatten)]
    common: bench::SceneArgs,
}

#[derive(Serialize)]
struct GBufferResult {
    width: u32,
    height: u32,
    gbuffer: Stat,
    /// Z-prepass plus the G-buffer pass with depth test Equal (begin of one to end of the other).
    gbuffer_with_prepass: Stat,
    /// Single pass time / prepass path time (> 1: the prepass path is faster).
    prepass_speedup: f64,
    clear_baseline: Stat,
    copy_baseline: Stat,
    ratio_to_clear: f64,
    ratio_to_copy: f64,
    gbuffer_bytes: u64,
    triangles_per_second_millions: f64,
    pixels_per_second_billions: f64,
}

#[derive(Serialize)]
struct Report {
    #[serde(flatten)]
    header: Header,
    scene: String,
    triangles: u64,
    camera: String,
    frames: u32,
    gbuffer: Vec<GBufferResult>,
}

fn bench_gbuffer(
    gpu: &Gpu,
    scene: &Scene,
    gpu_scene: &GpuScene,
    pass: &GBufferPass,
    camera: &Camera,
    (w, h): (u32, u32),
    frames: u32,
) -> Result<GBufferResult> {
    let device = &gpu.device;
    let targets = GBufferTargets::new(device, w, h)?;
    pass.write_frame(&gpu.queue, &Frame::new(camera, w, h));
    let bytes = targets.bytes();
    let copy = |label| {
        device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size: bytes,
            usage: wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        })
    };
    let (src, dst) = (copy("copy src"), copy("copy dst"));
    let timer = PassTimer::new(device, 6);
    let (mut g, mut c, mut k, mut z) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let measured = bench::warm_then_time(frames, || -> Result<Vec<gpu::PassTime>> {
        let mut encoder = device.create_command_encoder(&Default::default());
        GBufferPass::encode_clear(&mut encoder, &targets, timer.render_pass("clear"));
        pass.encode(
            &mut encoder,
            gpu_scene,
            &targets,
            timer.render_pass("gbuffer"),
        );
        // A compute pass around the copy gives it timestamps without TIMESTAMP_QUERY_INSIDE_ENCODERS.
        drop(encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("copy start"),
            timestamp_writes: timer.compute_pass("copy"),
        }));
        encoder.copy_buffer_to_buffer(&src, 0, &dst, 0, bytes);
        drop(encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("copy end"),
            timestamp_writes: timer.compute_pass("copy end"),
        }));
        pass.encode_with_prepass(
            &mut encoder,
            gpu_scene,
            &targets,
            timer.render_pass("z-prepass"),
            timer.render_pass("gbuffer after prepass"),
        );
        timer.resolve(&mut encoder);
        gpu.queue.submit([encoder.finish()]);
        let t = timer.read(&gpu.device, &gpu.queue)?;
        if t.len() != 6 {
            bail!("the adapter has no timestamp queries; nothing to measure");
        }
        Ok(t)
    })?;
    for t in measured {
        c.push(t[0].ms);
        g.push(t[1].ms);
        // From the begin of the marker pass before the copy to the end of the one after it.
        k.push(t[3].end_ms() - t[2].start_ms);
        z.push(t[5].end_ms() - t[4].start_ms);
    }
    let (g, c, k, z) = (Stat::of(g), Stat::of(c), Stat::of(k), Stat::of(z));
    Ok(GBufferResult {
        width: w,
        height: h,
        prepass_speedup: g.median_ms / z.median_ms,
        gbuffer_with_prepass: z,
        ratio_to_clear: g.median_ms / c.median_ms,
        ratio_to_copy: g.median_ms / k.median_ms,
        gbuffer_bytes: bytes,
        triangles_per_second_millions: scene.triangle_count() as f64 / g.median_ms * 1e-3,
        pixels_per_second_billions: f64::from(w * h) / g.median_ms * 1e-6,
        gbuffer: g,
        clear_baseline: c,
        copy_baseline: k,
    })
}

fn main() -> Result<()> {
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or("warn")).init();
    let args = Args::parse_from(bench::args());
    let gpu = args.common.options.gpu()?;
    let frames = args.common.options.frames(100);
    let (path, scene) = args.common.scene.load()?;
    // Inside the atrium, along its long axis, looking at the far arcades.
    let camera = Camera {
        eye: Vec3::new(-13.0, 2.0, 0.0),
        target: Vec3::new(10.0, 5.0, 0.0),
        up: Vec3::Y,
        fov_y: 60f32.to_radians(),
        near: 0.1,
        far: 60.0,
    };
    let pass = GBufferPass::new(&gpu.device)?;
    let gpu_scene = GpuScene::upload(&gpu.device, &gpu.queue, &scene, &pass)?;
    let mut results = Vec::new();
    for size in [(1920, 1080), (3840, 2160)].map(bench::size) {
        let r = bench_gbuffer(&gpu, &scene, &gpu_scene, &pass, &camera, size, frames)?;
        println!(
            "gbuffer {}x{}: {:.3} ms (min {:.3}); clear {:.3} ms; copy {:.3} ms; ×{:.2} clear, ×{:.2} copy; z-prepass path {:.3} ms (×{:.2})",
            r.width,
            r.height,
            r.gbuffer.median_ms,
            r.gbuffer.min_ms,
            r.clear_baseline.median_ms,
            r.copy_baseline.median_ms,
            r.ratio_to_clear,
            r.ratio_to_copy,
            r.gbuffer_with_prepass.median_ms,
            r.prepass_speedup
        );
        results.push(r);
    }
    let report = Report {
        header: Header::new(&gpu),
        scene: path
            .file_name()
            .map_or("scene".into(), |f| f.to_string_lossy().into_owned()),
        triangles: scene.triangle_count() as u64,
        camera: format!(
            "eye {:?}, target {:?}, fov_y 60°",
            camera.eye.to_array(),
            camera.target.to_array()
        ),
        frames: frames,
        gbuffer: results,
    };
    write_report(&bench::out_dir(&args.common.options.out), &report)
}

fn write_report(dir: &std::path::Path, r: &Report) -> Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    let base = dir.join(r.header.file_stem(""));
    std::fs::write(
        base.with_extension("json"),
        serde_json::to_string_pretty(r)?,
    )?;
    let mut md = r.header.markdown("Benchmarks", r.frames);
    md.push_str(&format!(
        "## G-buffer creation (MRT render pass)\n\nScene: `{}`, {} triangles; camera {}.\nTargets: depth32f + r32f linear depth + r32u normal + rgba8 albedo + r32u material + rgba16f emission = 28 bytes/pixel.\nBaselines in the same run: a pass that only clears and stores the six targets, and a buffer copy of the same number of bytes.\n\n",
        r.scene, r.triangles, r.camera
    ));
    md.push_str("| size | G-buffer ms (min) | clear-only ms | copy ms | × clear | × copy | Mtri/s | Gpix/s | z-prepass + G-buffer ms (min) | speed-up |\n|---|---|---|---|---|---|---|---|---|---|\n");
    for g in &r.gbuffer {
        md.push_str(&format!(
            "| {}×{} | {:.3} ({:.3}) | {:.3} | {:.3} | {:.2} | {:.2} | {:.0} | {:.2} | {:.3} ({:.3}) | {:.2} |\n",
            g.width,
            g.height,
            g.gbuffer.median_ms,
            g.gbuffer.min_ms,
            g.clear_baseline.median_ms,
            g.copy_baseline.median_ms,
            g.ratio_to_clear,
            g.ratio_to_copy,
            g.triangles_per_second_millions,
            g.pixels_per_second_billions,
            g.gbuffer_with_prepass.median_ms,
            g.gbuffer_with_prepass.min_ms,
            g.prepass_speedup
        ));
    }
    std::fs::write(base.with_extension("md"), md)?;
    println!("wrote {}.{{md,json}}", base.display());
    Ok(())
}
