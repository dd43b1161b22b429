//! `normal-map-interleaving`: Segovia et al. 2006, Fig. 7 on the toolkit — "the surface details
//! brought by a normal map are conserved with interleaved sampling and [the] fast Gaussian
//! blur … They disappear with sub-sampling." On Sponza with procedural normal-mapped materials
//! (`scene::dress_procedurally`), lit by its default sun's VPLs, the CPU reference path
//! computes the indirect light (the VPLs' diffuse and glossy light, composed with the
//! G-buffer's materials, no direct light) three ways:
//! - the non-interleaved reference: every VPL at every pixel;
//! - interleaved 4 × 4 with the discontinuity buffer and the 5 × 5 fast blur (the defaults);
//! - sub-sampling: every VPL at every 4th pixel along x and y (the reference rendered at a
//!   quarter of the size), its irradiance bilinearly upsampled — the same shading work as
//!   interleaving;
//!
//! and the ground truth: the path tracer's one-bounce light alone (`min_bounces = max_bounces
//! = 1`, rays through the pixel centres as the rasteriser samples), what the VPLs approximate.
//!
//! It prints each one's relative RMS error against the non-interleaved reference and against
//! the path tracer, overall and on the pixels whose normal the normal map tilts (more than 10°
//! off the interpolated one), and ꟻLIP on the images as shown (one exposure for all), and
//! writes the images side by side (`normal-map-interleaving.png`: path tracer | reference |
//! interleaved | sub-sampled).

use std::path::PathBuf;

use anyhow::Result;
use clap::Parser;
use gbuffer::{Frame, Image};
use glam::Vec3;
use instant_radiosity::{IndirectConfig, Interleaving, vpl};
use scene::reference::ReferenceConfig;

/// Reproduces Segovia 2006 Fig. 7.
#[derive(Parser, Debug)]
struct Args {
    #[command(flatten)]
    scene: bench::SceneOption,
    /// Output folder.
    #[arg(long, default_value = "out")]
    out: PathBuf,
    /// Image width (height 9/16 of it; a multiple of 4).
    #[arg(long, default_value_t = 480)]
    width: u32,
    /// VPLs.
    #[arg(long, default_value_t = 512)]
    vpls: usize,
    /// Keep the scene's own materials (no procedural normal maps), for comparison.
    #[arg(long)]
    plain: bool,
    /// Path-tracer samples per pixel of the ground truth (0 leaves it out).
    #[arg(long, default_value_t = 256)]
    spp: u32,
}

/// The indirect light (diffuse and glossy) of `scene` at `(w, h)` with `config`, the VPLs'
/// diffuse and specular irradiance images it was composed from, and the G-buffer.
fn indirect(
    scene: &scene::Scene,
    camera: &scene::Camera,
    (w, h): (u32, u32),
    set: &vpl::VplSet,
    config: &IndirectConfig,
) -> Result<(Image<[f32; 4]>, [Image<[f32; 4]>; 2], gbuffer::GBuffer)> {
    let gb = gbuffer::cpu::rasterize(scene, camera, w, h)?.gbuffer;
    let stages = instant_radiosity::cpu::indirect(&gb, &Frame::new(camera, w, h), set, config)?;
    let (diffuse, specular) = stages.result();
    let irradiance = [diffuse.clone(), specular.clone()];
    Ok((compose(&gb, &irradiance), irradiance, gb))
}

/// The radiance the composition makes of the indirect irradiance images alone.
fn compose(gb: &gbuffer::GBuffer, [diffuse, specular]: &[Image<[f32; 4]>; 2]) -> Image<[f32; 4]> {
    let none = Image::filled(gb.width(), gb.height(), Vec3::ZERO);
    pipeline::cpu::composition(gb, (&none, &none), Some((diffuse, specular)), Vec3::ZERO)
}

/// `low` (a quarter of the size) bilinearly upsampled to `(w, h)`, texel centres aligned.
fn upsample(low: &Image<[f32; 4]>, (w, h): (u32, u32)) -> Image<[f32; 4]> {
    let (lw, lh) = (low.width() as f32, low.height() as f32);
    let at = |x: i64, y: i64| {
        let p = low.get(x.clamp(0, lw as i64 - 1) as u32, y.clamp(0, lh as i64 - 1) as u32);
        Vec3::new(p[0], p[1], p[2])
    };
    let pixels = (0..w * h)
        .map(|i| {
            let u = ((i % w) as f32 + 0.5) / w as f32 * lw - 0.5;
            let v = ((i / w) as f32 + 0.5) / h as f32 * lh - 0.5;
            let (x, y) = (u.floor() as i64, v.floor() as i64);
            let (fx, fy) = (u - u.floor(), v - v.floor());
            let c =
                at(x, y).lerp(at(x + 1, y), fx).lerp(at(x, y + 1).lerp(at(x + 1, y + 1), fx), fy);
            [c.x, c.y, c.z, 1.0]
        })
        .collect();
    Image::from_vec(w, h, pixels).expect("w × h pixels")
}

/// Relative RMS error of `test` against `reference` over the pixels `keep` selects.
fn relative_rms(reference: &Image<[f32; 4]>, test: &Image<[f32; 4]>, keep: &[bool]) -> f64 {
    let (mut err, mut sum) = (0.0f64, 0.0f64);
    for ((r, t), &k) in reference.pixels().iter().zip(test.pixels()).zip(keep) {
        if k {
            for c in 0..3 {
                err += f64::from(r[c] - t[c]).powi(2);
                sum += f64::from(r[c]).powi(2);
            }
        }
    }
    (err / sum.max(1e-30)).sqrt()
}

fn main() -> Result<()> {
    let args = Args::parse_from(bench::args());
    let (path, mut scene, camera) = args.scene.load_viewed()?;
    if !args.plain {
        scene::dress_procedurally(&mut scene);
    }
    let w = args.width / 4 * 4;
    let h = (w * 9 / 16) / 4 * 4;
    let config = IndirectConfig::new(scene.bounds());
    let bvh = scene::Bvh::build(&scene);
    let set = vpl::generate_from_primary(&scene, &bvh, args.vpls, config.subsets(), 1)?;
    let reference_config =
        IndirectConfig { interleaving: Interleaving::Reference, blur: None, ..config.clone() };
    let (reference, _, gb) = indirect(&scene, &camera, (w, h), &set, &reference_config)?;
    let (interleaved, _, _) = indirect(&scene, &camera, (w, h), &set, &config)?;
    let (_, [low_d, low_s], _) =
        indirect(&scene, &camera, (w / 4, h / 4), &set, &reference_config)?;
    let subsampled = compose(&gb, &[upsample(&low_d, (w, h)), upsample(&low_s, (w, h))]);
    let truth = (args.spp > 0)
        .then(|| {
            let config = ReferenceConfig {
                min_bounces: 1,
                max_bounces: 1,
                jitter: false,
                ..Default::default()
            };
            let (lights, _, _) = vpl::primary_lights(&scene);
            bench::path_traced(&scene, &lights, camera, (w, h), config, args.spp)
        })
        .transpose()?;

    // Pixels whose shading normal the normal map tilts by more than 10° from the flat one.
    let mut flat = scene.clone();
    for m in &mut flat.materials {
        m.normal_texture = None;
    }
    let flat_gb = gbuffer::cpu::rasterize(&flat, &camera, w, h)?.gbuffer;
    let covered: Vec<bool> =
        gb.material.pixels().iter().map(|&m| m != gbuffer::NO_MATERIAL).collect();
    let tilted: Vec<bool> = (0..(w * h) as usize)
        .map(|i| {
            let a = gbuffer::normal::unpack_octahedral(gb.normal.pixels()[i]);
            let b = gbuffer::normal::unpack_octahedral(flat_gb.normal.pixels()[i]);
            covered[i] && gbuffer::normal::angle_deg(a, b) > 10.0
        })
        .collect();
    println!(
        "{} with {}, {w}×{h}, {} VPLs; {:.1} % of the covered pixels tilted > 10° by the normal map",
        path.display(),
        if args.plain { "its own materials" } else { "procedural normal maps" },
        set.vpls.len(),
        100.0 * tilted.iter().filter(|&&t| t).count() as f64
            / covered.iter().filter(|&&c| c).count().max(1) as f64
    );
    // One exposure for all three: the reference's 99th percentile maps to 0.9.
    let mut lum: Vec<f32> = reference.pixels().iter().map(|p| p[0].max(p[1]).max(p[2])).collect();
    lum.sort_by(f32::total_cmp);
    let scale = 0.9 / lum[lum.len() * 99 / 100].max(1e-6);
    let shown =
        |img: &Image<[f32; 4]>| img.map(|p| [p[0] * scale, p[1] * scale, p[2] * scale, 1.0]);
    // Left to right in the picture: the path tracer (when traced), then the three VPL images.
    let mut shown_images: Vec<(&str, &Image<[f32; 4]>)> =
        truth.iter().map(|t| ("path tracer", t)).collect();
    shown_images.extend([
        ("non-interleaved", &reference),
        ("interleaved 4×4 + blur", &interleaved),
        ("sub-sampled 4×4 + bilinear", &subsampled),
    ]);
    let references = shown_images[..shown_images.len() - 2].to_vec();
    for &(name, image) in &shown_images[references.len() - 1..] {
        for &(against, truth) in &references {
            if std::ptr::eq(truth, image) {
                continue;
            }
            println!(
                "{name:28} vs the {against:15}: relative RMS {:.3} overall, {:.3} on normal-mapped detail; ꟻLIP {:.3}",
                relative_rms(truth, image, &covered),
                relative_rms(truth, image, &tilted),
                bench::quality(&shown(truth), &shown(image)).flip_mean
            );
        }
    }
    let shown_all: Vec<_> = shown_images.iter().map(|(_, img)| shown(img)).collect();
    let row: Vec<[f32; 4]> = (0..h)
        .flat_map(|y| shown_all.iter().flat_map(move |img| (0..w).map(move |x| img.get(x, y))))
        .collect();
    std::fs::create_dir_all(&args.out)?;
    let out = args.out.join("normal-map-interleaving.png");
    Image::from_vec(shown_images.len() as u32 * w, h, row)?.write_png(&out)?;
    let names: Vec<_> = shown_images.iter().map(|(n, _)| *n).collect();
    println!("wrote {} ({})", out.display(), names.join(" | "));
    Ok(())
}
