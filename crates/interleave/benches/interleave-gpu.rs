//! `interleave-bench`: GPU benchmarks of Segovia 2006's passes, timed with timestamp queries,
//! written to `docs/bench/interleave-<adapter>-<date>.{md,json,svg}`.
//!
//! 1. Split and gather of a 16-byte/pixel G-buffer (one `Rgba32Uint` texture) at 1920×1080 and
//!    3840×2160, patterns 2×2, 4×4, 8×8, 8×6, every variant, as a fraction of the bandwidth of a
//!    `copy_texture_to_texture` of the same texture measured in the same run (§5.1, §5.3).
//! 2. The two-pass block-size sweep (Figure 5), at 1024×1024 as in the paper and at both
//!    sizes above.
//! 3. The blur at 1280×1024, 7×7, 11×11, 17×17, plain and fast (Table 2), and the
//!    discontinuity buffer.
//! 4. What splitting buys: split + shade + gather against the fused indirection of §3.1.

use std::fmt::Write as _;

use anyhow::{Context, Result, bail};
use bench::{Header, Stat};
use clap::Parser;
use gbuffer::Image;
use gpu::{Gpu, PassTimer, transfer, wgpu};
use interleave::{
    Block, Blur, BlurVariant, Pattern, SplitLayout, SplitVariant, Thresholds,
    cpu::SubsetLight,
    gpu::{BlurPass, DiscontinuityPass, Passes, Splitter, SubsetShading, upload_depth_normals},
};
use serde::Serialize;

/// GPU benchmarks of the interleave crate.
#[derive(Parser, Debug)]
#[command(version, about)]
struct Args {
    #[command(flatten)]
    options: bench::Options,
}

const SIZES: [(u32, u32); 2] = [(1920, 1080), (3840, 2160)];
const PATTERNS: [(u32, u32); 4] = [(2, 2), (4, 4), (8, 8), (8, 6)];
const BLOCK_SIDES: [u32; 6] = [8, 16, 32, 64, 128, 256];
const FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Uint;

#[derive(Serialize)]
struct SplitResult {
    width: u32,
    height: u32,
    pattern: String,
    variant: String,
    split: Stat,
    gather: Stat,
    /// `copy_texture_to_texture` time / split time: 1 = the split runs at copy bandwidth.
    split_fraction_of_copy: f64,
    gather_fraction_of_copy: f64,
    /// Compute-copy time / split time.
    split_fraction_of_compute_copy: f64,
    gather_fraction_of_compute_copy: f64,
    /// Bytes read + written per second, GB/s.
    split_gbps: f64,
    gather_gbps: f64,
    /// What the row measured, to measure it again: the pattern and the split and gather
    /// variants.
    #[serde(skip)]
    setup: (Pattern, SplitVariant, SplitVariant),
}

impl SplitResult {
    /// The row of `variant` (its name) measuring `split` and `gather` on a G-buffer of `size`
    /// whose copies `copy` measured.
    fn new(
        size: (u32, u32),
        variant: String,
        setup: (Pattern, SplitVariant, SplitVariant),
        (split, gather): (Stat, Stat),
        copy: &CopyResult,
    ) -> Self {
        let (c, cc) = (
            copy.copy_texture_to_texture.median_ms,
            copy.compute_copy.median_ms,
        );
        Self {
            width: size.0,
            height: size.1,
            pattern: setup.0.to_string(),
            variant,
            split,
            gather,
            split_fraction_of_copy: c / split.median_ms,
            gather_fraction_of_copy: c / gather.median_ms,
            split_fraction_of_compute_copy: cc / split.median_ms,
            gather_fraction_of_compute_copy: cc / gather.median_ms,
            split_gbps: gbps(size, split.median_ms),
            gather_gbps: gbps(size, gather.median_ms),
            setup,
        }
    }

    /// The row as the program prints it.
    fn line(&self) -> String {
        format!(
            "{} {} {}: split {:.3} ms ({:.0}% of copy, {:.0}% of compute copy), gather {:.3} ms ({:.0}%, {:.0}%)",
            name((self.width, self.height)),
            self.pattern,
            self.variant,
            self.split.median_ms,
            100.0 * self.split_fraction_of_copy,
            100.0 * self.split_fraction_of_compute_copy,
            self.gather.median_ms,
            100.0 * self.gather_fraction_of_copy,
            100.0 * self.gather_fraction_of_compute_copy
        )
    }
}

/// GB/s of a pass reading and writing a 16-byte/pixel image of `size` in `ms`.
fn gbps((w, h): (u32, u32), ms: f64) -> f64 {
    2.0 * f64::from(w * h) * 16.0 / ms * 1e-6
}

#[derive(Serialize)]
struct CopyResult {
    size: String,
    copy_texture_to_texture: Stat,
    /// Identity copy by the one-pass kernel with a 1×1 pattern.
    compute_copy: Stat,
    copy_gbps: f64,
    compute_copy_gbps: f64,
}

#[derive(Serialize)]
struct SweepResult {
    width: u32,
    height: u32,
    pattern: String,
    block: String,
    split: Stat,
    gather: Stat,
}

#[derive(Serialize)]
struct BlurResult {
    kernel: u32,
    plain: Stat,
    fast: Stat,
    fast_speedup: f64,
}

#[derive(Serialize)]
struct ShadingResult {
    width: u32,
    height: u32,
    pattern: String,
    lights_per_pixel: u32,
    fused: Stat,
    split_path: Stat,
    split_path_passes: Vec<(String, f64)>,
    /// Fused time / split-path time (> 1: splitting is faster).
    split_speedup: f64,
}

#[derive(Serialize)]
struct Report {
    #[serde(flatten)]
    header: Header,
    frames: u32,
    copy: Vec<CopyResult>,
    split: Vec<SplitResult>,
    sweep: Vec<SweepResult>,
    blur_1280x1024: Vec<BlurResult>,
    discontinuity: Vec<(String, Stat)>,
    shading: Vec<ShadingResult>,
}

struct Bench<'a> {
    gpu: &'a Gpu,
    frames: u32,
    timer: PassTimer,
}

impl Bench<'_> {
    /// Times `record` (which records timed passes) over the frames: per frame, from the begin
    /// of its first timed pass to the end of its last. Also returns each pass's median.
    fn time(
        &self,
        record: impl Fn(&mut wgpu::CommandEncoder, &PassTimer),
    ) -> Result<(Stat, Vec<(String, f64)>)> {
        let mut totals = Vec::new();
        let mut per_pass: Vec<(String, Vec<f64>)> = Vec::new();
        let frames = bench::warm_then_time(self.frames, || -> Result<Vec<gpu::PassTime>> {
            let mut encoder = self.gpu.device.create_command_encoder(&Default::default());
            record(&mut encoder, &self.timer);
            self.timer.resolve(&mut encoder);
            self.gpu.queue.submit([encoder.finish()]);
            let times = self.timer.read(&self.gpu.device, &self.gpu.queue)?;
            if times.is_empty() {
                bail!("the adapter has no timestamp queries");
            }
            Ok(times)
        })?;
        for times in frames {
            let (Some(first), Some(last)) = (times.first(), times.last()) else {
                continue;
            };
            totals.push(last.end_ms() - first.start_ms);
            for (i, t) in times.iter().enumerate() {
                if per_pass.len() <= i {
                    per_pass.push((t.name.clone(), Vec::new()));
                }
                per_pass[i].1.push(t.ms);
            }
        }
        Ok((
            Stat::of(totals),
            per_pass
                .into_iter()
                .map(|(n, v)| (n, Stat::of(v).median_ms))
                .collect(),
        ))
    }

    fn time_passes(&self, passes: &Passes) -> Result<Stat> {
        Ok(self.time(|e, t| passes.encode(e, Some(t)))?.0)
    }

    fn texture(
        &self,
        label: &str,
        (w, h): (u32, u32),
        format: wgpu::TextureFormat,
    ) -> wgpu::Texture {
        transfer::texture_2d(
            &self.gpu.device,
            label,
            w,
            h,
            format,
            wgpu::TextureUsages::TEXTURE_BINDING
                | wgpu::TextureUsages::STORAGE_BINDING
                | wgpu::TextureUsages::COPY_SRC
                | wgpu::TextureUsages::COPY_DST,
        )
    }

    /// `copy_texture_to_texture` of `src` into a new texture, between two empty timed marker
    /// passes.
    fn copy(&self, src: &wgpu::Texture) -> Result<Stat> {
        let dst = self.texture("copy dst", (src.width(), src.height()), src.format());
        Ok(self
            .time(|encoder, timer| {
                drop(encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some("copy start"),
                    timestamp_writes: timer.compute_pass("copy start"),
                }));
                encoder.copy_texture_to_texture(
                    src.as_image_copy(),
                    dst.as_image_copy(),
                    src.size(),
                );
                drop(encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some("copy end"),
                    timestamp_writes: timer.compute_pass("copy end"),
                }));
            })?
            .0)
    }

    /// A texture of random texels: GPUs compress uniform (e.g. never written, all-zero) data,
    /// which would make every pass look faster than memory allows.
    fn random_texture(
        &self,
        label: &str,
        (w, h): (u32, u32),
        format: wgpu::TextureFormat,
    ) -> Result<wgpu::Texture> {
        let bytes = (w * h * format.block_copy_size(None).unwrap_or(4)) as usize;
        let mut state = 0x2545_f491_4f6c_dd1du64 ^ bytes as u64;
        let data: Vec<u8> = (0..bytes.div_ceil(8))
            .flat_map(|_| {
                state ^= state << 13;
                state ^= state >> 7;
                state ^= state << 17;
                state.to_le_bytes()
            })
            .take(bytes)
            .collect();
        let t = self.texture(label, (w, h), format);
        self.gpu.queue.write_texture(
            t.as_image_copy(),
            &data,
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(bytes as u32 / h),
                rows_per_image: Some(h),
            },
            t.size(),
        );
        Ok(t)
    }

    /// Split and gather times of one variant on `image` (16 bytes/pixel, random texels).
    fn split_gather(
        &self,
        image: &wgpu::Texture,
        layout: &SplitLayout,
        variant: SplitVariant,
    ) -> Result<(Stat, Stat)> {
        let device = &self.gpu.device;
        let splitter = Splitter::new(device, layout, variant, FORMAT)?;
        let split = splitter.split_texture(device, "split gbuffer");
        let s = self.time_passes(&splitter.split(device, image, &split)?)?;
        let g = self.time_passes(&splitter.gather(device, &split, image)?)?;
        Ok((s, g))
    }
}

/// Linear depth and normals of the built-in spheres-on-a-plane scene from the CPU rasterizer.
fn scene_gbuffer(width: u32, height: u32) -> Result<(Image<f32>, Image<u32>)> {
    let scene = scene::spheres_on_plane(32);
    let camera = scene.camera_or_framed();
    let gb = gbuffer::cpu::rasterize(&scene, &camera, width, height)?.gbuffer;
    Ok((gb.linear_depth, gb.normal))
}

fn name((w, h): (u32, u32)) -> String {
    format!("{w}x{h}")
}

fn main() -> Result<()> {
    let args = Args::parse_from(bench::args());
    let gpu = args.options.gpu()?;
    let frames = args.options.frames(50);
    let bench = Bench {
        gpu: &gpu,
        frames: frames,
        timer: PassTimer::new(&gpu.device, 16),
    };
    let device = &gpu.device;

    // 1 + 2: copy baselines, block sweeps, split/gather table.
    let mut copy = Vec::new();
    let mut sweep = Vec::new();
    let mut split = Vec::new();
    for size in [(1024, 1024), SIZES[0], SIZES[1]].map(bench::size) {
        let image = bench.random_texture("gbuffer", size, FORMAT)?;
        let copy_ms = bench.copy(&image)?;
        // The 1×1 pattern's one-pass split is an identity copy through a compute kernel.
        let identity = SplitLayout::new(size.0, size.1, Pattern::new(1, 1)?)?;
        let compute_copy = bench
            .split_gather(&image, &identity, SplitVariant::OnePass)?
            .0;
        let gbps = |ms: f64| gbps(size, ms);
        println!(
            "copy {}: copy_texture_to_texture {:.3} ms ({:.0} GB/s), compute copy {:.3} ms ({:.0} GB/s)",
            name(size),
            copy_ms.median_ms,
            gbps(copy_ms.median_ms),
            compute_copy.median_ms,
            gbps(compute_copy.median_ms)
        );
        copy.push(CopyResult {
            size: name(size),
            copy_texture_to_texture: copy_ms,
            compute_copy,
            copy_gbps: gbps(copy_ms.median_ms),
            compute_copy_gbps: gbps(compute_copy.median_ms),
        });
        for (n, m) in PATTERNS {
            let pattern = Pattern::new(n, m)?;
            let layout = SplitLayout::new(size.0, size.1, pattern)?;
            let mut best: Option<(SplitVariant, Stat, SplitVariant, Stat)> = None;
            let mut seen = Vec::new();
            for side in BLOCK_SIDES {
                let block = Block::fitted(side, side, pattern);
                if seen.contains(&block) {
                    continue;
                }
                seen.push(block);
                let variant = SplitVariant::TwoPass(block);
                let (s, g) = bench.split_gather(&image, &layout, variant)?;
                sweep.push(SweepResult {
                    width: size.0,
                    height: size.1,
                    pattern: pattern.to_string(),
                    block: format!("{}x{}", block.p, block.q),
                    split: s,
                    gather: g,
                });
                let b = best.get_or_insert((variant, s, variant, g));
                if s.median_ms < b.1.median_ms {
                    (b.0, b.1) = (variant, s);
                }
                if g.median_ms < b.3.median_ms {
                    (b.2, b.3) = (variant, g);
                }
            }
            if size == (1024, 1024) {
                continue;
            }
            let one_pass = SplitVariant::OnePass;
            let mut rows = vec![
                (
                    one_pass.name(),
                    (pattern, one_pass, one_pass),
                    bench.split_gather(&image, &layout, one_pass)?,
                ),
                (
                    SplitVariant::Tiled.name(),
                    (pattern, SplitVariant::Tiled, SplitVariant::Tiled),
                    bench.split_gather(&image, &layout, SplitVariant::Tiled)?,
                ),
            ];
            if let Some((sv, s, gv, g)) = best {
                rows.insert(
                    1,
                    (
                        format!("best {} / gather {}", sv.name(), gv.name()),
                        (pattern, sv, gv),
                        (s, g),
                    ),
                );
            }
            let copied = copy.last().context("the copy of this size was measured")?;
            for (variant, setup, times) in rows {
                let r = SplitResult::new(size, variant, setup, times, copied);
                println!("{}", r.line());
                split.push(r);
            }
        }
    }
    // Along the patterns (by pixels per sub-buffer tile) of each size and kind of variant,
    // split and gather apart.
    let mut again = |r: &mut SplitResult| -> Result<()> {
        let size = (r.width, r.height);
        let image = bench.random_texture("gbuffer", size, FORMAT)?;
        let (pattern, sv, gv) = r.setup;
        let layout = SplitLayout::new(size.0, size.1, pattern)?;
        let s = bench.split_gather(&image, &layout, sv)?.0;
        let g = bench.split_gather(&image, &layout, gv)?.1;
        let copied = copy
            .iter()
            .find(|c| c.size == name(size))
            .context("the copy of this size was measured")?;
        *r = SplitResult::new(size, r.variant.clone(), r.setup, (s, g), copied);
        Ok(())
    };
    let sweep_of = |r: &SplitResult| {
        let kind = r.variant.split(' ').next().unwrap_or_default().to_owned();
        ((r.width, r.height, kind), f64::from(r.setup.0.count()))
    };
    let label =
        |r: &SplitResult| format!("{} {} {}", name((r.width, r.height)), r.pattern, r.variant);
    bench::remeasure_outliers(
        &mut split,
        sweep_of,
        |r| r.split.median_ms,
        |r| format!("split {}", label(r)),
        &mut again,
    )?;
    bench::remeasure_outliers(
        &mut split,
        sweep_of,
        |r| r.gather.median_ms,
        |r| format!("gather {}", label(r)),
        &mut again,
    )?;

    // 3: blur (Table 2) and discontinuity buffer.
    let (w, h) = bench::size((1280, 1024));
    let (depth, normals) = scene_gbuffer(w, h)?;
    let [depth_t, normal_t] = upload_depth_normals(&gpu.device, &gpu.queue, &depth, &normals)?;
    let disc_pass = DiscontinuityPass::new(device, &Thresholds::default())?;
    let disc = bench.texture(
        "discontinuities",
        (w, h),
        interleave::gpu::DISCONTINUITY_FORMAT,
    );
    let disc_passes = disc_pass.bind(device, &depth_t, &normal_t, &disc)?;
    let mut discontinuity = vec![(name((w, h)), bench.time_passes(&disc_passes)?)];
    let irr = bench.random_texture("irradiance", (w, h), interleave::gpu::IRRADIANCE_FORMAT)?;
    let scratch = bench.texture("scratch", (w, h), interleave::gpu::IRRADIANCE_FORMAT);
    let out = bench.texture("blurred", (w, h), interleave::gpu::IRRADIANCE_FORMAT);
    {
        let mut e = device.create_command_encoder(&Default::default());
        disc_passes.encode(&mut e, None);
        gpu.queue.submit([e.finish()]);
    }
    let mut blur = Vec::new();
    for kernel in [7, 11, 17] {
        let t = |variant| -> Result<Stat> {
            let pass = BlurPass::new(device, &Blur::new(kernel, variant)?)?;
            bench.time_passes(&pass.bind(device, &irr, &disc, &scratch, &out)?)
        };
        let (plain, fast) = (t(BlurVariant::Plain)?, t(BlurVariant::Fast)?);
        println!(
            "blur {kernel}x{kernel}: plain {:.3} ms, fast {:.3} ms",
            plain.median_ms, fast.median_ms
        );
        blur.push(BlurResult {
            kernel,
            plain,
            fast,
            fast_speedup: plain.median_ms / fast.median_ms,
        });
    }

    // 4: split + shade + gather against the fused indirection.
    let mut shading = Vec::new();
    for size in SIZES.map(bench::size) {
        let (depth, normals) = scene_gbuffer(size.0, size.1)?;
        let [depth_t, normal_t] = upload_depth_normals(&gpu.device, &gpu.queue, &depth, &normals)?;
        let d = bench.texture(
            "discontinuities",
            size,
            interleave::gpu::DISCONTINUITY_FORMAT,
        );
        discontinuity.push((
            name(size),
            bench.time_passes(&disc_pass.bind(device, &depth_t, &normal_t, &d)?)?,
        ));
        for (n, m) in [(4, 4), (8, 6)] {
            let pattern = Pattern::new(n, m)?;
            let layout = SplitLayout::new(size.0, size.1, pattern)?;
            let per_subset = 16;
            let lights: Vec<SubsetLight> = (0..pattern.count() * per_subset)
                .map(|l| {
                    let a = l as f32 * 2.399_963;
                    let z = 1.0 - (l as f32 + 0.5) / (pattern.count() * per_subset) as f32;
                    let r = (1.0 - z * z).sqrt();
                    SubsetLight {
                        direction: [r * a.cos(), z, r * a.sin(), 0.0],
                        color: [0.02, 0.02, 0.02, 0.0],
                    }
                })
                .collect();
            let shade = SubsetShading::new(device, &layout, &lights)?;
            let irr = bench.texture("irradiance", size, interleave::gpu::IRRADIANCE_FORMAT);
            let fused =
                bench.time_passes(&shade.shade_fused(device, &depth_t, &normal_t, &irr)?)?;
            let variant = SplitVariant::Tiled;
            let ds = Splitter::new(device, &layout, variant, gbuffer::LINEAR_DEPTH_FORMAT)?;
            let ns = Splitter::new(device, &layout, variant, gbuffer::NORMAL_FORMAT)?;
            let is = Splitter::new(device, &layout, variant, interleave::gpu::IRRADIANCE_FORMAT)?;
            let (sd, sn, si) = (
                ds.split_texture(device, "sd"),
                ns.split_texture(device, "sn"),
                is.split_texture(device, "si"),
            );
            let passes = ds
                .split(device, &depth_t, &sd)?
                .then(ns.split(device, &normal_t, &sn)?)
                .then(shade.shade_split(device, &sd, &sn, &si)?)
                .then(is.gather(device, &si, &irr)?);
            let (split_path, per_pass) = bench.time(|e, t| passes.encode(e, Some(t)))?;
            println!(
                "shading {} {pattern}, {per_subset} lights/pixel: fused {:.3} ms, split+shade+gather {:.3} ms",
                name(size),
                fused.median_ms,
                split_path.median_ms
            );
            shading.push(ShadingResult {
                width: size.0,
                height: size.1,
                pattern: pattern.to_string(),
                lights_per_pixel: per_subset,
                fused,
                split_path,
                split_path_passes: per_pass,
                split_speedup: fused.median_ms / split_path.median_ms,
            });
        }
    }

    let report = Report {
        header: Header::new(&gpu),
        frames: frames,
        copy,
        split,
        sweep,
        blur_1280x1024: blur,
        discontinuity,
        shading,
    };
    write_report(&bench::out_dir(&args.options.out), &report)
}

/// Figure 5: two-pass split time against block side, one line per pattern.
fn sweep_svg(r: &Report, (w, h): (u32, u32)) -> String {
    let rows: Vec<&SweepResult> = r
        .sweep
        .iter()
        .filter(|s| (s.width, s.height) == (w, h))
        .collect();
    let series = PATTERNS
        .into_iter()
        .map(|(n, m)| {
            let name = format!("{n}x{m}");
            let points = rows
                .iter()
                .filter(|s| s.pattern == name)
                .map(|s| {
                    let side: f64 = s
                        .block
                        .split('x')
                        .next()
                        .and_then(|v| v.parse().ok())
                        .unwrap_or(8.0);
                    (side.log2(), s.split.median_ms)
                })
                .collect();
            bench::chart::Series { name, points }
        })
        .collect();
    bench::chart::LineChart {
        title: format!("Two-pass split, {w}×{h}, 16 B/pixel ({})", r.header.adapter),
        x_label: "block side (pixels, rounded up to the pattern)".into(),
        y_label: "ms".into(),
        x_ticks: BLOCK_SIDES
            .map(|side| (f64::from(side).log2(), side.to_string()))
            .to_vec(),
        series,
    }
    .svg()
}

fn write_report(dir: &std::path::Path, r: &Report) -> Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    let stem = r.header.file_stem("interleave-");
    let base = dir.join(&stem);
    std::fs::write(
        base.with_extension("json"),
        serde_json::to_string_pretty(r)?,
    )?;
    for size in [(1024, 1024), SIZES[1]] {
        std::fs::write(
            dir.join(format!("{stem}-sweep-{}.svg", name(size))),
            sweep_svg(r, size),
        )?;
    }
    let mut md = r.header.markdown("Interleave benchmarks", r.frames);
    md.push_str("## Split and gather (Segovia 2006 §3, §5.1, §5.3)\n\nOne `Rgba32Uint` texture of random texels = a 16-byte/pixel G-buffer. Baselines in the same run: `copy_texture_to_texture` of the same texture, and a compute copy (the one-pass kernel with a 1×1 pattern: textureLoad → textureStore of the same texel). \"% of copy\" = baseline time / pass time (100 % = as fast as the baseline). GB/s counts bytes read + written. The two-pass row uses the fastest block of the sweep below for split and for gather.\n\n");
    let mut copies = bench::Table::new(&[
        "size",
        "copy_texture_to_texture ms (min)",
        "GB/s",
        "compute copy ms (min)",
        "GB/s",
    ]);
    for c in &r.copy {
        copies.row([
            c.size.clone(),
            c.copy_texture_to_texture.to_string(),
            format!("{:.0}", c.copy_gbps),
            c.compute_copy.to_string(),
            format!("{:.0}", c.compute_copy_gbps),
        ]);
    }
    let percent = |f: f64| format!("{:.0} %", 100.0 * f);
    let mut splits = bench::Table::new(&[
        "size",
        "pattern",
        "variant",
        "split ms (min)",
        "GB/s",
        "% of copy",
        "% of compute copy",
        "gather ms (min)",
        "GB/s",
        "% of copy",
        "% of compute copy",
    ]);
    for s in &r.split {
        splits.row([
            format!("{}×{}", s.width, s.height),
            s.pattern.clone(),
            s.variant.clone(),
            s.split.to_string(),
            format!("{:.0}", s.split_gbps),
            percent(s.split_fraction_of_copy),
            percent(s.split_fraction_of_compute_copy),
            s.gather.to_string(),
            format!("{:.0}", s.gather_gbps),
            percent(s.gather_fraction_of_copy),
            percent(s.gather_fraction_of_compute_copy),
        ]);
    }
    let _ = write!(
        md,
        "{copies}{splits}## Two-pass block-size sweep (Figure 5)\n\n![1024×1024 sweep]({stem}-sweep-1024x1024.svg)\n![4K sweep]({stem}-sweep-3840x2160.svg)\n\n"
    );
    let mut sweep = bench::Table::new(&["size", "pattern", "block p×q", "split ms", "gather ms"]);
    for s in &r.sweep {
        sweep.row([
            format!("{}×{}", s.width, s.height),
            s.pattern.clone(),
            s.block.clone(),
            format!("{:.3}", s.split.median_ms),
            format!("{:.3}", s.gather.median_ms),
        ]);
    }
    let mut blur =
        bench::Table::new(&["kernel", "plain ms (min)", "fast ms (min)", "fast speed-up"]);
    for b in &r.blur_1280x1024 {
        blur.row([
            format!("{0}×{0}", b.kernel),
            b.plain.to_string(),
            b.fast.to_string(),
            format!("{:.2}×", b.fast_speedup),
        ]);
    }
    let mut discontinuity = bench::Table::new(&["size", "ms (min)"]);
    for (s, d) in &r.discontinuity {
        discontinuity.row([s.clone(), d.to_string()]);
    }
    let mut shading = bench::Table::new(&[
        "size",
        "pattern",
        "fused ms (min)",
        "split path ms (min)",
        "passes (median ms)",
        "split speed-up",
    ]);
    for s in &r.shading {
        let passes: Vec<String> = s
            .split_path_passes
            .iter()
            .map(|(n, ms)| format!("{n} {ms:.3}"))
            .collect();
        shading.row([
            format!("{}×{}", s.width, s.height),
            s.pattern.clone(),
            s.fused.to_string(),
            s.split_path.to_string(),
            passes.join(", "),
            format!("{:.2}×", s.split_speedup),
        ]);
    }
    let _ = write!(
        md,
        "{sweep}## Edge-aware blur at 1280×1024 (Table 2)\n\nTwo separable passes on an `Rgba16Float` irradiance buffer guided by the discontinuity buffer of a rendered scene.\n\n{blur}## Discontinuity buffer\n\n{discontinuity}## What splitting buys: split + shade + gather against the fused indirection (§3.1)\n\nEach pixel shades the 16 directional lights of its sub-buffer's subset. Split path: split linear depth and normals (tiled), shade the split G-buffer, gather the irradiance. Fused: one pass in sub-buffer order reading and writing the interleaved buffers by strided address.\n\n{shading}"
    );
    std::fs::write(base.with_extension("md"), md)?;
    println!("wrote {}.{{md,json}} and the sweep plots", base.display());
    Ok(())
}
