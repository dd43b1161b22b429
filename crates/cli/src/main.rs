//! `deferred`: renders a scene with deferred shading (G-buffer → light accumulation: brute
//! force, light volumes, tiled, tiled with normal cones, tiled with slice masks or clustered → composition), optionally with one-bounce indirect light from VPLs shaded with
//! interleaved sampling (Segovia 2006: BS → SNSM → BG → DB → B), on the GPU, or on the CPU
//! when asked or when no GPU adapter exists; writes `render.png` and `render.exr` and prints
//! the milliseconds of each pass (per million fragments too, like the paper's Table 3).

use std::path::PathBuf;

use anyhow::{Context, Result, bail};
use clap::Parser;
use gbuffer::gpu::visibility::ResolvePath;
use glam::Vec3;
use instant_radiosity::{
    IndirectConfig, IndirectStages, Interleaving,
    shadows::{ShadowConfig, VplShadows},
    vpl,
};
use interleave::{Block, Blur, BlurVariant, Pattern, SplitVariant};
use pipeline::{DEFAULT_AMBIENT, PassTiming, Rendered, sequence};
use scene::{Light, Scene};

mod view;

/// Deferred shading of point, spot, hemispherical and directional lights, with optional
/// instant-radiosity indirect light shaded by interleaved sampling.
///
/// With no arguments, renders the built-in Cornell box to out/render.png and out/render.exr.
/// A scene without punctual lights is lit by its emissive meshes (as hemispherical lights),
/// or else by a default sun.
#[derive(Parser, Debug)]
#[command(version, about, long_about = None, args_conflicts_with_subcommands = true)]
#[command(args_override_self = true)]
#[command(group(clap::ArgGroup::new("seeded").args(["vpls", "reference"]).multiple(true)))]
struct Args {
    /// A command other than rendering.
    #[command(subcommand)]
    command: Option<Command>,
    /// Scene file (.gltf, .glb, .obj, .ply); default: the built-in scene named by --builtin.
    #[arg(long)]
    scene: Option<PathBuf>,
    /// Built-in scene when no --scene is given: cornell, spheres, checkerboard, gallery (the
    /// glTF material's parts, one sphere each), mirrors (64 mirror and glass spheres in the Cornell box,
    /// for --reflections), or the light-culling scenes of Ishmukhametov 2013 §4.2:
    /// walls-test1 .. walls-test4.
    #[arg(long, default_value = "cornell")]
    builtin: String,
    /// Image size as WIDTHxHEIGHT.
    #[arg(long, default_value = "1024x768", value_parser = parse_size)]
    size: (u32, u32),
    /// Replace the scene's lights with N point lights scattered through its bounds (seeded);
    /// at most 2^21 (64-byte lights in wgpu's default 128 MiB storage binding).
    #[arg(long, value_parser = parse_light_count)]
    lights: Option<usize>,
    /// Light accumulation: brute, tiled, tiled-cones (tiled with normal-cone back-face
    /// culling), tiled-slices (tile lists with depth-slice masks), clustered (per-cluster
    /// lists after Olsson 2012), volumes (traditional deferred shading: instanced light
    /// volumes, additive blending; the GPU needs FLOAT32_BLENDABLE), or forward (Forward+:
    /// the tiles' lists light the scene drawn again, and alpha-blended materials are blended
    /// over the frame back to front instead of dithered; not with --ssaa), or light-prepass
    /// (deferred lighting: a light buffer with monochrome specular, then a second geometry pass
    /// applying the materials — a comparator; not with --ssaa).
    #[arg(long, default_value = "tiled")]
    shading: pipeline::ShadingMethod,
    /// Alpha-blended materials: dithered into the G-buffer, or forward (blended over the frame
    /// back to front, lit from Forward+ lists; the GPU needs FLOAT32_BLENDABLE; not with --ssaa
    /// or --shading light-prepass). --shading forward always blends them forward.
    #[arg(long, default_value = "dithered")]
    blend: gbuffer::gpu::BlendedSurfaces,
    /// Tile side in pixels for the tiled and clustered light accumulation: 8, 16 or 32.
    #[arg(long, default_value_t = 16)]
    tile: u32,
    /// How the tiled and clustered light accumulation finds each tile's lights: tree (through
    /// a light hierarchy, Morton-ordered groups of 32) or flat (every light per tile, as the
    /// thesis); the same lists either way.
    #[arg(long, default_value = "tree")]
    light_search: pipeline::LightSearch,
    /// Cull lights against the view frustum on the CPU before the light accumulation
    /// (Ishmukhametov 2013 §4.1).
    #[arg(long)]
    frustum_cull: bool,
    /// Write the per-tile light counts as heatmap.png (tiled and clustered shading).
    #[arg(long)]
    heatmap: bool,
    /// Light count shown white in the heatmap (default: the frame's largest count).
    #[arg(long)]
    heatmap_max: Option<u32>,
    /// Add a light: point:X,Y,Z,RADIUS[,R,G,B,I] | spot:X,Y,Z,DX,DY,DZ,RADIUS,INNER°,OUTER°[,R,G,B,I] | hemi:X,Y,Z,DX,DY,DZ,RADIUS[,R,G,B,I] | dir:DX,DY,DZ[,R,G,B,I].
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
    /// Vertical field of view in degrees, 0.1 to 179.
    #[arg(long, value_parser = parse_fov)]
    fov: Option<f32>,
    /// Ambient light R,G,B (linear); default 0.03, or 0 with --vpls.
    #[arg(long, value_parser = parse_vec3)]
    ambient: Option<Vec3>,
    /// Add one-bounce indirect light from about N VPLs (instant radiosity, 1 to 16384),
    /// rounded to a multiple of the sub-buffer count.
    #[arg(long, value_parser = parse_vpl_count)]
    vpls: Option<usize>,
    /// With --vpls: bounces of indirect light the VPLs carry (photons continue by Russian
    /// roulette and place a VPL at every later hit; the VPL count stays N).
    #[arg(long, value_name = "B", default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=64))]
    vpl_bounces: u32,
    /// Interleaved sampling pattern NxM: one VPL subset per sub-buffer.
    #[arg(long, default_value = "4x4", requires = "vpls")]
    pattern: Pattern,
    /// Edge-aware blur kernel size (odd, 5 to 17); 0 turns the blur off.
    #[arg(long, default_value_t = 5, requires = "vpls")]
    blur: u32,
    /// Use the plain blur (one fetch per tap) instead of the fast bilinear one.
    #[arg(long, requires = "vpls")]
    plain_blur: bool,
    /// How the shading is interleaved: fused (no split/gather passes), tiled, one-pass or
    /// two-pass (the paper's split → shade → gather).
    #[arg(long, default_value = "fused", requires = "vpls")]
    interleaving: String,
    /// Shade every VPL at every pixel (the non-interleaved reference).
    #[arg(long, requires = "vpls")]
    no_interleave: bool,
    /// Render only the indirect light (no direct light, no ambient).
    #[arg(long)]
    indirect_only: bool,
    /// Write every stage: G-buffer channels, the split buffer, irradiance before and after
    /// the blur, the discontinuity buffer, the final image.
    #[arg(long)]
    dump_stages: bool,
    /// Seed of the VPL sampling (with --vpls) or of the path tracer (with --reference).
    #[arg(long, default_value_t = 1, requires = "seeded")]
    seed: u64,
    /// Exposure compensation of render.png in stops (render.exr stays linear radiance).
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    exposure: f32,
    /// Also expose render.png automatically: the frame's log-average luminance maps to 0.18
    /// (Reinhard et al. 2002), on the GPU where the frame is rendered there.
    #[arg(long)]
    auto_exposure: bool,
    /// Tone curve of render.png: aces (Hill's fitted ACES RRT + sRGB ODT) or clamp.
    #[arg(long, default_value = "aces")]
    tone_map: pipeline::output::ToneMapper,
    /// Replace the scene's materials with procedural normal-mapped ones (brick walls, floor
    /// tiles; `scene::dress_procedurally`), e.g. for the untextured Sponza.
    #[arg(long)]
    procedural_materials: bool,
    /// Largest anisotropy of the texture filter (1 = trilinear .. 16).
    #[arg(long, default_value_t = 16, value_parser = clap::value_parser!(u32).range(1..=16))]
    anisotropy: u32,
    /// Distance under which a VPL's 1/d² is clamped (default: 2 % of the scene diagonal).
    #[arg(long, requires = "vpls")]
    vpl_clamp: Option<f32>,
    /// Shadow maps for every direct light: RES×RES texels per view (spot: one view, point:
    /// six cube faces, hemispherical: five, directional: four cascades); with --cpu their
    /// depth is ray-cast through every texel (slow at large RES).
    #[arg(long, value_name = "RES", value_parser = clap::value_parser!(u32).range(8..=16384))]
    shadows: Option<u32>,
    /// ManyLoD shadows for the point, spot and hemispherical lights instead (GPU only;
    /// Holländer 2013 §3.6 for many lights): TILE×TILE paraboloid views (one per spot, two per
    /// point light) cut and splatted from 2^20 surfels, one pass for all lights; directional
    /// lights keep --shadows' cascades.
    #[arg(long, value_name = "TILE", value_parser = clap::value_parser!(u32).range(4..=256))]
    manylod_shadows: Option<u32>,
    /// Exact hard shadows for every direct light instead of maps: a ray per pixel and light
    /// through a BVH of the scene's triangles, as the path tracer's shadow rays (GPU only).
    #[arg(long, conflicts_with_all = ["shadows", "manylod_shadows"])]
    ray_shadows: bool,
    /// Give back the light the VPL clamp takes (Kollig & Keller 2004's bias compensation,
    /// `instant_radiosity::near_field`): a ray of the clamp's length per pixel, the lights and
    /// 64 VPLs at its hit (GPU only; needs --vpls).
    #[arg(long, requires = "vpls")]
    near_field: bool,
    /// Stand in for each emissive mesh with N hemispherical lights spread over its area
    /// (with --shadows they draw its penumbrae); default 1, at its centroid.
    #[arg(long, value_name = "N", default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=4096))]
    area_samples: u32,
    /// VPL visibility from per-VPL shadow maps in an atlas (GPU only): `manylod` (Holländer
    /// 2013 §3.6: a many-view LoD cut of 2^20 surfels per VPL, incremental after the first
    /// frame), `ism` (imperfect shadow maps: 8 k random surfels per VPL), `ssm` (exact: every
    /// VPL's hemicube rasterised, Segovia 2006 §4.3; its cost grows with the triangles) or
    /// `none` (VPLs light through walls). Default `auto`: `manylod` on the GPU, `none` with
    /// --cpu (said on stderr). Also writes the atlas as vpl-shadow-atlas.png.
    #[arg(long, value_name = "MODE", default_value = "auto")]
    vpl_shadows: ShadowMode,
    /// With --vpl-shadows manylod: the cut threshold ε in micro-view pixels.
    #[arg(long, default_value_t = 2.0)]
    vpl_shadow_epsilon: f32,
    /// With --vpl-shadows manylod or ism: 2^LOG2 surfels sampled on the scene (a small scene
    /// needs fewer; the hierarchy is built on the CPU at start).
    #[arg(long, value_name = "LOG2", default_value_t = 20, value_parser = clap::value_parser!(u32).range(8..=24))]
    vpl_shadow_points: u32,
    /// Supersample with M×M samples per pixel (2..=8; Holländer 2013 §4.3, GPU only): full
    /// supersampling, or with --adaptive only where the metrics ask for samples. The samples'
    /// direct light goes through the frame's light accumulation and shadows; indirect light is
    /// shaded per pixel and shared by its samples.
    #[arg(long, value_name = "M")]
    ssaa: Option<u32>,
    /// With --ssaa: adaptive supersampling (geometric + shading metric, dither-ordered samples);
    /// also writes the sample counts as ssaa-samples.png.
    #[arg(long, requires = "ssaa")]
    adaptive: bool,
    /// With --ssaa --adaptive: the geometric metric, MM, NC, DV, NV or ND.
    #[arg(long, default_value = "ND", requires = "adaptive")]
    ssaa_metric: adaptive_ssaa::GeometricMetric,
    /// One-bounce indirect light by point-based GI instead of VPLs (GPU; Holländer 2013
    /// §3.6.1): every frame the scene's surfels are lit by the direct lights (shadow rays) and a
    /// receiver every STRIDE pixels gathers them through a many-view cut of paraboloid views,
    /// upsampled edge-aware to the frame. The surfels stay where they were sampled at load.
    #[arg(long, value_name = "STRIDE", conflicts_with = "vpls", value_parser = clap::value_parser!(u32).range(1..=64))]
    pbgi: Option<u32>,
    /// With --pbgi: each receiver's paraboloid view in T×T texels.
    #[arg(long, value_name = "T", default_value_t = 16, requires = "pbgi", value_parser = clap::value_parser!(u32).range(4..=256))]
    pbgi_tile: u32,
    /// With --pbgi: the cut threshold ε in texels.
    #[arg(long, value_name = "E", default_value_t = 2.0, requires = "pbgi")]
    pbgi_epsilon: f32,
    /// With --pbgi: 2^LOG2 surfels sampled on the scene.
    #[arg(long, value_name = "LOG2", default_value_t = 20, requires = "pbgi", value_parser = clap::value_parser!(u32).range(4..=24))]
    pbgi_points: u32,
    /// Mirror (metallic ≥ 0.9) and glass (transmission > 0) materials of roughness ≤ 0.2
    /// reflect and refract the scene through maps (GPU; Holländer 2013 §3.6.1, Fig. 3.19):
    /// every such mesh gets a dual-paraboloid map of T×T texels per half, made every frame from
    /// the scene's surfels (lit on the CPU by the direct lights) through a many-view cut; each
    /// of its pixels adds Fresnel × its map in the mirrored view direction, and glass adds what
    /// it transmits along the refracted one. Try `--builtin mirrors`.
    #[arg(long, value_name = "T", conflicts_with = "vpls", value_parser = clap::value_parser!(u32).range(4..=256))]
    reflections: Option<u32>,
    /// With --reflections: the cut threshold ε in texels.
    #[arg(
        long,
        value_name = "E",
        default_value_t = 1.0,
        requires = "reflections"
    )]
    reflection_epsilon: f32,
    /// With --reflections: 2^LOG2 surfels sampled on the scene.
    #[arg(long, value_name = "LOG2", default_value_t = 18, requires = "reflections", value_parser = clap::value_parser!(u32).range(4..=24))]
    reflection_points: u32,
    /// Draw the G-buffer through the compute rasteriser's visibility buffer and its resolve
    /// (GPU; `gbuffer::gpu::visibility`) instead of the hardware z-prepass and G-buffer pass;
    /// `--visibility=auto` measures both from the first camera, the visibility buffer per
    /// split (meshes of large triangles drawn into it by the hardware rasteriser), and keeps the
    /// fastest (the summary's `gbuffer:` line gives every time). Runs on any device (64-bit atomics where it
    /// has them, else two passes of 32-bit ones); Forward+ and the light pre-pass are refused.
    #[arg(long, value_enum, value_name = "MODE", num_args = 0..=1, require_equals = true, default_missing_value = "on")]
    visibility: Option<VisibilityMode>,
    /// Screen-space ambient occlusion of the ambient and indirect light (GPU): `filter` (eq. 7.1),
    /// `crytek`, `vo` (volumetric obscurance), `hbao` or `gtao`, over the k×k kernel, or with
    /// `-separable` (e.g. `filter-separable`, Holländer 2013 annex 7.2: two 1D passes).
    #[arg(long, value_name = "METHOD")]
    ssao: Option<ssao::Estimator>,
    /// With --ssao: the kernel side in pixels (odd, 3 to 63).
    #[arg(long, value_name = "K", default_value_t = 11, requires = "ssao")]
    ssao_kernel: u32,
    /// With --ssao: the occlusion radius in world units (default: 5 % of the scene's diagonal).
    #[arg(long, value_name = "R", requires = "ssao")]
    ssao_radius: Option<f32>,
    /// Render the path-traced ground truth instead, with SPP samples per pixel (CPU;
    /// `scene::reference`): every light casts shadows, emissive meshes are area lights, light
    /// interreflects up to --max-bounces times. No ambient term.
    #[arg(long, value_name = "SPP", value_parser = parse_spp, conflicts_with_all = ["vpls", "ssaa"])]
    reference: Option<u32>,
    /// With --reference: bounces after the first surface (0 = direct light only; 1, the
    /// default, is what one-bounce VPLs approximate).
    #[arg(long, default_value_t = 1, requires = "reference", value_parser = clap::value_parser!(u32).range(0..=1000))]
    max_bounces: u32,
    /// Replace every mesh by its Loop subdivision surface at this level (1–6; Holländer 2013
    /// ch. 2: computational entries, then basis-function tables, on the GPU unless --cpu),
    /// with Subdivision Shading normals. Meshes are welded by position first. In an animated
    /// scene only the meshes its animation moves are subdivided, every frame from their posed
    /// control meshes (texture coordinates through the same stencils).
    #[arg(long, value_name = "LEVEL")]
    subdiv: Option<u32>,
    /// With --subdiv: adaptive tessellation up to LEVEL, each control edge split so its fine
    /// edges are about PIXELS long in this view (screen-space metric, crack-free transitions,
    /// geomorph).
    #[arg(long, value_name = "PIXELS", requires = "subdiv")]
    subdiv_pixels: Option<f32>,
    /// With --subdiv: shade with geometric (flat, per-triangle) normals instead of Subdivision
    /// Shading.
    #[arg(long, requires = "subdiv")]
    subdiv_flat: bool,
    /// With --subdiv-pixels: colour every triangle by its patch's level (1 blue … 6 red).
    #[arg(long, requires = "subdiv_pixels")]
    subdiv_show_levels: bool,
    /// Render a sequence of N frames on a fixed-step clock (frame k at k / --fps seconds),
    /// playing the scene's animation (glTF skins, morph targets, node animation): numbered
    /// PNGs in OUT/frames, timings.csv (a row per frame, a column per pass) and trace.json
    /// (the GPU passes for chrome://tracing or ui.perfetto.dev).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=100_000))]
    frames: Option<u32>,
    /// With --frames: frames per second of the clock.
    #[arg(long, default_value_t = 24.0, requires = "frames", value_parser = parse_fps)]
    fps: f32,
    /// The animation played: a clip's name or index (default: the file's first).
    #[arg(long)]
    clip: Option<String>,
    /// Seconds into the animation of a single frame (loops over the clip).
    #[arg(long, value_name = "SECONDS", default_value_t = 0.0, conflicts_with = "frames", value_parser = parse_time)]
    time: f32,
    /// With --frames: turn the camera about the vertical axis through its target by DEG a
    /// second (counter-clockwise seen from above).
    #[arg(long, value_name = "DEG", requires = "frames", allow_hyphen_values = true, value_parser = parse_orbit)]
    orbit: Option<f32>,
    /// With --frames: also write each frame's linear radiance as EXR.
    #[arg(long, requires = "frames")]
    frame_exr: bool,
    /// With --frames: write every K-th frame only (and only those into preview.gif); the
    /// timings keep every frame.
    #[arg(long, value_name = "K", default_value_t = 1, requires = "frames", value_parser = clap::value_parser!(u32).range(1..))]
    frame_every: u32,
    /// With --frames: first render N frames of the sequence's start, not recorded or written
    /// (a GPU's clock rises under load before the timed frames).
    #[arg(long, value_name = "N", default_value_t = 0, requires = "frames", value_parser = clap::value_parser!(u32).range(0..=10_000))]
    warm_up: u32,
    /// With --frames: the camera through keyframes T:EX,EY,EZ:TX,TY,TZ (seconds, eye,
    /// target; repeat the flag, in time order), interpolated linearly.
    #[arg(long = "camera-key", value_name = "KEY", conflicts_with = "orbit", value_parser = parse_camera_key)]
    camera_keys: Vec<(f32, Vec3, Vec3)>,
    /// With --frames: the direct lights turn about the vertical axis through the scene's
    /// centre by DEG a second (the VPLs are traced again each frame).
    #[arg(long, value_name = "DEG", requires = "frames", allow_hyphen_values = true, value_parser = parse_orbit)]
    light_orbit: Option<f32>,
    /// Add a model to the scene: PATH[@X,Y,Z[,SCALE[,YAW°]]] (its meshes, materials, lights
    /// and animation, placed at X,Y,Z, scaled, turned about +Y). Repeat for more models.
    /// A path may start with `fixtures:` for the shared fixtures folder.
    #[arg(long = "add-model", value_name = "MODEL", value_parser = parse_model)]
    models: Vec<(PathBuf, glam::Mat4)>,
    /// Read the render's settings from a TOML recipe: every key is a long flag of this
    /// program (`size = "640x480"`, `vpls = 1024`, `shadows = 512`, `light = ["point:…"]`,
    /// `adaptive = true`), relative paths are relative to the recipe's folder, and flags on the
    /// command line override the recipe's.
    #[arg(long, value_name = "FILE")]
    recipe: Option<PathBuf>,
}

#[derive(clap::Subcommand, Debug)]
enum Command {
    /// Writes the Loop subdivision of a triangle OBJ: the refined mesh Mᵏ (recursive CPU
    /// reference), or with --limit every vertex on the limit surface (basis-function tables on
    /// the GPU; with --cpu, recursive subdivision + limit projection).
    Subdivide {
        /// Control mesh (.obj; polygons are fan-split; OpenSubdiv `t` tags honoured).
        input: PathBuf,
        /// Subdivision level k (4^k triangles per input triangle).
        #[arg(long)]
        level: u32,
        /// Project to the limit surface (and write normals).
        #[arg(long)]
        limit: bool,
        /// Use the CPU reference only.
        #[arg(long)]
        cpu: bool,
        /// Output .obj.
        #[arg(short = 'o', long)]
        output: PathBuf,
    },
}

/// The default basis-function tables (cached in the user's cache folder, `BftSet::default_path`).
fn bft_tables() -> Result<subdiv_bft::BftSet> {
    use subdiv_bft::{BftSet, DEFAULT_LEVEL, MAX_VALENCE};
    Ok(BftSet::cached(
        &BftSet::default_path(DEFAULT_LEVEL, MAX_VALENCE),
        DEFAULT_LEVEL,
        MAX_VALENCE,
    )?)
}

/// `deferred subdivide`.
fn subdivide_command(
    input: &std::path::Path,
    level: u32,
    limit: bool,
    cpu: bool,
    output: &std::path::Path,
) -> Result<()> {
    use subdiv_bft::{Subdivider, obj::ObjMesh};
    let mesh = ObjMesh::read(input)?
        .into_mesh()
        .with_context(|| format!("{}", input.display()))?;
    let text = if limit && !cpu {
        let bft = bft_tables()?;
        let sub = Subdivider::new(&mesh.topology, &bft)?;
        let gpu = gpu::Gpu::from_env().context("no GPU for --limit (use --cpu)")?;
        let out = subdiv_bft::gpu::run(&gpu, &sub, &bft, &mesh.positions_f32(), level)?;
        ObjMesh::write(&out.positions, Some(&out.normals), &out.indices)
    } else {
        let fine = mesh.subdivide(level)?;
        let indices: Vec<u32> = fine.topology.triangles.iter().flatten().copied().collect();
        if limit {
            let mut projected = fine;
            projected.positions = projected.limit_positions();
            let n: Vec<Vec3> = projected
                .limit_normals()
                .iter()
                .map(|n| n.as_vec3())
                .collect();
            ObjMesh::write(&projected.positions_f32(), Some(&n), &indices)
        } else {
            ObjMesh::write(&fine.positions_f32(), None, &indices)
        }
    };
    save_text(&text, output)?;
    println!("wrote {}", output.display());
    Ok(())
}

/// `--subdiv LEVEL [--subdiv-pixels PX] [--subdiv-flat] [--subdiv-show-levels]`: every mesh
/// replaced by its limit-surface tessellation (GPU, or the CPU mirror when `--cpu` or no
/// adapter), uniform or adaptive for `camera`, read back once at load.
fn subdivide_scene(
    scene: &mut Scene,
    args: &Args,
    level: u32,
    camera: &scene::Camera,
) -> Result<()> {
    use subdiv_bft::{Subdivider, TriMesh, adaptive::ScreenView};
    let bft = bft_tables()?;
    let gpu = if args.cpu {
        None
    } else {
        gpu::Gpu::from_env().ok()
    };
    let view = args.subdiv_pixels.map(|target_pixels| ScreenView {
        view_proj: camera.view_projection(args.size.0 as f32 / args.size.1 as f32),
        viewport: args.size,
        target_pixels,
    });
    if let Some(v) = &view {
        v.check()?;
    }
    let mut level_meshes = Vec::new();
    for mesh in &mut scene.meshes {
        let control = TriMesh::welded(&mesh.positions, &mesh.indices)
            .with_context(|| format!("mesh {:?}", mesh.name))?;
        let sub = Subdivider::new(&control.topology, &bft)
            .with_context(|| format!("mesh {:?}", mesh.name))?;
        let m0 = control.positions_f32();
        let out = match (&gpu, &view) {
            (Some(g), None) => subdiv_bft::gpu::run(g, &sub, &bft, &m0, level)?,
            (None, None) => sub.evaluate_cpu(&bft, &m0, level)?,
            (g, Some(v)) => {
                let s_max = sub.segments(level)?;
                let (mut out, factors) = match g {
                    Some(g) => subdiv_bft::gpu::run_adaptive(g, &sub, &bft, &m0, level, v)?,
                    None => {
                        let (p1, _) = sub.initial_step_f32(&m0)?;
                        let f = subdiv_bft::adaptive::screen_factors(&sub.m1, &p1, v, s_max);
                        (sub.evaluate_adaptive_cpu(&bft, &m0, &f, level)?, f)
                    }
                };
                if args.subdiv_show_levels {
                    // The same triangles in patch order, s² per patch, to know their levels.
                    out.indices = sub.patches.triangulate_adaptive(&factors, s_max);
                    let levels: Vec<u32> = (0..sub.patches.patches.len())
                        .flat_map(|p| {
                            let s = sub.patches.patch_levels(p, &factors, s_max).segments;
                            std::iter::repeat_n(s.ilog2() + 1, (s * s) as usize)
                        })
                        .collect();
                    level_meshes.push((mesh.name.clone(), out.clone(), levels));
                }
                out.without_collapsed()
            }
        };
        let out = if args.subdiv_flat {
            flat_shaded(&out)
        } else {
            out
        };
        mesh.uvs = vec![glam::Vec2::ZERO; out.positions.len()];
        mesh.positions = out.positions;
        mesh.normals = out.normals;
        mesh.indices = out.indices;
    }
    if args.subdiv_show_levels {
        scene.meshes.clear();
        for (name, out, levels) in level_meshes {
            for l in 1..=level {
                let mut part = subdiv_bft::Refined {
                    indices: out
                        .indices
                        .chunks_exact(3)
                        .zip(&levels)
                        .filter(|&(_, &k)| k == l)
                        .flat_map(|(t, _)| t.iter().copied())
                        .collect(),
                    ..out.clone()
                }
                .without_collapsed();
                if part.indices.is_empty() {
                    continue;
                }
                if args.subdiv_flat {
                    part = flat_shaded(&part);
                }
                scene.materials.push(scene::Material {
                    name: format!("level {l}"),
                    base_color: level_colour(l).extend(1.0),
                    ..Default::default()
                });
                scene.meshes.push(scene::Mesh {
                    name: format!("{name} level {l}"),
                    uvs: vec![glam::Vec2::ZERO; part.positions.len()],
                    positions: part.positions,
                    normals: part.normals,
                    indices: part.indices,
                    material: scene.materials.len() as u32 - 1,
                    ..Default::default()
                });
            }
        }
    }
    Ok(())
}

/// Colour of surface level `l` (1 blue … 6 red).
fn level_colour(l: u32) -> Vec3 {
    const RAMP: [[f32; 3]; 6] = [
        [0.10, 0.25, 0.85],
        [0.10, 0.65, 0.85],
        [0.20, 0.75, 0.30],
        [0.85, 0.80, 0.15],
        [0.90, 0.45, 0.10],
        [0.85, 0.10, 0.10],
    ];
    Vec3::from(RAMP[(l.clamp(1, 6) - 1) as usize])
}

/// Geometric normals: every triangle with its own three vertices and face normal.
fn flat_shaded(mesh: &subdiv_bft::Refined) -> subdiv_bft::Refined {
    let mut out = subdiv_bft::Refined::default();
    for t in mesh.indices.chunks_exact(3) {
        let [a, b, c] = [t[0], t[1], t[2]].map(|i| mesh.positions[i as usize]);
        let n = (b - a).cross(c - a).normalize_or_zero();
        for p in [a, b, c] {
            out.indices.push(out.positions.len() as u32);
            out.positions.push(p);
            out.normals.push(n);
        }
    }
    out
}

/// `--reference SPP [--max-bounces B]`: the path tracer, in batches of samples with a progress
/// bar; writes render.png and render.exr.
fn render_reference(
    args: &Args,
    scene: &Scene,
    camera: scene::Camera,
    lights: &[Light],
    spp: u32,
) -> Result<()> {
    use scene::reference::{PathTracer, ReferenceConfig};
    let (width, height) = args.size;
    if u64::from(width) * u64::from(height) > MAX_CPU_PIXELS {
        bail!("--size {width}x{height}: the CPU reference renders at most {MAX_CPU_PIXELS} pixels");
    }
    pipeline::validate_lights(lights)?;
    let config = ReferenceConfig {
        max_bounces: args.max_bounces,
        seed: args.seed,
        ..ReferenceConfig::default()
    };
    let start = std::time::Instant::now();
    let mut pt = PathTracer::new(scene, camera, width, height, lights, config);
    let bar = indicatif::ProgressBar::new(u64::from(spp)).with_message("path tracing");
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "{spinner} {msg} [{bar:30}] {pos}/{len} spp, {eta} left",
        )
        .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    while pt.samples() < spp {
        pt.add_samples((spp - pt.samples()).min(4));
        bar.set_position(u64::from(pt.samples()));
    }
    bar.finish_and_clear();
    let pixels: Vec<[f32; 4]> = pt.image().iter().map(|c| [c.x, c.y, c.z, 1.0]).collect();
    let image = gbuffer::Image::from_vec(width, height, pixels)?;
    make_dir(&args.out)?;
    let (png, exr) = (args.out.join("render.png"), args.out.join("render.exr"));
    save_png(&output_transform(args)?.apply(&image), &png)?;
    save_exr(&image, &exr)?;
    println!("device:  CPU path tracer (the ground truth, rayon)");
    println!(
        "scene:   {} triangles, {} punctual lights + emissive triangles as area lights, {width}x{height}",
        scene.triangle_count(),
        lights.len()
    );
    println!(
        "reference: {spp} samples per pixel, {} bounces, seed {} in {:.1} s",
        args.max_bounces,
        args.seed,
        start.elapsed().as_secs_f64()
    );
    println!("wrote:   {} and {}", png.display(), exr.display());
    Ok(())
}

fn indirect_config(args: &Args, scene: &Scene) -> Result<IndirectConfig> {
    let interleaving = if args.no_interleave {
        Interleaving::Reference
    } else {
        match args.interleaving.as_str() {
            "fused" => Interleaving::Fused,
            "tiled" => Interleaving::Split(SplitVariant::Tiled),
            "one-pass" => Interleaving::Split(SplitVariant::OnePass),
            "two-pass" => {
                Interleaving::Split(SplitVariant::TwoPass(Block::fitted(32, 32, args.pattern)))
            }
            other => bail!("unknown interleaving {other:?} (fused, tiled, one-pass, two-pass)"),
        }
    };
    let blur = match args.blur {
        0 => None,
        k => Some(Blur::new(
            k,
            if args.plain_blur {
                BlurVariant::Plain
            } else {
                BlurVariant::Fast
            },
        )?),
    };
    let defaults = IndirectConfig::new(scene.bounds());
    Ok(IndirectConfig {
        pattern: args.pattern,
        interleaving,
        blur,
        clamp_distance: args.vpl_clamp.unwrap_or(defaults.clamp_distance),
        ..defaults
    })
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

/// The most lights `--lights` scatters: 64-byte lights filling wgpu's default 128 MiB storage
/// binding.
const MAX_LIGHTS: usize = (128 << 20) / 64;

fn parse_light_count(s: &str) -> Result<usize, String> {
    match s.trim().parse::<usize>() {
        Ok(n) if n <= MAX_LIGHTS => Ok(n),
        _ => Err(format!("expected a light count from 0 to {MAX_LIGHTS}")),
    }
}

fn parse_vpl_count(s: &str) -> Result<usize, String> {
    let max = *vpl::VPL_RANGE.end();
    match s.trim().parse::<usize>() {
        Ok(n) if (1..=max).contains(&n) => Ok(n),
        _ => Err(format!("expected a VPL count from 1 to {max}")),
    }
}

fn parse_spp(s: &str) -> Result<u32, String> {
    match s.trim().parse::<u32>() {
        Ok(n) if (1..=65536).contains(&n) => Ok(n),
        _ => Err("expected samples per pixel from 1 to 65536".into()),
    }
}

fn parse_fps(s: &str) -> Result<f32, String> {
    match s.trim().parse::<f32>() {
        Ok(f) if f > 0.0 && f <= sequence::MAX_FPS => Ok(f),
        _ => Err(format!(
            "expected frames per second above 0, at most {}",
            sequence::MAX_FPS
        )),
    }
}

fn parse_time(s: &str) -> Result<f32, String> {
    match s.trim().parse::<f32>() {
        Ok(t) if t.is_finite() && t >= 0.0 => Ok(t),
        _ => Err("expected a time of 0 seconds or more".into()),
    }
}

fn parse_orbit(s: &str) -> Result<f32, String> {
    match s.trim().parse::<f32>() {
        Ok(d) if d.is_finite() && d.abs() <= 36_000.0 => Ok(d),
        _ => Err("expected degrees a second from -36000 to 36000".into()),
    }
}

fn parse_camera_key(s: &str) -> Result<(f32, Vec3, Vec3), String> {
    let parts: Vec<&str> = s.split(':').collect();
    let [t, eye, target] = parts[..] else {
        return Err("expected T:EX,EY,EZ:TX,TY,TZ".into());
    };
    let t = parse_time(t)?;
    Ok((t, parse_vec3(eye)?, parse_vec3(target)?))
}

/// `PATH[@X,Y,Z[,SCALE[,YAW°]]]` as the path and its placement.
fn parse_model(s: &str) -> Result<(PathBuf, glam::Mat4), String> {
    let (path, place) = s.rsplit_once('@').unwrap_or((s, ""));
    let v: Vec<f32> = if place.is_empty() {
        Vec::new()
    } else {
        place
            .split(',')
            .map(|c| match c.trim().parse::<f32>() {
                Ok(f) if f.is_finite() => Ok(f),
                _ => Err(format!("{c:?} is not a finite number")),
            })
            .collect::<Result<_, _>>()?
    };
    let (t, scale, yaw) = match v[..] {
        [] => (Vec3::ZERO, 1.0, 0.0),
        [x, y, z] => (Vec3::new(x, y, z), 1.0, 0.0),
        [x, y, z, s] => (Vec3::new(x, y, z), s, 0.0),
        [x, y, z, s, yaw] => (Vec3::new(x, y, z), s, yaw),
        _ => return Err("expected PATH[@X,Y,Z[,SCALE[,YAW]]]".into()),
    };
    if scale <= 0.0 {
        return Err(format!("the scale must be above 0, not {scale}"));
    }
    let placement = glam::Mat4::from_scale_rotation_translation(
        Vec3::splat(scale),
        glam::Quat::from_rotation_y(yaw.to_radians()),
        t,
    );
    Ok((PathBuf::from(path), placement))
}

fn parse_fov(s: &str) -> Result<f32, String> {
    match s.trim().parse::<f32>() {
        Ok(d) if (0.1..=179.0).contains(&d) => Ok(d),
        _ => Err("expected a vertical field of view from 0.1 to 179 degrees".into()),
    }
}

/// The most pixels the CPU reference renders: it keeps about 200 bytes per pixel (G-buffer,
/// per-light sums, indirect stages, the image), so 2^25 pixels (e.g. 8192×4096) stay near
/// 7 GiB.
const MAX_CPU_PIXELS: u64 = 1 << 25;

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

/// `path`, or for `fixtures:REST` the shared fixtures folder's `REST`
/// ([`scene::shared_fixtures`]: `DEFERRED_FIXTURES`, else `../shared/fixtures`).
fn resolve(path: &std::path::Path) -> Result<PathBuf> {
    match path.to_str().and_then(|p| p.strip_prefix("fixtures:")) {
        Some(rest) => Ok(scene::shared_fixtures()
            .with_context(|| {
                format!(
                    "{}: no shared fixtures folder (set DEFERRED_FIXTURES)",
                    path.display()
                )
            })?
            .join(rest)),
        None => Ok(path.to_owned()),
    }
}

/// The scene with every `--add-model` inserted.
fn load_scene(args: &Args) -> Result<Scene> {
    let mut scene = load_base_scene(args)?;
    for (path, placement) in &args.models {
        let path = resolve(path)?;
        let model = Scene::load(&path)?;
        scene
            .insert(model, *placement)
            .with_context(|| format!("--add-model {}", path.display()))?;
    }
    Ok(scene)
}

fn load_base_scene(args: &Args) -> Result<Scene> {
    let Some(path) = &args.scene else {
        return Ok(match args.builtin.as_str() {
            "cornell" => scene::cornell_box(),
            "spheres" => scene::spheres_on_plane(8),
            "checkerboard" => scene::checkerboard(),
            "gallery" => scene::material_gallery(),
            "mirrors" => scene::mirror_spheres(64),
            "walls-test1" => scene::thesis_walls(0),
            "walls-test2" => scene::thesis_walls(100),
            "walls-test3" => scene::thesis_walls(500),
            "walls-test4" => scene::thesis_walls(1000),
            other => bail!(
                "unknown built-in scene {other:?} (cornell, spheres, checkerboard, gallery, mirrors, walls-test1 .. walls-test4)"
            ),
        });
    };
    let bar = indicatif::ProgressBar::new(1).with_message(format!("loading {}", path.display()));
    bar.set_style(
        indicatif::ProgressStyle::with_template("{spinner} {msg} [{bar:30}] {pos}/{len} meshes")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    bar.enable_steady_tick(std::time::Duration::from_millis(100));
    let path = &resolve(path)?;
    let scene = Scene::load_with_progress(path, &mut |done, total| {
        bar.set_length(total as u64);
        bar.set_position(done as u64);
    });
    bar.finish_and_clear();
    Ok(scene?)
}

/// What `deferred` without arguments renders: the built-in Cornell box with shadow maps and
/// one-bounce indirect light from 1024 interleaved VPLs with ManyLoD visibility (2^16 surfels
/// suffice for its 32 triangles), adaptive 2×2 supersampling (4×4 costs a software adapter
/// another ten seconds), ACES tone mapping — about ten seconds on a software adapter.
const FIRST_IMPRESSION: [&str; 9] = [
    "--shadows",
    "512",
    "--vpls",
    "1024",
    "--vpl-shadow-points",
    "16",
    "--ssaa",
    "2",
    "--adaptive",
];

/// The most bytes a recipe file may hold.
const RECIPE_LIMIT: u64 = 1 << 20;

/// `argv` with the keys of its `--recipe FILE` (if any) put before its own flags, as flags:
/// `key = "v"` → `--key=v`, numbers likewise, `key = true` → `--key`, arrays → the flag
/// repeated. Relative paths of `scene`, `add-model` and `out` are taken from the recipe's
/// folder; `fixtures:` paths stay as they are.
fn with_recipe(argv: Vec<std::ffi::OsString>) -> Result<Vec<std::ffi::OsString>> {
    use clap::CommandFactory;
    if argv.len() == 1 {
        println!(
            "no arguments: the first-impression render `deferred {}` (see --help)",
            FIRST_IMPRESSION.join(" ")
        );
        let mut with_defaults = argv;
        with_defaults.extend(FIRST_IMPRESSION.iter().map(Into::into));
        return Ok(with_defaults);
    }
    let at = argv.iter().position(|a| {
        a.to_str()
            .is_some_and(|a| a == "--recipe" || a.starts_with("--recipe="))
    });
    let Some(at) = at else {
        return Ok(argv);
    };
    let path = match argv[at].to_str().and_then(|a| a.strip_prefix("--recipe=")) {
        Some(p) => PathBuf::from(p),
        None => match argv.get(at + 1) {
            Some(p) => PathBuf::from(p),
            None => return Ok(argv), // clap reports the missing value
        },
    };
    let fail = |problem: String| anyhow::anyhow!("recipe {}: {problem}", path.display());
    let file = std::fs::File::open(&path).map_err(|e| fail(e.to_string()))?;
    let mut text = String::new();
    std::io::Read::read_to_string(&mut std::io::Read::take(file, RECIPE_LIMIT + 1), &mut text)
        .map_err(|e| fail(e.to_string()))?;
    if text.len() as u64 > RECIPE_LIMIT {
        return Err(fail(format!("longer than {RECIPE_LIMIT} bytes")));
    }
    let table: toml::Table = toml::from_str(&text).map_err(|e| fail(e.to_string()))?;
    let folder = path.parent().unwrap_or(std::path::Path::new("."));
    let command = Args::command();
    let known: Vec<&str> = command
        .get_arguments()
        .filter_map(|a| a.get_long())
        .filter(|l| *l != "recipe" && *l != "help" && *l != "version")
        .collect();
    let mut flags: Vec<std::ffi::OsString> = Vec::new();
    for (key, value) in &table {
        let flag = key.replace('_', "-");
        if !known.contains(&flag.as_str()) {
            return Err(fail(format!(
                "unknown key {key:?} (every key is a long flag of `deferred`: {})",
                known.join(", ")
            )));
        }
        let text = |v: &toml::Value| -> Result<String> {
            let s = match v {
                toml::Value::String(s) => s.clone(),
                toml::Value::Integer(i) => i.to_string(),
                toml::Value::Float(f) => f.to_string(),
                other => {
                    return Err(fail(format!(
                        "{key}: a {} is not a string or number",
                        other.type_str()
                    )));
                }
            };
            let relative = matches!(flag.as_str(), "scene" | "add-model" | "out")
                && !s.starts_with("fixtures:")
                && std::path::Path::new(&s).is_relative();
            Ok(if relative {
                folder.join(&s).to_string_lossy().into_owned()
            } else {
                s
            })
        };
        match value {
            toml::Value::Boolean(true) => flags.push(format!("--{flag}").into()),
            toml::Value::Boolean(false) => {}
            // `--flag=value`: a value starting with `-` (`eye = "-8,2,0"`) is not a flag.
            toml::Value::Array(items) => {
                for item in items {
                    flags.push(format!("--{flag}={}", text(item)?).into());
                }
            }
            v => flags.push(format!("--{flag}={}", text(v)?).into()),
        }
    }
    let mut out = vec![argv[0].clone()];
    out.extend(flags);
    out.extend(argv.into_iter().skip(1));
    Ok(out)
}

/// The files this run wrote ([`save_png`], [`save_exr`], [`save_text`]). Every output is
/// written atomically; when the run fails, the outputs it already wrote are removed again, so a
/// failed run leaves none of its files behind.
static WRITTEN: std::sync::Mutex<Vec<PathBuf>> = std::sync::Mutex::new(Vec::new());

fn record(path: &std::path::Path) {
    if let Ok(mut written) = WRITTEN.lock() {
        written.push(path.to_owned());
    }
}

/// The folders this run created, to remove again (when empty) if it fails.
static CREATED: std::sync::Mutex<Vec<PathBuf>> = std::sync::Mutex::new(Vec::new());

/// Creates folder `dir` (and its parents), recording each one it creates.
fn make_dir(dir: &std::path::Path) -> Result<()> {
    let missing: Vec<PathBuf> = dir
        .ancestors()
        .take_while(|d| !d.as_os_str().is_empty() && !d.exists())
        .map(PathBuf::from)
        .collect();
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    if let Ok(mut created) = CREATED.lock() {
        created.extend(missing.into_iter().rev());
    }
    Ok(())
}

/// Writes `image` as a PNG at `path` (atomically) and records it as this run's output.
/// The output transform of render.png (--exposure, --auto-exposure, --tone-map).
fn output_transform(args: &Args) -> Result<pipeline::output::OutputTransform> {
    let t = pipeline::output::OutputTransform {
        exposure_ev: args.exposure,
        auto_exposure: args.auto_exposure,
        tone_mapper: args.tone_map,
    };
    t.validate()?;
    Ok(t)
}

/// The texture filtering of --anisotropy.
fn texture_options(args: &Args) -> gbuffer::TextureOptions {
    gbuffer::TextureOptions {
        max_anisotropy: args.anisotropy,
    }
}

fn save_png(image: &gbuffer::Image<[f32; 4]>, path: &std::path::Path) -> Result<()> {
    image.write_png(path)?;
    record(path);
    Ok(())
}

/// Writes `image` as an OpenEXR file at `path` (atomically) and records it.
fn save_exr(image: &gbuffer::Image<[f32; 4]>, path: &std::path::Path) -> Result<()> {
    image.write_exr(path)?;
    record(path);
    Ok(())
}

/// Writes `text` at `path` (atomically) and records it.
fn save_text(text: &str, path: &std::path::Path) -> Result<()> {
    gbuffer::write_atomically(path, |tmp| {
        std::fs::write(tmp, text).map_err(|e| e.to_string())
    })?;
    record(path);
    Ok(())
}

fn main() -> Result<()> {
    let result = run();
    if result.is_err()
        && let Ok(written) = WRITTEN.lock()
    {
        for path in written.iter() {
            let _ = std::fs::remove_file(path);
        }
        // The folders it made, innermost first; only empty ones go.
        if let Ok(created) = CREATED.lock() {
            for dir in created.iter().rev() {
                let _ = std::fs::remove_dir(dir);
            }
        }
    }
    result
}

fn run() -> Result<()> {
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or("warn")).init();
    let mut argv: Vec<std::ffi::OsString> = std::env::args_os().collect();
    if argv.get(1).is_some_and(|a| a == "view") {
        argv.remove(1);
        return view::run(argv);
    }
    let args = Args::parse_from(with_recipe(argv)?);
    if let Some(Command::Subdivide {
        input,
        level,
        limit,
        cpu,
        output,
    }) = &args.command
    {
        return subdivide_command(input, *level, *limit, *cpu, output);
    }
    let setup = prepare(&args)?;
    if let Some(spp) = args.reference {
        let drawn = drawn(setup.plan.as_ref(), &setup.scene);
        return render_reference(&args, &drawn, setup.camera, &setup.reference_lights, spp);
    }
    let (width, height) = args.size;
    if args.ssao.is_some() && args.cpu {
        bail!("--ssao runs on the GPU only (the CPU frame has no ambient occlusion; drop --cpu)");
    }
    if args.ssaa.is_some() && args.cpu {
        bail!("--ssaa runs on the GPU only (the CPU frame has no supersampling; drop --cpu)");
    }
    if args.manylod_shadows.is_some() && args.cpu {
        bail!("--manylod-shadows runs on the GPU only (no --cpu)");
    }
    if args.ray_shadows && args.cpu {
        bail!("--ray-shadows runs on the GPU only (no --cpu)");
    }
    if args.near_field && args.cpu {
        bail!("--near-field runs on the GPU only (no --cpu)");
    }
    if args.visibility.is_some() && args.cpu {
        bail!("--visibility runs on the GPU only (no --cpu)");
    }
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
    let frozen = setup.indirect.is_some()
        && setup
            .vpl_shadows
            .is_some_and(|m| !matches!(m, VplShadows::ManyLod | VplShadows::Ism));
    if setup.scene.rig.is_some()
        && args.frames.is_some()
        && (frozen || args.ray_shadows || args.near_field)
    {
        eprintln!(
            "note: rasterised VPL maps and the ray BVHs are built once: the moving meshes cast \
             those shadows in the first frame's pose (ManyLoD and ISM refit every frame)"
        );
    }
    let (device, rendered, display, stages, gbuffer, gbuffer_path) = match &gpu {
        Some(gpu) => {
            let (d, q) = (&gpu.device, &gpu.queue);
            let (mut renderer, gbuffer_path) = gpu_renderer(&args, gpu, &setup)?;
            if let Some(frames) = args.frames {
                let seq = Sequence::new(&args, frames, &setup.camera)?;
                let device = format!("GPU {}", gpu.describe());
                print_setup(&args, &setup, &device, Some(&gbuffer_path));
                return gpu_sequence(&args, gpu, &mut renderer, &setup, seq);
            }
            let (camera, ambient) = (setup.camera, setup.ambient);
            renderer.render(d, q, &camera, ambient)?; // warm-up: first use of pipelines and caches
            if renderer.check_pbgi(d, q)? {
                eprintln!("note: point-based GI's cut lists grew to hold the cut");
            }
            if renderer.check_reflections(d, q)? {
                eprintln!("note: the reflection maps' cut lists grew to hold the cut");
            }
            if renderer.check_visibility(d, q)? {
                eprintln!("note: the visibility buffer's lists grew to hold every triangle");
            }
            let rendered = renderer.render(d, q, &camera, ambient)?;
            let display = pipeline::gpu::read_display(
                d,
                q,
                renderer
                    .display()
                    .context("the renderer has an output stage")?,
            )?;
            if let Some(shadows) = renderer
                .vpl_shadows()
                .filter(|s| s.mode() != VplShadows::Rays)
            {
                write_shadow_atlas(&args, gpu, shadows)?;
            }
            write_ssaa_samples(&args, gpu, &renderer)?;
            if args.heatmap {
                // With supersampling the tiles are of samples.
                let m = renderer.ssaa().map_or(1, |c| c.m);
                match renderer.light_counts(d, q)? {
                    Some(counts) => {
                        write_heatmap(&args, &setup.shading, width * m, height * m, &counts)?;
                    }
                    None => eprintln!(
                        "no heatmap: {} keeps no per-tile lists",
                        setup.shading.method
                    ),
                }
            }
            let (stages, gbuffer) = if args.dump_stages {
                (
                    renderer.indirect().map(|s| s.read(d, q)).transpose()?,
                    Some(renderer.targets().read(&gpu.device, &gpu.queue)?),
                )
            } else {
                (None, None)
            };
            (
                format!("GPU {}", gpu.describe()),
                rendered,
                display,
                stages,
                gbuffer,
                Some(gbuffer_path),
            )
        }
        None => {
            if args.manylod_shadows.is_some() {
                bail!("--manylod-shadows needs a GPU (the CPU frame has no ManyLoD cut)");
            }
            if args.ray_shadows {
                bail!("--ray-shadows needs a GPU (the CPU frame has no ray shadows)");
            }
            if args.near_field {
                bail!("--near-field needs a GPU (the CPU frame has no near field)");
            }
            if args.ssaa.is_some() {
                bail!("--ssaa needs a GPU (the CPU frame has no supersampling)");
            }
            if args.ssao.is_some() {
                bail!("--ssao needs a GPU (the CPU frame has no ambient occlusion)");
            }
            if u64::from(width) * u64::from(height) > MAX_CPU_PIXELS {
                bail!(
                    "--size {width}x{height}: the CPU reference renders at most {MAX_CPU_PIXELS} pixels"
                );
            }
            let device = "CPU (reference path, rayon)";
            if let Some(frames) = args.frames {
                let seq = Sequence::new(&args, frames, &setup.camera)?;
                print_setup(&args, &setup, device, None);
                return cpu_sequence(&args, &setup, seq);
            }
            let (rendered, stages) = cpu_frame(
                &args,
                &setup,
                (&setup.scene, &setup.lights),
                &setup.camera,
                None,
            )?;
            if args.heatmap {
                let camera = &setup.camera;
                let gb = gbuffer::cpu::rasterize(
                    &drawn(setup.plan.as_ref(), &setup.scene),
                    camera,
                    width,
                    height,
                )?
                .gbuffer;
                let frame = gbuffer::Frame::new(camera, width, height);
                let lights = pipeline::validate_lights(&setup.lights)?;
                let shaded =
                    tiled_shading::cpu::shade(&gb, &frame, camera, &lights, &setup.shading, None)?;
                write_heatmap(&args, &setup.shading, width, height, &shaded.counts)?;
            }
            let gbuffer = args
                .dump_stages
                .then(|| {
                    gbuffer::cpu::rasterize(
                        &drawn(setup.plan.as_ref(), &setup.scene),
                        &setup.camera,
                        width,
                        height,
                    )
                })
                .transpose()?
                .map(|r| r.gbuffer);
            let display = setup.output.apply(&rendered.image);
            (device.to_owned(), rendered, display, stages, gbuffer, None)
        }
    };

    make_dir(&args.out)?;
    let png = args.out.join("render.png");
    let exr = args.out.join("render.exr");
    save_png(&display, &png)?;
    save_exr(&rendered.image, &exr)?;
    if let Some(gb) = &gbuffer {
        dump_stages(&args.out, gb, stages.as_ref())?;
    }
    print_setup(&args, &setup, &device, gbuffer_path.as_deref());
    println!("wrote:   {} and {}", png.display(), exr.display());
    println!();
    print_table(&rendered.timings, f64::from(width) * f64::from(height));
    if rendered.timings.is_empty() {
        println!("(this GPU has no timestamp queries: no pass times)");
    }
    Ok(())
}

/// `camera` moved to `eye`, looking at `target`, with a vertical field of view of `fov`
/// degrees, where given (`--eye`, `--target`, `--fov`): its depth range fitted to `bounds`
/// when it moved.
fn aimed(
    mut camera: scene::Camera,
    eye: Option<Vec3>,
    target: Option<Vec3>,
    fov: Option<f32>,
    bounds: scene::Aabb,
) -> scene::Camera {
    if let Some(eye) = eye {
        camera.eye = eye;
    }
    if let Some(target) = target {
        camera.target = target;
    }
    if let Some(fov) = fov {
        camera.fov_y = fov.to_radians();
    }
    if eye.is_some() || target.is_some() {
        camera.fit_planes(bounds);
        // Looking straight up or down: the default +Y up is along the view, so take −Z.
        let view = (camera.target - camera.eye).normalize_or_zero();
        if view.cross(camera.up.normalize_or_zero()).length() < 1e-3 {
            camera.up = Vec3::NEG_Z;
        }
    }
    camera
}

/// Everything a render needs that is not the device: the scene loaded and posed at the first
/// frame, the camera, lights, VPLs, shading and shadow settings of `args` (checked).
fn prepare(args: &Args) -> Result<Setup> {
    let mut scene = load_scene(args)?;
    if args.procedural_materials {
        scene::dress_procedurally(&mut scene);
    }
    let (width, height) = args.size;

    let mut camera = match (&scene.camera, &args.scene) {
        (None, Some(path)) => {
            scene::preset_view(path, &scene).unwrap_or_else(|| scene.camera_or_framed())
        }
        _ => scene.camera_or_framed(),
    };
    camera = aimed(camera, args.eye, args.target, args.fov, scene.bounds());
    let camera_source = if args.eye.is_some() || args.target.is_some() || args.fov.is_some() {
        "the camera of --eye/--target/--fov"
    } else if scene.camera.is_some() {
        "the scene file's camera"
    } else {
        "the camera framing the scene"
    };
    gbuffer::validate_camera(&camera).context(camera_source)?;
    // Smooth subdivision (uniform or adaptive) runs every frame from the (animated) control
    // meshes; flat or level-coloured subdivision is evaluated once at load.
    let per_frame = !args.subdiv_flat && !args.subdiv_show_levels;
    let tessellation = match args.subdiv_pixels {
        Some(target_pixels) => pipeline::subdivision::Tessellation::Adaptive { target_pixels },
        None => pipeline::subdivision::Tessellation::Uniform,
    };
    let plan = match args.subdiv {
        Some(level) if per_frame => {
            let meshes: Vec<usize> = match &scene.rig {
                Some(rig) => {
                    let mut moved: Vec<usize> =
                        rig.deformers.iter().map(|d| d.mesh as usize).collect();
                    moved.sort_unstable();
                    moved.dedup();
                    moved
                }
                None => (0..scene.meshes.len()).collect(),
            };
            let (prepared, plan) = pipeline::subdivision::prepare(
                &scene,
                &meshes,
                (level, tessellation),
                bft_tables()?,
            )
            .with_context(|| format!("--subdiv {level}"))?;
            scene = prepared;
            Some(plan)
        }
        Some(level) => {
            if scene.rig.take().is_some() {
                eprintln!(
                    "note: --subdiv-flat and --subdiv-show-levels are evaluated once at load: the scene's animation is dropped"
                );
            }
            subdivide_scene(&mut scene, args, level, &camera)?;
            None
        }
        None => None,
    };
    let clip = animation_clip(args, &scene)?;
    // The scene at the single frame's time, or at the sequence's start: what the structures
    // built on the CPU (VPLs, BVHs, surfels) see.
    if let Some(rig) = &scene.rig {
        let t = clip.map_or(0.0, |c| sequence::looped(args.time, rig.clips[c].duration));
        rig.apply(&rig.pose(clip, t), &mut scene.meshes);
    }
    if let Some(plan) = &plan {
        plan.refine_cpu(&mut scene, &camera, args.size)?;
    }
    let scene = scene;
    // What is drawn of it (without the subdivided control meshes), and what the CPU traces VPLs
    // and samples surfels on (with the control meshes instead of their subdivision surfaces).
    let proxy_scene = proxy(plan.as_ref(), &scene);
    let own_lights = args.lights.is_none() && !scene.lights.is_empty();
    let (mut lights, emissive_photons, lit_by) = match args.lights {
        Some(n) => (
            scene::scatter_point_lights(scene.bounds(), n, 1),
            false,
            "scattered point lights",
        ),
        None => vpl::primary_lights_sampled(&scene, args.area_samples),
    };
    let mut photon_lights = vpl::photon_lights(&lights, emissive_photons).to_vec();
    photon_lights.extend(args.extra_lights.iter().copied());
    lights.extend(args.extra_lights.iter().copied());
    let shading = pipeline::ShadingConfig {
        method: args.shading,
        tile_size: args.tile,
        search: args.light_search,
    };
    shading.validate()?;
    let indirect = match args.vpls {
        Some(count) => {
            let config = indirect_config(args, &scene)?;
            let subsets = config.subsets();
            let vpls = vpl::VplConfig {
                count: vpl::per_subset(count, subsets) as usize * subsets as usize,
                subsets,
                seed: args.seed,
                emissive: emissive_photons,
                bounces: args.vpl_bounces,
            };
            let set = vpl::generate(
                &proxy_scene,
                &scene::Bvh::build(&proxy_scene),
                &photon_lights,
                &vpls,
            )?;
            Some((config, set, vpls))
        }
        None => None,
    };
    let pbgi = match args.pbgi {
        Some(stride) => {
            if args.cpu {
                bail!("--pbgi runs on the GPU only (no --cpu)");
            }
            let config = instant_radiosity::pbgi::PbgiConfig {
                tile: args.pbgi_tile,
                epsilon: args.pbgi_epsilon,
                points_log2: args.pbgi_points,
            };
            // Sampled here, lit by the renderer's lights on the GPU every frame.
            let lit = instant_radiosity::pbgi::LitPoints::sampled(&proxy_scene, &config)
                .context("--pbgi")?;
            Some((lit, stride))
        }
        None => None,
    };
    let reflections = match args.reflections {
        Some(tile) => {
            if args.cpu {
                bail!("--reflections runs on the GPU only (no --cpu)");
            }
            let config = instant_radiosity::pbgi::PbgiConfig {
                tile,
                epsilon: args.reflection_epsilon,
                points_log2: args.reflection_points,
            };
            // Sampled here, lit by the renderer's lights on the CPU.
            let lit = instant_radiosity::pbgi::LitPoints::sampled(&proxy_scene, &config)
                .context("--reflections")?;
            Some((lit, tile))
        }
        None => None,
    };
    let default_ambient = if indirect.is_some() || pbgi.is_some() {
        Vec3::ZERO
    } else {
        DEFAULT_AMBIENT
    };
    let mut ambient = args.ambient.unwrap_or(default_ambient);
    let direct_lights = if args.indirect_only {
        if indirect.is_none() && pbgi.is_none() {
            bail!("--indirect-only needs --vpls N or --pbgi STRIDE");
        }
        ambient = Vec3::ZERO;
        Vec::new()
    } else {
        lights.clone()
    };
    let all_direct = direct_lights.len();
    let direct_lights: Vec<Light> = if args.frustum_cull {
        let aspect = width as f32 / height as f32;
        let kept = tiled_shading::frustum_cull(
            &camera,
            aspect,
            &pipeline::validate_lights(&direct_lights)?,
        );
        kept.iter().map(|&i| direct_lights[i as usize]).collect()
    } else {
        direct_lights
    };

    // The true emitters, not the hemispherical stand-ins the rasteriser lights with (for
    // --reference).
    let mut reference_lights = if emissive_photons {
        scene.lights.clone()
    } else {
        lights.clone()
    };
    if emissive_photons {
        reference_lights.extend(args.extra_lights.iter().copied());
    }
    let vpl_shadows = match (args.vpl_shadows, args.cpu) {
        (ShadowMode::Auto, false) => Some(VplShadows::ManyLod),
        (ShadowMode::Auto, true) => {
            if indirect.is_some() {
                eprintln!("note: the CPU path has no VPL visibility: VPLs light through walls");
            }
            None
        }
        (ShadowMode::None, _) => None,
        (mode, cpu) => {
            if cpu || indirect.is_none() {
                bail!("--vpl-shadows needs --vpls N and runs on the GPU only (no --cpu)");
            }
            Some(match mode {
                ShadowMode::Ism => VplShadows::Ism,
                ShadowMode::Ssm => VplShadows::Rasterised,
                ShadowMode::Rays => VplShadows::Rays,
                _ => VplShadows::ManyLod,
            })
        }
    };
    let shadow_config = args
        .shadows
        .map(|resolution| tiled_shading::shadows::ShadowMapConfig {
            resolution,
            ..Default::default()
        });
    Ok(Setup {
        pbgi,
        reflections,
        reference_lights,
        scene,
        plan,
        camera,
        lights: direct_lights,
        photon_lights,
        all_direct,
        lit_by,
        shading,
        indirect,
        ambient,
        output: output_transform(args)?,
        shadow_config,
        vpl_shadows,
        clip,
        own_lights: (
            own_lights && !args.frustum_cull && !args.indirect_only,
            own_lights && !emissive_photons,
        ),
    })
}

/// What a render is made of, after the arguments were read: the scene (at the first frame's
/// pose), camera, direct lights, indirect light, output transform and shadows.
struct Setup {
    /// The scene the GPU draws: with --subdiv, the control meshes and their refined meshes
    /// ([`pipeline::subdivision::prepare`]).
    scene: Scene,
    /// The per-frame subdivision of --subdiv, if any.
    plan: Option<pipeline::subdivision::SubdivisionPlan>,
    /// What --reference lights the scene with: the true emitters, not the hemispherical
    /// stand-ins the rasteriser lights with.
    reference_lights: Vec<Light>,
    /// --pbgi's lit surfels and receiver stride.
    pbgi: Option<(instant_radiosity::pbgi::LitPoints, u32)>,
    /// --reflections' surfels and texels.
    reflections: Option<(instant_radiosity::pbgi::LitPoints, u32)>,
    camera: scene::Camera,
    /// The direct lights the frame shades (after --indirect-only and --frustum-cull).
    lights: Vec<Light>,
    /// The lights VPLs are traced from.
    photon_lights: Vec<Light>,
    /// Direct lights before frustum culling.
    all_direct: usize,
    lit_by: &'static str,
    shading: pipeline::ShadingConfig,
    indirect: Option<(IndirectConfig, vpl::VplSet, vpl::VplConfig)>,
    ambient: Vec3,
    output: pipeline::output::OutputTransform,
    shadow_config: Option<tiled_shading::shadows::ShadowMapConfig>,
    vpl_shadows: Option<VplShadows>,
    /// The animation clip played, if the scene has one.
    clip: Option<usize>,
    /// Whether the direct and the photon lights start with the scene's own lights (whose nodes
    /// may move: `Rig::place_lights`).
    own_lights: (bool, bool),
}

/// `--clip`: the clip of the scene's rig by name or index (the first by default), `None` for a
/// still scene.
fn animation_clip(args: &Args, scene: &Scene) -> Result<Option<usize>> {
    let Some(rig) = scene.rig.as_ref().filter(|r| !r.clips.is_empty()) else {
        if let Some(c) = &args.clip {
            bail!("--clip {c:?}: the scene has no animation");
        }
        return Ok(None);
    };
    let Some(wanted) = &args.clip else {
        return Ok(Some(0));
    };
    let names: Vec<&str> = rig.clips.iter().map(|c| c.name.as_str()).collect();
    names
        .iter()
        .position(|n| n == wanted)
        .or_else(|| wanted.parse::<usize>().ok().filter(|&i| i < names.len()))
        .map(Some)
        .with_context(|| {
            format!(
                "--clip {wanted:?}: the scene's clips are {names:?} (or 0 .. {})",
                names.len() - 1
            )
        })
}

/// The GPU renderer with every stage the arguments ask for.
/// The GPU renderer `args` ask for, and how it draws the G-buffer (the summary's `gbuffer:`).
fn gpu_renderer(
    args: &Args,
    gpu: &gpu::Gpu,
    setup: &Setup,
) -> Result<(pipeline::gpu::GpuRenderer, String)> {
    let (d, q) = (&gpu.device, &gpu.queue);
    let mut renderer = pipeline::gpu::GpuRenderer::new_with(
        d,
        q,
        &setup.scene,
        &setup.lights,
        args.size,
        &texture_options(args),
    )?;
    if let Some(plan) = &setup.plan {
        renderer.set_subdivision(d, q, plan)?;
    }
    // The structures built on the CPU: those built once see what is drawn, those that follow
    // the moving meshes (surfels) the control meshes (without the rig, so say whether they
    // must follow).
    let drawn = drawn(setup.plan.as_ref(), &setup.scene);
    let proxy = proxy(setup.plan.as_ref(), &setup.scene);
    let (scene, surfels) = (&*drawn, &*proxy);
    let moves = setup.scene.rig.is_some();
    renderer.set_output(d, Some(setup.output))?;
    renderer.set_shading(d, q, &setup.shading)?;
    renderer.set_blended(d, q, args.blend)?;
    renderer.set_visibility(d, args.visibility == Some(VisibilityMode::On))?;
    renderer.set_shadows(d, q, setup.shadow_config.as_ref())?;
    if let Some(tile) = args.manylod_shadows {
        let config = ShadowConfig {
            tile,
            refit: moves,
            ..ShadowConfig::default()
        };
        renderer.set_manylod_shadows(d, q, surfels, Some(&config))?;
    }
    if args.ray_shadows {
        renderer.set_ray_shadows(d, q, Some(scene))?;
    }
    if let Some((config, set, _)) = &setup.indirect {
        match setup.vpl_shadows {
            Some(mode) => renderer.set_vpl_shadows(
                d,
                surfels,
                mode,
                &ShadowConfig {
                    epsilon: args.vpl_shadow_epsilon,
                    points_log2: args.vpl_shadow_points,
                    refit: moves,
                    ..ShadowConfig::for_mode(mode)
                },
                config,
                set,
            )?,
            None => renderer.set_indirect(d, config, set)?,
        }
        if args.near_field {
            renderer.set_near_field(d, Some(scene))?;
        }
    }
    if let Some((lit, stride)) = &setup.pbgi {
        renderer.set_pbgi(d, Some((lit, *stride, scene)))?;
    }
    if let Some((lit, tile)) = &setup.reflections {
        renderer
            .set_reflections(d, Some((lit, *tile, scene)))
            .context("--reflections")?;
    }
    renderer.set_ssaa(d, q, ssaa_config(args)?.as_ref())?;
    if let Some((config, estimator)) = ssao_setting(args, &setup.scene)? {
        renderer.set_ssao(d, q, Some((&config, estimator)))?;
    }
    renderer.set_ambient(q, setup.ambient);
    let gbuffer = match args.visibility {
        Some(VisibilityMode::Auto) => {
            let choice = renderer
                .choose_gbuffer_path(d, q, &setup.camera, 5)
                .context("--visibility=auto")?;
            match renderer.visibility_resolve() {
                Some(path) => format!("{choice}; {}", resolve_words(path)),
                None => choice.to_string(),
            }
        }
        Some(VisibilityMode::On) => {
            let resolve = renderer
                .visibility_resolve()
                .map_or("resolve", resolve_words);
            format!("visibility buffer (compute rasteriser, {resolve}, depth drawn from it)")
        }
        None => "hardware rasteriser (z-prepass, then the G-buffer pass)".into(),
    };
    Ok((renderer, gbuffer))
}

/// How the visibility buffer's resolve runs, for the `gbuffer:` line.
fn resolve_words(path: ResolvePath) -> &'static str {
    match path {
        ResolvePath::OneDispatch => "resolve in one dispatch",
        ResolvePath::Classified => "resolve by material tiles",
    }
}

/// `--ssao METHOD [--ssao-kernel K --ssao-radius R]` (checked).
fn ssao_setting(
    args: &Args,
    scene: &Scene,
) -> Result<Option<(ssao::cpu::KernelConfig, ssao::Estimator)>> {
    let Some(estimator) = args.ssao else {
        return Ok(None);
    };
    let config = ssao::cpu::KernelConfig {
        size: args.ssao_kernel,
        ao: ssao::AoConfig {
            radius: args.ssao_radius.unwrap_or(0.05 * scene.bounds().diagonal()),
        },
    };
    config.validate().context("--ssao")?;
    Ok(Some((config, estimator)))
}

/// `--ssaa M [--adaptive --ssaa-metric METRIC]` as the frame's supersampling (checked).
fn ssaa_config(args: &Args) -> Result<Option<adaptive_ssaa::SsaaConfig>> {
    let Some(m) = args.ssaa else {
        return Ok(None);
    };
    let config = adaptive_ssaa::SsaaConfig {
        m,
        metric: Some(args.ssaa_metric),
        min_samples: if args.adaptive {
            1
        } else {
            m.saturating_mul(m)
        },
        anisotropy: args.anisotropy,
        ..Default::default()
    };
    config.validate().with_context(|| format!("--ssaa {m}"))?;
    Ok(Some(config))
}

/// Writes the samples each pixel took as `ssaa-samples.png` and says their share.
fn write_ssaa_samples(
    args: &Args,
    gpu: &gpu::Gpu,
    renderer: &pipeline::gpu::GpuRenderer,
) -> Result<()> {
    let (Some(config), Some(counts)) = (
        renderer.ssaa(),
        renderer.ssaa_counts(&gpu.device, &gpu.queue)?,
    ) else {
        return Ok(());
    };
    let (m, n) = (config.m, config.samples());
    let total: u64 = counts.pixels().iter().map(|&k| u64::from(k)).sum();
    let share = 100.0 * total as f64 / (counts.pixels().len() as f64 * f64::from(n));
    if args.adaptive {
        make_dir(&args.out)?;
        let path = args.out.join("ssaa-samples.png");
        save_png(&adaptive_ssaa::cpu::sample_heatmap(&counts, n), &path)?;
        println!(
            "ssaa:    adaptive {m}x{m}, {} + shading metric: {share:.1} % of the samples ({})",
            args.ssaa_metric,
            path.display()
        );
    } else {
        println!("ssaa:    full {m}x{m} supersampling");
    }
    Ok(())
}

/// The frame's VPLs for `scene` posed at some time (the same seed, so the same Halton
/// indices and random numbers each frame: the subsets stay put where nothing moved).
/// The scene as a sequence poses it on the CPU, and the BVH its VPLs are traced through: built
/// when VPLs are first traced and again only after meshes moved (lights alone moving reuse it;
/// without indirect light none is built).
struct Posed {
    scene: Scene,
    /// Whether the subdivision surfaces are evaluated on the CPU too (the CPU frame draws them).
    refine: bool,
    /// The scene the VPLs and surfels follow (the control meshes of subdivided ones) and its
    /// BVH, made when first asked for after a pose.
    proxy: Option<(Scene, Option<scene::Bvh>)>,
}

impl Posed {
    fn new(setup: &Setup, refine: bool) -> Self {
        Self {
            scene: setup.scene.clone(),
            refine,
            proxy: None,
        }
    }

    /// The meshes at `pose` of `rig`, if given, and, when refining, their subdivision surfaces
    /// by `plan` (CPU; adaptive surfaces for `camera` over a `size` frame, whether the meshes
    /// moved or not). Whether the meshes moved.
    fn pose(
        &mut self,
        plan: Option<&pipeline::subdivision::SubdivisionPlan>,
        posed: Option<(&scene::animation::Rig, &scene::animation::Pose)>,
        camera: &scene::Camera,
        size: (u32, u32),
    ) -> Result<bool> {
        let adaptive = plan.is_some_and(|p| {
            matches!(
                p.tessellation(),
                pipeline::subdivision::Tessellation::Adaptive { .. }
            )
        });
        if let Some((rig, pose)) = posed {
            rig.apply(pose, &mut self.scene.meshes);
            self.proxy = None;
        }
        if let Some(plan) = plan.filter(|_| self.refine && (posed.is_some() || adaptive)) {
            plan.refine_cpu(&mut self.scene, camera, size)?;
        }
        Ok(posed.is_some())
    }

    /// What the VPLs and surfels follow of the posed scene subdivided by `plan`.
    fn proxy(&mut self, plan: Option<&pipeline::subdivision::SubdivisionPlan>) -> &Scene {
        let scene = &self.scene;
        &self
            .proxy
            .get_or_insert_with(|| (proxy(plan, scene).into_owned(), None))
            .0
    }

    /// The frame's VPLs from `photon_lights`.
    fn vpls(&mut self, setup: &Setup, photon_lights: &[Light]) -> Result<Option<vpl::VplSet>> {
        let Some((_, _, config)) = &setup.indirect else {
            return Ok(None);
        };
        self.proxy(setup.plan.as_ref());
        let Some((scene, bvh)) = &mut self.proxy else {
            return Ok(None);
        };
        let bvh = bvh.get_or_insert_with(|| scene::Bvh::build(scene));
        Ok(Some(vpl::generate(scene, bvh, photon_lights, config)?))
    }
}

/// What the CPU traces VPLs and samples surfels on: `scene` with the control meshes `plan`
/// subdivides instead of their subdivision surfaces.
fn proxy<'s>(
    plan: Option<&pipeline::subdivision::SubdivisionPlan>,
    scene: &'s Scene,
) -> std::borrow::Cow<'s, Scene> {
    planned(plan, scene, pipeline::subdivision::SubdivisionPlan::proxy)
}

/// What the GPU draws of `scene`: without the control meshes `plan` subdivides.
fn drawn<'s>(
    plan: Option<&pipeline::subdivision::SubdivisionPlan>,
    scene: &'s Scene,
) -> std::borrow::Cow<'s, Scene> {
    planned(plan, scene, pipeline::subdivision::SubdivisionPlan::drawn)
}

/// `scene` as `view` of `plan` sees it, or `scene` itself without a plan.
fn planned<'s>(
    plan: Option<&pipeline::subdivision::SubdivisionPlan>,
    scene: &'s Scene,
    view: fn(&pipeline::subdivision::SubdivisionPlan, &Scene) -> Scene,
) -> std::borrow::Cow<'s, Scene> {
    match plan {
        Some(plan) => std::borrow::Cow::Owned(view(plan, scene)),
        None => std::borrow::Cow::Borrowed(scene),
    }
}

/// The direct and photon lights at `t` seconds turned by --light-orbit about the vertical
/// axis through the scene's centre, or `None` when they stay.
fn moved_lights(
    args: &Args,
    setup: &Setup,
    t: f32,
    pose: Option<&scene::animation::Pose>,
) -> Option<(Vec<Light>, Vec<Light>)> {
    // The file's lights on moving nodes, where the lists start with the scene's lights.
    let rig = setup.scene.rig.as_ref().filter(|r| !r.lights.is_empty());
    let placed = match (rig, pose) {
        (Some(rig), Some(pose)) => {
            let place = |lights: &[Light], own: bool| {
                let mut lights = lights.to_vec();
                if own {
                    rig.place_lights(pose, &mut lights);
                }
                lights
            };
            let (direct, photons) = setup.own_lights;
            Some((
                place(&setup.lights, direct),
                place(&setup.photon_lights, photons),
            ))
        }
        _ => None,
    };
    let Some(degrees_per_second) = args.light_orbit else {
        return placed;
    };
    let centre = setup.scene.bounds().center();
    let turn = glam::Mat4::from_translation(centre)
        * glam::Mat4::from_rotation_y((degrees_per_second * t).to_radians())
        * glam::Mat4::from_translation(-centre);
    let moved = |lights: &[Light]| lights.iter().map(|l| l.transformed(turn)).collect();
    let (direct, photons) =
        placed.unwrap_or_else(|| (setup.lights.clone(), setup.photon_lights.clone()));
    Some((moved(&direct), moved(&photons)))
}

/// The CPU frame of `scene` from `camera` (with `vpls` instead of the set-up's, when given).
fn cpu_frame(
    args: &Args,
    setup: &Setup,
    (scene, lights): (&Scene, &[Light]),
    camera: &scene::Camera,
    vpls: Option<&vpl::VplSet>,
) -> Result<(Rendered, Option<IndirectStages>)> {
    let scene = &*drawn(setup.plan.as_ref(), scene);
    let mut inputs =
        pipeline::cpu::FrameInputs::new(scene, camera, lights, args.size, setup.ambient)
            .with_textures(texture_options(args));
    if let Some(config) = setup.shadow_config {
        inputs = inputs.with_shadows(config);
    }
    let indirect = setup
        .indirect
        .as_ref()
        .map(|(config, set, _)| (config, vpls.unwrap_or(set)));
    Ok(pipeline::cpu::render_indirect(
        &inputs,
        &setup.shading,
        indirect,
    )?)
}

/// A sequence's clock, camera path and output folder, and its per-frame bookkeeping.
struct Sequence {
    frames: u32,
    clock: sequence::Clock,
    path: sequence::CameraPath,
    dir: PathBuf,
    timeline: sequence::Timeline,
    start: std::time::Instant,
    bar: indicatif::ProgressBar,
    /// The frames at preview size ([`PREVIEW_WIDTH`]), for preview.gif.
    preview: Vec<image::RgbaImage>,
}

/// A written frame: its display image and, with --frame-exr, its radiance.
type FrameImages<'a> = (
    &'a gbuffer::Image<[f32; 4]>,
    Option<&'a gbuffer::Image<[f32; 4]>>,
);

/// The widest preview.gif frame.
const PREVIEW_WIDTH: u32 = 320;

impl Sequence {
    /// The sequence's clock, camera path (checked before anything is written) and folder.
    fn new(args: &Args, frames: u32, base: &scene::Camera) -> Result<Self> {
        let (clock, path) = (sequence::Clock::new(args.fps)?, camera_path(args, base)?);
        let dir = args.out.join("frames");
        make_dir(&dir)?;
        let bar = indicatif::ProgressBar::new(u64::from(frames)).with_message("rendering");
        bar.set_style(
            indicatif::ProgressStyle::with_template(
                "{spinner} {msg} [{bar:30}] {pos}/{len} frames, {eta} left",
            )
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
        );
        Ok(Self {
            frames,
            clock,
            path,
            dir,
            timeline: Default::default(),
            start: std::time::Instant::now(),
            bar,
            preview: Vec::new(),
        })
    }

    /// The camera at `t`: the path's; or, with no path and no --eye/--target/--fov, the scene
    /// file's camera where its node moves.
    fn camera(
        &self,
        args: &Args,
        setup: &Setup,
        t: f32,
        pose: Option<&scene::animation::Pose>,
    ) -> scene::Camera {
        let own = args.eye.is_none() && args.target.is_none() && args.fov.is_none();
        let moving = match (&setup.scene.rig, pose) {
            (Some(rig), Some(pose)) if own && self.path == sequence::CameraPath::Still => {
                rig.camera(pose)
            }
            _ => None,
        };
        moving.unwrap_or_else(|| self.path.camera(&setup.camera, t))
    }

    /// The scene's pose at frame time `t` (looping its clip), or `None` for a still scene.
    fn pose(setup: &Setup, t: f32) -> Option<scene::animation::Pose> {
        let rig = setup.scene.rig.as_ref()?;
        let time = setup
            .clip
            .map_or(0.0, |c| sequence::looped(t, rig.clips[c].duration));
        Some(rig.pose(setup.clip, time))
    }

    /// Writes frame `k`'s display image (and radiance with --frame-exr) and records its passes.
    fn finish_frame(
        &mut self,
        args: &Args,
        k: u32,
        t: f32,
        submitted_us: f64,
        images: Option<FrameImages>,
        passes: Vec<gpu::PassTime>,
    ) -> Result<()> {
        self.timeline.push(k, t, submitted_us, passes);
        self.bar.inc(1);
        let Some((display, radiance)) = images else {
            return Ok(());
        };
        save_png(display, &self.dir.join(format!("frame-{k:05}.png")))?;
        let (w, h) = (display.width(), display.height());
        let rgba: Vec<u8> = display
            .to_srgb8()
            .chunks_exact(3)
            .flat_map(|c| [c[0], c[1], c[2], 255])
            .collect();
        let frame = image::RgbaImage::from_raw(w, h, rgba).context("a frame's pixels")?;
        let scale = (PREVIEW_WIDTH as f32 / w as f32).min(1.0);
        let size = (
            (w as f32 * scale).round().max(1.0) as u32,
            (h as f32 * scale).round().max(1.0) as u32,
        );
        self.preview.push(image::imageops::resize(
            &frame,
            size.0,
            size.1,
            image::imageops::FilterType::Triangle,
        ));
        if let Some(radiance) = radiance.filter(|_| args.frame_exr) {
            save_exr(radiance, &self.dir.join(format!("frame-{k:05}.exr")))?;
        }
        Ok(())
    }

    /// Writes timings.csv and trace.json and prints the per-pass median and 99th percentile.
    fn finish(self, args: &Args) -> Result<()> {
        self.bar.finish_and_clear();
        let csv = args.out.join("timings.csv");
        let trace = args.out.join("trace.json");
        let (plot, gif) = (args.out.join("timings.svg"), args.out.join("preview.gif"));
        save_text(&self.timeline.csv(), &csv)?;
        save_text(&self.timeline.chrome_trace(), &trace)?;
        save_text(
            &self.timeline.plot_svg("GPU time per pass and frame")?,
            &plot,
        )?;
        let delay =
            image::Delay::from_numer_denom_ms(1000, (self.clock.fps().round() as u32).max(1));
        gbuffer::write_atomically(&gif, |tmp| {
            let file = std::fs::File::create(tmp).map_err(|e| e.to_string())?;
            let mut encoder = image::codecs::gif::GifEncoder::new_with_speed(file, 10);
            encoder
                .set_repeat(image::codecs::gif::Repeat::Infinite)
                .map_err(|e| e.to_string())?;
            encoder
                .encode_frames(
                    self.preview
                        .into_iter()
                        .map(|f| image::Frame::from_parts(f, 0, 0, delay)),
                )
                .map_err(|e| e.to_string())
        })?;
        record(&gif);
        let n = self.timeline.frames.len();
        println!(
            "wrote:   {n} frames in {} ({:.1} s), {}, {}, {} and {}",
            self.dir.display(),
            self.start.elapsed().as_secs_f64(),
            csv.display(),
            trace.display(),
            plot.display(),
            gif.display()
        );
        println!();
        println!(
            "{:<32} {:>10} {:>10}",
            "pass (over the frames)", "median ms", "p99 ms"
        );
        for s in self.timeline.summary() {
            println!("{:<32} {:>10.3} {:>10.3}", s.name, s.median_ms, s.p99_ms);
        }
        Ok(())
    }
}

/// The camera path of --orbit or --camera-key (eye and target from the keys, the rest from
/// `base`).
fn camera_path(args: &Args, base: &scene::Camera) -> Result<sequence::CameraPath> {
    if let Some(degrees_per_second) = args.orbit {
        return Ok(sequence::CameraPath::Orbit { degrees_per_second });
    }
    if args.camera_keys.is_empty() {
        return Ok(sequence::CameraPath::Still);
    }
    if args.camera_keys.windows(2).any(|w| w[1].0 <= w[0].0) {
        bail!("--camera-key: the keys' times must increase");
    }
    let keys = args
        .camera_keys
        .iter()
        .map(|&(t, eye, target)| {
            let mut camera = scene::Camera {
                eye,
                target,
                ..*base
            };
            if (target - eye).normalize_or_zero().cross(camera.up).length() < 1e-3 {
                camera.up = Vec3::NEG_Z;
            }
            gbuffer::validate_camera(&camera).with_context(|| format!("--camera-key at {t} s"))?;
            Ok((t, camera))
        })
        .collect::<Result<_>>()?;
    Ok(sequence::CameraPath::Keyframes(keys))
}

/// Poses the GPU frame at `t` seconds of the clip: skinning pose, moving lights, the surfels
/// and VPLs the CPU builds from moving meshes. Returns the camera `camera` picks for the pose
/// (the adaptive tessellation follows it).
fn pose_frame(
    args: &Args,
    gpu: &gpu::Gpu,
    renderer: &mut pipeline::gpu::GpuRenderer,
    setup: &Setup,
    posed: &mut Posed,
    t: f32,
    camera: impl FnOnce(Option<&scene::animation::Pose>) -> scene::Camera,
) -> Result<scene::Camera> {
    let (d, q) = (&gpu.device, &gpu.queue);
    let pose = Sequence::pose(setup, t);
    let lights = moved_lights(args, setup, t, pose.as_ref());
    if let Some(pose) = &pose {
        renderer.set_pose(q, pose)?;
    }
    if let Some((direct, _)) = &lights {
        renderer.set_lights(d, q, direct)?;
    }
    let camera = camera(pose.as_ref());
    // The CPU follows the meshes where it builds from them (surfels, VPLs); an adaptive
    // tessellation changes with the camera, a refit needs the same triangles, so the
    // surfels follow only moving meshes.
    let surfels = setup.indirect.is_some() || args.manylod_shadows.is_some();
    let moved = match (&pose, &setup.scene.rig, surfels) {
        (Some(pose), Some(rig), true) => {
            posed.pose(setup.plan.as_ref(), Some((rig, pose)), &camera, args.size)?;
            let (positions, _) =
                instant_radiosity::shadows::scene_mesh(posed.proxy(setup.plan.as_ref()));
            renderer.set_scene_positions(q, &positions)?;
            true
        }
        _ => false,
    };
    if setup.indirect.is_some() && (moved || lights.is_some()) {
        let photons = lights.as_ref().map_or(&setup.photon_lights, |(_, p)| p);
        if let Some(set) = posed.vpls(setup, photons)? {
            renderer.set_vpls(q, &set)?;
        }
    }
    Ok(camera)
}

/// `--frames N` on the GPU: the renderer skins the animated meshes every frame; the VPLs are
/// traced again on the CPU for the posed scene when it moves.
fn gpu_sequence(
    args: &Args,
    gpu: &gpu::Gpu,
    renderer: &mut pipeline::gpu::GpuRenderer,
    setup: &Setup,
    mut seq: Sequence,
) -> Result<()> {
    let (d, q) = (&gpu.device, &gpu.queue);
    let frames = seq.frames;
    renderer.set_animation(d, q, setup.scene.rig.as_ref())?;
    let mut posed = Posed::new(setup, false);
    let mut warmed = 0;
    for k in (0..args.warm_up).map(|_| 0).chain(0..frames) {
        let t = seq.clock.time(k);
        let camera = pose_frame(args, gpu, renderer, setup, &mut posed, t, |pose| {
            seq.camera(args, setup, t, pose)
        })?;
        renderer.set_camera(q, &camera)?;
        renderer.follow_visibility_split(d)?;
        let submitted_us = seq.start.elapsed().as_secs_f64() * 1e6;
        let mut encoder = d.create_command_encoder(&Default::default());
        renderer.encode(&mut encoder);
        q.submit([encoder.finish()]);
        let passes = renderer.pass_times(d, q)?;
        if renderer.check_pbgi(d, q)? {
            eprintln!("note: point-based GI's cut lists grew to hold frame {k}'s cut");
        }
        if renderer.check_reflections(d, q)? {
            eprintln!("note: the reflection maps' cut lists grew to hold frame {k}'s cut");
        }
        if renderer.check_visibility(d, q)? {
            eprintln!("note: the visibility buffer's lists grew to hold frame {k}'s triangles");
        }
        if warmed < args.warm_up {
            warmed += 1;
            continue;
        }
        let images = if k % args.frame_every == 0 {
            let display = renderer
                .display()
                .context("the renderer has an output stage")?;
            let display = pipeline::gpu::read_display(d, q, display)?;
            let radiance = args
                .frame_exr
                .then(|| pipeline::gpu::read_radiance(d, q, renderer.output()))
                .transpose()?;
            Some((display, radiance))
        } else {
            None
        };
        let images = images.as_ref().map(|(d, r)| (d, r.as_ref()));
        seq.finish_frame(args, k, t, submitted_us, images, passes)?;
    }
    seq.finish(args)
}

/// `--frames N` on the CPU: every frame poses the scene (`Rig::deform`, the GPU skinning's
/// twin), traces the VPLs again when it moves, and renders with the CPU frame.
fn cpu_sequence(args: &Args, setup: &Setup, mut seq: Sequence) -> Result<()> {
    let frames = seq.frames;
    let mut posed = Posed::new(setup, true);
    for k in 0..frames {
        let t = seq.clock.time(k);
        let pose = Sequence::pose(setup, t);
        let lights = moved_lights(args, setup, t, pose.as_ref());
        let camera = seq.camera(args, setup, t, pose.as_ref());
        let rigged = pose
            .as_ref()
            .zip(setup.scene.rig.as_ref())
            .map(|(p, r)| (r, p));
        let moved = posed.pose(setup.plan.as_ref(), rigged, &camera, args.size)?;
        let (direct, photons) = match &lights {
            Some((direct, photons)) => (&direct[..], &photons[..]),
            None => (&setup.lights[..], &setup.photon_lights[..]),
        };
        let vpls = if moved || lights.is_some() {
            posed.vpls(setup, photons)?
        } else {
            None
        };
        let submitted_us = seq.start.elapsed().as_secs_f64() * 1e6;
        let (rendered, _) = cpu_frame(args, setup, (&posed.scene, direct), &camera, vpls.as_ref())?;
        let mut start_ms = 0.0;
        let passes = rendered
            .timings
            .iter()
            .map(|p| {
                let pass = gpu::PassTime {
                    name: p.name.clone(),
                    ms: p.ms,
                    start_ms,
                };
                start_ms += p.ms;
                pass
            })
            .collect();
        let display = setup.output.apply(&rendered.image);
        let images = (k % args.frame_every == 0).then_some((&display, Some(&rendered.image)));
        seq.finish_frame(args, k, t, submitted_us, images, passes)?;
    }
    seq.finish(args)
}

/// Prints the device, scene, light accumulation and indirect light of the render.
/// The summary of the run's setup; `gbuffer`: how the GPU draws the G-buffer (none on the CPU).
fn print_setup(args: &Args, setup: &Setup, device: &str, gbuffer: Option<&str>) {
    let (width, height) = args.size;
    let shading = &setup.shading;
    if let Some(recipe) = &args.recipe {
        println!("recipe:  {}", recipe.display());
    }
    println!("device:  {device}");
    println!(
        "scene:   {} triangles, {} direct lights ({}), {width}x{height}",
        drawn(setup.plan.as_ref(), &setup.scene).triangle_count(),
        setup.all_direct,
        setup.lit_by,
    );
    if let Ok(Some((config, estimator))) = ssao_setting(args, &setup.scene) {
        println!(
            "ssao:    {estimator:?}, kernel {}, radius {}",
            config.size, config.ao.radius
        );
    }
    if let Some(plan) = &setup.plan {
        println!(
            "subdiv:  Loop level {} of {} control meshes, every frame from their posed vertices",
            plan.level(),
            plan.controls().count()
        );
    }
    if let (Some(rig), Some(c)) = (&setup.scene.rig, setup.clip) {
        let clip = &rig.clips[c];
        println!(
            "animation: clip {c} {:?} ({:.2} s), {} moving meshes{}",
            clip.name,
            clip.duration,
            rig.deformers.len(),
            match args.frames {
                Some(n) => format!(", {n} frames at {} fps", args.fps),
                None => format!(", at {} s", args.time),
            }
        );
    }
    if let Some(gbuffer) = gbuffer {
        println!("gbuffer: {gbuffer}");
    }
    println!(
        "shading: {}{}{}",
        shading.method,
        if matches!(
            shading.method,
            pipeline::ShadingMethod::BruteForce | pipeline::ShadingMethod::LightVolumes
        ) {
            String::new()
        } else {
            format!(", {0}x{0} tiles", shading.tile_size)
        },
        if args.frustum_cull {
            format!(", CPU frustum culling kept {} lights", setup.lights.len())
        } else {
            String::new()
        },
    );
    let shadows = if args.ray_shadows {
        "exact, a ray per pixel and light".to_owned()
    } else {
        let maps = setup
            .shadow_config
            .map(|c| format!("shadow maps of {0}x{0} texels a view", c.resolution));
        let manylod = args
            .manylod_shadows
            .map(|t| format!("ManyLoD paraboloids of {t}x{t} for point/spot lights"));
        let both: Vec<String> = maps.into_iter().chain(manylod).collect();
        if both.is_empty() {
            "none".to_owned()
        } else {
            both.join(", ")
        }
    };
    println!("shadows: {shadows}");
    if let Some((config, set, _)) = &setup.indirect {
        println!(
            "indirect: {} VPLs in {} subsets of {} ({}), blur {}",
            set.vpls.len(),
            set.subsets,
            set.per_subset,
            match config.interleaving {
                Interleaving::Reference => "no interleaving: every pixel shades every VPL".into(),
                Interleaving::Fused => format!("{}x{} fused", config.pattern.n, config.pattern.m),
                Interleaving::Split(v) => format!(
                    "{}x{} split {}",
                    config.pattern.n,
                    config.pattern.m,
                    v.name()
                ),
            },
            config.applied_blur().map_or("off".into(), |b| format!(
                "{0}x{0} {1:?}",
                b.kernel, b.variant
            )),
        );
        println!(
            "visibility: {}",
            match setup.vpl_shadows {
                Some(VplShadows::ManyLod) => format!(
                    "ManyLoD cuts, ε {} px, 2^{} surfels",
                    args.vpl_shadow_epsilon, args.vpl_shadow_points
                ),
                Some(VplShadows::Ism) => format!("ISM, 2^{} surfels", args.vpl_shadow_points),
                Some(VplShadows::Rasterised) => "rasterised hemicubes (exact)".into(),
                Some(VplShadows::Rays) => "rays (exact)".into(),
                None => "none: VPLs light through walls".into(),
            }
        );
    }
    if let Some((lit, stride)) = &setup.pbgi {
        let c = lit.config();
        println!(
            "indirect: point-based GI, a receiver every {stride} px, {0}x{0} texels, ε {1}, 2^{2} surfels",
            c.tile, c.epsilon, c.points_log2
        );
    }
    if let Some((lit, _)) = &setup.reflections {
        let c = lit.config();
        let probes = instant_radiosity::reflections::Probes::of_scene(&setup.scene);
        println!(
            "reflect: {} mirror and glass meshes, maps of 2 × {}x{} texels, ε {}, 2^{} surfels",
            probes.len(),
            c.tile,
            c.tile,
            c.epsilon,
            c.points_log2
        );
    }
    let o = &setup.output;
    println!(
        "output:  {:?} tone curve, exposure {:+} EV{}",
        o.tone_mapper,
        o.exposure_ev,
        if o.auto_exposure { " + automatic" } else { "" }
    );
}

/// Writes the per-tile light counts as `heatmap.png` (the thesis's light-count figures).
fn write_heatmap(
    args: &Args,
    shading: &pipeline::ShadingConfig,
    width: u32,
    height: u32,
    counts: &[u32],
) -> Result<()> {
    let out = &args.out;
    make_dir(out)?;
    let max = args
        .heatmap_max
        .unwrap_or_else(|| counts.iter().copied().max().unwrap_or(0));
    let path = out.join("heatmap.png");
    save_png(
        &tiled_shading::heatmap(counts, shading, width, height, max.max(1)),
        &path,
    )?;
    println!(
        "heatmap: {} (black 0 → white {max} lights per tile)",
        path.display()
    );
    Ok(())
}

/// Per-pass milliseconds summed by name, in first-seen order, and per million fragments.
fn print_table(timings: &[PassTiming], fragments: f64) {
    let mut rows: Vec<(String, f64)> = Vec::new();
    for t in timings {
        match rows.iter_mut().find(|(n, _)| *n == t.name) {
            Some(row) => row.1 += t.ms,
            None => rows.push((t.name.clone(), t.ms)),
        }
    }
    println!("{:<32} {:>10} {:>14}", "pass", "ms", "ms/Mfragment");
    let per = |ms: f64| ms / (fragments / 1e6);
    for (name, ms) in &rows {
        println!("{name:<32} {ms:>10.3} {:>14.3}", per(*ms));
    }
    if !rows.is_empty() {
        let total: f64 = rows.iter().map(|r| r.1).sum();
        println!("{:<32} {total:>10.3} {:>14.3}", "total", per(total));
    }
}

/// A G-buffer channel as an image ([`gbuffer_channel`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum GBufferChannel {
    /// View-space depth, near white to far black (empty pixels black).
    Depth,
    /// Octahedral normals as RGB = (n + 1) / 2.
    Normal,
    /// Base colour.
    Albedo,
    /// Roughness in red, metallic in green.
    Material,
}

/// `channel` of `gb` as a linear image to show or write.
fn gbuffer_channel(gb: &gbuffer::GBuffer, channel: GBufferChannel) -> gbuffer::Image<[f32; 4]> {
    match channel {
        GBufferChannel::Depth => {
            let max_depth = gb
                .linear_depth
                .pixels()
                .iter()
                .copied()
                .fold(0.0f32, f32::max);
            gb.linear_depth.map(|d| {
                let v = if d > 0.0 {
                    1.0 - d / max_depth.max(1e-6)
                } else {
                    0.0
                };
                [v, v, v, 1.0]
            })
        }
        GBufferChannel::Normal => normal_image(&gb.normal),
        GBufferChannel::Albedo => gb
            .albedo
            .map(|a| [0, 1, 2, 3].map(|c| gbuffer::srgb_to_linear(f32::from(a[c]) / 255.0))),
        GBufferChannel::Material => gb.material.map(|w| {
            let (r, m, _) = gbuffer::unpack_material(w);
            if w == gbuffer::NO_MATERIAL {
                [0.0; 4]
            } else {
                [r, m, 0.0, 1.0]
            }
        }),
    }
}

/// Octahedral normal words as RGB = (n + 1) / 2.
fn normal_image(img: &gbuffer::Image<u32>) -> gbuffer::Image<[f32; 4]> {
    img.map(|w| {
        let n = gbuffer::normal::unpack_octahedral(w);
        [n.x * 0.5 + 0.5, n.y * 0.5 + 0.5, n.z * 0.5 + 0.5, 1.0]
    })
}

/// The discontinuity buffer's bytes as an image.
fn discontinuity_image(db: &gbuffer::Image<[u8; 4]>) -> gbuffer::Image<[f32; 4]> {
    db.map(|p| [0, 1, 2, 3].map(|c| f32::from(p[c]) / 255.0))
}

/// Writes the G-buffer channels and every indirect stage as PNGs (irradiance also as EXR).
fn dump_stages(
    out: &std::path::Path,
    gb: &gbuffer::GBuffer,
    stages: Option<&IndirectStages>,
) -> Result<()> {
    use gbuffer::Image;
    let dir = out.join("stages");
    make_dir(&dir)?;
    for (channel, name) in [
        (GBufferChannel::Depth, "gbuffer-depth.png"),
        (GBufferChannel::Normal, "gbuffer-normal.png"),
        (GBufferChannel::Albedo, "gbuffer-albedo.png"),
        (GBufferChannel::Material, "gbuffer-roughness-metallic.png"),
    ] {
        save_png(&gbuffer_channel(gb, channel), &dir.join(name))?;
    }
    let Some(s) = stages else {
        return Ok(());
    };
    let opaque = |img: &Image<[f32; 4]>| img.map(|p| [p[0], p[1], p[2], 1.0]);
    let irradiance = |name: &str, img: &Image<[f32; 4]>| -> Result<()> {
        save_png(&opaque(img), &dir.join(format!("{name}.png")))?;
        save_exr(&opaque(img), &dir.join(format!("{name}.exr")))?;
        Ok(())
    };
    if let Some(split) = &s.split_normal {
        save_png(&normal_image(split), &dir.join("split-normal.png"))?;
        irradiance("split-indirect-diffuse", &s.shaded_diffuse)?;
    }
    irradiance("indirect-diffuse", &s.diffuse)?;
    irradiance("indirect-specular", &s.specular)?;
    if let Some(db) = &s.discontinuities {
        save_png(&discontinuity_image(db), &dir.join("discontinuities.png"))?;
    }
    if let Some([d, sp]) = &s.blurred {
        irradiance("indirect-diffuse-blurred", d)?;
        irradiance("indirect-specular-blurred", sp)?;
    }
    Ok(())
}

/// `--visibility` modes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
enum VisibilityMode {
    /// The visibility buffer.
    On,
    /// The faster of the visibility buffer and the hardware rasteriser, measured.
    Auto,
}

/// `--vpl-shadows` modes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
enum ShadowMode {
    /// ManyLoD on the GPU, none with --cpu.
    Auto,
    /// No VPL visibility.
    None,
    /// ManyLoDs cuts.
    Manylod,
    /// Imperfect shadow maps.
    Ism,
    /// Exact: every VPL's hemicube rasterised (Segovia 2006's SSM).
    Ssm,
    /// Exact without maps: a ray per pixel and VPL through a BVH of the scene on the GPU.
    Rays,
}

/// Writes the VPL shadow-map atlas as a grey image (near = dark, empty = white).
fn write_shadow_atlas(
    args: &Args,
    gpu: &gpu::Gpu,
    shadows: &instant_radiosity::shadows::VplShadowMaps,
) -> Result<()> {
    let atlas = atlas_image(gpu, shadows)?;
    make_dir(&args.out)?;
    let path = args.out.join("vpl-shadow-atlas.png");
    save_png(&atlas, &path)?;
    println!("wrote {}", path.display());
    Ok(())
}

/// The VPL shadow-map atlas as a grey image (near = dark, empty = white).
fn atlas_image(
    gpu: &gpu::Gpu,
    shadows: &instant_radiosity::shadows::VplShadowMaps,
) -> Result<gbuffer::Image<[f32; 4]>> {
    let (w, h) = shadows.layout().size();
    let atlas = shadows.read_atlas(&gpu.device, &gpu.queue)?;
    let pixels: Vec<[f32; 4]> = atlas
        .iter()
        .map(|&word| {
            let d = manylod::splat::unpack_depth(word).clamp(0.0, 1.0).sqrt();
            [d, d, d, 1.0]
        })
        .collect();
    Ok(gbuffer::Image::from_vec(w, h, pixels)?)
}
