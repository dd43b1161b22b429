//! GPU deferred renderer: the G-buffer render pass, then the light accumulation
//! ([`tiled_shading::gpu::LightShading`]) and composition compute passes. Pipelines and bind groups are built once; nothing is read
//! back between passes.

use ::gpu::kernel::{Binding, Kernel, Passes, Workgroups};
use ::gpu::{PassTimer, transfer};
use adaptive_ssaa::SsaaConfig;
use gbuffer::{
    Frame, Image, TextureOptions,
    gpu::{
        BlendedSurfaces, GBufferPass, GBufferTargets, GpuScene,
        visibility::{Atomics, Capacity, Resolve, ResolvePass, Visibility, VisibilityPass},
    },
};
use glam::{Vec3, Vec4};
use scene::{Camera, Light, Scene};

use crate::output::{self, BoundOutput, OutputPass, OutputTransform};
use wgpu::util::DeviceExt;

use crate::skinning::{BoundSkinning, Skinning};
use crate::subdivision::{SubdivisionPlan, SubdivisionStage};
use crate::supersampling::{Supersampling, SupersamplingKernels};
use crate::{GpuLight, PassTiming, RenderError, Rendered, ShadingConfig, ShadingMethod};
use instant_radiosity::{
    IndirectConfig,
    gpu::{BoundIndirect, IndirectStage},
    near_field::{BoundNearField, NearField},
    shadows::{ShadowConfig, VplShadowMaps, VplShadows},
    vpl::VplSet,
};
use scene::animation::{Pose, Rig};
use tiled_shading::ShadingError;
use tiled_shading::gpu::forward::{BoundForward, ForwardPass};
use tiled_shading::gpu::light_prepass::{BoundLightPrePass, LightPrePass};
use tiled_shading::gpu::shadows::{
    AtlasBindings, GpuRays, GpuShadowMaps, ShadowInputs, ShadowMapPass,
};
use tiled_shading::gpu::{ACCUMULATION_FORMAT, BoundShading, LightShading};
use tiled_shading::rays::RayShadows;
use tiled_shading::shadows::{self, ShadowMapConfig};

/// The nodes' exit radiance of `lit` as `vec4<f32>` words.
fn radiance_words(lit: &instant_radiosity::pbgi::LitPoints) -> Vec<[f32; 4]> {
    lit.radiance
        .iter()
        .map(|r| r.extend(0.0).to_array())
        .collect()
}

fn view(t: &wgpu::Texture) -> wgpu::TextureView {
    t.create_view(&Default::default())
}

/// `composition.wgsl`: ambient, emission and occlusion; albedo, material, direct diffuse and
/// specular; radiance output; indirect diffuse and specular; the VPLs' near field; the
/// screen-space ambient occlusion.
const COMPOSITION_BINDINGS: [Binding; 11] = [
    Binding::Uniform,
    Binding::TextureUnfilterable,
    Binding::TextureUnfilterable,
    Binding::TextureUint,
    Binding::TextureUnfilterable,
    Binding::TextureUnfilterable,
    Binding::StorageTexture(RADIANCE_FORMAT),
    Binding::TextureUnfilterable,
    Binding::TextureUnfilterable,
    Binding::TextureUnfilterable,
    Binding::StorageRead,
];

/// Format of the renderer's output ([`GpuRenderer::output`]): linear radiance.
pub const RADIANCE_FORMAT: wgpu::TextureFormat = ACCUMULATION_FORMAT;

fn indirect_texture(device: &wgpu::Device, label: &str, width: u32, height: u32) -> wgpu::Texture {
    transfer::texture_2d(
        device,
        label,
        width,
        height,
        interleave::gpu::IRRADIANCE_FORMAT,
        wgpu::TextureUsages::TEXTURE_BINDING,
    )
}

/// The composition's bind group (`composition.wgsl`).
#[allow(clippy::too_many_arguments)]
fn composition_group(
    device: &wgpu::Device,
    composition: &Kernel,
    ambient: &wgpu::Buffer,
    targets: &GBufferTargets,
    direct: [&wgpu::Texture; 2],
    radiance: &wgpu::Texture,
    (indirect, accessibility): ([&wgpu::Texture; 3], &wgpu::Buffer),
) -> wgpu::BindGroup {
    let views = [
        view(&targets.emission),
        view(&targets.albedo),
        view(&targets.material),
        view(direct[0]),
        view(direct[1]),
        view(radiance),
        view(indirect[0]),
        view(indirect[1]),
        view(indirect[2]),
    ];
    let mut resources = vec![ambient.as_entire_binding()];
    resources.extend(views.iter().map(wgpu::BindingResource::TextureView));
    resources.push(accessibility.as_entire_binding());
    composition.bind(device, &resources)
}

/// A deferred renderer for one scene, on the caller's device: `new` uploads the scene and
/// builds every pipeline once; [`GpuRenderer::set_camera`], [`GpuRenderer::set_ambient`] and
/// [`GpuRenderer::set_lights`] only write buffers; [`GpuRenderer::resize`] rebinds the
/// size-dependent targets; [`GpuRenderer::encode`] records a frame (z-prepass, G-buffer,
/// light accumulation, the indirect stage if set, composition) into the caller's encoder and
/// reads nothing back; [`GpuRenderer::output`] is the radiance texture the caller samples,
/// copies or presents.
///
/// ```no_run
/// # let gpu = gpu::Gpu::from_env()?;
/// let scene = scene::cornell_box();
/// let mut renderer =
///     pipeline::gpu::GpuRenderer::new(&gpu.device, &gpu.queue, &scene, &scene.lights, 640, 480)?;
/// renderer.set_camera(&gpu.queue, &scene.camera_or_framed())?;
/// let mut encoder = gpu.device.create_command_encoder(&Default::default());
/// renderer.encode(&mut encoder);
/// gpu.queue.submit([encoder.finish()]);
/// let radiance: &gpu::wgpu::Texture = renderer.output();
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub struct GpuRenderer {
    gbuffer_pass: GBufferPass,
    scene: GpuScene,
    sized: SizedTargets,
    lights: Vec<GpuLight>,
    shading: LightShading,
    shading_bound: BoundShading,
    /// The forward pass of [`tiled_shading::Method::ForwardPlus`], or of blended surfaces.
    forward: Option<ForwardStage>,
    /// How blended surfaces are drawn ([`GpuRenderer::set_blended`]).
    blended: BlendedSurfaces,
    /// The second geometry pass of [`tiled_shading::Method::LightPrePass`].
    prepass: Option<PrePassStage>,
    composition: Kernel,
    composition_group: wgpu::BindGroup,
    ambient: wgpu::Buffer,
    camera: Option<Camera>,
    indirect: Option<Indirect>,
    vpl_shadows: Option<VplShadowMaps>,
    shadows: Option<DirectShadows>,
    light_atlas: Option<LightAtlas>,
    ray_shadows: Option<GpuRays>,
    near_field: Option<NearFieldStage>,
    pbgi: Option<PbgiStage>,
    reflections: Option<ReflectionStage>,
    output: Option<OutputStage>,
    animation: Option<Animation>,
    supersampling: Option<Supersampling>,
    subdivision: Option<SubdivisionStage>,
    /// The G-buffer through the visibility buffer ([`GpuRenderer::set_visibility`]).
    visibility: Option<VisibilityStage>,
    ssao: Option<SsaoStage>,
    /// The ambient radiance of the composition (the buffer's w says whether SSAO is on).
    ambient_radiance: Vec3,
    /// The composition's accessibility when SSAO is off (one unread value).
    no_ssao: wgpu::Buffer,
    bounds: scene::Aabb,
    timer: PassTimer,
}

/// What cannot be combined, as an error naming both: supersampling shades samples of the
/// G-buffer, so it excludes the methods that draw the scene again (Forward+, the light
/// pre-pass) and blended surfaces drawn forward (absent from the G-buffer); the light pre-pass
/// has no forward pass for blended surfaces.
fn exclusions(
    method: ShadingMethod,
    blended: BlendedSurfaces,
    supersampling: bool,
) -> Result<(), RenderError> {
    let redraws = matches!(
        method,
        ShadingMethod::ForwardPlus | ShadingMethod::LightPrePass
    );
    let forward = blended == BlendedSurfaces::Forward;
    let clash = if supersampling && redraws {
        format!(
            "{method} and supersampling exclude each other: supersampling shades samples of the G-buffer, {method} draws the scene again"
        )
    } else if supersampling && forward {
        "blended surfaces drawn forward and supersampling exclude each other: supersampling shades samples of the G-buffer, which then holds no blended surfaces".into()
    } else if forward && method == ShadingMethod::LightPrePass {
        "the light pre-pass and blended surfaces drawn forward exclude each other: it has no forward pass for them".into()
    } else {
        return Ok(());
    };
    Err(ShadingError::Incompatible(format!("{clash}; switch one off first")).into())
}

/// The pixels per triangle ([`GpuScene::pixels_per_triangle`]) above which
/// [`GpuRenderer::choose_gbuffer_path`] tries drawing meshes with the hardware rasteriser into
/// the visibility buffer, from none (infinity) to every mesh on screen (0).
pub const SPLIT_PIXELS: [f32; 8] = [f32::INFINITY, 4096.0, 1024.0, 256.0, 64.0, 16.0, 4.0, 0.0];

/// The distinct splits [`GpuRenderer::choose_gbuffer_path`] measures, given each mesh's
/// pixels per triangle ([`GpuScene::pixels_per_triangle`]): for each of [`SPLIT_PIXELS`] in
/// order, the threshold and the meshes above it, a threshold that moves no mesh left out.
pub fn visibility_splits(pixels: &[f32]) -> Vec<(f32, Vec<usize>)> {
    let mut splits: Vec<(f32, Vec<usize>)> = Vec::new();
    for above_pixels in SPLIT_PIXELS {
        let meshes = meshes_above(pixels, above_pixels);
        if splits.last().is_none_or(|(_, last)| *last != meshes) {
            splits.push((above_pixels, meshes));
        }
    }
    splits
}

/// The meshes whose pixels per triangle (`pixels`, per mesh) exceed `above_pixels`: those a
/// split of that threshold hands to the hardware rasteriser.
fn meshes_above(pixels: &[f32], above_pixels: f32) -> Vec<usize> {
    (0..pixels.len())
        .filter(|&m| pixels[m] > above_pixels)
        .collect()
}

/// One sharing of the visibility buffer's meshes between the two rasterisers, measured by
/// [`GpuRenderer::choose_gbuffer_path`].
#[derive(Clone, Debug, PartialEq)]
pub struct VisibilitySplit {
    /// Meshes whose triangles cover more pixels than this on average went to the hardware
    /// rasteriser (one of [`SPLIT_PIXELS`]).
    pub above_pixels: f32,
    /// Those meshes ([`GpuRenderer::set_visibility_split`]; alpha-tested ones go there
    /// anyway and are not listed).
    pub hardware_meshes: Vec<usize>,
    /// The visibility path's median GPU time (rasterisers, resolve, depth), ms.
    pub ms: f64,
}

/// What [`GpuRenderer::choose_gbuffer_path`] measured and kept.
#[derive(Clone, Debug, PartialEq)]
pub struct GBufferChoice {
    /// The hardware path's median GPU time (z-prepass + G-buffer pass), ms.
    pub hardware_ms: f64,
    /// The visibility path's fastest split's time, ms; why it cannot run, instead.
    pub visibility_ms: Result<f64, String>,
    /// Every split of the visibility path measured, in the order tried (fewest meshes by the
    /// hardware rasteriser first; empty where it cannot run).
    pub splits: Vec<VisibilitySplit>,
    /// Whether the visibility path was kept (its fastest split beat the hardware path).
    pub visibility: bool,
}

impl GBufferChoice {
    /// The fastest split measured.
    pub fn fastest_split(&self) -> Option<&VisibilitySplit> {
        fastest_split(&self.splits)
    }
}

/// The split of least time among `splits`.
fn fastest_split(splits: &[VisibilitySplit]) -> Option<&VisibilitySplit> {
    splits.iter().min_by(|a, b| a.ms.total_cmp(&b.ms))
}

impl std::fmt::Display for GBufferChoice {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let kept = if self.visibility {
            "visibility buffer"
        } else {
            "hardware rasteriser"
        };
        let (Ok(ms), Some(fastest)) = (&self.visibility_ms, self.fastest_split()) else {
            let why = self.visibility_ms.as_ref().err().map_or("", String::as_str);
            return write!(
                f,
                "{kept} (chosen: the visibility buffer cannot run: {why})"
            );
        };
        let meshes = match fastest.hardware_meshes.len() {
            0 => "all meshes by the compute rasteriser".to_string(),
            n => format!(
                "{n} meshes of > {} px per triangle by the hardware rasteriser",
                fastest.above_pixels
            ),
        };
        let tried: Vec<String> = self
            .splits
            .iter()
            .map(|s| match s.above_pixels {
                p if p.is_finite() => format!("> {p} px: {:.3}", s.ms),
                _ => format!("none: {:.3}", s.ms),
            })
            .collect();
        write!(
            f,
            "{kept} (chosen: visibility buffer {ms:.3} ms with {meshes}, hardware {:.3} ms; splits tried, ms: {})",
            self.hardware_ms,
            tried.join(", ")
        )
    }
}

/// The G-buffer through the compute rasteriser's visibility buffer and its resolve
/// ([`GpuRenderer::set_visibility`]), bound to the frame's targets and, with supersampling, to
/// the supersampled G-buffer's.
struct VisibilityStage {
    raster: VisibilityPass,
    resolve: ResolvePass,
    /// Meshes drawn by the hardware rasteriser besides the alpha-tested ones
    /// ([`GpuRenderer::set_visibility_split`]).
    hardware_meshes: Vec<usize>,
    /// The pixels per triangle above which a mesh goes to the hardware rasteriser, re-applied
    /// as the camera moves ([`GpuRenderer::set_visibility_split_rule`]); `None` for a split
    /// by hand.
    split_rule: Option<f32>,
    main: BoundVisibility,
    ss: Option<BoundVisibility>,
}

/// The visibility path bound to one G-buffer: its visibility buffer, passes and the name of
/// its depth pass.
struct BoundVisibility {
    vis: Visibility,
    resolved: Resolve,
    depth_pass: &'static str,
}

impl VisibilityStage {
    fn new(
        device: &wgpu::Device,
        gbuffer_pass: &GBufferPass,
        scene: &GpuScene,
        targets: &GBufferTargets,
        capacity: Capacity,
    ) -> Result<Self, RenderError> {
        let atomics = Atomics::best(device);
        let raster = VisibilityPass::with(device, gbuffer_pass, capacity, atomics)?;
        let resolve = ResolvePass::new(device, gbuffer_pass)?;
        let main = Self::bind(
            device,
            (&raster, &resolve, &[]),
            (gbuffer_pass.frame_buffer(), targets),
            scene,
            "",
        )?;
        Ok(Self {
            raster,
            resolve,
            hardware_meshes: Vec::new(),
            split_rule: None,
            main,
            ss: None,
        })
    }

    /// The path bound to `targets` seen through `frame`, the meshes `hardware` drawn by the
    /// hardware rasteriser; its passes' names start with `prefix`.
    fn bind(
        device: &wgpu::Device,
        (raster, resolve, hardware): (&VisibilityPass, &ResolvePass, &[usize]),
        (frame, targets): (&wgpu::Buffer, &GBufferTargets),
        scene: &GpuScene,
        prefix: &'static str,
    ) -> Result<BoundVisibility, RenderError> {
        let size = (targets.width, targets.height);
        let buffer = VisibilityPass::buffer(device, size.0, size.1)?;
        let vis = raster
            .bind_split(device, scene, frame, size, &buffer, hardware)?
            .named(prefix);
        let mut resolved = resolve.bind(device, scene, frame, &vis, targets)?;
        if !prefix.is_empty() {
            resolved.passes = resolved
                .passes
                .named(&format!("{prefix}visibility resolve"));
        }
        Ok(BoundVisibility {
            vis,
            resolved,
            depth_pass: if prefix.is_empty() {
                "visibility depth"
            } else {
                "ss visibility depth"
            },
        })
    }

    /// Binds again to the frame's targets and to the supersampled G-buffer (`ss`), if any.
    fn rebind(
        &mut self,
        device: &wgpu::Device,
        (gbuffer_pass, scene): (&GBufferPass, &GpuScene),
        targets: &GBufferTargets,
        ss: Option<(&wgpu::Buffer, &GBufferTargets)>,
    ) -> Result<(), RenderError> {
        let pair = (&self.raster, &self.resolve, self.hardware_meshes.as_slice());
        let frame = gbuffer_pass.frame_buffer();
        self.main = Self::bind(device, pair, (frame, targets), scene, "")?;
        self.ss = ss
            .map(|g| Self::bind(device, pair, g, scene, "ss "))
            .transpose()?;
        Ok(())
    }

    fn encode(
        &self,
        bound: &BoundVisibility,
        encoder: &mut wgpu::CommandEncoder,
        depth: &wgpu::Texture,
        timer: &PassTimer,
    ) {
        bound
            .vis
            .encode(encoder, Some(depth), Some(timer))
            .expect("the G-buffer's depth target has its visibility buffer's size");
        bound.resolved.passes.encode(encoder, Some(timer));
        self.resolve.encode_depth(
            &bound.resolved,
            encoder,
            depth,
            timer.render_pass(bound.depth_pass),
        );
    }
}

/// The methods that draw the scene again test depth `Equal` against the hardware
/// rasteriser's own depth, which the visibility buffer's may differ from by a rounding.
fn visibility_exclusion(method: ShadingMethod, visibility: bool) -> Result<(), RenderError> {
    if visibility
        && matches!(
            method,
            ShadingMethod::ForwardPlus | ShadingMethod::LightPrePass
        )
    {
        return Err(ShadingError::Incompatible(format!(
            "{method} and the visibility-buffer G-buffer exclude each other: {method} draws the scene again and tests depth Equal against the hardware rasteriser's; switch one off first"
        ))
        .into());
    }
    Ok(())
}

/// Forward+ as the renderer holds it: the forward pass and its binding to the culling pass's
/// lists (`None` until [`GpuRenderer::rebind`] makes them), and, when the light accumulation is
/// a deferred method drawing blended surfaces forward ([`GpuRenderer::set_blended`]), the
/// Forward+ culling pass of their lists and its binding.
struct ForwardStage {
    pass: ForwardPass,
    bound: Option<BoundForward>,
    cull: Option<(LightShading, Option<BoundShading>)>,
}

/// The light pre-pass as the renderer holds it: the materials pass, and the light buffer of the
/// frame's size with the pass bound to it (`None` until [`GpuRenderer::rebind`] makes them).
struct PrePassStage {
    pass: LightPrePass,
    bound: Option<(wgpu::Texture, BoundLightPrePass)>,
}

/// Screen-space ambient occlusion as the renderer holds it ([`GpuRenderer::set_ssao`]): the
/// kernels, their binding to the G-buffer, the accessibility they write and what they were
/// set with (to rebind on a resize).
struct SsaoStage {
    kernels: ssao::gpu::SsaoKernels,
    bound: ssao::gpu::BoundSsao,
    accessibility: wgpu::Buffer,
    config: ssao::cpu::KernelConfig,
    estimator: ssao::Estimator,
}

/// The skinning stage as the renderer holds it ([`GpuRenderer::set_animation`]): the rig and
/// its kernel bound to the uploaded scene.
struct Animation {
    rig: Rig,
    bound: BoundSkinning,
}

/// The output transform as the renderer holds it ([`GpuRenderer::set_output`]): its kernels,
/// its binding to the radiance and the display texture it writes.
struct OutputStage {
    transform: OutputTransform,
    pass: OutputPass,
    bound: BoundOutput,
    display: wgpu::Texture,
}

/// ManyLoD shadows of the point, spot and hemispherical lights (Holländer 2013 §3.6's
/// many-view cut, as for VPLs): the scene's triangles to sample, the maps' configuration, the
/// lights' paraboloid views (which tile each light owns, and the views the maps were built
/// for) and their maps (`None` while no light has such views).
struct LightAtlas {
    mesh: (Vec<Vec3>, Vec<u32>),
    config: ShadowConfig,
    plan: shadows::ShadowPlan,
    views: Vec<manylod::View>,
    maps: Option<VplShadowMaps>,
}

/// Shadow maps of the direct lights as the renderer holds them: the raster pass, the maps
/// (one layer per view of every light) and their configuration.
struct DirectShadows {
    pass: ShadowMapPass,
    maps: GpuShadowMaps,
    config: ShadowMapConfig,
}

/// The indirect stage as the renderer holds it: its pipelines for the frame size, their
/// binding to the G-buffer and VPLs, the output textures the composition reads, and what it
/// was made from (to rebuild it on a resize).
struct Indirect {
    stage: IndirectStage,
    bound: BoundIndirect,
    outputs: [wgpu::Texture; 2],
    config: IndirectConfig,
    set: VplSet,
}

/// Point-based GI as the renderer holds it ([`GpuRenderer::set_pbgi`]): the gather bound to the
/// current targets, the indirect diffuse it writes, and what it was made from (to rebuild it
/// on a resize).
struct PbgiStage {
    gather: instant_radiosity::pbgi::GpuGather,
    output: wgpu::Texture,
    lit: instant_radiosity::pbgi::LitPoints,
    stride: u32,
    /// The scene the surfels' shadow rays are traced through.
    scene: Scene,
    /// Node-views each cut list holds.
    capacity: usize,
}

/// Reflection maps as the renderer holds them ([`GpuRenderer::set_reflections`]): the maps
/// bound to the current targets, the reflections they write, the surfels' radiance (lit on the
/// CPU) and what they were made from.
struct ReflectionStage {
    maps: instant_radiosity::reflections::GpuReflections,
    output: wgpu::Texture,
    radiance: wgpu::Buffer,
    lit: instant_radiosity::pbgi::LitPoints,
    tile: u32,
    scene: Scene,
    capacity: usize,
}

/// Node-views a point-based GI view's cut may hold per `(tile / ε)²` (its drawn nodes are
/// about ε texels wide; measured: up to 12 on the Cornell box at 32² texels and ε = 1).
const PBGI_NODE_VIEWS_PER_CELL: f32 = 16.0;

/// The VPLs' near field as the renderer holds it ([`GpuRenderer::set_near_field`]): the kernel
/// for the scene, its binding to the current targets, lights and VPLs, and its output.
struct NearFieldStage {
    kernel: NearField,
    bound: Option<(BoundNearField, wgpu::Texture)>,
}

impl NearFieldStage {
    /// Its binding, once bound.
    fn bound_mut(&mut self) -> Option<&mut BoundNearField> {
        self.bound.as_mut().map(|(bound, _)| bound)
    }
}

/// Textures of one frame size: G-buffer targets, radiance, direct light, no indirect light.
struct SizedTargets {
    targets: GBufferTargets,
    radiance: wgpu::Texture,
    direct: [wgpu::Texture; 2],
    no_indirect: [wgpu::Texture; 2],
}

impl SizedTargets {
    fn new(device: &wgpu::Device, width: u32, height: u32) -> Result<Self, RenderError> {
        transfer::check_texture_size(device, "frame", width, height)?;
        transfer::allocation(
            device,
            &format!("the {width}×{height} frame's targets"),
            || Self::allocate(device, width, height),
        )
    }

    fn allocate(device: &wgpu::Device, width: u32, height: u32) -> Result<Self, RenderError> {
        Ok(Self {
            targets: GBufferTargets::new(device, width, height)?,
            radiance: transfer::texture_2d(
                device,
                "radiance",
                width,
                height,
                RADIANCE_FORMAT,
                // Forward+ blends transparent surfaces over it.
                transfer::STORAGE_OUTPUT | wgpu::TextureUsages::RENDER_ATTACHMENT,
            ),
            direct: LightShading::output_textures(device, width, height),
            no_indirect: [
                indirect_texture(device, "no indirect diffuse", width, height),
                indirect_texture(device, "no indirect specular", width, height),
            ],
        })
    }
}

impl GpuRenderer {
    /// Uploads `scene` and `lights` and builds pipelines and targets for `width × height`,
    /// with the default (tiled) light accumulation.
    pub fn new(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        scene: &Scene,
        lights: &[Light],
        width: u32,
        height: u32,
    ) -> Result<Self, RenderError> {
        Self::new_with(
            device,
            queue,
            scene,
            lights,
            (width, height),
            &TextureOptions::default(),
        )
    }

    /// [`GpuRenderer::new`] at `(width, height)` with the scene's textures filtered as
    /// `textures` says.
    pub fn new_with(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        scene: &Scene,
        lights: &[Light],
        (width, height): (u32, u32),
        textures: &TextureOptions,
    ) -> Result<Self, RenderError> {
        let gpu_lights = crate::validate_lights(lights)?;
        let sized = SizedTargets::new(device, width, height)?;
        let gbuffer_pass = GBufferPass::new(device)?;
        let gpu_scene = GpuScene::upload_with(device, queue, scene, &gbuffer_pass, textures)?;
        let ambient = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("ambient"),
            contents: bytemuck::bytes_of(&crate::DEFAULT_AMBIENT.extend(0.0)),
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        });
        let shading = LightShading::new(device, &ShadingConfig::default())?;
        let module = crate::SHADERS.module(device, "composition.wgsl")?;
        let composition = Kernel::new(
            device,
            &module,
            "composition_main",
            &COMPOSITION_BINDINGS,
            &[],
        );
        let outputs = [&sized.direct[0], &sized.direct[1]];
        let shading_bound = Self::bind_shading(
            device,
            queue,
            &shading,
            &gbuffer_pass,
            &sized,
            outputs,
            &gpu_lights,
        )?;
        let no_ssao = transfer::buffer_init(
            device,
            "no ssao",
            bytemuck::bytes_of(&1.0f32),
            wgpu::BufferUsages::STORAGE,
        )?;
        let composition_group = composition_group(
            device,
            &composition,
            &ambient,
            &sized.targets,
            [&sized.direct[0], &sized.direct[1]],
            &sized.radiance,
            (
                [
                    &sized.no_indirect[0],
                    &sized.no_indirect[1],
                    &sized.no_indirect[0],
                ],
                &no_ssao,
            ),
        );
        Ok(Self {
            gbuffer_pass,
            scene: gpu_scene,
            sized,
            lights: gpu_lights,
            shading,
            shading_bound,
            forward: None,
            blended: BlendedSurfaces::Dithered,
            prepass: None,
            composition,
            composition_group,
            ambient,
            camera: None,
            indirect: None,
            vpl_shadows: None,
            shadows: None,
            light_atlas: None,
            ray_shadows: None,
            near_field: None,
            pbgi: None,
            reflections: None,
            output: None,
            animation: None,
            supersampling: None,
            subdivision: None,
            visibility: None,
            ssao: None,
            ambient_radiance: crate::DEFAULT_AMBIENT,
            no_ssao,
            bounds: scene.bounds(),
            timer: PassTimer::new(device, 48),
        })
    }

    fn bind_shading(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        shading: &LightShading,
        gbuffer_pass: &GBufferPass,
        sized: &SizedTargets,
        outputs: [&wgpu::Texture; 2],
        lights: &[GpuLight],
    ) -> Result<BoundShading, RenderError> {
        let mut bound = shading.bind(
            device,
            gbuffer_pass.frame_buffer(),
            (&sized.targets).into(),
            outputs,
            lights.len(),
            false,
        )?;
        shading.bind_depth(&mut bound, &sized.targets.depth)?;
        bound.set_lights(queue, lights)?;
        Ok(bound)
    }

    /// Rebinds the light accumulation and the composition to the current targets, lights,
    /// camera and indirect stage.
    fn rebind(&mut self, device: &wgpu::Device, queue: &wgpu::Queue) -> Result<(), RenderError> {
        // The light pre-pass's lighting pass writes its light buffer, not the diffuse light.
        if let Some(p) = &mut self.prepass {
            let (w, h) = (self.sized.targets.width, self.sized.targets.height);
            let light_buffer = LightPrePass::light_buffer(device, w, h);
            let bound = p.pass.bind(device, &light_buffer)?;
            p.bound = Some((light_buffer, bound));
        }
        let first = match &self.prepass {
            Some(PrePassStage {
                bound: Some((light_buffer, _)),
                ..
            }) => light_buffer,
            _ => &self.sized.direct[0],
        };
        let mut bound = Self::bind_shading(
            device,
            queue,
            &self.shading,
            &self.gbuffer_pass,
            &self.sized,
            [first, &self.sized.direct[1]],
            &self.lights,
        )?;
        if let Some(camera) = &self.camera {
            bound.set_camera(queue, camera);
        }
        if let Some(f) = &mut self.forward {
            let lists = match &mut f.cull {
                Some((cull, slot)) => {
                    let direct = [&self.sized.direct[0], &self.sized.direct[1]];
                    let (pass, sized) = (&self.gbuffer_pass, &self.sized);
                    let mut lists =
                        Self::bind_shading(device, queue, cull, pass, sized, direct, &self.lights)?;
                    if let Some(camera) = &self.camera {
                        lists.set_camera(queue, camera);
                    }
                    &*slot.insert(lists)
                }
                None => &bound,
            };
            f.bound = Some(f.pass.bind(device, lists, &self.ambient)?);
        }
        self.shading_bound = bound;
        if let Some(s) = self.supersampling.take() {
            let config = *s.config();
            let kernels = Some(s.into_kernels());
            self.supersampling = Some(self.new_supersampling(device, queue, &config, kernels)?);
        }
        self.rebind_visibility(device)?;
        if let Some(s) = self.ssao.take() {
            let kernels = Some(s.kernels);
            self.ssao = Some(self.new_ssao(device, kernels, &s.config, s.estimator)?);
        }
        self.bind_shadow_lookup(device)?;
        self.bind_composition(device);
        if let Some(output) = self.output.take() {
            self.set_output(device, Some(output.transform))?;
        }
        Ok(())
    }

    /// Sets the output transform (exposure, tone mapper) run after the composition into the
    /// display texture ([`GpuRenderer::display`]), or with `None` removes it.
    pub fn set_output(
        &mut self,
        device: &wgpu::Device,
        transform: Option<OutputTransform>,
    ) -> Result<(), RenderError> {
        let Some(transform) = transform else {
            self.output = None;
            return Ok(());
        };
        let pass = match self.output.take() {
            Some(stage) => stage.pass,
            None => OutputPass::new(device)?,
        };
        let (w, h) = self.size();
        let display = transfer::texture_2d(
            device,
            "display",
            w,
            h,
            output::DISPLAY_FORMAT,
            transfer::STORAGE_OUTPUT,
        );
        let bound = pass.bind(device, &self.sized.radiance, &display, &transform)?;
        self.output = Some(OutputStage {
            transform,
            pass,
            bound,
            display,
        });
        Ok(())
    }

    /// The display-linear image the output transform writes ([`output::DISPLAY_FORMAT`],
    /// `TEXTURE_BINDING | COPY_SRC`), if one is set; encode it as sRGB to show or store it.
    pub fn display(&self) -> Option<&wgpu::Texture> {
        self.output.as_ref().map(|o| &o.display)
    }

    /// Rebinds the composition to the current targets and indirect stage.
    fn bind_composition(&mut self, device: &wgpu::Device) {
        let [no_diffuse, no_specular] = &self.sized.no_indirect;
        let near_field = self
            .near_field
            .as_ref()
            .and_then(|n| n.bound.as_ref())
            .map_or(no_diffuse, |(_, output)| output);
        // Reflections take the indirect specular slot, which only the VPLs' stage fills
        // otherwise (the two are exclusive).
        let specular = self.reflections.as_ref().map_or(no_specular, |r| &r.output);
        let indirect = match (&self.indirect, &self.pbgi) {
            (Some(i), _) => [&i.outputs[0], &i.outputs[1], near_field],
            (None, Some(p)) => [&p.output, specular, no_diffuse],
            (None, None) => [no_diffuse, specular, no_diffuse],
        };
        let accessibility = self
            .ssao
            .as_ref()
            .map_or(&self.no_ssao, |s| &s.accessibility);
        self.composition_group = composition_group(
            device,
            &self.composition,
            &self.ambient,
            &self.sized.targets,
            [&self.sized.direct[0], &self.sized.direct[1]],
            &self.sized.radiance,
            (indirect, accessibility),
        );
        if let Some(s) = &mut self.supersampling {
            s.bind(
                device,
                &self.ambient,
                indirect,
                accessibility,
                &self.sized.radiance,
            );
        }
    }

    /// The supersampling stage for `config` at the frame size, with `kernels` (compiled here if
    /// `None`), bound to the current lights, camera (cascades set with it) and shadows by the
    /// caller.
    fn new_supersampling(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        config: &SsaaConfig,
        kernels: Option<SupersamplingKernels>,
    ) -> Result<Supersampling, RenderError> {
        let kernels = match kernels {
            Some(k) => k,
            None => SupersamplingKernels::new(device)?,
        };
        let mut s = Supersampling::new(
            device,
            queue,
            kernels,
            &self.gbuffer_pass,
            &self.shading,
            config,
            self.size(),
            &self.lights,
        )?;
        if let Some(camera) = &self.camera {
            s.set_camera(queue, camera);
        }
        Ok(s)
    }

    /// Supersamples the frame (`Some`: `config.m × config.m` samples per pixel — adaptively as
    /// Holländer 2013 §4.3 decides with `config`'s metrics, or every sample when
    /// `config.min_samples` is `m²`), or stops (`None`). The frame's own G-buffer is jittered
    /// onto every pixel's first sample, so the frame without supersampling computes the first
    /// sample's radiance; the other samples' direct light runs through the frame's light
    /// accumulation with its method, culling and shadows; indirect light is shaded once per
    /// pixel on the first sample's G-buffer and shared by the pixel's samples (each composed
    /// with its own albedo and material); textures are filtered over the whole pixel.
    /// `config`'s ambient, background, resolve and stall are not used: the frame's ambient
    /// ([`GpuRenderer::set_ambient`]) applies, no surface is black.
    pub fn set_ssaa(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        config: Option<&SsaaConfig>,
    ) -> Result<(), RenderError> {
        exclusions(self.shading.config().method, self.blended, config.is_some())?;
        self.supersampling = match config {
            Some(config) => Some(self.new_supersampling(device, queue, config, None)?),
            None => None,
        };
        self.rebind_visibility(device)?;
        self.bind_shadow_lookup(device)?;
        self.bind_composition(device);
        // The pixels sample at their first samples with supersampling, at their centres without.
        match self.camera {
            Some(camera) => self.set_camera(queue, &camera),
            None => Ok(()),
        }
    }

    /// The supersampling configuration, if set.
    pub fn ssaa(&self) -> Option<&SsaaConfig> {
        self.supersampling.as_ref().map(Supersampling::config)
    }

    /// Reads back how many samples each pixel took in the last frame (`None` without
    /// supersampling).
    pub fn ssaa_counts(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
    ) -> Result<Option<Image<u32>>, RenderError> {
        self.supersampling
            .as_ref()
            .map(|s| s.read_counts(device, queue))
            .transpose()
    }

    /// Switches the light accumulation to `config` (brute force, light volumes, tiled, tiled
    /// with normal cones, clustered, Forward+; tile size). Forward+ draws the scene a second
    /// time, lit from its tiles' lists, and draws alpha-blended materials over the composed
    /// frame, back to front (lit directly and by the ambient light, without the frame's
    /// indirect light and screen-space occlusion); every other method, and
    /// Forward+ on a device without `FLOAT32_BLENDABLE`, dithers them into the G-buffer.
    /// Forward+ and supersampling exclude each other (an error names the other).
    pub fn set_shading(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        config: &ShadingConfig,
    ) -> Result<(), RenderError> {
        if self.shading.config() == config {
            return Ok(());
        }
        exclusions(config.method, self.blended, self.supersampling.is_some())?;
        visibility_exclusion(config.method, self.visibility.is_some())?;
        let shading = LightShading::new(device, config)?;
        let forward = self.forward_stage(device, config, self.blended)?;
        let prepass = if config.method == ShadingMethod::LightPrePass {
            Some(PrePassStage {
                pass: LightPrePass::new(device, &self.gbuffer_pass)?,
                bound: None,
            })
        } else {
            None
        };
        self.shading = shading;
        self.forward = forward;
        self.prepass = prepass;
        self.draw_blended();
        self.rebind(device, queue)
    }

    /// Draws alpha-blended materials forward, over the composed frame and back to front
    /// ([`BlendedSurfaces::Forward`], lit from Forward+ lists built by their own culling pass
    /// beside the light accumulation), or dithers them into the G-buffer
    /// ([`BlendedSurfaces::Dithered`], the default). Forward+ always draws them forward. Drawn
    /// forward they are lit directly and by the ambient light, without the frame's indirect
    /// light and screen-space occlusion; it needs `FLOAT32_BLENDABLE` (an error names it) and
    /// excludes supersampling and the light pre-pass (errors say so).
    pub fn set_blended(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        blended: BlendedSurfaces,
    ) -> Result<(), RenderError> {
        if blended == self.blended {
            return Ok(());
        }
        let config = *self.shading.config();
        if blended == BlendedSurfaces::Forward {
            ::gpu::DeviceNeeds {
                features: wgpu::Features::FLOAT32_BLENDABLE,
                ..Default::default()
            }
            .check(device.features(), &device.limits())?;
        }
        exclusions(config.method, blended, self.supersampling.is_some())?;
        self.forward = self.forward_stage(device, &config, blended)?;
        self.blended = blended;
        self.draw_blended();
        self.rebind(device, queue)
    }

    /// The forward pass `config` and `blended` need: Forward+'s own (lit from the light
    /// accumulation's lists), blended surfaces' over a deferred method (with their own culling
    /// pass), or none.
    fn forward_stage(
        &self,
        device: &wgpu::Device,
        config: &ShadingConfig,
        blended: BlendedSurfaces,
    ) -> Result<Option<ForwardStage>, RenderError> {
        let own = config.method == ShadingMethod::ForwardPlus;
        if !own && blended == BlendedSurfaces::Dithered {
            return Ok(None);
        }
        let lists = ShadingConfig {
            method: ShadingMethod::ForwardPlus,
            ..*config
        };
        let cull = if own {
            None
        } else {
            Some((LightShading::new(device, &lists)?, None))
        };
        Ok(Some(ForwardStage {
            pass: ForwardPass::new(device, &self.gbuffer_pass, &lists)?,
            bound: None,
            cull,
        }))
    }

    /// Keeps blended meshes out of the G-buffer while a forward pass draws them (where the
    /// device blends the frame's format), else dithers them into it.
    fn draw_blended(&mut self) {
        let forward = self.forward.as_ref().is_some_and(|f| f.pass.blends());
        self.scene.set_blended(if forward {
            BlendedSurfaces::Forward
        } else {
            BlendedSurfaces::Dithered
        });
    }

    /// Replaces the direct lights (the light buffer is rebound for their count; no shader is
    /// recompiled).
    pub fn set_lights(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        lights: &[Light],
    ) -> Result<(), RenderError> {
        let lights = crate::validate_lights(lights)?;
        let rebind = lights.len() > self.shading_bound.capacity()
            || self
                .supersampling
                .as_ref()
                .is_some_and(|s| lights.len() > s.shading().capacity());
        self.lights = lights;
        if rebind {
            self.rebind(device, queue)?;
        }
        if let Some(bound) = self.near_field.as_mut().and_then(NearFieldStage::bound_mut)
            && !bound.set_lights(queue, &self.lights)
        {
            self.bind_near_field(device)?;
            self.bind_composition(device);
        }
        if let Some(r) = &mut self.reflections {
            r.lit
                .light(&r.scene, &self.lights)
                .map_err(RenderError::from)?;
            queue.write_buffer(
                &r.radiance,
                0,
                bytemuck::cast_slice(&radiance_words(&r.lit)),
            );
        }
        if let Some(p) = &self.pbgi
            && p.gather.set_lights(queue, &self.lights).is_err()
        {
            // More lights than the surfels were set up for: light them anew.
            let PbgiStage {
                lit, stride, scene, ..
            } = self.pbgi.take().expect("checked");
            self.set_pbgi(device, Some((&lit, stride, &scene)))?;
        }
        self.plan_shadows(device, queue)
    }

    /// Gives every direct light a shadow map (`Some`: [`tiled_shading::shadows`]; spot,
    /// point and hemispherical lights by their views, directional ones by cascades that follow
    /// the camera), or removes them (`None`). The maps are drawn each frame before the light
    /// accumulation.
    pub fn set_shadows(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        config: Option<&ShadowMapConfig>,
    ) -> Result<(), RenderError> {
        self.shadows = match config {
            Some(config) => {
                config.validate()?;
                let pass = ShadowMapPass::new(device)?;
                let maps = pass.bind(device, config, 1)?;
                Some(DirectShadows {
                    pass,
                    maps,
                    config: *config,
                })
            }
            None => None,
        };
        self.plan_shadows(device, queue)
    }

    /// Gives the point, spot and hemispherical lights ManyLoD shadows (`Some`: one paraboloid
    /// view per spot or hemispherical light, two per point light, `config.tile` pixels, cut
    /// and splatted over surfels of `scene` every frame, [`tiled_shading::shadows`]'s
    /// `PARABOLOID_SHADOW`), or removes them (`None`). Directional lights keep their
    /// cascades when [`GpuRenderer::set_shadows`] is set.
    pub fn set_manylod_shadows(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        scene: &Scene,
        config: Option<&ShadowConfig>,
    ) -> Result<(), RenderError> {
        self.light_atlas = config.map(|config| LightAtlas {
            mesh: instant_radiosity::shadows::scene_mesh(scene),
            config: ShadowConfig {
                refit: config.refit || scene.rig.is_some(),
                ..*config
            },
            plan: shadows::ShadowPlan::default(),
            views: Vec::new(),
            maps: None,
        });
        self.plan_shadows(device, queue)
    }

    /// Gives every direct light exact hard shadows by a ray per pixel through a BVH of
    /// `scene`'s triangles (`Some`: [`tiled_shading::rays::RayShadows`], the path tracer's
    /// shadows, no maps drawn), or takes them away (`None`: the maps and ManyLoD shadows set
    /// with [`GpuRenderer::set_shadows`] and [`GpuRenderer::set_manylod_shadows`] again).
    pub fn set_ray_shadows(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        scene: Option<&Scene>,
    ) -> Result<(), RenderError> {
        self.ray_shadows = match scene {
            Some(scene) => {
                let rays = RayShadows::new(scene)?;
                Some(GpuRays::new(device, &rays.bvh, rays.params)?)
            }
            None => None,
        };
        self.plan_shadows(device, queue)
    }

    /// Binds the light accumulation's shadow lookup to the current maps and atlas.
    fn bind_shadow_lookup(&mut self, device: &wgpu::Device) -> Result<(), RenderError> {
        let inputs = ShadowInputs {
            maps: self.shadows.as_ref().map(|s| &s.maps),
            atlas: self
                .light_atlas
                .as_ref()
                .and_then(|a| a.maps.as_ref())
                .map(|m| {
                    let b = m.bindings();
                    AtlasBindings {
                        atlas: b.atlas,
                        params: b.params,
                    }
                }),
            rays: self.ray_shadows.as_ref(),
        };
        if let Some(s) = &mut self.supersampling {
            s.bind_shadows(device, &self.shading, inputs)?;
        }
        if let Some(ForwardStage {
            pass,
            bound: Some(bound),
            ..
        }) = &mut self.forward
        {
            pass.bind_shadows(device, bound, inputs)?;
        }
        Ok(self
            .shading
            .bind_shadows(device, &mut self.shading_bound, inputs)?)
    }

    /// Writes the lights (with their shadow views) into the light accumulation's buffers.
    fn write_lights(&mut self, queue: &wgpu::Queue) -> Result<(), RenderError> {
        if let Some(s) = &mut self.supersampling {
            s.shading_mut().set_lights(queue, &self.lights)?;
        }
        if let Some(ForwardStage {
            cull: Some((_, Some(lists))),
            ..
        }) = &mut self.forward
        {
            lists.set_lights(queue, &self.lights)?;
        }
        Ok(self.shading_bound.set_lights(queue, &self.lights)?)
    }

    /// Plans the lights' shadows — ManyLoD paraboloids where set (remade for the lights),
    /// depth views for the others (the maps grow when they need more layers) — and writes the
    /// lights with their views; without shadows, clears the lights' views.
    fn plan_shadows(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
    ) -> Result<(), RenderError> {
        for l in &mut self.lights {
            l.shadow_first = 0;
            l.shadow_count = if self.ray_shadows.is_some() {
                shadows::RAY_SHADOW
            } else {
                shadows::NO_SHADOW
            };
        }
        if self.ray_shadows.is_some() {
            self.write_lights(queue)?;
            return self.bind_shadow_lookup(device);
        }
        let diagonal = self.bounds.diagonal();
        if let Some(a) = &mut self.light_atlas {
            let lit: Vec<bool> = self
                .lights
                .iter()
                .map(|l| l.kind != tiled_shading::LIGHT_DIRECTIONAL)
                .collect();
            let (views, plan) = shadows::paraboloid_plan(&self.lights, &lit);
            let size = a.config.tile;
            let views: Vec<manylod::View> = views
                .into_iter()
                .map(|(position, normal)| manylod::View::Paraboloid {
                    position,
                    normal,
                    size,
                })
                .collect();
            // Sampling the surfels and building the hierarchy is CPU work: only when the number
            // of views changes (lights added or removed); lights that move only move the views.
            match &a.maps {
                Some(maps) if views.len() == a.views.len() => {
                    if views != a.views {
                        maps.set_views(queue, &views)?;
                    }
                }
                _ => {
                    let mesh = (&a.mesh.0[..], &a.mesh.1[..]);
                    a.maps = if views.is_empty() {
                        None
                    } else {
                        let (mode, config) = (VplShadows::ManyLod, &a.config);
                        let v = views.clone();
                        Some(VplShadowMaps::from_views(
                            device, mesh, diagonal, v, 0.0, mode, config,
                        )?)
                    };
                }
            }
            a.views = views;
            a.plan = plan;
        }
        if let Some(plan) = self.shadow_plan(device.limits().max_texture_array_layers)? {
            if let Some(s) = &mut self.shadows
                && plan.views.len() > s.maps.capacity()
            {
                s.maps = s.pass.bind(device, &s.config, plan.views.len())?;
            }
            self.write_shadow_plan(queue, &plan)?;
        } else {
            self.assign_paraboloids();
            self.write_lights(queue)?;
        }
        self.bind_shadow_lookup(device)
    }

    /// Writes the ManyLoD paraboloid views into the lights that have them.
    fn assign_paraboloids(&mut self) {
        if let Some(a) = &self.light_atlas {
            for (l, &(first, count)) in self.lights.iter_mut().zip(&a.plan.lights) {
                if count != shadows::NO_SHADOW {
                    l.shadow_first = first;
                    l.shadow_count = count;
                }
            }
        }
    }

    /// The shadow views of every light (the directional ones only when ManyLoD shadows the
    /// others) for the current camera (or one framing the scene before the first camera), at
    /// most `max_views`; `None` without shadow maps or with ray shadows.
    fn shadow_plan(&self, max_views: u32) -> Result<Option<shadows::ShadowPlan>, RenderError> {
        let Some(s) = self.drawn_maps() else {
            return Ok(None);
        };
        let camera = self.camera.unwrap_or_else(|| Camera::framing(self.bounds));
        let (w, h) = self.size();
        let rasterised: Vec<bool> = self
            .lights
            .iter()
            .map(|l| self.light_atlas.is_none() || l.kind == tiled_shading::LIGHT_DIRECTIONAL)
            .collect();
        Ok(Some(shadows::plan(
            &self.lights,
            &rasterised,
            &camera,
            w as f32 / h as f32,
            self.bounds,
            &s.config,
            max_views,
        )?))
    }

    /// Writes `plan`'s views into the maps and the lights with their views (and the ManyLoD
    /// paraboloids).
    fn write_shadow_plan(
        &mut self,
        queue: &wgpu::Queue,
        plan: &shadows::ShadowPlan,
    ) -> Result<(), RenderError> {
        if let Some(s) = &mut self.shadows {
            s.maps.set_views(queue, &plan.views)?;
        }
        plan.assign(&mut self.lights);
        self.assign_paraboloids();
        self.write_lights(queue)
    }

    /// Moves the scene's meshes by `rig` (`Some`: the rig of the scene this renderer was made
    /// from; the skinning runs first in every frame, at the rest pose until
    /// [`GpuRenderer::set_pose`]), or stops moving them (`None`: they keep the last pose).
    /// The shadow maps and the G-buffer see the moved meshes; the ManyLoD hierarchies follow
    /// them through [`GpuRenderer::set_scene_positions`] (ISM points too); the structures built
    /// on the CPU from the scene at set-up (rasterised VPL maps' meshes, ray-shadow and
    /// near-field BVHs) keep the set-up pose.
    pub fn set_animation(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        rig: Option<&Rig>,
    ) -> Result<(), RenderError> {
        self.animation = match rig {
            Some(rig) => {
                let bound = Skinning::new(device)?.bind(device, rig, &self.scene)?;
                bound.set_pose(queue, rig, &rig.pose(None, 0.0));
                Some(Animation {
                    rig: rig.clone(),
                    bound,
                })
            }
            None => None,
        };
        Ok(())
    }

    /// Draws the G-buffer through the compute rasteriser's visibility buffer and its resolve
    /// (`gbuffer::gpu::visibility`: the same G-buffer within the hardware pass's tolerances,
    /// and the depth target drawn from it; alpha-tested meshes drawn into it by the hardware
    /// rasteriser), or, with `false`, through the hardware z-prepass and G-buffer pass (the
    /// default); with supersampling, its supersampled G-buffer too. The device needs
    /// `gbuffer::gpu::visibility::device_needs()`; Forward+ and the light pre-pass are refused
    /// with an error that says why. Timed as the passes "visibility" (and "visibility
    /// alpha-tested", "visibility ids" …), "visibility resolve" and "visibility depth" (and the
    /// same with "ss " for the supersampled G-buffer). [`GpuRenderer::choose_gbuffer_path`]
    /// picks the faster of the two by measuring them.
    pub fn set_visibility(&mut self, device: &wgpu::Device, on: bool) -> Result<(), RenderError> {
        if !on {
            self.visibility = None;
            return Ok(());
        }
        self.set_visibility_with(device, Capacity::default())
    }

    /// [`GpuRenderer::set_visibility`] on, its deferred triangles' lists of `capacity` at most
    /// (grown by [`GpuRenderer::check_visibility`] when a frame overflows them).
    pub fn set_visibility_with(
        &mut self,
        device: &wgpu::Device,
        capacity: Capacity,
    ) -> Result<(), RenderError> {
        visibility_exclusion(self.shading.config().method, true)?;
        let stage = VisibilityStage::new(
            device,
            &self.gbuffer_pass,
            &self.scene,
            &self.sized.targets,
            capacity,
        )?;
        self.visibility = Some(stage);
        let bound = self.rebind_visibility(device);
        if bound.is_err() {
            self.visibility = None;
        }
        bound
    }

    /// Binds the visibility path again to the frame's targets and to the supersampled
    /// G-buffer's (after a resize, new supersampling or hidden meshes).
    fn rebind_visibility(&mut self, device: &wgpu::Device) -> Result<(), RenderError> {
        if let Some(v) = &mut self.visibility {
            let ss = self.supersampling.as_ref().map(Supersampling::gbuffer);
            v.rebind(
                device,
                (&self.gbuffer_pass, &self.scene),
                &self.sized.targets,
                ss,
            )?;
        }
        Ok(())
    }

    /// Whether the G-buffer is drawn through the visibility buffer
    /// ([`GpuRenderer::set_visibility`]).
    pub fn visibility(&self) -> bool {
        self.visibility.is_some()
    }

    /// How the visibility path resolves the frame's G-buffer: in one dispatch where the
    /// device has binding arrays for the scene's textures, else classified by material
    /// (`gbuffer::gpu::visibility::ResolvePath`); `None` without the path.
    pub fn visibility_resolve(&self) -> Option<gbuffer::gpu::visibility::ResolvePath> {
        self.visibility.as_ref().map(|v| v.main.resolved.path)
    }

    /// Draws the meshes `hardware` (indices in the scene's meshes) into the visibility buffer
    /// with the hardware rasteriser instead of the compute rasteriser (alpha-tested meshes are
    /// drawn so anyway): meshes of large triangles, which it covers faster
    /// (`gbuffer::gpu::visibility::VisibilityPass::bind_split`). Needs the visibility path on
    /// ([`GpuRenderer::set_visibility`]); an index past the scene's meshes is refused and the
    /// split left as it was. A split by hand ends a split rule
    /// ([`GpuRenderer::set_visibility_split_rule`]); [`GpuRenderer::choose_gbuffer_path`]
    /// measures where to split.
    pub fn set_visibility_split(
        &mut self,
        device: &wgpu::Device,
        hardware: &[usize],
    ) -> Result<(), RenderError> {
        self.split_meshes(device, hardware)?;
        if let Some(v) = &mut self.visibility {
            v.split_rule = None;
        }
        Ok(())
    }

    /// Splits the visibility buffer's meshes by their size on screen from the camera set, and
    /// again whenever a frame is rendered from another ([`GpuRenderer::follow_visibility_split`]):
    /// meshes whose triangles cover more than `above_pixels` pixels on average
    /// ([`GpuScene::pixels_per_triangle`]) go to the hardware rasteriser — the split rule
    /// [`GpuRenderer::choose_gbuffer_path`] measures and keeps. Needs the visibility path on
    /// and a camera; `f32::INFINITY` hands no mesh over.
    pub fn set_visibility_split_rule(
        &mut self,
        device: &wgpu::Device,
        above_pixels: f32,
    ) -> Result<(), RenderError> {
        if above_pixels.is_nan() {
            return Err(RenderError::Visibility(
                "a split rule's pixels per triangle must be a number (f32::INFINITY: none)".into(),
            ));
        }
        let meshes = self.meshes_on_screen_above(above_pixels)?;
        self.split_meshes(device, &meshes)?;
        if let Some(v) = &mut self.visibility {
            v.split_rule = Some(above_pixels);
        }
        Ok(())
    }

    /// The split rule in force ([`GpuRenderer::set_visibility_split_rule`]); `None` without
    /// the path or for a split by hand.
    pub fn visibility_split_rule(&self) -> Option<f32> {
        self.visibility.as_ref().and_then(|v| v.split_rule)
    }

    /// Applies the split rule ([`GpuRenderer::set_visibility_split_rule`]) to the camera set:
    /// binds the visibility path again if another set of meshes is above it now, and says
    /// whether it did. [`GpuRenderer::render`] and [`GpuRenderer::time_frame`] call it; call it
    /// after [`GpuRenderer::set_camera`] when recording frames with
    /// [`GpuRenderer::encode`]. Nothing to do without a rule.
    pub fn follow_visibility_split(&mut self, device: &wgpu::Device) -> Result<bool, RenderError> {
        // An infinite threshold moves no mesh, whatever the camera.
        let Some(rule) = self.visibility_split_rule().filter(|r| r.is_finite()) else {
            return Ok(false);
        };
        let meshes = self.meshes_on_screen_above(rule)?;
        if self
            .visibility
            .as_ref()
            .is_some_and(|v| v.hardware_meshes == meshes)
        {
            return Ok(false);
        }
        self.split_meshes(device, &meshes)?;
        Ok(true)
    }

    /// The meshes whose triangles cover more than `above_pixels` pixels on average from the
    /// camera set.
    fn meshes_on_screen_above(&self, above_pixels: f32) -> Result<Vec<usize>, RenderError> {
        let Some(camera) = &self.camera else {
            return Err(RenderError::Visibility(
                "a split rule measures meshes on screen: set a camera first (set_camera)".into(),
            ));
        };
        let (width, height) = self.size();
        let pixels = self
            .scene
            .pixels_per_triangle(&Frame::new(camera, width, height));
        Ok(meshes_above(&pixels, above_pixels))
    }

    /// [`GpuRenderer::set_visibility_split`] without touching the split rule.
    fn split_meshes(
        &mut self,
        device: &wgpu::Device,
        hardware: &[usize],
    ) -> Result<(), RenderError> {
        let Some(v) = &mut self.visibility else {
            return Err(RenderError::Visibility(
                "the visibility buffer's split between the rasterisers needs the visibility path on (set_visibility)".into(),
            ));
        };
        let before = std::mem::replace(&mut v.hardware_meshes, hardware.to_vec());
        let bound = self.rebind_visibility(device);
        if bound.is_err() {
            if let Some(v) = &mut self.visibility {
                v.hardware_meshes = before;
            }
            self.rebind_visibility(device)?;
        }
        bound
    }

    /// The meshes the visibility path draws with the hardware rasteriser: the alpha-tested
    /// ones and those of [`GpuRenderer::set_visibility_split`] (`None` without the path).
    pub fn visibility_hardware_meshes(&self) -> Option<&[usize]> {
        self.visibility
            .as_ref()
            .map(|v| v.main.vis.hardware.as_slice())
    }

    /// Checks that the last frame's visibility buffer lost no triangle to its lists (reads back
    /// four counters per bound G-buffer). When it did, the lists grow fourfold (at most the
    /// device's largest binding) and the answer is `true`: render the frame again. An error when
    /// even the largest lists are too small; `false` without the visibility path.
    pub fn check_visibility(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
    ) -> Result<bool, RenderError> {
        let Some(v) = &mut self.visibility else {
            return Ok(false);
        };
        let mut lost = v.main.vis.overflow(device, queue)?;
        if let Some(ss) = &v.ss {
            lost += ss.vis.overflow(device, queue)?;
        }
        if lost == 0 {
            return Ok(false);
        }
        let Some(grown) = v.raster.capacity().grown(device) else {
            return Err(RenderError::Visibility(format!(
                "{lost} list entries did not fit in the visibility buffer's largest lists ({:?}): lower the resolution or the triangle count",
                v.raster.capacity()
            )));
        };
        v.raster = VisibilityPass::with(device, &self.gbuffer_pass, grown, v.raster.atomics())?;
        self.rebind_visibility(device)?;
        Ok(true)
    }

    /// Measures the G-buffer's two paths from `camera` over `frames` frames each (median GPU
    /// time of their passes, the supersampled G-buffer's included) and keeps the faster: the
    /// visibility buffer ([`GpuRenderer::set_visibility`]) or the hardware rasteriser. The
    /// visibility path is measured per mesh split ([`VisibilitySplit`]): for each of
    /// [`SPLIT_PIXELS`], the meshes whose triangles cover more pixels on average
    /// ([`GpuScene::pixels_per_triangle`] from `camera`) drawn by the hardware rasteriser
    /// into the buffer, the others by the compute rasteriser (a split equal to the one before
    /// is not measured again); its fastest split's threshold is kept as the split rule, which
    /// follows the camera ([`GpuRenderer::set_visibility_split_rule`]). The visibility path is skipped,
    /// with the reason, where it cannot run (a missing device feature, Forward+, the light
    /// pre-pass). Needs timestamp queries; renders `frames` frames per path and split and
    /// leaves the camera set.
    pub fn choose_gbuffer_path(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        camera: &Camera,
        frames: u32,
    ) -> Result<GBufferChoice, RenderError> {
        if !self.timer.enabled() {
            return Err(RenderError::Visibility(
                "choosing the G-buffer path measures both: the device has no timestamp queries"
                    .into(),
            ));
        }
        self.set_camera(queue, camera)?;
        self.set_visibility(device, false)?;
        let hardware_ms = self.median_ms(device, queue, frames.max(1), |name| {
            matches!(
                name,
                "z-prepass" | "gbuffer" | "ss z-prepass" | "ss gbuffer"
            )
        })?;
        let mut splits: Vec<VisibilitySplit> = Vec::new();
        let visibility_ms = match self.set_visibility(device, true) {
            Ok(()) => {
                let (width, height) = self.size();
                let pixels = self
                    .scene
                    .pixels_per_triangle(&Frame::new(camera, width, height));
                for (above_pixels, hardware_meshes) in visibility_splits(&pixels) {
                    self.set_visibility_split(device, &hardware_meshes)?;
                    let ms = self.median_ms(device, queue, frames.max(1), |name| {
                        name.starts_with("visibility") || name.starts_with("ss visibility")
                    })?;
                    splits.push(VisibilitySplit {
                        above_pixels,
                        hardware_meshes,
                        ms,
                    });
                }
                // The first split is always measured.
                let fastest = fastest_split(&splits);
                let (ms, rule) =
                    fastest.map_or((f64::INFINITY, f32::INFINITY), |s| (s.ms, s.above_pixels));
                self.set_visibility_split_rule(device, rule)?;
                Ok(ms)
            }
            Err(e) => Err(e.to_string()),
        };
        let visibility = matches!(visibility_ms, Ok(ms) if ms < hardware_ms);
        if !visibility {
            self.set_visibility(device, false)?;
        }
        Ok(GBufferChoice {
            hardware_ms,
            visibility_ms,
            splits,
            visibility,
        })
    }

    /// The median over `frames` frames of the summed GPU time of the passes `counted` names.
    fn median_ms(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        frames: u32,
        counted: impl Fn(&str) -> bool,
    ) -> Result<f64, RenderError> {
        let mut times = Vec::with_capacity(frames as usize);
        for _ in 0..frames {
            let timings = self.run_timed(device, queue)?;
            times.push(
                timings
                    .iter()
                    .filter(|t| counted(&t.name))
                    .map(|t| t.ms)
                    .sum::<f64>(),
            );
        }
        times.sort_by(f64::total_cmp);
        Ok(times[times.len() / 2])
    }

    /// Subdivides the meshes of `plan` every frame (`Some`: this renderer was made from the
    /// scene [`crate::subdivision::prepare`] returned with `plan`): the control meshes are no
    /// longer drawn; after the skinning, each is gathered into M⁰, its limit surface evaluated
    /// at the plan's level on the GPU and written into its refined mesh, which every pass
    /// draws; adaptive plans tessellate for the camera of each frame
    /// ([`GpuRenderer::set_camera`]) and need [`subdiv_bft::adaptive_device_needs`]. Give the
    /// setters that build on the CPU ([`GpuRenderer::set_vpl_shadows`], the shadows, the near
    /// field) [`SubdivisionPlan::drawn`]. Set once: there is no way back to the control meshes.
    pub fn set_subdivision(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        plan: &SubdivisionPlan,
    ) -> Result<(), RenderError> {
        let stage = SubdivisionStage::new(device, plan, &self.scene)?;
        for control in plan.controls() {
            self.scene.hide(control);
        }
        for (mesh, args) in stage.indirect_draws() {
            self.scene.draw_indirect(mesh, args.clone());
        }
        self.subdivision = Some(stage);
        // The hidden control meshes leave the visibility buffer's mesh table.
        self.rebind_visibility(device)?;
        self.set_subdivision_view(queue)
    }

    /// Sets the view of adaptive subdivision's factors (the camera over the frame).
    fn set_subdivision_view(&self, queue: &wgpu::Queue) -> Result<(), RenderError> {
        match (&self.subdivision, &self.camera) {
            (Some(s), Some(camera)) => s.set_camera(queue, camera, self.size()),
            _ => Ok(()),
        }
    }

    /// Poses the animated meshes for the following frames (a pose of the rig given to
    /// [`GpuRenderer::set_animation`]; only joint matrices and morph weights are written).
    pub fn set_pose(&self, queue: &wgpu::Queue, pose: &Pose) -> Result<(), RenderError> {
        let Some(a) = &self.animation else {
            return Err(RenderError::Animation(
                "the renderer has no animation: set one (set_animation) before a pose".into(),
            ));
        };
        if pose.world.len() != a.rig.nodes.len() {
            return Err(RenderError::Animation(format!(
                "a pose of {} nodes for a rig of {}",
                pose.world.len(),
                a.rig.nodes.len()
            )));
        }
        a.bound.set_pose(queue, &a.rig, pose);
        Ok(())
    }

    /// Gives the ManyLoD hierarchies (VPL visibility, the lights' ManyLoD shadows) the posed
    /// scene's triangle positions (`positions`: [`instant_radiosity::shadows::scene_mesh`] of
    /// the scene at the pose given to [`GpuRenderer::set_pose`]); the next frame refits them
    /// before its cuts. Set up from a scene with a rig, the ManyLoD and ISM maps can refit;
    /// rasterised and ray visibility keep the set-up pose.
    pub fn set_scene_positions(
        &mut self,
        queue: &wgpu::Queue,
        positions: &[Vec3],
    ) -> Result<(), RenderError> {
        if let Some(maps) = self
            .vpl_shadows
            .as_mut()
            .filter(|m| matches!(m.mode(), VplShadows::ManyLod | VplShadows::Ism))
        {
            maps.set_positions(queue, positions)?;
        }
        if let Some(a) = &mut self.light_atlas
            && a.mesh.0.len() == positions.len()
        {
            a.mesh.0 = positions.to_vec();
            if let Some(maps) = &mut a.maps {
                maps.set_positions(queue, positions)?;
            }
        }
        Ok(())
    }

    /// Sets the camera of the following frames (validated: finite, positive field of view).
    pub fn set_camera(&mut self, queue: &wgpu::Queue, camera: &Camera) -> Result<(), RenderError> {
        gbuffer::validate_camera(camera)?;
        let mut frame = Frame::new(camera, self.sized.targets.width, self.sized.targets.height);
        if let Some(s) = &self.supersampling {
            frame = frame.with_jitter(s.jitter());
        }
        self.gbuffer_pass.write_frame(queue, &frame);
        self.shading_bound.set_camera(queue, camera);
        if let Some(ForwardStage {
            cull: Some((_, Some(lists))),
            ..
        }) = &mut self.forward
        {
            lists.set_camera(queue, camera);
        }
        if let Some(s) = &mut self.supersampling {
            s.set_camera(queue, camera);
        }
        self.camera = Some(*camera);
        self.set_subdivision_view(queue)?;
        // Directional cascades follow the camera (the view count does not change); the other
        // lights' views do not depend on it.
        let cascaded = self.lights.iter().any(|l| {
            l.kind == tiled_shading::LIGHT_DIRECTIONAL && l.shadow_count != shadows::NO_SHADOW
        });
        let made = self.shadows.as_ref().map_or(0, |s| s.maps.capacity());
        if cascaded && let Some(plan) = self.shadow_plan(u32::try_from(made).unwrap_or(u32::MAX))? {
            self.write_shadow_plan(queue, &plan)?;
        }
        Ok(())
    }

    /// Sets the ambient light of the composition.
    pub fn set_ambient(&mut self, queue: &wgpu::Queue, ambient: Vec3) {
        self.ambient_radiance = ambient;
        self.write_ambient(queue);
    }

    /// Writes the ambient radiance and whether SSAO scales it.
    fn write_ambient(&self, queue: &wgpu::Queue) {
        let on = if self.ssao.is_some() { 1.0 } else { 0.0 };
        let value = self.ambient_radiance.extend(on);
        queue.write_buffer(&self.ambient, 0, bytemuck::bytes_of(&value));
    }

    /// Adds screen-space ambient occlusion (`Some`: [`ssao`]'s `estimator` with `config`, run
    /// after the G-buffer on its depth and normals), or removes it (`None`). Its accessibility
    /// multiplies the material's occlusion, so it darkens the ambient and the indirect light,
    /// not the direct light (with supersampling: each sample by its pixel's).
    pub fn set_ssao(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        ssao: Option<(&ssao::cpu::KernelConfig, ssao::Estimator)>,
    ) -> Result<(), RenderError> {
        self.ssao = match ssao {
            Some((config, estimator)) => {
                let kernels = self.ssao.take().map(|s| s.kernels);
                Some(self.new_ssao(device, kernels, config, estimator)?)
            }
            None => None,
        };
        self.bind_composition(device);
        self.write_ambient(queue);
        Ok(())
    }

    /// The SSAO stage for the current targets (with `kernels` if already built: a rebind
    /// compiles nothing).
    fn new_ssao(
        &self,
        device: &wgpu::Device,
        kernels: Option<ssao::gpu::SsaoKernels>,
        config: &ssao::cpu::KernelConfig,
        estimator: ssao::Estimator,
    ) -> Result<SsaoStage, RenderError> {
        let (w, h) = self.size();
        let accessibility = transfer::buffer(
            device,
            "accessibility",
            u64::from(w) * u64::from(h) * 4,
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        )?;
        let kernels = match kernels {
            Some(k) => k,
            None => ssao::gpu::SsaoKernels::new(device)?,
        };
        let t = &self.sized.targets;
        let bound = kernels.bind(
            device,
            self.gbuffer_pass.frame_buffer(),
            [&t.linear_depth, &t.normal],
            &accessibility,
            config,
            estimator,
        )?;
        Ok(SsaoStage {
            kernels,
            bound,
            accessibility,
            config: *config,
            estimator,
        })
    }

    /// The screen-space accessibility of the last frame, one `f32` a pixel (`None` without
    /// SSAO): copy or read it after a frame.
    pub fn ssao_accessibility(&self) -> Option<&wgpu::Buffer> {
        self.ssao.as_ref().map(|s| &s.accessibility)
    }

    /// Resizes the frame: new targets and output, rebinds the light accumulation, the
    /// indirect stage and the composition (pipelines are kept). The camera's aspect follows.
    pub fn resize(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        width: u32,
        height: u32,
    ) -> Result<(), RenderError> {
        let sized = SizedTargets::new(device, width, height)?;
        self.sized = sized;
        if let Some(Indirect { config, set, .. }) = self.indirect.take() {
            self.set_indirect(device, &config, &set)?;
        }
        if let Some(PbgiStage {
            lit, stride, scene, ..
        }) = self.pbgi.take()
        {
            self.set_pbgi(device, Some((&lit, stride, &scene)))?;
        }
        if let Some(ReflectionStage {
            lit, tile, scene, ..
        }) = self.reflections.take()
        {
            self.set_reflections(device, Some((&lit, tile, &scene)))?;
        }
        self.rebind(device, queue)?;
        if let Some(camera) = self.camera {
            self.set_camera(queue, &camera)?;
        }
        Ok(())
    }

    /// The frame size.
    pub fn size(&self) -> (u32, u32) {
        (self.sized.targets.width, self.sized.targets.height)
    }

    /// The light accumulation stage.
    pub fn shading(&self) -> &LightShading {
        &self.shading
    }

    /// Reads back each tile's light count of the last frame (`None` for brute force); with
    /// supersampling, of the tiles of samples (the grid of `m` times the frame size) in the
    /// samples' light accumulation (samples 2..k of each pixel).
    pub fn light_counts(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
    ) -> Result<Option<Vec<u32>>, RenderError> {
        let bound = match &self.supersampling {
            Some(s) => s.shading(),
            None => &self.shading_bound,
        };
        Ok(bound.read_counts(device, queue)?)
    }

    /// Adds one-bounce indirect light from `set`'s VPLs as `config` says (the stage reads this
    /// renderer's G-buffer; the composition adds its output). Replaces an earlier stage.
    pub fn set_indirect(
        &mut self,
        device: &wgpu::Device,
        config: &IndirectConfig,
        set: &VplSet,
    ) -> Result<(), RenderError> {
        if self.reflections.is_some() {
            return Err(instant_radiosity::IndirectError::Config(
                "the VPLs' indirect light and reflection maps both fill the indirect specular \
                 light: remove the reflections first (point-based GI combines with them)"
                    .into(),
            )
            .into());
        }
        let stage = IndirectStage::new(device, config, self.size())?;
        let outputs = stage.output_textures(device);
        let bound = stage.bind(
            device,
            self.gbuffer_pass.frame_buffer(),
            (&self.sized.targets).into(),
            set,
            self.vpl_shadows.as_ref(),
            outputs.each_ref(),
        )?;
        self.indirect = Some(Indirect {
            stage,
            bound,
            outputs,
            config: *config,
            set: set.clone(),
        });
        self.pbgi = None;
        self.bind_near_field(device)?;
        self.bind_composition(device);
        Ok(())
    }

    /// Lights the frame's indirect diffuse light by point-based GI (`Some((lit, stride,
    /// scene))`, Holländer 2013 §3.6.1, [`instant_radiosity::pbgi`]): every frame the surfels
    /// of `lit` are lit by the renderer's lights with shadow rays through `scene`'s triangles,
    /// a receiver every `stride` pixels of the G-buffer gathers them through a many-view cut,
    /// and the irradiance is upsampled edge-aware to the frame — instead of the VPLs' indirect
    /// stage, which this removes (with its near field); or removes it (`None`). The surfels stay
    /// where `lit` sampled them (meshes that move later are not followed). The cut lists hold
    /// `PBGI_NODE_VIEWS_PER_CELL` node-views per `(tile / ε)²` of every view (at most the
    /// device's largest binding); [`GpuRenderer::check_pbgi`] grows them when a frame's cut
    /// did not fit.
    pub fn set_pbgi(
        &mut self,
        device: &wgpu::Device,
        setting: Option<(&instant_radiosity::pbgi::LitPoints, u32, &Scene)>,
    ) -> Result<(), RenderError> {
        self.set_pbgi_with(device, setting, None)
    }

    /// [`GpuRenderer::set_pbgi`] with cut lists of `capacity` node-views (default: the
    /// estimate), at most the device's largest binding.
    fn set_pbgi_with(
        &mut self,
        device: &wgpu::Device,
        setting: Option<(&instant_radiosity::pbgi::LitPoints, u32, &Scene)>,
        capacity: Option<usize>,
    ) -> Result<(), RenderError> {
        let Some((lit, stride, scene)) = setting else {
            self.pbgi = None;
            self.bind_composition(device);
            return Ok(());
        };
        use instant_radiosity::pbgi::{GpuGather, ReceiverGrid};
        let grid = ReceiverGrid::new(self.size(), stride)?;
        let largest = manylod::gpu::largest_capacity(device);
        let cells = (lit.config().tile as f32 / lit.config().epsilon.max(0.25)).powi(2);
        let estimate = (grid.len() as f32 * cells * PBGI_NODE_VIEWS_PER_CELL) as usize;
        let capacity = capacity
            .unwrap_or(estimate)
            .clamp(grid.len().max(2), largest);
        let placeholder = vec![(Vec3::ZERO, Vec3::Y); grid.len()];
        let mut gather = GpuGather::new(device, lit, &placeholder, capacity)?;
        gather.light_on_gpu(device, scene, lit, &self.lights)?;
        let (w, h) = self.size();
        let output = transfer::texture_2d(
            device,
            "pbgi indirect diffuse",
            w,
            h,
            interleave::gpu::IRRADIANCE_FORMAT,
            transfer::STORAGE_OUTPUT,
        );
        gather.bind_frame(
            device,
            &grid,
            self.gbuffer_pass.frame_buffer(),
            (&self.sized.targets).into(),
            &output,
        )?;
        self.indirect = None;
        self.near_field = None;
        self.pbgi = Some(PbgiStage {
            gather,
            output,
            lit: lit.clone(),
            stride,
            scene: scene.clone(),
            capacity,
        });
        self.bind_composition(device);
        Ok(())
    }

    /// Checks that the last frame's point-based GI cuts fit their lists (reads back a few
    /// counters). When they did not, the lists grow to twice what the cut needed (at most the
    /// device's largest binding) and the answer is `true`: render the frame again. An error
    /// when even the largest lists are too small; `false` without PBGI.
    pub fn check_pbgi(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
    ) -> Result<bool, RenderError> {
        let Some(p) = &self.pbgi else {
            return Ok(false);
        };
        match p.gather.check(device, queue) {
            Ok(()) => Ok(false),
            Err(instant_radiosity::IndirectError::ManyLod(manylod::ManyLodError::Capacity {
                needed,
                ..
            })) => {
                let largest = manylod::gpu::largest_capacity(device);
                if p.capacity >= largest {
                    return Err(instant_radiosity::IndirectError::Config(format!(
                        "point-based GI's cuts need {needed} node-views per list, more than this \
                         device's largest binding holds ({largest}): raise ε or the stride, or \
                         lower the texels"
                    ))
                    .into());
                }
                let PbgiStage {
                    lit, stride, scene, ..
                } = self.pbgi.take().expect("checked");
                let grown = (2 * needed as usize).min(largest);
                self.set_pbgi_with(device, Some((&lit, stride, &scene)), Some(grown))?;
                Ok(true)
            }
            Err(e) => Err(e.into()),
        }
    }

    /// Reflects (and refracts) the scene in its mirror and glass materials through maps
    /// (`Some((lit, tile, scene))`, Holländer 2013 §3.6.1 Fig. 3.19,
    /// [`instant_radiosity::reflections`]): a dual-paraboloid map of `tile²` texels per mirror
    /// or glass mesh of `scene` (metallic ≥ 0.9 or transmission > 0, roughness ≤ 0.2), made
    /// every frame from `lit`'s surfels (lit here on the CPU by the renderer's lights through
    /// `scene`'s triangles, and again when the lights change) by a many-view cut at `lit`'s ε;
    /// every such pixel adds Fresnel × its probe's map in the mirrored view direction, and on
    /// glass what it transmits along the refracted one, to its indirect specular light. `None` removes them. Not with
    /// the VPLs' indirect stage (the same slot; an error), and not in supersampled frames'
    /// samples (per pixel, like the other indirect light). The cut lists hold an estimate
    /// that [`GpuRenderer::check_reflections`] grows.
    pub fn set_reflections(
        &mut self,
        device: &wgpu::Device,
        setting: Option<(&instant_radiosity::pbgi::LitPoints, u32, &Scene)>,
    ) -> Result<(), RenderError> {
        self.set_reflections_with(device, setting, None)
    }

    fn set_reflections_with(
        &mut self,
        device: &wgpu::Device,
        setting: Option<(&instant_radiosity::pbgi::LitPoints, u32, &Scene)>,
        capacity: Option<usize>,
    ) -> Result<(), RenderError> {
        let Some((lit, tile, scene)) = setting else {
            self.reflections = None;
            self.bind_composition(device);
            return Ok(());
        };
        if self.indirect.is_some() {
            return Err(instant_radiosity::IndirectError::Config(
                "reflection maps and the VPLs' indirect light both fill the indirect specular \
                 light: use point-based GI (or no indirect light) with reflections"
                    .into(),
            )
            .into());
        }
        use instant_radiosity::reflections::{GpuReflections, Probes, REFLECTION_FORMAT};
        let probes = Probes::of_scene(scene);
        let mut lit = lit.clone();
        lit.light(scene, &self.lights)?;
        let radiance = transfer::buffer_init(
            device,
            "reflection radiance",
            bytemuck::cast_slice(&radiance_words(&lit)),
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
        )?;
        let largest = manylod::gpu::largest_capacity(device);
        let cells = (tile as f32 / lit.config().epsilon.max(0.25)).powi(2);
        let estimate = (2.0 * probes.len() as f32 * cells * PBGI_NODE_VIEWS_PER_CELL) as usize;
        let capacity = capacity
            .unwrap_or(estimate)
            .clamp((2 * probes.len()).max(2), largest);
        let mut maps = GpuReflections::new(device, &lit, &radiance, (&probes, tile), capacity)?;
        let (w, h) = self.size();
        let output = transfer::texture_2d(
            device,
            "reflections",
            w,
            h,
            REFLECTION_FORMAT,
            transfer::STORAGE_OUTPUT,
        );
        maps.bind_frame(
            device,
            self.gbuffer_pass.frame_buffer(),
            (&self.sized.targets).into(),
            &output,
        )?;
        self.reflections = Some(ReflectionStage {
            maps,
            output,
            radiance,
            lit,
            tile,
            scene: scene.clone(),
            capacity,
        });
        self.bind_composition(device);
        Ok(())
    }

    /// [`GpuRenderer::check_pbgi`] for the reflection maps' cut lists.
    pub fn check_reflections(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
    ) -> Result<bool, RenderError> {
        let Some(r) = &self.reflections else {
            return Ok(false);
        };
        match r.maps.check(device, queue) {
            Ok(()) => Ok(false),
            Err(instant_radiosity::IndirectError::ManyLod(manylod::ManyLodError::Capacity {
                needed,
                ..
            })) => {
                let largest = manylod::gpu::largest_capacity(device);
                if r.capacity >= largest {
                    return Err(instant_radiosity::IndirectError::Config(format!(
                        "the reflection maps' cuts need {needed} node-views per list, more than \
                         this device's largest binding holds ({largest}): raise ε or lower the \
                         texels"
                    ))
                    .into());
                }
                let ReflectionStage {
                    lit, tile, scene, ..
                } = self.reflections.take().expect("checked");
                let grown = (2 * needed as usize).min(largest);
                self.set_reflections_with(device, Some((&lit, tile, &scene)), Some(grown))?;
                Ok(true)
            }
            Err(e) => Err(e.into()),
        }
    }

    /// Adds the VPLs' near field (`Some(scene)`: Kollig & Keller 2004's compensation of the
    /// VPL clamp, [`instant_radiosity::near_field`] — a ray of the clamp's length per pixel
    /// through a BVH of `scene`, its light added to the indirect diffuse light), or removes it
    /// (`None`). It follows the indirect stage's VPLs and clamp and the direct lights; each
    /// new VPL set ([`GpuRenderer::set_vpls`]) draws another sample. Without an indirect
    /// stage it is an error.
    pub fn set_near_field(
        &mut self,
        device: &wgpu::Device,
        scene: Option<&Scene>,
    ) -> Result<(), RenderError> {
        if self.indirect.is_none() && scene.is_some() {
            return Err(RenderError::NoIndirect);
        }
        self.near_field = match scene {
            Some(scene) => Some(NearFieldStage {
                kernel: NearField::new(device, scene)?,
                bound: None,
            }),
            None => None,
        };
        self.bind_near_field(device)?;
        self.bind_composition(device);
        Ok(())
    }

    /// Binds the near field, if set, to the current targets, lights and indirect stage.
    fn bind_near_field(&mut self, device: &wgpu::Device) -> Result<(), RenderError> {
        let (Some(stage), Some(indirect)) = (&mut self.near_field, &self.indirect) else {
            return Ok(());
        };
        let (w, h) = (self.sized.targets.width, self.sized.targets.height);
        let output = transfer::texture_2d(
            device,
            "near field",
            w,
            h,
            interleave::gpu::IRRADIANCE_FORMAT,
            wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::STORAGE_BINDING,
        );
        let bound = stage.kernel.bind(
            device,
            self.gbuffer_pass.frame_buffer(),
            (&self.sized.targets).into(),
            &self.lights,
            &indirect.set,
            indirect.config.clamp_distance,
            &output,
        )?;
        stage.bound = Some((bound, output));
        Ok(())
    }

    /// Adds VPL visibility to the indirect light (`mode`: ManyLoDs cuts or the ISM baseline,
    /// built over `scene` for the VPLs of `set`) and rebuilds the indirect stage with it. Every
    /// frame then finds the cuts (incremental after the first frame) and splats the atlas
    /// before the VPL shading.
    pub fn set_vpl_shadows(
        &mut self,
        device: &wgpu::Device,
        scene: &Scene,
        mode: VplShadows,
        shadow_config: &ShadowConfig,
        config: &IndirectConfig,
        set: &VplSet,
    ) -> Result<(), RenderError> {
        let shadow_config = ShadowConfig {
            refit: shadow_config.refit
                || (scene.rig.is_some() && matches!(mode, VplShadows::ManyLod | VplShadows::Ism)),
            ..*shadow_config
        };
        self.vpl_shadows = Some(VplShadowMaps::new(
            device,
            scene,
            set,
            mode,
            &shadow_config,
        )?);
        self.set_indirect(device, config, set)
    }

    /// Replaces the indirect light's VPLs (and their shadow maps' views) by another set of as
    /// many VPLs in as many subsets — a progressive frame's new set, VPLs after the lights
    /// moved — rebuilding nothing. Without an indirect stage it is an error.
    pub fn set_vpls(&mut self, queue: &wgpu::Queue, set: &VplSet) -> Result<(), RenderError> {
        let Some(indirect) = &mut self.indirect else {
            return Err(RenderError::NoIndirect);
        };
        indirect.bound.set_vpls(queue, set)?;
        if let Some(shadows) = &self.vpl_shadows {
            shadows.set_vpls(queue, set)?;
        }
        if let Some(bound) = self.near_field.as_mut().and_then(NearFieldStage::bound_mut) {
            bound.set_vpls(queue, set)?;
        }
        indirect.set = set.clone();
        Ok(())
    }

    /// Shadow views of the direct lights the frame renders (0 without shadows).
    pub fn shadow_view_count(&self) -> usize {
        self.drawn_maps().map_or(0, |s| s.maps.count())
    }

    /// The direct lights' shadow maps where they are drawn: set, and not replaced by rays.
    fn drawn_maps(&self) -> Option<&DirectShadows> {
        self.shadows.as_ref().filter(|_| self.ray_shadows.is_none())
    }

    /// The direct lights' ManyLoD shadow maps, if set and some light has paraboloid views.
    pub fn manylod_shadows(&self) -> Option<&VplShadowMaps> {
        self.light_atlas.as_ref().and_then(|a| a.maps.as_ref())
    }

    /// The VPL shadow maps, if set.
    pub fn vpl_shadows(&self) -> Option<&VplShadowMaps> {
        self.vpl_shadows.as_ref()
    }

    /// The bound indirect stage, if one was set (read its stages back with
    /// [`BoundIndirect::read`] after a frame).
    pub fn indirect(&self) -> Option<&BoundIndirect> {
        self.indirect.as_ref().map(|i| &i.bound)
    }

    /// The G-buffer targets (read them back with [`GBufferTargets::read`] after a frame).
    pub fn targets(&self) -> &GBufferTargets {
        &self.sized.targets
    }

    /// The frame's linear radiance ([`RADIANCE_FORMAT`], `TEXTURE_BINDING | COPY_SRC`): sample,
    /// copy or tone-map it into a surface after submitting [`GpuRenderer::encode`].
    pub fn output(&self) -> &wgpu::Texture {
        &self.sized.radiance
    }

    /// Records one frame into `encoder`, each pass timed (read with
    /// [`GpuRenderer::timings`]). Needs a camera ([`GpuRenderer::set_camera`]); reads nothing
    /// back, so frames can be encoded back to back.
    pub fn encode(&mut self, encoder: &mut wgpu::CommandEncoder) {
        self.timer.reset();
        if let Some(a) = &self.animation {
            a.bound.encode(encoder, Some(&self.timer));
        }
        if let Some(s) = &self.subdivision {
            s.encode(encoder, &self.timer);
        }
        match &self.visibility {
            Some(v) => v.encode(&v.main, encoder, &self.sized.targets.depth, &self.timer),
            // The z-prepass path: 1.3× faster than the single MRT pass on Sponza on an H100
            // (docs/bench), and the same G-buffer.
            None => self.gbuffer_pass.encode_with_prepass(
                encoder,
                &self.scene,
                &self.sized.targets,
                self.timer.render_pass("z-prepass"),
                self.timer.render_pass("gbuffer"),
            ),
        }
        if let Some(s) = &self.ssao {
            s.kernels.encode(&s.bound, encoder, Some(&self.timer));
        }
        if let Some(s) = &self.supersampling {
            match self
                .visibility
                .as_ref()
                .and_then(|v| Some((v, v.ss.as_ref()?)))
            {
                Some((v, bound)) => v.encode(bound, encoder, &s.gbuffer().1.depth, &self.timer),
                None => s.encode_gbuffer(encoder, &self.gbuffer_pass, &self.scene, &self.timer),
            }
        }
        if let Some(shadows) = &mut self.vpl_shadows
            && self.indirect.is_some()
        {
            shadows.encode(encoder, Some(&self.timer));
        }
        if let Some(s) = self.drawn_maps() {
            s.pass
                .encode(&s.maps, &self.scene, encoder, Some(&self.timer));
        }
        if let Some(maps) = self
            .light_atlas
            .as_mut()
            .and_then(|a| a.maps.as_mut())
            .filter(|_| self.ray_shadows.is_none())
        {
            maps.encode(encoder, Some(&self.timer));
        }
        self.shading
            .encode(&self.shading_bound, encoder, Some(&self.timer));
        if let Some(ForwardStage {
            pass,
            bound: Some(bound),
            cull,
        }) = &self.forward
        {
            match cull {
                // Blended surfaces over a deferred method: only their lists.
                Some((cull, Some(lists))) => {
                    cull.encode_as(
                        lists,
                        encoder,
                        Some(&self.timer),
                        "forward+ lists (blended)",
                    );
                }
                _ => {
                    let direct = [&self.sized.direct[0], &self.sized.direct[1]];
                    let scene = (&self.gbuffer_pass, &self.scene);
                    let depth = &self.sized.targets.depth;
                    pass.encode_opaque(bound, encoder, scene, depth, direct, Some(&self.timer));
                }
            }
        }
        if let Some(PrePassStage {
            pass,
            bound: Some((_, bound)),
        }) = &self.prepass
        {
            let direct = [&self.sized.direct[0], &self.sized.direct[1]];
            let scene = (&self.gbuffer_pass, &self.scene);
            let depth = &self.sized.targets.depth;
            pass.encode(bound, encoder, scene, depth, direct, Some(&self.timer));
        }
        if let Some(i) = &self.indirect {
            i.stage.encode(&i.bound, encoder, Some(&self.timer));
        }
        if let Some(p) = &mut self.pbgi {
            p.gather.encode(encoder, Some(&self.timer));
        }
        if let Some(r) = &mut self.reflections {
            r.maps.encode(encoder, Some(&self.timer));
        }
        if let Some((bound, _)) = self.near_field.as_ref().and_then(|n| n.bound.as_ref()) {
            bound.encode(encoder, Some(&self.timer));
        }
        let (w, h) = self.size();
        Passes::one(
            "composition",
            &self.composition.pipeline,
            vec![self.composition_group.clone()],
            Workgroups::covering(w, h, 8),
        )
        .encode(encoder, Some(&self.timer));
        if let (
            Some(ForwardStage {
                pass,
                bound: Some(bound),
                ..
            }),
            Some(camera),
        ) = (&self.forward, &self.camera)
        {
            let scene = (&self.gbuffer_pass, &self.scene);
            let (depth, radiance) = (&self.sized.targets.depth, &self.sized.radiance);
            pass.encode_blended(
                bound,
                encoder,
                scene,
                depth,
                radiance,
                camera.eye,
                Some(&self.timer),
            );
        }
        if let Some(s) = &self.supersampling {
            s.encode(encoder, &self.shading, &self.timer);
        }
        if let Some(output) = &self.output {
            output.bound.encode(encoder, Some(&self.timer));
        }
        self.timer.resolve(encoder);
    }

    /// The GPU time and start (from the frame's first pass) of each pass of the last encoded
    /// frame (waits for it; empty without timestamp queries).
    pub fn pass_times(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
    ) -> Result<Vec<::gpu::PassTime>, RenderError> {
        Ok(self.timer.read(device, queue)?)
    }

    /// The GPU time of each pass of the last encoded frame (waits for it; empty without
    /// timestamp queries).
    pub fn timings(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
    ) -> Result<Vec<PassTiming>, RenderError> {
        Ok(self
            .pass_times(device, queue)?
            .into_iter()
            .map(|t| PassTiming {
                name: t.name,
                ms: t.ms,
            })
            .collect())
    }

    /// Renders a frame from `camera` with `ambient` and reports the GPU time of each pass,
    /// reading nothing else back (for benchmarks).
    pub fn time_frame(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        camera: &Camera,
        ambient: Vec3,
    ) -> Result<Vec<PassTiming>, RenderError> {
        self.set_camera(queue, camera)?;
        self.set_ambient(queue, ambient);
        self.follow_visibility_split(device)?;
        self.run_timed(device, queue)
    }

    /// Records and submits one frame as set, and reports the GPU time of each pass.
    fn run_timed(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
    ) -> Result<Vec<PassTiming>, RenderError> {
        let mut encoder = device.create_command_encoder(&Default::default());
        self.encode(&mut encoder);
        queue.submit([encoder.finish()]);
        self.timings(device, queue)
    }

    /// Renders a frame from `camera` with `ambient`, reads the radiance back and reports
    /// the GPU time of each pass.
    pub fn render(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        camera: &Camera,
        ambient: Vec3,
    ) -> Result<Rendered, RenderError> {
        let timings = self.time_frame(device, queue, camera, ambient)?;
        Ok(Rendered {
            image: read_radiance(device, queue, &self.sized.radiance)?,
            timings,
        })
    }
}

/// Reads a [`output::DISPLAY_FORMAT`] texture (half floats) back as RGBA.
pub fn read_display(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    texture: &wgpu::Texture,
) -> Result<Image<[f32; 4]>, RenderError> {
    let bytes = transfer::read_texture(device, queue, texture, wgpu::TextureAspect::All)?;
    let halves: Vec<half::f16> = bytemuck::pod_collect_to_vec(&bytes);
    let pixels = halves
        .chunks_exact(4)
        .map(|c| [0, 1, 2, 3].map(|k| c[k].to_f32()))
        .collect();
    image_of(texture, pixels)
}

/// The read-back `pixels` of `texture` as an image of its size.
fn image_of(
    texture: &wgpu::Texture,
    pixels: Vec<[f32; 4]>,
) -> Result<Image<[f32; 4]>, RenderError> {
    Ok(Image::from_vec(texture.width(), texture.height(), pixels)
        .map_err(|e| ::gpu::GpuError::Readback(e.to_string()))?)
}

/// Reads a [`RADIANCE_FORMAT`] texture back as linear RGBA.
pub fn read_radiance(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    texture: &wgpu::Texture,
) -> Result<Image<[f32; 4]>, RenderError> {
    let bytes = transfer::read_texture(device, queue, texture, wgpu::TextureAspect::All)?;
    let pixels: Vec<[f32; 4]> = bytemuck::cast_slice::<u8, Vec4>(&bytes)
        .iter()
        .map(|v| v.to_array())
        .collect();
    image_of(texture, pixels)
}

#[cfg(test)]
mod tests {
    #[test]
    fn renderer_is_send_and_sync() {
        fn check<T: Send + Sync>() {}
        check::<super::GpuRenderer>();
    }
}
