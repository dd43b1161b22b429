//! The shared harness of the GPU benchmark programs (`crates/*/benches/*-gpu.rs`, run by
//! `cargo xtask bench`): timing statistics and the warm-up rule ([`timing`]), the adapter and
//! SM-clock header every report under `docs/bench/` starts with, the software-adapter refusal,
//! image quality against a reference, the benchmark scene. Not published.

use std::sync::OnceLock;

use serde::Serialize;

use gpu::Gpu;

pub mod chart;
pub mod timing;

pub use timing::{
    OUTLIER_FACTOR, REPEAT_TOLERANCE, Remeasurement, Verdict, WARM_UP_RULE, orbiting_spot,
    pass_stat, per_frame_sum, remeasure_outliers, scene_labels, time_encoded, time_named,
    time_recorded, warm_then_time, write_report,
};

/// Median and minimum of a set of timings.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct Stat {
    /// Median, ms.
    pub median_ms: f64,
    /// Minimum, ms.
    pub min_ms: f64,
}

impl Stat {
    /// Statistics of `v` (at least one value; an empty list gives NaN).
    pub fn of(mut v: Vec<f64>) -> Self {
        v.sort_by(f64::total_cmp);
        Self {
            median_ms: v.get(v.len() / 2).copied().unwrap_or(f64::NAN),
            min_ms: v.first().copied().unwrap_or(f64::NAN),
        }
    }
}

/// `median (min)` in ms with three decimals, a report's usual cell.
impl std::fmt::Display for Stat {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{:.3} ({:.3})", self.median_ms, self.min_ms)
    }
}

/// A Markdown table of a report: the header, then one row of cells per [`Table::row`];
/// `Display` writes it with a blank line after.
///
/// ```
/// let mut t = bench::Table::new(&["size", "ms"]);
/// t.row([format!("{}×{}", 1920, 1080), format!("{:.3}", 0.25)]);
/// assert_eq!(t.to_string(), "| size | ms |\n|---|---|\n| 1920×1080 | 0.250 |\n\n");
/// ```
pub struct Table(String);

impl Table {
    /// A table with the column names of `header`.
    pub fn new(header: &[&str]) -> Self {
        Self(format!(
            "| {} |\n|{}\n",
            header.join(" | "),
            "---|".repeat(header.len())
        ))
    }

    /// Appends a row of `cells`.
    pub fn row(&mut self, cells: impl IntoIterator<Item = String>) {
        let cells: Vec<String> = cells.into_iter().collect();
        self.0 += &format!("| {} |\n", cells.join(" | "));
    }
}

impl std::fmt::Display for Table {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(f, "{}", self.0)
    }
}

/// The program's arguments without the `--bench` that `cargo bench` passes to every bench
/// target: what the benchmark programs parse.
pub fn args() -> impl Iterator<Item = String> {
    std::env::args().filter(|a| a != "--bench")
}

/// Run-once mode: the program was started without `--bench`, as `cargo test --benches` (and
/// so `cargo xtask test` in CI) starts it, the convention criterion and wgpu's benches follow.
/// Every measurement then runs one frame without warm-up at [`size`]d-down resolutions on any
/// adapter, software included, and the report goes to a temporary folder ([`out_dir`]): the
/// benchmark's code paths are exercised so it cannot rot, and nothing it prints is a
/// measurement. `cargo bench` and `cargo xtask bench` pass `--bench`; pass it yourself when
/// you start a benchmark executable directly.
pub fn run_once() -> bool {
    static RUN_ONCE: OnceLock<bool> = OnceLock::new();
    *RUN_ONCE.get_or_init(|| {
        let once = !std::env::args().any(|a| a == "--bench");
        if once {
            eprintln!(
                "run-once mode (no --bench argument): one frame per measurement at reduced sizes; \
                 the times are not measurements"
            );
        }
        once
    })
}

/// `(width, height)`, or in [run-once mode](run_once) an eighth of it rounded down to a
/// multiple of 24 (at least 24), which every interleave pattern of the benchmarks divides.
pub fn size((width, height): (u32, u32)) -> (u32, u32) {
    let reduce = |v: u32| (v / 8 / 24).max(1) * 24;
    if run_once() {
        (reduce(width), reduce(height))
    } else {
        (width, height)
    }
}

/// Where the reports go: `out`, or in [run-once mode](run_once) a folder under the system's
/// temporary directory, so that a test run never overwrites a measured report.
pub fn out_dir(out: &std::path::Path) -> std::path::PathBuf {
    if run_once() {
        std::env::temp_dir().join("deferred-bench-run-once")
    } else {
        out.to_path_buf()
    }
}

/// Today's date (UTC) as YYYY-MM-DD, from the Unix clock (Hinnant's civil-from-days).
pub fn today() -> String {
    let secs = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    let z = (secs / 86_400) as i64 + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    format!("{:04}-{m:02}-{d:02}", yoe + era * 400 + i64::from(m <= 2))
}

/// A benchmark refused to run on a software rasterizer.
#[derive(Debug, thiserror::Error)]
#[error(
    "{0} is a software rasterizer: its times are not GPU performance (pass --allow-software to measure anyway)"
)]
pub struct SoftwareAdapter(pub String);

/// Fails on a software rasterizer unless `allow_software`. Every benchmark calls it first;
/// it also records the SM clock before any work ([`Header`]).
pub fn require_hardware(gpu: &Gpu, allow_software: bool) -> Result<(), SoftwareAdapter> {
    clock_before();
    if gpu.is_software() && !allow_software && !run_once() {
        return Err(SoftwareAdapter(gpu.info.name.clone()));
    }
    Ok(())
}

/// Who measured and when: the first fields of every report.
#[derive(Clone, Debug, Serialize)]
pub struct Header {
    /// YYYY-MM-DD.
    pub date: String,
    /// Adapter name.
    pub adapter: String,
    /// wgpu backend.
    pub backend: String,
    /// Driver name.
    pub driver: String,
    /// Driver version.
    pub driver_info: String,
    /// Discrete, integrated, CPU, ...
    pub device_type: String,
    /// SM clock (MHz, `nvidia-smi`) when the benchmark started, before any GPU work.
    pub sm_clock_before_mhz: Option<u32>,
    /// SM clock (MHz) when the header was made, after the measurements.
    pub sm_clock_after_mhz: Option<u32>,
    /// The least and greatest SM clock (MHz) read as a measurement's timed frames began.
    pub sm_clock_measuring_mhz: Option<(u32, u32)>,
    /// The configurations measured again under the bench stability rule
    /// ([`remeasure_outliers`]), with what was measured each time; none where the benchmark
    /// does not apply the rule.
    pub remeasured: Option<Vec<Remeasurement>>,
}

/// The current SM clock in MHz from `nvidia-smi` (first GPU), where it is present.
pub fn sm_clock_mhz() -> Option<u32> {
    query_clock("clocks.sm")
}

/// The greatest SM clock in MHz the first GPU may run at (`nvidia-smi`), where it is present.
pub fn sm_clock_max_mhz() -> Option<u32> {
    static MAX: OnceLock<Option<u32>> = OnceLock::new();
    *MAX.get_or_init(|| query_clock("clocks.max.sm"))
}

/// The clock `field` of `nvidia-smi --query-gpu` for the first GPU, in MHz.
fn query_clock(field: &str) -> Option<u32> {
    let out = std::process::Command::new("nvidia-smi")
        .args([
            &format!("--query-gpu={field}"),
            "--format=csv,noheader,nounits",
        ])
        .output()
        .ok()?;
    String::from_utf8_lossy(&out.stdout)
        .lines()
        .next()?
        .trim()
        .parse()
        .ok()
}

fn clock_before() -> Option<u32> {
    static BEFORE: OnceLock<Option<u32>> = OnceLock::new();
    *BEFORE.get_or_init(sm_clock_mhz)
}

/// The least and greatest SM clock read when a measurement's timed frames began
/// ([`warm_then_time`]), over every measurement so far.
static MEASURED: std::sync::Mutex<Option<(u32, u32)>> = std::sync::Mutex::new(None);

fn record_measured_clock(mhz: u32) {
    let mut range = MEASURED.lock().unwrap_or_else(|e| e.into_inner());
    *range = Some(range.map_or((mhz, mhz), |(lo, hi)| (lo.min(mhz), hi.max(mhz))));
}

fn measured_clocks() -> Option<(u32, u32)> {
    *MEASURED.lock().unwrap_or_else(|e| e.into_inner())
}

/// Every configuration [`remeasure_outliers`] measured again so far.
static REMEASURED: std::sync::Mutex<Option<Vec<Remeasurement>>> = std::sync::Mutex::new(None);

fn record_remeasured(r: &[Remeasurement]) {
    REMEASURED
        .lock()
        .unwrap_or_else(|e| e.into_inner())
        .get_or_insert_default()
        .extend_from_slice(r);
}

impl Header {
    /// The header for `gpu`, dated today.
    pub fn new(gpu: &Gpu) -> Self {
        let i = &gpu.info;
        Self {
            date: today(),
            adapter: i.name.clone(),
            backend: format!("{:?}", i.backend),
            driver: i.driver.clone(),
            driver_info: i.driver_info.clone(),
            device_type: format!("{:?}", i.device_type),
            sm_clock_before_mhz: clock_before(),
            sm_clock_after_mhz: sm_clock_mhz(),
            sm_clock_measuring_mhz: measured_clocks(),
            remeasured: REMEASURED.lock().unwrap_or_else(|e| e.into_inner()).clone(),
        }
    }

    /// `<prefix><adapter-slug>-<date>`: the report's file name without extension.
    pub fn file_stem(&self, prefix: &str) -> String {
        let slug: String = self
            .adapter
            .to_lowercase()
            .chars()
            .map(|c| if c.is_ascii_alphanumeric() { c } else { '-' })
            .collect();
        let slug = slug
            .split('-')
            .filter(|s| !s.is_empty())
            .collect::<Vec<_>>()
            .join("-");
        format!("{prefix}{slug}-{}", self.date)
    }

    /// The Markdown title and the adapter/driver/date/clock/timing lines.
    pub fn markdown(&self, title: &str, frames: u32) -> String {
        let clock =
            |c: Option<u32>| c.map_or("not read (no nvidia-smi)".into(), |c| format!("{c} MHz"));
        format!(
            "# {title} on {} ({})\n\n- Date: {}\n- Adapter: {} ({}, {})\n- Driver: {} {}\n- SM clock: {} before, {} after the measurements, {} as measurements began\n- Timing: GPU timestamp queries, median (and minimum) of {frames} frames after a warm-up of {WARM_UP_RULE}\n{}\n",
            self.adapter,
            self.backend,
            self.date,
            self.adapter,
            self.device_type,
            self.backend,
            self.driver,
            self.driver_info,
            clock(self.sm_clock_before_mhz),
            clock(self.sm_clock_after_mhz),
            self.sm_clock_measuring_mhz
                .map_or("not read".into(), |(lo, hi)| format!("{lo}–{hi} MHz")),
            self.remeasured
                .as_ref()
                .map_or(String::new(), |r| remeasured_line(r)),
        )
    }
}

/// The header's line on the bench stability rule's re-measurements.
fn remeasured_line(r: &[Remeasurement]) -> String {
    let rule = format!(
        "- Outliers: a configuration more than {OUTLIER_FACTOR}× off the trend of its neighbours is measured again"
    );
    if r.is_empty() {
        return format!("{rule}; none was\n");
    }
    let each: Vec<String> = r
        .iter()
        .map(|m| {
            format!(
                "{} {:.3} → {:.3} ms (trend {:.3}){}",
                m.configuration,
                m.first_ms,
                m.again_ms,
                m.expected_ms,
                m.verdict.words()
            )
        })
        .collect();
    format!("{rule}: {}\n", each.join("; "))
}

/// The options every GPU benchmark program takes (`#[command(flatten)]` into its own).
#[derive(clap::Args, Debug)]
pub struct Options {
    /// Report folder.
    #[arg(long, default_value = "docs/bench")]
    pub out: std::path::PathBuf,
    /// Timed frames per measurement, after the warm-up (default: the benchmark's own); at
    /// least 10, so that every median is of 10 frames or more.
    #[arg(long, value_parser = clap::value_parser!(u32).range(10..))]
    pub frames: Option<u32>,
    /// Measure on a software adapter too (its timings are not GPU performance).
    #[arg(long)]
    pub allow_software: bool,
}

impl Options {
    /// `--frames`, or the benchmark's `default`.
    pub fn frames(&self, default: u32) -> u32 {
        self.frames.unwrap_or(default)
    }

    /// The GPU to measure on ([`Gpu::from_env`]), printed; a software adapter is refused
    /// without `--allow-software` ([`require_hardware`]).
    pub fn gpu(&self) -> anyhow::Result<Gpu> {
        clock_before();
        let gpu = Gpu::from_env()?;
        println!("adapter: {}", gpu.describe());
        require_hardware(&gpu, self.allow_software)?;
        Ok(gpu)
    }

    /// Writes `report` and its `markdown` as `<prefix><adapter>-<date>.{json,md}` into the
    /// report folder ([`out_dir`]).
    pub fn write_report(
        &self,
        header: &Header,
        prefix: &str,
        report: &impl Serialize,
        markdown: &str,
    ) -> anyhow::Result<()> {
        write_report(
            &out_dir(&self.out),
            &header.file_stem(prefix),
            report,
            markdown,
        )
    }
}

/// The options of a benchmark that renders a scene: [`SceneOption`] and [`Options`].
#[derive(clap::Args, Debug)]
pub struct SceneArgs {
    #[command(flatten)]
    #[allow(missing_docs)]
    pub scene: SceneOption,
    #[command(flatten)]
    #[allow(missing_docs)]
    pub options: Options,
}

/// `--quick`: a smoke test of a benchmark that sweeps configurations.
#[derive(clap::Args, Debug)]
pub struct Quick {
    /// Only the first entry of every sweep (sizes, counts, patterns; a smoke test).
    #[arg(long)]
    pub quick: bool,
}

impl Quick {
    /// `all`, or with `--quick` or in [run-once mode](run_once) its first entry.
    pub fn sweep<'a, T>(&self, all: &'a [T]) -> &'a [T] {
        if self.quick || run_once() {
            &all[..all.len().min(1)]
        } else {
            all
        }
    }
}

/// The scene option of the benchmarks that render one.
#[derive(clap::Args, Debug)]
pub struct SceneOption {
    /// Scene (default: ../shared/fixtures/sponza/dabrovic/sponza.gltf).
    #[arg(long)]
    pub scene: Option<std::path::PathBuf>,
}

impl SceneOption {
    /// The scene's path (`--scene`, or else the shared fixtures' Dabrovic Sponza).
    pub fn path(&self) -> anyhow::Result<std::path::PathBuf> {
        use anyhow::Context;
        Ok(match &self.scene {
            Some(p) => p.clone(),
            None => scene::shared_fixtures()
                .context("../shared/fixtures not found; pass --scene")?
                .join("sponza/dabrovic/sponza.gltf"),
        })
    }

    /// The scene's path and the scene, loaded.
    pub fn load(&self) -> anyhow::Result<(std::path::PathBuf, scene::Scene)> {
        let path = self.path()?;
        let scene = scene::Scene::load(&path)?;
        Ok((path, scene))
    }

    /// [`SceneOption::load`] and the scene's view: its preset in views.json, else its own
    /// camera or one framing it.
    pub fn load_viewed(&self) -> anyhow::Result<(std::path::PathBuf, scene::Scene, scene::Camera)> {
        let (path, scene) = self.load()?;
        let camera = scene::preset_view(&path, &scene).unwrap_or_else(|| scene.camera_or_framed());
        Ok((path, scene, camera))
    }
}

/// `file` of `../shared/fixtures` and its view from views.json (the Cornell box's is issue
/// 21's: eye (0, 1, 3.9), target (0, 1, 0), fov 39.3°).
pub fn fixture(file: &str) -> anyhow::Result<(scene::Scene, scene::Camera)> {
    let dir =
        scene::shared_fixtures().ok_or_else(|| anyhow::anyhow!("../shared/fixtures not found"))?;
    let path = dir.join(file);
    let scene = scene::Scene::load(&path)?;
    let camera = scene::preset_view(&path, &scene)
        .ok_or_else(|| anyhow::anyhow!("no view of {} in views.json", path.display()))?;
    Ok((scene, camera))
}

/// The path tracer's image (`scene::reference`) of `scene` lit by `lights` and its emissive
/// triangles, from `camera` at `(w, h)` with `config`, at `spp` samples per pixel.
pub fn path_traced(
    scene: &scene::Scene,
    lights: &[scene::Light],
    camera: scene::Camera,
    (w, h): (u32, u32),
    config: scene::reference::ReferenceConfig,
    spp: u32,
) -> anyhow::Result<gbuffer::Image<[f32; 4]>> {
    let mut pt = scene::reference::PathTracer::new(scene, camera, w, h, lights, config);
    pt.add_samples(spp);
    Ok(gbuffer::Image::from_vec(
        w,
        h,
        pt.image().iter().map(|c| [c.x, c.y, c.z, 1.0]).collect(),
    )?)
}

/// [`path_traced`], kept in the folder `cache` when one is given: a truth traced once (here,
/// where CPU time is free) is read back by later runs (on the lent GPU, whose time is not).
/// The file is named by a hash of everything the image depends on — the meshes, materials,
/// lights, camera, size, configuration and `spp` — but not the path tracer's code: empty the
/// folder when `scene::reference` changes. A file that does not hold a whole image of the
/// size is an error, never a truth.
#[allow(clippy::too_many_arguments)]
pub fn path_traced_cached(
    cache: Option<&std::path::Path>,
    scene: &scene::Scene,
    lights: &[scene::Light],
    camera: scene::Camera,
    (w, h): (u32, u32),
    config: scene::reference::ReferenceConfig,
    spp: u32,
) -> anyhow::Result<gbuffer::Image<[f32; 4]>> {
    let Some(dir) = cache else {
        return path_traced(scene, lights, camera, (w, h), config, spp);
    };
    let path = dir.join(format!(
        "truth-{w}x{h}-{spp}spp-{:016x}.f32",
        truth_key(scene, lights, camera, (w, h), config, spp)
    ));
    let bytes = 16 * w as usize * h as usize;
    if let Ok(data) = std::fs::read(&path) {
        anyhow::ensure!(
            data.len() == bytes,
            "{}: {} bytes, not a {w}×{h} RGBA f32 image ({bytes})",
            path.display(),
            data.len()
        );
        let pixels = data
            .chunks_exact(16)
            .map(|p| {
                std::array::from_fn(|c| f32::from_le_bytes([0, 1, 2, 3].map(|b| p[4 * c + b])))
            })
            .collect();
        println!("  truth read from {}", path.display());
        return Ok(gbuffer::Image::from_vec(w, h, pixels)?);
    }
    let image = path_traced(scene, lights, camera, (w, h), config, spp)?;
    std::fs::create_dir_all(dir)?;
    gbuffer::write_atomically(&path, |tmp| {
        let data: Vec<u8> = image
            .pixels()
            .iter()
            .flatten()
            .flat_map(|c| c.to_le_bytes())
            .collect();
        std::fs::write(tmp, data).map_err(|e| e.to_string())
    })?;
    println!("  truth written to {}", path.display());
    Ok(image)
}

/// FNV-1a over what a path-traced image depends on ([`path_traced_cached`]).
fn truth_key(
    scene: &scene::Scene,
    lights: &[scene::Light],
    camera: scene::Camera,
    size: (u32, u32),
    config: scene::reference::ReferenceConfig,
    spp: u32,
) -> u64 {
    let mut hash = 0xcbf2_9ce4_8422_2325_u64;
    let mut eat = |bytes: &[u8]| {
        for &b in bytes {
            hash = (hash ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3);
        }
    };
    for mesh in &scene.meshes {
        eat(bytemuck::cast_slice(&mesh.positions));
        eat(bytemuck::cast_slice(&mesh.normals));
        eat(bytemuck::cast_slice(&mesh.uvs));
        eat(bytemuck::cast_slice(&mesh.indices));
        eat(&mesh.material.to_le_bytes());
    }
    for texture in &scene.textures {
        eat(&texture.width.to_le_bytes());
        eat(&texture.rgba8);
    }
    eat(format!(
        "{:?}{lights:?}{camera:?}{size:?}{config:?}{spp}",
        scene.materials
    )
    .as_bytes());
    hash
}

/// Image error against a reference, on what a PNG shows (RGB clamped to \[0, 1\], sRGB).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Quality {
    /// Root-mean-square error.
    pub rmse: f64,
    /// Peak signal-to-noise ratio, dB ([`gbuffer::psnr`]).
    pub psnr: f64,
    /// Mean of the FLIP error map (LDR FLIP, 67 pixels per degree; 0 = identical, 1 = maximal).
    pub flip_mean: f64,
}

/// [`Quality`] of `test` against `reference` (same size).
pub fn quality(reference: &gbuffer::Image<[f32; 4]>, test: &gbuffer::Image<[f32; 4]>) -> Quality {
    let psnr = gbuffer::psnr(reference, test);
    let rmse = 10f64.powf(-psnr / 20.0);
    let srgb8 = |img: &gbuffer::Image<[f32; 4]>| -> Vec<u8> {
        img.pixels()
            .iter()
            .flat_map(|p| {
                [0, 1, 2]
                    .map(|c| (gbuffer::linear_to_srgb(p[c].clamp(0.0, 1.0)) * 255.0).round() as u8)
            })
            .collect()
    };
    let (w, h) = (reference.width(), reference.height());
    let map = nv_flip::flip(
        nv_flip::FlipImageRgb8::with_data(w, h, &srgb8(reference)),
        nv_flip::FlipImageRgb8::with_data(w, h, &srgb8(test)),
        nv_flip::DEFAULT_PIXELS_PER_DEGREE,
    );
    Quality {
        rmse,
        psnr,
        flip_mean: f64::from(nv_flip::FlipPool::from_image(&map).mean()),
    }
}
