//! `peers-bench`: Loop subdivision beside the libraries users would pick instead, on the same
//! meshes, machine and run — fandisk, spot, the Stanford bunny and CesiumMan (welded at its
//! texture seams), uniform levels 1–5 (bunny to 4):
//!
//! - OpenSubdiv 3.7 (`opensubdiv-petite` 0.3.1): topology refinement and stencil-table build
//!   (wall clock), evaluation by its CPU evaluator (one thread, wall clock) and by its GPU
//!   evaluator (WGSL on wgpu 29, timestamps around the dispatch), stencil-table bytes;
//! - ours: basis-function tables on the GPU (initial + main step, timestamps), the same on the
//!   CPU (rayon, all threads), and the recursive CPU reference;
//! - MeshLab (`pymeshlab`) and Open3D (`open3d`) Loop on the CPU, where Python imports them.
//!
//! Positions of the vertices triangles use are compared as point sets, as fractions of the
//! control mesh's bounding-box diagonal: OpenSubdiv's refined vertices against our recursive
//! reference (and its GPU evaluator against its CPU one), and our GPU limit positions against
//! OpenSubdiv's level projected to the limit by Loop's limit mask (OpenSubdiv's C API in
//! `opensubdiv-petite` has no limit of refined vertices); our CPU twin's where our GPU path
//! cannot hold the level. OpenSubdiv's stencils give refined positions only; ours give limit
//! positions and normals — the GPU ratio compares the evaluation a renderer runs per frame for
//! each. Writes `peers-<adapter>-<date>.{md,json}`.

use std::time::Instant;

use anyhow::{Context, Result};
use bench::Stat;
use clap::Parser;
use glam::DVec3;
use gpu::PassTimer;
use peers::opensubdiv::{GpuEvaluator, Refinement};
use peers::python::{self, Outcome};
use serde::Serialize;
use subdiv_bft::{BftSet, DEFAULT_LEVEL, MAX_VALENCE, Subdivider, TriMesh, gpu::GpuSubdivider};

/// Benchmarks Loop subdivision against OpenSubdiv, MeshLab and Open3D.
#[derive(Parser, Debug)]
struct Args {
    #[command(flatten)]
    options: bench::Options,
    /// Runs of each CPU measurement (the median is reported).
    #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u32).range(1..))]
    cpu_runs: u32,
    /// Highest level the Python peers run (MeshLab and Open3D take seconds per level 5 step).
    #[arg(long, default_value_t = 4)]
    python_level: u32,
    /// Only these meshes (fandisk, spot, bunny, cesium-man).
    #[arg(long, value_delimiter = ',')]
    meshes: Vec<String>,
    /// Only these levels (default 1–5, the bunny to 4; run-once mode: 1–2).
    #[arg(long, value_delimiter = ',')]
    levels: Vec<u32>,
}

#[derive(Serialize)]
struct Row {
    mesh: String,
    control_vertices: usize,
    control_triangles: usize,
    /// Wall-clock ms of our per-mesh set-up (any level): `Subdivider::new` (topology, M¹,
    /// patches) and `GpuSubdivider::new` (uploads). The tables are built once for every mesh.
    ours_setup_ms: f64,
    level: u32,
    vertices: usize,
    triangles: usize,
    osd_refine_ms: f64,
    osd_stencil_ms: f64,
    osd_stencil_bytes: usize,
    osd_cpu_ms: f64,
    /// OpenSubdiv's GPU evaluator, or why it did not run.
    osd_gpu: Result<Stat, String>,
    /// Ours on the GPU, or why it did not run (then the limit comparison takes the CPU twin's
    /// positions).
    ours_gpu: Result<Stat, String>,
    ours_cpu_bft_ms: f64,
    ours_cpu_recursive_ms: f64,
    /// Point-set distances / bounding-box diagonal.
    osd_vs_reference: f64,
    osd_gpu_vs_cpu: Option<f64>,
    limit_vs_ours: f64,
}

#[derive(Serialize)]
struct PythonRow {
    mesh: String,
    level: u32,
    library: String,
    /// Version and median ms, and the distance to our recursive reference / diagonal; or why
    /// it did not run.
    result: Result<(String, f64, f64), String>,
}

#[derive(Serialize)]
struct Report {
    header: bench::Header,
    frames: u32,
    cpu_runs: u32,
    cpu_threads: usize,
    bft_level: u32,
    bft_bytes: usize,
    rows: Vec<Row>,
    python: Vec<PythonRow>,
}

/// The meshes: name, control mesh.
fn meshes(only: &[String]) -> Result<Vec<(String, TriMesh)>> {
    let fixtures = scene::shared_fixtures().context("../shared/fixtures not found")?;
    let obj = |file: &str| -> Result<TriMesh> {
        Ok(subdiv_bft::obj::ObjMesh::read(&fixtures.join(file))?.into_mesh()?)
    };
    let mut out = Vec::new();
    for name in ["fandisk", "spot", "bunny", "cesium-man"] {
        if !only.is_empty() && !only.iter().any(|m| m == name) {
            continue;
        }
        let mesh = match name {
            "fandisk" => obj("subdiv/fandisk.obj")?,
            "spot" => obj("subdiv/spot/spot_triangulated.obj")?,
            "bunny" => obj("stanford/stanford-bunny.obj")?,
            _ => {
                let path = fixtures.join("animated/CesiumMan/CesiumMan.glb");
                let scene = scene::Scene::load(&path)?;
                let m = scene.meshes.first().context("CesiumMan has no mesh")?;
                TriMesh::welded(&m.positions, &m.indices)?
            }
        };
        out.push((name.to_owned(), mesh));
    }
    Ok(out)
}

/// Median wall-clock ms of `runs` calls of `f`, and its last result.
fn wall<T>(runs: u32, mut f: impl FnMut() -> Result<T>) -> Result<(f64, T)> {
    let mut times = Vec::new();
    let mut last = None;
    for _ in 0..runs {
        let start = Instant::now();
        last = Some(f()?);
        times.push(start.elapsed().as_secs_f64() * 1e3);
    }
    Ok((Stat::of(times).median_ms, last.context("no run")?))
}

fn main() -> Result<()> {
    let args = Args::parse_from(bench::args());
    let gpu = args.options.gpu()?;
    let frames = args.options.frames(20);
    let timer = PassTimer::new(&gpu.device, 8);
    let osd_gpu = GpuEvaluator::new(&gpu.info.name).map_err(|e| format!("{e:#}"));
    if let Err(e) = &osd_gpu {
        println!("OpenSubdiv's GPU evaluator does not run here: {e}");
    }
    let bft = BftSet::cached(
        &BftSet::default_path(DEFAULT_LEVEL, MAX_VALENCE),
        DEFAULT_LEVEL,
        MAX_VALENCE,
    )?;
    let scratch = std::env::temp_dir().join(format!("deferred-peers-{}", std::process::id()));
    std::fs::create_dir_all(&scratch)?;
    let cpu_runs = if bench::run_once() { 1 } else { args.cpu_runs };
    let mut rows = Vec::new();
    let mut python_rows = Vec::new();
    for (name, mesh) in meshes(&args.meshes)? {
        let top = match (bench::run_once(), name.as_str()) {
            (true, _) => 2,
            (false, "bunny") => 4,
            _ => 5,
        };
        let diagonal = mesh.diagonal();
        let positions = mesh.positions_f32();
        let control: Vec<[f32; 3]> = positions.iter().map(|p| p.to_array()).collect();
        let start = Instant::now();
        let sub = Subdivider::new(&mesh.topology, &bft)?;
        let g = GpuSubdivider::new(&gpu.device, &sub, &bft)?;
        let ours_setup_ms = start.elapsed().as_secs_f64() * 1e3;
        g.set_positions(&gpu.queue, &positions)?;
        let obj = scratch.join(format!("{name}.obj"));
        let indices = flat(&mesh.topology.triangles);
        std::fs::write(
            &obj,
            subdiv_bft::obj::ObjMesh::write(&positions, None, &indices),
        )?;
        for level in (1..=top).filter(|l| args.levels.is_empty() || args.levels.contains(l)) {
            // Progress on stderr: a level-5 row takes minutes on the CPU side.
            let began = Instant::now();
            let step = |what: &str| {
                eprintln!(
                    "{name} level {level}: {what} ({:.1} s)",
                    began.elapsed().as_secs_f64()
                )
            };
            let osd = Refinement::new(&mesh, level)?;
            step("OpenSubdiv refined, stencils built");
            let (osd_cpu_ms, osd_positions) = wall(cpu_runs, || osd.evaluate_cpu(&control))?;
            let osd_triangles = osd.triangles()?;
            let osd_positions = peers::dvec3s(&osd_positions);
            let (osd_gpu_stat, osd_gpu_positions) = match osd_gpu
                .as_ref()
                .map(|e| (e, e.bind(&osd, &control)))
            {
                // A refused evaluation is the row's, not the run's.
                Ok((e, Ok(bound))) => match bench::warm_then_time(frames, || e.evaluate(&bound)) {
                    Ok(times) => (Ok(Stat::of(times)), Some(peers::dvec3s(&e.read(&bound)?))),
                    Err(why) => (Err(format!("{why:#}")), None),
                },
                Ok((_, Err(why))) => (Err(format!("{why:#}")), None),
                Err(why) => (Err(why.clone()), None),
            };
            step("OpenSubdiv evaluated on the CPU and GPU");
            let ours_gpu = g.level(&gpu.device, &sub, level).map_err(|e| e.to_string());
            let ours_gpu = match ours_gpu {
                Ok(out) => {
                    let stat = bench::time_encoded(&gpu, &timer, frames, false, &|e, t| {
                        g.encode_initial(e, Some(t));
                        g.encode_evaluate(e, &out, Some(t));
                    })?;
                    Ok((stat, g.read_level(&gpu.device, &gpu.queue, &out)?))
                }
                Err(why) => Err(why),
            };
            let (ours_cpu_bft_ms, ours_cpu) =
                wall(cpu_runs, || Ok(sub.evaluate_cpu(&bft, &positions, level)?))?;
            let ours = ours_gpu.as_ref().map_or(&ours_cpu, |(_, refined)| refined);
            let ours_positions: Vec<DVec3> = ours.positions.iter().map(|p| p.as_dvec3()).collect();
            step("ours evaluated on the GPU and CPU");
            let (ours_cpu_recursive_ms, reference) = wall(cpu_runs, || Ok(mesh.subdivide(level)?))?;
            step("recursive reference subdivided");
            // Distances beyond a thousandth of the diagonal read as infinite.
            let reach = 1e-3 * diagonal;
            let relative = |d: f64| d / diagonal;
            let reference_indices = flat(&reference.topology.triangles);
            let reference_surface = peers::surface_points(&reference.positions, &reference_indices);
            let osd_surface = peers::surface_points(&osd_positions, &osd_triangles);
            let osd_vs_reference =
                relative(peers::hausdorff(&osd_surface, &reference_surface, reach));
            let osd_gpu_vs_cpu = osd_gpu_positions.as_ref().map(|p| {
                let gpu_surface = peers::surface_points(p, &osd_triangles);
                relative(peers::hausdorff(&gpu_surface, &osd_surface, reach))
            });
            step("OpenSubdiv's distances measured");
            let osd_mesh = TriMesh::new(osd_positions, triangles(&osd_triangles))?;
            let limit_vs_ours = relative(peers::hausdorff(
                &peers::surface_points(&osd_mesh.limit_positions(), &osd_triangles),
                &peers::surface_points(&ours_positions, &ours.indices),
                reach,
            ));
            let row = Row {
                mesh: name.clone(),
                control_vertices: mesh.positions.len(),
                control_triangles: mesh.topology.triangles.len(),
                ours_setup_ms,
                level,
                vertices: osd.vertex_count(),
                triangles: osd_mesh.topology.triangles.len(),
                osd_refine_ms: osd.refine_ms,
                osd_stencil_ms: osd.stencil_ms,
                osd_stencil_bytes: osd.stencil_bytes(),
                osd_cpu_ms,
                osd_gpu: osd_gpu_stat,
                ours_gpu: ours_gpu.map(|(stat, _)| stat),
                ours_cpu_bft_ms,
                ours_cpu_recursive_ms,
                osd_vs_reference,
                osd_gpu_vs_cpu,
                limit_vs_ours,
            };
            println!(
                "{name} level {level}: {} vertices; OpenSubdiv stencils {:.1} ms ({:.1} MB), CPU {:.3} ms, GPU {}; ours GPU {}, CPU BFT {:.2} ms, recursive {:.2} ms; distances {:.1e} (OSD vs reference), {:.1e} (limit vs ours)",
                row.vertices,
                row.osd_stencil_ms,
                row.osd_stencil_bytes as f64 / 1e6,
                row.osd_cpu_ms,
                row.osd_gpu
                    .as_ref()
                    .map_or("–".into(), |s| format!("{:.4} ms", s.median_ms)),
                row.ours_gpu
                    .as_ref()
                    .map_or("–".into(), |s| format!("{:.4} ms", s.median_ms)),
                row.ours_cpu_bft_ms,
                row.ours_cpu_recursive_ms,
                row.osd_vs_reference,
                row.limit_vs_ours
            );
            rows.push(row);
            if level <= args.python_level {
                for peer in python::PEERS {
                    let result =
                        match python::loop_subdivide(peer, &obj, level, cpu_runs, &scratch)? {
                            Outcome::Ran {
                                version,
                                ms,
                                positions,
                            } => {
                                let d = relative(peers::hausdorff(
                                    &positions,
                                    &reference_surface,
                                    reach,
                                ));
                                println!(
                                    "{name} level {level}: {} {version} {:.2} ms, distance {d:.1e}",
                                    peer.name,
                                    Stat::of(ms.clone()).median_ms
                                );
                                Ok((version, Stat::of(ms).median_ms, d))
                            }
                            Outcome::Unavailable(why) => Err(why),
                        };
                    python_rows.push(PythonRow {
                        mesh: name.clone(),
                        level,
                        library: peer.name.into(),
                        result,
                    });
                }
            }
        }
    }
    std::fs::remove_dir_all(&scratch).ok();
    let header = bench::Header::new(&gpu);
    let md = markdown(&header, frames, cpu_runs, &bft, &rows, &python_rows);
    let report = Report {
        header,
        frames,
        cpu_runs,
        cpu_threads: rayon::current_num_threads(),
        bft_level: bft.level,
        bft_bytes: bft.weight_bytes(),
        rows,
        python: python_rows,
    };
    args.options
        .write_report(&report.header, "peers-", &report, &md)
}

/// Three indices per triangle, in order.
fn flat(triangles: &[[u32; 3]]) -> Vec<u32> {
    triangles.iter().flatten().copied().collect()
}

fn triangles(indices: &[u32]) -> Vec<[u32; 3]> {
    indices
        .chunks_exact(3)
        .map(|t| [t[0], t[1], t[2]])
        .collect()
}

fn markdown(
    header: &bench::Header,
    frames: u32,
    cpu_runs: u32,
    bft: &BftSet,
    rows: &[Row],
    python: &[PythonRow],
) -> String {
    let mut md = header.markdown(
        "Loop subdivision beside OpenSubdiv, MeshLab and Open3D",
        frames,
    );
    md.push_str(&format!(
        "\nOpenSubdiv 3.7.0 through opensubdiv-petite 0.3.1 (Loop, boundaries edge-only, uniform \
         refinement, stencils of the last level only); its GPU evaluator is opensubdiv-petite's \
         WGSL port of OpenSubdiv's GLSL compute kernel on wgpu 29, timed by timestamps around its \
         dispatch (median of {frames}); its CPU evaluator runs on one thread. Ours: \
         basis-function tables (level {}, {:.2} MB for every mesh) — GPU initial + main step \
         (limit positions and normals), the same on the CPU with {} rayon threads, and the \
         recursive CPU reference (refined positions). CPU times: median of {cpu_runs} runs, wall \
         clock. Distances: Hausdorff distance of the point sets / the control mesh's bounding-box \
         diagonal (∞: some point farther than 1e-3); 'limit vs ours': OpenSubdiv's level \
         projected to the limit by Loop's limit mask, against our GPU positions.\n\n",
        bft.level,
        bft.weight_bytes() as f64 / 1e6,
        rayon::current_num_threads()
    ));
    let mut t = bench::Table::new(&[
        "mesh",
        "level",
        "vertices",
        "OSD refine + stencils ms",
        "OSD stencils MB",
        "ours set-up ms",
        "BFT MB ÷ OSD MB",
        "OSD CPU ms",
        "OSD GPU ms",
        "ours GPU ms",
        "OSD GPU ÷ ours",
        "ours CPU BFT ms",
        "ours CPU recursive ms",
        "OSD vs reference",
        "OSD GPU vs CPU",
        "limit vs ours",
    ]);
    let e = |d: f64| format!("{d:.1e}");
    for r in rows {
        let osd_gpu = r.osd_gpu.as_ref().ok().map(|s| s.median_ms);
        let ours_gpu = r.ours_gpu.as_ref().ok().map(|s| s.median_ms);
        t.row([
            r.mesh.clone(),
            r.level.to_string(),
            r.vertices.to_string(),
            format!("{:.1} + {:.1}", r.osd_refine_ms, r.osd_stencil_ms),
            format!("{:.2}", r.osd_stencil_bytes as f64 / 1e6),
            format!("{:.1}", r.ours_setup_ms),
            format!(
                "{:.3}",
                bft.weight_bytes() as f64 / r.osd_stencil_bytes as f64
            ),
            format!("{:.3}", r.osd_cpu_ms),
            osd_gpu.map_or("–".into(), |ms| format!("{ms:.4}")),
            ours_gpu.map_or("–".into(), |ms| format!("{ms:.4}")),
            osd_gpu.map_or("–".into(), |ms| {
                ours_gpu.map_or("–".into(), |ours| format!("{:.1}", ms / ours))
            }),
            format!("{:.2}", r.ours_cpu_bft_ms),
            format!("{:.2}", r.ours_cpu_recursive_ms),
            e(r.osd_vs_reference),
            r.osd_gpu_vs_cpu.map_or("–".into(), e),
            e(r.limit_vs_ours),
        ]);
    }
    md.push_str(&t.to_string());
    for r in rows {
        if let Err(why) = &r.osd_gpu {
            md.push_str(&format!(
                "\nOpenSubdiv's GPU evaluator did not run on {} level {}: {why}\n",
                r.mesh, r.level
            ));
        }
        if let Err(why) = &r.ours_gpu {
            md.push_str(&format!(
                "\nOur GPU evaluation did not run on {} level {} ({why}); 'limit vs ours' \
                 compares the CPU twin's positions.\n",
                r.mesh, r.level
            ));
        }
    }
    md.push_str(
        "\n## MeshLab and Open3D (CPU)\n\nLoop subdivision of the same control mesh (written as \
         OBJ), wall clock of the subdivision call in Python (median), Hausdorff distance of the \
         vertices triangles use to our recursive reference's / diagonal.\n\n",
    );
    let mut p = bench::Table::new(&[
        "mesh",
        "level",
        "library",
        "version",
        "ms",
        "ours recursive ms",
        "distance",
    ]);
    for r in python {
        let ours = rows
            .iter()
            .find(|o| o.mesh == r.mesh && o.level == r.level)
            .map_or("–".into(), |o| format!("{:.2}", o.ours_cpu_recursive_ms));
        match &r.result {
            Ok((version, ms, d)) => p.row([
                r.mesh.clone(),
                r.level.to_string(),
                r.library.clone(),
                version.clone(),
                format!("{ms:.2}"),
                ours,
                e(*d),
            ]),
            Err(why) => p.row([
                r.mesh.clone(),
                r.level.to_string(),
                r.library.clone(),
                format!("not run: {why}"),
                "–".into(),
                ours,
                "–".into(),
            ]),
        }
    }
    md.push_str(&p.to_string());
    md
}
