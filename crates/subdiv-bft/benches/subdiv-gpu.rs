//! `subdiv-bench`: Loop subdivision with basis-function tables (Holländer 2013 §2.3, Table 2.1)
//! on the meshes of `../shared/fixtures` (fandisk, spot, the Stanford bunny), surface levels
//! 2–5 (bunny 2–4): GPU time of the initial step (computational entries, M⁰ → M¹ positions and
//! normals) and of the main step (every patch from the level-5 tables), fine vertices/s and
//! triangles/s, against a baseline measured in the same run: clearing the same output bytes
//! (the write bandwidth the evaluation cannot beat). Adaptive tessellation: screen-space factors
//! for a camera framing the mesh at 1920×1080 (fine edges of 1–4 pixels, up to level 6), the
//! metric and the adaptive main step, against the uniform level 6 in the same run. Writes
//! `subdiv-bft-<adapter>-<date>.{md,json}`.

use anyhow::{Context, Result};
use bench::Stat;
use clap::Parser;
use gpu::{Gpu, PassTimer};
use serde::Serialize;
use subdiv_bft::{
    BftSet, DEFAULT_LEVEL, MAX_VALENCE, Subdivider, gpu::GpuSubdivider, obj::ObjMesh,
};

/// Benchmarks GPU Loop subdivision with basis-function tables.
#[derive(Parser, Debug)]
struct Args {
    #[command(flatten)]
    options: bench::Options,
}

#[derive(Serialize)]
struct Row {
    mesh: String,
    input_triangles: usize,
    level: u32,
    triangles: usize,
    vertices: usize,
    /// Patches per workgroup of the main step (`subdiv_bft::gpu::patch_slots`).
    patches_per_workgroup: u32,
    initial: Stat,
    evaluate: Stat,
    clear_baseline: Stat,
    /// Fine vertices per second of the main step (median).
    vertices_per_s: f64,
    /// Fine vertices per second of both steps.
    vertices_per_s_total: f64,
    /// Triangles per second of both steps.
    triangles_per_s_total: f64,
}

#[derive(Serialize)]
struct AdaptiveRow {
    mesh: String,
    /// Target fine edge length in pixels.
    target_pixels: f32,
    max_level: u32,
    /// Triangles written (collapsed ones included) and drawn (without them).
    triangles_written: usize,
    triangles_drawn: usize,
    factors: Stat,
    evaluate: Stat,
    /// The uniform main step at `max_level`, same run.
    uniform_max: Stat,
    uniform_max_triangles: usize,
}

#[derive(Serialize)]
struct Report {
    header: bench::Header,
    frames: u32,
    table_level: u32,
    table_megabytes: f64,
    tables: usize,
    rows: Vec<Row>,
    adaptive: Vec<AdaptiveRow>,
}

fn main() -> Result<()> {
    let args = Args::parse_from(bench::args());
    let gpu = args.options.gpu()?;
    let frames = args.options.frames(20);
    let fixtures = scene::shared_fixtures().context("../shared/fixtures not found")?;
    let bft = BftSet::cached(
        &BftSet::default_path(DEFAULT_LEVEL, MAX_VALENCE),
        DEFAULT_LEVEL,
        MAX_VALENCE,
    )?;
    let timer = PassTimer::new(&gpu.device, 8);
    let mut rows = Vec::new();
    let mut adaptive = Vec::new();
    // Run-once mode (a test, not a measurement) stops at level 2.
    let top = |level: u32| if bench::run_once() { 2 } else { level };
    for (name, file, levels) in [
        ("fandisk", "subdiv/fandisk.obj", 2..=top(5)),
        ("spot", "subdiv/spot/spot_triangulated.obj", 2..=top(5)),
        ("bunny", "stanford/stanford-bunny.obj", 2..=top(4)),
    ] {
        let mesh = ObjMesh::read(&fixtures.join(file))?.into_mesh()?;
        let sub = Subdivider::new(&mesh.topology, &bft)?;
        let g = GpuSubdivider::new(&gpu.device, &sub, &bft)?;
        g.set_positions(&gpu.queue, &mesh.positions_f32())?;
        let first_row = rows.len();
        for level in levels {
            let out = g.level(&gpu.device, &sub, level)?;
            let initial = bench::time_encoded(&gpu, &timer, frames, false, &|e, t| {
                g.encode_initial(e, Some(t));
            })?;
            let evaluate = bench::time_encoded(&gpu, &timer, frames, false, &|e, t| {
                g.encode_evaluate(e, &out, Some(t));
            })?;
            let clear_baseline = bench::time_encoded(&gpu, &timer, frames, true, &|e, t| {
                let pass = e.begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some("start"),
                    timestamp_writes: t.compute_pass("clear"),
                });
                drop(pass);
                e.clear_buffer(&out.positions, 0, None);
                e.clear_buffer(&out.normals, 0, None);
                let pass = e.begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some("end"),
                    timestamp_writes: t.compute_pass("clear end"),
                });
                drop(pass);
            })?;
            let vertices = out.vertex_count as usize;
            let triangles = out.index_count as usize / 3;
            let per_s = |ms: f64, n: usize| n as f64 / (ms * 1e-3);
            let total = initial.median_ms + evaluate.median_ms;
            println!(
                "{name} level {level}: {triangles} triangles, initial {:.3} ms, evaluate {:.3} ms, clear {:.3} ms, {:.2} G vertices/s",
                initial.median_ms,
                evaluate.median_ms,
                clear_baseline.median_ms,
                per_s(evaluate.median_ms, vertices) / 1e9
            );
            rows.push(Row {
                mesh: name.into(),
                input_triangles: mesh.topology.triangles.len(),
                level,
                triangles,
                vertices,
                patches_per_workgroup: subdiv_bft::gpu::patch_slots(out.segments),
                vertices_per_s: per_s(evaluate.median_ms, vertices),
                vertices_per_s_total: per_s(total, vertices),
                triangles_per_s_total: per_s(total, triangles),
                initial,
                evaluate,
                clear_baseline,
            });
        }
        // Along the levels of this mesh, by vertex count (the main step is linear in it).
        bench::remeasure_outliers(
            &mut rows[first_row..],
            |r: &Row| ((), r.vertices as f64),
            |r| r.evaluate.median_ms,
            |r| format!("{name} level {} main step", r.level),
            |r| -> Result<()> {
                let out = g.level(&gpu.device, &sub, r.level)?;
                r.evaluate = bench::time_encoded(&gpu, &timer, frames, false, &|e, t| {
                    g.encode_evaluate(e, &out, Some(t));
                })?;
                let per_s = |ms: f64| r.vertices as f64 / (ms * 1e-3);
                r.vertices_per_s = per_s(r.evaluate.median_ms);
                r.vertices_per_s_total = per_s(r.initial.median_ms + r.evaluate.median_ms);
                r.triangles_per_s_total =
                    r.vertices_per_s_total * r.triangles as f64 / r.vertices as f64;
                Ok(())
            },
        )?;
        if name != "bunny" {
            adaptive.extend(bench_adaptive(&gpu, &timer, frames, name, &mesh, &sub, &g)?);
        }
    }
    let header = bench::Header::new(&gpu);
    let mut md = header.markdown(
        "Loop subdivision with basis-function tables (Holländer 2013 §2.3)",
        frames,
    );
    md.push_str(&format!(
        "\nTables: level {} ({}×{} segments per M¹ patch), {} configurations, {:.2} MB. GPU times \
         (median of {} frames, timestamp queries): initial step = computational entries M⁰ → M¹ \
         (positions, then tangent-mask normals); main step = every fine vertex (position + \
         Subdivision Shading normal, vec4 f32 each) from the tables. Vertices are shared (each \
         evaluated once). Baseline: clearing the same two output buffers (write bandwidth), same run. \
         The paper (Table 2.1, GTX 295): BigGuy level 5, 2.97 M triangles at 21 fps; Dupuy & \
         Vanhoey 2021: 2.9 M faces in under 3 ms on an RTX 2080.\n\n",
        bft.level,
        bft.segments(),
        bft.segments(),
        bft.tables.len(),
        bft.weight_bytes() as f64 / 1e6,
        frames
    ));
    let ms = |s: &Stat| format!("{:.3}", s.median_ms);
    let mut uniform = bench::Table::new(&[
        "mesh",
        "input tri",
        "level",
        "triangles",
        "vertices",
        "initial ms",
        "patches per workgroup",
        "main ms",
        "clear ms",
        "main ÷ clear",
        "G vertices/s (main)",
        "G vertices/s (both)",
        "G triangles/s (both)",
    ]);
    for r in &rows {
        uniform.row([
            r.mesh.clone(),
            r.input_triangles.to_string(),
            r.level.to_string(),
            r.triangles.to_string(),
            r.vertices.to_string(),
            ms(&r.initial),
            r.patches_per_workgroup.to_string(),
            ms(&r.evaluate),
            ms(&r.clear_baseline),
            format!("{:.2}", r.evaluate.median_ms / r.clear_baseline.median_ms),
            format!("{:.2}", r.vertices_per_s / 1e9),
            format!("{:.2}", r.vertices_per_s_total / 1e9),
            format!("{:.2}", r.triangles_per_s_total / 1e9),
        ]);
    }
    md.push_str(&uniform.to_string());
    md.push_str(
        "## Adaptive tessellation\n\nScreen-space factors (each M¹ edge split so its fine edges \
         are about the target length on a 1920×1080 image of a camera framing the mesh), up to \
         level 6 (32 segments per M¹ edge); metric pass and adaptive main step (vertices with \
         geomorph, triangles appended to an indirect draw), against the uniform level-6 main step \
         measured in the same run.\n\n",
    );
    let mut tessellation = bench::Table::new(&[
        "mesh",
        "target px",
        "triangles drawn",
        "written",
        "metric ms",
        "adaptive main ms",
        "uniform level 6 ms (triangles)",
        "adaptive ÷ uniform",
    ]);
    for r in &adaptive {
        tessellation.row([
            r.mesh.clone(),
            r.target_pixels.to_string(),
            r.triangles_drawn.to_string(),
            r.triangles_written.to_string(),
            ms(&r.factors),
            ms(&r.evaluate),
            format!("{} ({})", ms(&r.uniform_max), r.uniform_max_triangles),
            format!("{:.2}", r.evaluate.median_ms / r.uniform_max.median_ms),
        ]);
    }
    md.push_str(&tessellation.to_string());
    let report = Report {
        header,
        frames: frames,
        table_level: bft.level,
        table_megabytes: bft.weight_bytes() as f64 / 1e6,
        tables: bft.tables.len(),
        rows,
        adaptive,
    };
    args.options
        .write_report(&report.header, "subdiv-bft-", &report, &md)
}

/// Adaptive rows of one mesh: screen-space factors for 4, 2 and 1 pixel edges.
fn bench_adaptive(
    gpu: &Gpu,
    timer: &PassTimer,
    frames: u32,
    name: &str,
    mesh: &subdiv_bft::TriMesh,
    sub: &Subdivider,
    g: &GpuSubdivider,
) -> Result<Vec<AdaptiveRow>> {
    let max_level = if bench::run_once() { 3 } else { 6 };
    let viewport = bench::size((1920, 1080));
    let bounds = mesh
        .positions_f32()
        .iter()
        .fold(scene::Aabb::EMPTY, |b, &p| b.grow(p));
    let view_proj =
        scene::Camera::framing(bounds).view_projection(viewport.0 as f32 / viewport.1 as f32);
    let a = g.adaptive(&gpu.device, sub, max_level)?;
    let uniform = g.level(&gpu.device, sub, max_level)?;
    let uniform_max = bench::time_encoded(gpu, timer, frames, false, &|e, t| {
        g.encode_evaluate(e, &uniform, Some(t));
    })?;
    let mut rows = Vec::new();
    for target_pixels in [4.0, 2.0, 1.0] {
        a.set_view(
            &gpu.queue,
            &subdiv_bft::adaptive::ScreenView {
                view_proj,
                viewport,
                target_pixels,
            },
        )?;
        let factors = bench::time_encoded(gpu, timer, frames, false, &|e, t| {
            g.encode_screen_factors(e, &a, Some(t));
        })?;
        let evaluate = bench::time_encoded(gpu, timer, frames, false, &|e, t| {
            g.encode_adaptive(e, &a, Some(t));
        })?;
        let out = g.read_adaptive(&gpu.device, &gpu.queue, &a)?;
        let written = out.indices.len() / 3;
        let drawn = out.without_collapsed().indices.len() / 3;
        println!(
            "{name} adaptive {target_pixels} px: {drawn} triangles, metric {:.3} ms, main {:.3} ms (uniform level {max_level}: {:.3} ms)",
            factors.median_ms, evaluate.median_ms, uniform_max.median_ms
        );
        rows.push(AdaptiveRow {
            mesh: name.into(),
            target_pixels,
            max_level,
            triangles_written: written,
            triangles_drawn: drawn,
            factors,
            evaluate,
            uniform_max: uniform_max.clone(),
            uniform_max_triangles: uniform.index_count as usize / 3,
        });
    }
    Ok(rows)
}
