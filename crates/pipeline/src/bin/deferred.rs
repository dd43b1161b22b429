//! `deferred`: renders a scene with classic deferred shading (G-buffer → light accumulation
//! → composition) on the GPU, or on the CPU when asked or when no GPU adapter exists, writes
//! `render.png` and `render.exr`, and prints the milliseconds of each pass.

use std::path::PathBuf;

use anyhow::{Context, Result, bail};
use clap::Parser;
use glam::Vec3;
use pipeline::{DEFAULT_AMBIENT, Rendered};
use scene::{Light, Scene};

/// Classic deferred shading of point, spot and directional lights.
///
/// With no arguments, renders the built-in Cornell box to out/render.png and out/render.exr.
#[derive(Parser, Debug)]
#[command(version, about, long_about = None)]
struct Args {
    /// Scene file (.gltf, .glb, .obj, .ply); default: the built-in scene named by --builtin.
    #[arg(long)]
    scene: Option<PathBuf>,
    /// Built-in scene when no --scene is given: cornell, spheres or checkerboard.
    #[arg(long, default_value = "cornell")]
    builtin: String,
    /// Image size as WIDTHxHEIGHT.
    #[arg(long, default_value = "1024x768", value_parser = parse_size)]
    size: (u32, u32),
    /// Replace the scene's lights with N point lights scattered through its bounds (seeded).
    #[arg(long)]
    lights: Option<usize>,
    /// Add a light: point:X,Y,Z,RADIUS[,R,G,B,I] | spot:X,Y,Z,DX,DY,DZ,RADIUS,INNER°,OUTER°[,R,G,B,I] | dir:DX,DY,DZ[,R,G,B,I].
    #[arg(long = "light")]
    extra_lights: Vec<Light>,
    /// Output folder for render.png and render.exr.
    #[arg(long, default_value = "out")]
    out: PathBuf,
    /// Render on the CPU reference path even when a GPU exists.
    #[arg(long)]
    cpu: bool,
    /// Camera position X,Y,Z (default: the scene's camera, else one framing the scene).
    #[arg(long, value_parser = parse_vec3)]
    eye: Option<Vec3>,
    /// Point the camera looks at, X,Y,Z.
    #[arg(long, value_parser = parse_vec3)]
    target: Option<Vec3>,
    /// Vertical field of view in degrees.
    #[arg(long)]
    fov: Option<f32>,
    /// Ambient light R,G,B (linear).
    #[arg(long, value_parser = parse_vec3)]
    ambient: Option<Vec3>,
}

fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or("expected WIDTHxHEIGHT, e.g. 1920x1080")?;
    let parse = |v: &str| {
        v.trim()
            .parse::<u32>()
            .map_err(|_| format!("{v:?} is not a positive integer"))
    };
    let (w, h) = (parse(w)?, parse(h)?);
    if w == 0 || h == 0 || w > gbuffer::MAX_SIZE || h > gbuffer::MAX_SIZE {
        return Err(format!(
            "size must be between 1 and {} on each side",
            gbuffer::MAX_SIZE
        ));
    }
    Ok((w, h))
}

fn parse_vec3(s: &str) -> Result<Vec3, String> {
    let v: Vec<f32> = s
        .split(',')
        .map(|c| {
            c.trim()
                .parse::<f32>()
                .map_err(|_| format!("{c:?} is not a number"))
        })
        .collect::<Result<_, _>>()?;
    match v[..] {
        [x, y, z] if v.iter().all(|c| c.is_finite()) => Ok(Vec3::new(x, y, z)),
        _ => Err("expected three finite numbers X,Y,Z".into()),
    }
}

fn load_scene(args: &Args) -> Result<Scene> {
    let Some(path) = &args.scene else {
        return Ok(match args.builtin.as_str() {
            "cornell" => scene::cornell_box(),
            "spheres" => scene::spheres_on_plane(8),
            "checkerboard" => scene::checkerboard(),
            other => bail!("unknown built-in scene {other:?} (cornell, spheres, checkerboard)"),
        });
    };
    let bar = indicatif::ProgressBar::new(1).with_message(format!("loading {}", path.display()));
    bar.set_style(
        indicatif::ProgressStyle::with_template("{spinner} {msg} [{bar:30}] {pos}/{len} meshes")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    bar.enable_steady_tick(std::time::Duration::from_millis(100));
    let scene = Scene::load_with_progress(path, &mut |done, total| {
        bar.set_length(total as u64);
        bar.set_position(done as u64);
    });
    bar.finish_and_clear();
    Ok(scene?)
}

fn main() -> Result<()> {
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or("warn")).init();
    let args = Args::parse();
    let scene = load_scene(&args)?;
    let (width, height) = args.size;

    let mut camera = scene.camera_or_framed();
    if let Some(eye) = args.eye {
        camera.eye = eye;
    }
    if let Some(target) = args.target {
        camera.target = target;
    }
    if let Some(fov) = args.fov {
        camera.fov_y = fov.to_radians();
    }
    if args.eye.is_some() || args.target.is_some() {
        camera.fit_planes(scene.bounds());
    }
    let mut lights = match args.lights {
        Some(n) => scene::scatter_point_lights(scene.bounds(), n, 1),
        None => scene.lights.clone(),
    };
    lights.extend(args.extra_lights.iter().copied());
    let ambient = args.ambient.unwrap_or(DEFAULT_AMBIENT);

    let gpu = if args.cpu {
        None
    } else {
        match gpu::Gpu::from_env() {
            Ok(gpu) => Some(gpu),
            Err(e) => {
                eprintln!("no GPU: {e}; rendering on the CPU");
                None
            }
        }
    };
    let (device, rendered): (String, Rendered) = match &gpu {
        Some(gpu) => {
            let mut renderer =
                pipeline::gpu::GpuRenderer::new(gpu, &scene, &lights, width, height)?;
            renderer.render(gpu, &camera, ambient)?; // warm-up: first use of pipelines and caches
            (
                format!("GPU {}", gpu.describe()),
                renderer.render(gpu, &camera, ambient)?,
            )
        }
        None => (
            "CPU (reference path, rayon)".into(),
            pipeline::cpu::render(&scene, &camera, &lights, width, height, ambient)?,
        ),
    };

    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("cannot create {}", args.out.display()))?;
    let png = args.out.join("render.png");
    let exr = args.out.join("render.exr");
    rendered.image.write_png(&png)?;
    rendered.image.write_exr(&exr)?;

    println!("device:  {device}");
    println!(
        "scene:   {} triangles, {} lights, {width}x{height}",
        scene.triangle_count(),
        lights.len()
    );
    println!("wrote:   {} and {}", png.display(), exr.display());
    println!();
    println!("{:<20} {:>10}", "pass", "ms");
    for t in &rendered.timings {
        println!("{:<20} {:>10.3}", t.name, t.ms);
    }
    if rendered.timings.is_empty() {
        println!("(this GPU has no timestamp queries: no pass times)");
    } else {
        println!(
            "{:<20} {:>10.3}",
            "total",
            rendered.timings.iter().map(|t| t.ms).sum::<f64>()
        );
    }
    Ok(())
}
