//! `visibility-gpu`: the compute rasteriser's visibility buffer and its resolve into the
//! G-buffer (issue 29) against the hardware path as the renderer runs it (z-prepass + G-buffer
//! pass), same scene, camera and run: Dabrovic Sponza at 1920×1080, 3840×2160 and the adaptive
//! SSAA's supersampled 4096×3072, and Loop-subdivided meshes of 1.5–17.8 M triangles (spot at
//! levels 4 and 5, fandisk at 5, the bunny at 4; limit surfaces by the basis-function tables on
//! the CPU) at 1920×1080. Alpha-tested meshes take the hardware rasteriser in both paths (the
//! hardware draw into the buffer in the visibility path). Also the share of pixels whose
//! material word the two paths agree on, the visibility path per split of the meshes between
//! the two rasterisers (`pipeline::gpu::SPLIT_PIXELS`), the fastest reported, each
//! dispatch of the visibility path timed on its own, and the classified resolve (a list of
//! tiles and a dispatch per material) against the one-dispatch resolve where the device has
//! binding arrays.

use anyhow::{Context, Result};
use bench::{Header, Stat};
use clap::Parser;
use gbuffer::{
    Frame,
    gpu::{
        GBufferPass, GBufferTargets, GpuScene,
        visibility::{Atomics, Capacity, RASTER_STAGES, ResolvePass, ResolvePath, VisibilityPass},
    },
};
use gpu::{Gpu, PassTimer};
use scene::{Camera, Scene};
use serde::Serialize;
use subdiv_bft::{BftSet, DEFAULT_LEVEL, MAX_VALENCE, Subdivider};

/// Visibility buffer against the hardware G-buffer; writes docs/bench/visibility-<adapter>-<date>.{md,json}.
#[derive(Parser, Debug)]
#[command(version, about)]
struct Args {
    #[command(flatten)]
    options: bench::Options,
    #[command(flatten)]
    quick: bench::Quick,
}

#[derive(Serialize)]
struct Row {
    scene: String,
    width: u32,
    height: u32,
    triangles: usize,
    /// Z-prepass + G-buffer pass.
    hardware: Stat,
    /// The compute rasteriser (with the hardware draw of alpha-tested meshes), 64-bit atomics.
    raster: Stat,
    /// The same with the 32-bit fallback's two passes (`Atomics::Narrow`).
    raster_narrow: Stat,
    /// Rasteriser + resolve (along `resolve`).
    visibility: Stat,
    /// The resolve's path: `OneDispatch` where the device has binding arrays for the
    /// scene's textures, else `Classified`.
    resolve: String,
    /// Rasteriser + the classified resolve (`ResolvePath::Classified`), whatever the device.
    classified: Stat,
    /// Hardware ÷ visibility (medians).
    speedup: f64,
    /// Rasteriser + resolve per split between the rasterisers, as the renderer's
    /// `choose_gbuffer_path` measures them (the first is `visibility`'s).
    splits: Vec<Split>,
    /// Pixels whose material word both paths wrote alike.
    agreement: f64,
    /// The visibility path (64-bit atomics, no split) with each dispatch timed on its own
    /// (`Visibility::profiled`, `Resolve::profiled`), in pass order.
    stages: Vec<Stage>,
}

/// One stage of the profile.
#[derive(Serialize)]
struct Stage {
    pass: String,
    time: Stat,
}

/// Meshes of more than `above_pixels` pixels per triangle drawn into the visibility buffer by
/// the hardware rasteriser (`VisibilityPass::bind_split`).
#[derive(Serialize)]
struct Split {
    /// One of `pipeline::gpu::SPLIT_PIXELS` (`null`: none).
    above_pixels: f32,
    hardware_meshes: usize,
    visibility: Stat,
}

impl Row {
    /// The profile as `pass ms, …`.
    fn stages_line(&self) -> String {
        let stages: Vec<String> = self
            .stages
            .iter()
            .map(|s| format!("{} {:.3}", s.pass, s.time.median_ms))
            .collect();
        stages.join(", ")
    }

    /// The fastest split.
    fn fastest(&self) -> Option<&Split> {
        self.splits
            .iter()
            .min_by(|a, b| a.visibility.median_ms.total_cmp(&b.visibility.median_ms))
    }
}

#[derive(Serialize)]
struct Report {
    #[serde(flatten)]
    header: Header,
    frames: u32,
    rows: Vec<Row>,
}

/// The meshes subdivided for the visibility rows (issue 29: 1–25 M triangles): fixture, name,
/// Loop level. Triangles: 1.5 M, 6.0 M, 13.3 M, 17.8 M.
const SUBDIVIDED: [(&str, &str, u32); 4] = [
    ("subdiv/spot/spot_triangulated.obj", "spot", 4),
    ("subdiv/spot/spot_triangulated.obj", "spot", 5),
    ("subdiv/fandisk.obj", "fandisk", 5),
    ("stanford/stanford-bunny.obj", "bunny", 4),
];

/// The cage `file` of the shared fixtures Loop-subdivided `level` times by the basis-function
/// tables on the CPU (limit positions and normals, `Subdivider::evaluate_cpu`), one default
/// material named `label`, framed.
fn subdivided(file: &str, label: &str, level: u32, bft: &BftSet) -> Result<(Scene, Camera)> {
    let fixtures = scene::shared_fixtures().context("../shared/fixtures not found")?;
    let cage = subdiv_bft::obj::ObjMesh::read(&fixtures.join(file))?.into_mesh()?;
    let fine =
        Subdivider::new(&cage.topology, bft)?.evaluate_cpu(bft, &cage.positions_f32(), level)?;
    let mesh = scene::Mesh {
        name: label.to_owned(),
        uvs: vec![glam::Vec2::ZERO; fine.positions.len()],
        normals: fine.normals,
        positions: fine.positions,
        uvs1: Vec::new(),
        tangents: Vec::new(),
        colors: Vec::new(),
        indices: fine.indices,
        material: 0,
    };
    let scene = Scene {
        meshes: vec![mesh],
        materials: vec![scene::Material::default()],
        ..Scene::default()
    };
    let camera = scene.camera_or_framed();
    Ok((scene, camera))
}

/// One row: both paths timed in the same run, their material words compared.
fn measure(
    gpu: &Gpu,
    (name, scene, camera): (&str, &Scene, &Camera),
    (w, h): (u32, u32),
    frames: u32,
) -> Result<Row> {
    let device = &gpu.device;
    let gpass = GBufferPass::new(device)?;
    let uploaded = GpuScene::upload(device, &gpu.queue, scene, &gpass)?;
    let frame = Frame::new(camera, w, h);
    let hardware_targets = GBufferTargets::new(device, w, h)?;
    gpass.write_frame(&gpu.queue, &frame);
    let timer = PassTimer::new(device, 4);
    let hardware = bench::timing::time_encoded(gpu, &timer, frames, true, &|encoder, timer| {
        gpass.encode_with_prepass(
            encoder,
            &uploaded,
            &hardware_targets,
            timer.render_pass("z-prepass"),
            timer.render_pass("gbuffer"),
        )
    })?;
    let targets = GBufferTargets::new(device, w, h)?;
    let buffer = VisibilityPass::buffer(device, w, h)?;
    let frame_buffer = gpass.frame_buffer();
    let bind = |atomics, hardware: &[usize]| -> Result<_> {
        Ok(
            VisibilityPass::with(device, &gpass, Capacity::default(), atomics)?.bind_split(
                device,
                &uploaded,
                frame_buffer,
                (w, h),
                &buffer,
                hardware,
            )?,
        )
    };
    let (vis, narrow) = (bind(Atomics::Wide, &[])?, bind(Atomics::Narrow, &[])?);
    // The depth attachment of the hardware draw (cleared, not stored): the G-buffer's.
    let depth = Some(&targets.depth);
    let raster_with = |vis: &gbuffer::gpu::visibility::Visibility| {
        bench::timing::time_encoded(gpu, &timer, frames, true, &|encoder, timer| {
            vis.encode(encoder, depth, Some(timer))
                .expect("depth target of the visibility buffer's size");
        })
    };
    let raster_narrow = raster_with(&narrow)?;
    let raster = raster_with(&vis)?;
    let resolve_pass = ResolvePass::new(device, &gpass)?;
    let classified_pass = ResolvePass::with(device, &gpass, ResolvePath::Classified)?;
    let resolved_with =
        |vis: &gbuffer::gpu::visibility::Visibility, resolve_pass: &ResolvePass| -> Result<Stat> {
            let resolve = resolve_pass.bind(device, &uploaded, frame_buffer, vis, &targets)?;
            Ok(bench::timing::time_encoded(
                gpu,
                &timer,
                frames,
                true,
                &|encoder, timer| {
                    vis.encode(encoder, depth, Some(timer))
                        .expect("depth target of the visibility buffer's size");
                    resolve.passes.encode(encoder, Some(timer));
                },
            )?)
        };
    let visibility_with =
        |vis: &gbuffer::gpu::visibility::Visibility| resolved_with(vis, &resolve_pass);
    let pixels = uploaded.pixels_per_triangle(&frame);
    let mut splits: Vec<(f32, Vec<usize>, Stat)> = Vec::new();
    for (above_pixels, meshes) in pipeline::gpu::visibility_splits(&pixels) {
        let stat = visibility_with(&bind(Atomics::Wide, &meshes)?)?;
        splits.push((above_pixels, meshes, stat));
    }
    let (stages, path) = {
        let profiled = bind(Atomics::Wide, &[])?.profiled();
        let bound = resolve_pass.bind(device, &uploaded, frame_buffer, &profiled, &targets)?;
        let resolve = bound.profiled();
        // A pass per rasteriser dispatch, the hardware draw, and a pass per resolve dispatch.
        let passes = RASTER_STAGES.len() + 1 + resolve.names().count();
        let stages_timer = PassTimer::new(device, passes as u32);
        let by_name = bench::timing::time_recorded(gpu, &stages_timer, frames, |encoder, t| {
            profiled
                .encode(encoder, depth, Some(t))
                .expect("depth target of the visibility buffer's size");
            resolve.encode(encoder, Some(t));
        })?;
        let stages = by_name
            .into_iter()
            .map(|(pass, v)| Stage {
                pass,
                time: Stat::of(v),
            })
            .collect::<Vec<_>>();
        (stages, bound.path)
    };
    let classified = resolved_with(&vis, &classified_pass)?;
    // Last the split without hardware meshes, whose G-buffer is compared below.
    let visibility = visibility_with(&vis)?;
    let (a, b) = (
        hardware_targets.read(device, &gpu.queue)?,
        targets.read(device, &gpu.queue)?,
    );
    let same = a
        .material
        .pixels()
        .iter()
        .zip(b.material.pixels())
        .filter(|(x, y)| x == y)
        .count();
    let row = Row {
        scene: name.into(),
        width: w,
        height: h,
        triangles: scene.triangle_count(),
        speedup: hardware.median_ms / visibility.median_ms,
        agreement: same as f64 / f64::from(w * h),
        stages,
        hardware,
        raster,
        raster_narrow,
        visibility,
        resolve: format!("{path:?}"),
        classified,
        splits: splits
            .into_iter()
            .map(|(above_pixels, meshes, visibility)| Split {
                above_pixels,
                hardware_meshes: meshes.len(),
                visibility,
            })
            .collect(),
    };
    let tried: Vec<String> = row
        .splits
        .iter()
        .map(|s| format!("{} {:.3}", split_rule(s), s.visibility.median_ms))
        .collect();
    println!(
        "{name} {w}x{h}: hardware {:.3} ms, visibility {:.3} ms (resolve {}; classified {:.3}; raster {:.3}, 32-bit {:.3}), ×{:.2}, material words agree on {:.2} %; splits: {}",
        row.hardware.median_ms,
        row.visibility.median_ms,
        row.resolve,
        row.classified.median_ms,
        row.raster.median_ms,
        row.raster_narrow.median_ms,
        row.speedup,
        row.agreement * 100.0,
        tried.join(", ")
    );
    println!("  stages, ms: {}", row.stages_line());
    Ok(row)
}

/// `none` or `> T px (n meshes)`: the meshes the split draws by the hardware rasteriser.
fn split_rule(s: &Split) -> String {
    if s.above_pixels.is_finite() {
        format!("> {} px ({} meshes)", s.above_pixels, s.hardware_meshes)
    } else {
        "none".into()
    }
}

fn main() -> Result<()> {
    let args = Args::parse_from(bench::args());
    // The adapter's limits and optional features: the visibility passes say what is missing.
    let gpu = args.options.gpu()?;
    let frames = args.options.frames(20);
    let (sponza, sponza_camera) = bench::fixture("sponza/dabrovic/sponza.gltf")?;
    let mut rows = Vec::new();
    let sizes = [(1920, 1080), (3840, 2160), (4096, 3072)];
    for size in args.quick.sweep(&sizes).iter().copied().map(bench::size) {
        rows.push(measure(
            &gpu,
            ("Sponza", &sponza, &sponza_camera),
            size,
            frames,
        )?);
    }
    if !args.quick.quick && !bench::run_once() {
        let bft = BftSet::cached(
            &BftSet::default_path(DEFAULT_LEVEL, MAX_VALENCE),
            DEFAULT_LEVEL,
            MAX_VALENCE,
        )?;
        for (file, name, level) in SUBDIVIDED {
            let label = format!("{name} level {level}");
            // A mesh the device cannot hold (its largest binding) is reported, not fatal.
            let row = subdivided(file, &label, level, &bft).and_then(|(scene, camera)| {
                measure(&gpu, (&label, &scene, &camera), (1920, 1080), frames)
            });
            match row {
                Ok(row) => rows.push(row),
                Err(e) => println!("{label} 1920x1080: not measured: {e:#}"),
            }
        }
    }
    let header = Header::new(&gpu);
    let mut md = header.markdown(
        "Visibility buffer by compute rasterisation against the hardware G-buffer",
        frames,
    );
    md.push_str(
        "Hardware = z-prepass + G-buffer pass (as the renderer runs them); visibility = the \
         compute rasteriser (`gbuffer::gpu::visibility`, 64-bit atomicMin of depth and id) + \
         the hardware draw of alpha-tested meshes into it + the resolve into the same G-buffer \
         targets along the path `resolve` names: `OneDispatch` (every pixel in one dispatch, \
         materials and textures through binding arrays) where the device has binding arrays, \
         else `Classified` (pixels classified by 8×8 tile, one indirect dispatch per \
         material); classified = the visibility path with the classified resolve, same run; raster = \
         the rasteriser with the hardware draw; 32-bit = the same with the fallback's two \
         passes of 32-bit atomics (`Atomics::Narrow`). Same scene, camera and run. \
         Agreement: pixels whose material word (roughness, metallic, material id) both wrote \
         alike. Best split: the fastest visibility path (rasteriser + resolve) over the splits \
         `choose_gbuffer_path` tries — meshes of more than T pixels per triangle drawn into \
         the buffer by the hardware rasteriser, T in `SPLIT_PIXELS` — and its rule.\n\n| scene | size | triangles | hardware ms | visibility ms | resolve | classified ms | raster ms | 32-bit raster ms | × | agreement | best split ms | its rule | × best |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for r in &rows {
        let best = r.fastest().context("no split measured")?;
        md.push_str(&format!(
            "| {} | {}×{} | {} | {:.3} | {:.3} | {} | {:.3} | {:.3} | {:.3} | {:.2} | {:.2} % | {:.3} | {} | {:.2} |\n",
            r.scene,
            r.width,
            r.height,
            r.triangles,
            r.hardware.median_ms,
            r.visibility.median_ms,
            r.resolve,
            r.classified.median_ms,
            r.raster.median_ms,
            r.raster_narrow.median_ms,
            r.speedup,
            r.agreement * 100.0,
            best.visibility.median_ms,
            split_rule(best),
            r.hardware.median_ms / best.visibility.median_ms
        ));
    }
    md.push_str(
        "\nStages of the visibility path (no split): each dispatch in a compute pass of its own \
         (`Visibility::profiled`, `Resolve::profiled`; the pass boundaries add to the sum), \
         median ms; `visibility hardware` is the hardware draw of the alpha-tested meshes, \
         `visibility resolve materials` the classified resolve's material dispatches together, \
         `visibility resolve one dispatch` the one-dispatch resolve.\n\n| scene | size | stages, ms |\n|---|---|---|\n",
    );
    for r in &rows {
        md.push_str(&format!(
            "| {} | {}×{} | {} |\n",
            r.scene,
            r.width,
            r.height,
            r.stages_line()
        ));
    }
    let report = Report {
        header,
        frames,
        rows,
    };
    args.options
        .write_report(&report.header, "visibility-", &report, &md)
}
