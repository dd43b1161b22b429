//! `materials-gpu`: what the glTF material costs the G-buffer pass (issue 22). In one run, the
//! same geometry and camera with and without textures: Dabrovic Sponza as shipped (factors
//! only) against the same Sponza with its procedural normal-mapped materials
//! (`scene::dress_procedurally`: base colour, normal map, occlusion), filtered with anisotropy
//! 16 and trilinearly; and DamagedHelmet with its five textures against its factors alone.
//! Each is timed as the renderer runs it: z-prepass + G-buffer pass (begin of one to end of
//! the other), at 1920×1080 and 3840×2160. Also the load-time cost of the mip chains: the
//! wall time of uploading the textures and drawing their mips, waited for.

use anyhow::Result;
use bench::{Header, Stat};
use clap::Parser;
use gbuffer::{
    Frame, TextureOptions,
    gpu::{GBufferPass, GBufferTargets, GpuScene, MaterialTextures},
};
use glam::Vec3;
use gpu::{Gpu, PassTimer};
use scene::{Camera, Scene};
use serde::Serialize;

/// Texture cost of the G-buffer; writes docs/bench/materials-<adapter>-<date>.{md,json}.
#[derive(Parser, Debug)]
#[command(version, about)]
struct Args {
    #[command(flatten)]
    options: bench::Options,
}

#[derive(Serialize)]
struct Row {
    scene: String,
    variant: String,
    width: u32,
    height: u32,
    /// Z-prepass + G-buffer pass.
    gbuffer: Stat,
    /// Its median over the untextured variant's in the same run.
    ratio_to_untextured: f64,
}

#[derive(Serialize)]
struct Upload {
    scene: String,
    textures: usize,
    texels: u64,
    /// Wall time of uploading level 0 and drawing every mip level, waited for.
    ms: f64,
}

#[derive(Serialize)]
struct Report {
    #[serde(flatten)]
    header: Header,
    frames: u32,
    rows: Vec<Row>,
    uploads: Vec<Upload>,
}

/// The scene's factors alone: every texture reference removed.
fn untextured(scene: &Scene) -> Scene {
    let mut s = scene.clone();
    for m in &mut s.materials {
        m.base_color_texture = None;
        m.metallic_roughness_texture = None;
        m.normal_texture = None;
        m.occlusion_texture = None;
        m.emissive_texture = None;
    }
    s
}

fn time_gbuffer(
    gpu: &Gpu,
    pass: &GBufferPass,
    scene: &GpuScene,
    camera: &Camera,
    (w, h): (u32, u32),
    frames: u32,
) -> Result<Stat> {
    let targets = GBufferTargets::new(&gpu.device, w, h)?;
    pass.write_frame(&gpu.queue, &Frame::new(camera, w, h));
    let timer = PassTimer::new(&gpu.device, 2);
    Ok(bench::timing::time_encoded(
        gpu,
        &timer,
        frames,
        true,
        &|encoder, timer| {
            pass.encode_with_prepass(
                encoder,
                scene,
                &targets,
                timer.render_pass("z-prepass"),
                timer.render_pass("gbuffer"),
            )
        },
    )?)
}

fn upload_time(gpu: &Gpu, name: &str, scene: &Scene) -> Result<Upload> {
    let start = std::time::Instant::now();
    let _store = MaterialTextures::upload(&gpu.device, &gpu.queue, scene, &Default::default())?;
    gpu.wait()?;
    Ok(Upload {
        scene: name.into(),
        textures: scene.textures.len(),
        texels: scene
            .textures
            .iter()
            .map(|t| u64::from(t.width) * u64::from(t.height))
            .sum(),
        ms: start.elapsed().as_secs_f64() * 1e3,
    })
}

fn main() -> Result<()> {
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or("warn")).init();
    let args = Args::parse_from(bench::args());
    let gpu = args.options.gpu()?;
    let frames = args.options.frames(100);
    let pass = GBufferPass::new(&gpu.device)?;

    let (sponza, sponza_camera) = bench::fixture("sponza/dabrovic/sponza.gltf")?;
    let mut dressed = sponza.clone();
    scene::dress_procedurally(&mut dressed);
    let helmet = Scene::load(
        &scene::shared_fixtures()
            .ok_or_else(|| anyhow::anyhow!("../shared/fixtures not found"))?
            .join("gltf/DamagedHelmet/DamagedHelmet.glb"),
    )?;
    let helmet_camera = Camera {
        eye: Vec3::new(1.6, 0.6, 2.6),
        target: Vec3::ZERO,
        up: Vec3::Y,
        fov_y: 45f32.to_radians(),
        near: 0.05,
        far: 20.0,
    };
    let trilinear = TextureOptions { max_anisotropy: 1 };
    let variants: [(&str, &str, Scene, &Camera, TextureOptions); 5] = [
        (
            "Sponza",
            "factors only",
            untextured(&sponza),
            &sponza_camera,
            Default::default(),
        ),
        (
            "Sponza",
            "procedural textures, anisotropy 16",
            dressed.clone(),
            &sponza_camera,
            Default::default(),
        ),
        (
            "Sponza",
            "procedural textures, trilinear",
            dressed.clone(),
            &sponza_camera,
            trilinear,
        ),
        (
            "DamagedHelmet",
            "factors only",
            untextured(&helmet),
            &helmet_camera,
            Default::default(),
        ),
        (
            "DamagedHelmet",
            "five textures, anisotropy 16",
            helmet.clone(),
            &helmet_camera,
            Default::default(),
        ),
    ];
    let uploaded = variants
        .iter()
        .map(|(_, _, scene, _, options)| {
            GpuScene::upload_with(&gpu.device, &gpu.queue, scene, &pass, options)
        })
        .collect::<Result<Vec<_>, _>>()?;
    let mut rows: Vec<Row> = Vec::new();
    for size in [(1920, 1080), (3840, 2160)].map(bench::size) {
        for ((name, variant, _, camera, _), uploaded) in variants.iter().zip(&uploaded) {
            let t = time_gbuffer(&gpu, &pass, uploaded, camera, size, frames)?;
            let base = rows
                .iter()
                .find(|r| r.scene == *name && r.width == size.0 && r.variant == "factors only")
                .map_or(t.median_ms, |r| r.gbuffer.median_ms);
            println!(
                "{name} {variant} {}x{}: {:.3} ms (min {:.3}), ×{:.2} untextured",
                size.0,
                size.1,
                t.median_ms,
                t.min_ms,
                t.median_ms / base
            );
            rows.push(Row {
                scene: (*name).into(),
                variant: (*variant).into(),
                width: size.0,
                height: size.1,
                ratio_to_untextured: t.median_ms / base,
                gbuffer: t,
            });
        }
    }
    let uploads = vec![
        upload_time(&gpu, "Sponza, procedural textures", &dressed)?,
        upload_time(&gpu, "DamagedHelmet", &helmet)?,
    ];
    let header = Header::new(&gpu);
    let mut md = header.markdown("The glTF material in the G-buffer", frames);
    md.push_str(
        "Z-prepass + G-buffer pass (as the renderer runs them), each textured variant against \
         the same geometry and camera with its material factors only, in the same run. \
         Sponza's textures are the procedural ones of `scene::dress_procedurally` (128² brick \
         and tile base colour, normal map, occlusion); DamagedHelmet's its five 2048² ones.\n\n\
         | scene | material | size | ms (min) | × factors only |\n|---|---|---|---|---|\n",
    );
    for r in &rows {
        md.push_str(&format!(
            "| {} | {} | {}×{} | {:.3} ({:.3}) | {:.2} |\n",
            r.scene,
            r.variant,
            r.width,
            r.height,
            r.gbuffer.median_ms,
            r.gbuffer.min_ms,
            r.ratio_to_untextured
        ));
    }
    md.push_str("\nLoad time of the textures (upload of level 0 and the mip chains drawn on the GPU, wall clock, waited for):\n\n| scene | textures | texels | ms |\n|---|---|---|---|\n");
    for u in &uploads {
        md.push_str(&format!(
            "| {} | {} | {} | {:.1} |\n",
            u.scene, u.textures, u.texels, u.ms
        ));
    }
    let report = Report {
        header,
        frames,
        rows,
        uploads,
    };
    args.options
        .write_report(&report.header, "materials-", &report, &md)
}
