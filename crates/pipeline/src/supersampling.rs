//! Supersampling inside the frame (`shaders/pipeline/supersampling.wgsl`): the scene drawn
//! into a second G-buffer of `m × m` samples per pixel and resolved into the frame's radiance —
//! adaptively (Holländer 2013 §4.3, Listing 4.1: the first sample of every pixel,
//! [`adaptive_ssaa`]'s sample-count evaluation, the remaining samples) or fully.
//!
//! The first sample of every pixel is the frame itself: the pixel-resolution G-buffer is
//! jittered onto each window's first sample ([`gbuffer::Frame::with_jitter`]), so the frame's
//! light accumulation, indirect light and composition compute `S`, the first sample's radiance,
//! exactly as without supersampling. The remaining samples are lit by the same light
//! accumulation (method, culling, shadows) bound to the sample grid: the `mask_*` passes copy
//! the linear depth of the samples to shade and write 0 (no surface) for the others, so its
//! tiles bound only the samples it shades.
//!
//! The rule for indirect light: it is shaded once per pixel on the first sample's G-buffer
//! (Segovia's interleaved pipeline unchanged, its split, discontinuity buffer and blur on the
//! pixel grid) and shared by the pixel's samples. A sample's radiance is the composition of its
//! own G-buffer (albedo, material, emission, occlusion) and direct light with the pixel's
//! indirect diffuse, near-field and indirect specular light, so an edge pixel mixes the albedos
//! of its surfaces under one irradiance. Textures are filtered over the whole pixel for every
//! sample ([`gbuffer::Frame::with_texture_footprint`]): right for the pixels of one sample,
//! which are most; an average of `k` samples is then blurred a little more than a pixel's
//! footprint.

use ::gpu::kernel::{self, Binding, Layout, Passes, Workgroups};
use ::gpu::{PassTimer, transfer};
use adaptive_ssaa::SsaaConfig;
use adaptive_ssaa::gpu::Ssaa;
use gbuffer::gpu::{FrameUniform, GBufferPass, GBufferTargets, GBufferTextures, GpuScene};
use gbuffer::{Frame, LINEAR_DEPTH_FORMAT};
use scene::Camera;
use tiled_shading::GpuLight;
use tiled_shading::gpu::shadows::ShadowInputs;
use tiled_shading::gpu::{BoundShading, LightShading};

use crate::RenderError;
use crate::gpu::RADIANCE_FORMAT;

/// Uniform block of `supersampling.wgsl` (`Params`).
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct Params {
    width: u32,
    height: u32,
    m: u32,
    n: u32,
    /// Dither order, `x | y << 8` per sample.
    order: [u32; 64],
    /// The order's inverse: cell `y·m + x` → its rank.
    rank: [u32; 64],
}

impl Params {
    fn new(m: u32, (width, height): (u32, u32)) -> Self {
        let mut order = [0u32; 64];
        let mut rank = [0u32; 64];
        for (i, c) in adaptive_ssaa::dither_order(m).into_iter().enumerate() {
            order[i] = c[0] | (c[1] << 8);
            rank[(c[1] * m + c[0]) as usize] = i as u32;
        }
        Self {
            width,
            height,
            m,
            n: m * m,
            order,
            rank,
        }
    }
}

/// `supersampling.wgsl`'s bindings but `store_first`'s radiance (15): params, ambient; linear
/// depth, masked depth (storage); emission, albedo, material, direct diffuse and specular
/// (samples); indirect diffuse, specular, near field (pixels); counts, S; radiance (storage);
/// screen-space ambient occlusion (16).
const BINDINGS: [(u32, Binding); 16] = [
    (0, Binding::Uniform),
    (1, Binding::Uniform),
    (2, Binding::TextureUnfilterable),
    (3, Binding::StorageTexture(LINEAR_DEPTH_FORMAT)),
    (4, Binding::TextureUnfilterable),
    (5, Binding::TextureUnfilterable),
    (6, Binding::TextureUint),
    (7, Binding::TextureUnfilterable),
    (8, Binding::TextureUnfilterable),
    (9, Binding::TextureUnfilterable),
    (10, Binding::TextureUnfilterable),
    (11, Binding::TextureUnfilterable),
    (12, Binding::StorageRead),
    (13, Binding::Storage),
    (14, Binding::StorageTexture(RADIANCE_FORMAT)),
    (16, Binding::StorageRead),
];

/// `store_first`'s bindings: params, S, the frame's radiance (sampled).
const STORE_FIRST_BINDINGS: [(u32, Binding); 3] = [
    (0, Binding::Uniform),
    (13, Binding::Storage),
    (15, Binding::TextureUnfilterable),
];

/// The entry points of `supersampling.wgsl` and their layouts: compiled once per renderer
/// (a resize or new lights rebuild the stage's resources, not these).
pub(crate) struct SupersamplingKernels {
    layout: Layout,
    store_layout: Layout,
    store_first: wgpu::ComputePipeline,
    mask_rest: wgpu::ComputePipeline,
    mask_full: wgpu::ComputePipeline,
    resolve_adaptive: wgpu::ComputePipeline,
    resolve_full: wgpu::ComputePipeline,
}

impl SupersamplingKernels {
    /// Compiles the entry points.
    pub(crate) fn new(device: &wgpu::Device) -> Result<Self, RenderError> {
        let module = crate::SHADERS.module(device, "supersampling.wgsl")?;
        let layout = Layout::compute_numbered(device, "supersampling", &BINDINGS);
        let store_layout =
            Layout::compute_numbered(device, "supersampling S", &STORE_FIRST_BINDINGS);
        let make = |entry: &str| kernel::pipeline(device, &module, entry, &[&layout], &[]);
        Ok(Self {
            store_first: kernel::pipeline(device, &module, "store_first", &[&store_layout], &[]),
            mask_rest: make("mask_rest"),
            mask_full: make("mask_full"),
            resolve_adaptive: make("resolve_adaptive"),
            resolve_full: make("resolve_full"),
            layout,
            store_layout,
        })
    }
}

/// The supersampling stage of one frame size: the supersampled G-buffer and its frame, the
/// masked depth, the samples' direct light, the light accumulation bound to them, the
/// sample-count evaluation and the resolve kernels (bound by [`Supersampling::bind`]).
pub(crate) struct Supersampling {
    config: SsaaConfig,
    size: (u32, u32),
    frame: FrameUniform,
    targets: GBufferTargets,
    masked_depth: wgpu::Texture,
    direct: [wgpu::Texture; 2],
    shading: BoundShading,
    evaluation: Ssaa,
    params: wgpu::Buffer,
    kernels: SupersamplingKernels,
    groups: Option<[wgpu::BindGroup; 2]>,
}

impl Supersampling {
    /// Builds the stage for `config` at `size` pixels with `kernels`, the light accumulation
    /// `shading` bound to the samples for `lights` (the caller then binds the shadow lookup).
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn new(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        kernels: SupersamplingKernels,
        gbuffer_pass: &GBufferPass,
        shading: &LightShading,
        config: &SsaaConfig,
        size: (u32, u32),
        lights: &[GpuLight],
    ) -> Result<Self, RenderError> {
        config.validate()?;
        let m = config.m;
        let samples = (size.0.checked_mul(m), size.1.checked_mul(m));
        let (Some(sw), Some(sh)) = samples else {
            return Err(adaptive_ssaa::SsaaError::InvalidSize {
                width: size.0,
                height: size.1,
                m,
            }
            .into());
        };
        transfer::check_texture_size(device, "supersampled G-buffer", sw, sh)?;
        let (targets, masked_depth, direct) = transfer::allocation(
            device,
            &format!("the {sw}×{sh} supersampled G-buffer"),
            || -> Result<_, RenderError> {
                Ok((
                    GBufferTargets::new(device, sw, sh)?,
                    transfer::texture_2d(
                        device,
                        "masked linear depth",
                        sw,
                        sh,
                        LINEAR_DEPTH_FORMAT,
                        wgpu::TextureUsages::STORAGE_BINDING | wgpu::TextureUsages::TEXTURE_BINDING,
                    ),
                    LightShading::output_textures(device, sw, sh),
                ))
            },
        )?;
        let frame = gbuffer_pass.frame_uniform(device);
        let masked = GBufferTextures {
            linear_depth: &masked_depth,
            ..(&targets).into()
        };
        let mut bound = shading.bind(
            device,
            frame.buffer(),
            masked,
            [&direct[0], &direct[1]],
            lights.len(),
            false,
        )?;
        bound.set_lights(queue, lights)?;
        let geometry = [&targets.linear_depth, &targets.normal, &targets.material];
        let evaluation = Ssaa::evaluation(device, frame.buffer(), geometry, config, size)?;
        let params = transfer::buffer_init(
            device,
            "supersampling params",
            bytemuck::bytes_of(&Params::new(m, size)),
            wgpu::BufferUsages::UNIFORM,
        )?;
        Ok(Self {
            config: *config,
            size,
            frame,
            targets,
            masked_depth,
            direct,
            shading: bound,
            evaluation,
            params,
            kernels,
            groups: None,
        })
    }

    /// The configuration.
    pub(crate) fn config(&self) -> &SsaaConfig {
        &self.config
    }

    /// The compiled kernels, for the stage that replaces this one.
    pub(crate) fn into_kernels(self) -> SupersamplingKernels {
        self.kernels
    }

    /// Full supersampling: every pixel takes `m²` samples (`min_samples` = `m²`).
    fn full(&self) -> bool {
        self.config.min_samples >= self.config.samples()
    }

    /// The light accumulation bound to the samples.
    pub(crate) fn shading_mut(&mut self) -> &mut BoundShading {
        &mut self.shading
    }

    /// The light accumulation bound to the samples.
    pub(crate) fn shading(&self) -> &BoundShading {
        &self.shading
    }

    /// Binds the light accumulation's shadow lookup.
    pub(crate) fn bind_shadows(
        &mut self,
        device: &wgpu::Device,
        shading: &LightShading,
        inputs: ShadowInputs<'_>,
    ) -> Result<(), RenderError> {
        Ok(shading.bind_shadows(device, &mut self.shading, inputs)?)
    }

    /// Binds the resolve to the composition's `ambient`, the pixels' `indirect` light
    /// (diffuse, specular, near field), their screen-space `accessibility` and the frame's
    /// `radiance`.
    pub(crate) fn bind(
        &mut self,
        device: &wgpu::Device,
        ambient: &wgpu::Buffer,
        indirect: [&wgpu::Texture; 3],
        accessibility: &wgpu::Buffer,
        radiance: &wgpu::Texture,
    ) {
        let view = |t: &wgpu::Texture| t.create_view(&Default::default());
        let t = &self.targets;
        let views = [
            view(&t.linear_depth),
            view(&self.masked_depth),
            view(&t.emission),
            view(&t.albedo),
            view(&t.material),
            view(&self.direct[0]),
            view(&self.direct[1]),
            view(indirect[0]),
            view(indirect[1]),
            view(indirect[2]),
        ];
        let mut resources = vec![self.params.as_entire_binding(), ambient.as_entire_binding()];
        resources.extend(views.iter().map(wgpu::BindingResource::TextureView));
        resources.extend([
            self.evaluation.counts().as_entire_binding(),
            self.evaluation.first().as_entire_binding(),
        ]);
        let radiance = view(radiance);
        resources.push(wgpu::BindingResource::TextureView(&radiance));
        resources.push(accessibility.as_entire_binding());
        let group = self.kernels.layout.bind(device, &resources);
        let store = self.kernels.store_layout.bind(
            device,
            &[
                self.params.as_entire_binding(),
                self.evaluation.first().as_entire_binding(),
                wgpu::BindingResource::TextureView(&radiance),
            ],
        );
        self.groups = Some([group, store]);
    }

    /// Where the frame's pixels sample: the first sample of their windows, in pixels from the
    /// centre ([`gbuffer::Frame::with_jitter`]).
    pub(crate) fn jitter(&self) -> glam::Vec2 {
        let m = self.config.m;
        let [x, y] = adaptive_ssaa::dither_order(m)[0];
        (glam::Vec2::new(x as f32, y as f32) + 0.5) / m as f32 - 0.5
    }

    /// Writes `camera` at the sample resolution (textures filtered over the pixel).
    pub(crate) fn set_camera(&mut self, queue: &wgpu::Queue, camera: &Camera) {
        let m = self.config.m;
        let (w, h) = (self.size.0 * m, self.size.1 * m);
        let frame = Frame::new(camera, w, h).with_texture_footprint(m as f32);
        self.frame.write(queue, &frame);
        self.shading.set_camera(queue, camera);
        self.evaluation.set_far(queue, camera.far);
    }

    /// The supersampled G-buffer's frame uniform and targets (what the visibility path binds).
    pub(crate) fn gbuffer(&self) -> (&wgpu::Buffer, &GBufferTargets) {
        (self.frame.buffer(), &self.targets)
    }

    /// Records the supersampled G-buffer (z-prepass, G-buffer).
    pub(crate) fn encode_gbuffer(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        gbuffer_pass: &GBufferPass,
        scene: &GpuScene,
        timer: &PassTimer,
    ) {
        let timestamps = (
            timer.render_pass("ss z-prepass"),
            timer.render_pass("ss gbuffer"),
        );
        gbuffer_pass.encode_with_prepass_at(encoder, &self.frame, scene, &self.targets, timestamps);
    }

    fn dispatch(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        pipeline: &wgpu::ComputePipeline,
        (width, height): (u32, u32),
        (name, timer): (&str, &PassTimer),
    ) {
        let Some(groups) = &self.groups else {
            return;
        };
        let store = std::ptr::eq(pipeline, &self.kernels.store_first);
        let group = &groups[usize::from(store)];
        Passes::one(
            name,
            pipeline,
            vec![group.clone()],
            Workgroups::covering(width, height, 8),
        )
        .encode(encoder, Some(timer));
    }

    /// Records the supersampling after the frame's composition (which wrote `S` into the
    /// radiance): `S` kept, the evaluation (adaptive), the remaining samples' direct light
    /// through `shading`, their averages.
    pub(crate) fn encode(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        shading: &LightShading,
        timer: &PassTimer,
    ) {
        let p = &self.kernels;
        self.dispatch(
            encoder,
            &p.store_first,
            self.size,
            ("ss first sample", timer),
        );
        let full = self.full();
        if !full {
            self.evaluation.encode_evaluate(encoder, Some(timer));
        }
        let (mask, resolve, which) = if full {
            (&p.mask_full, &p.resolve_full, "full")
        } else {
            (&p.mask_rest, &p.resolve_adaptive, "adaptive")
        };
        let samples = self.targets_size();
        self.dispatch(
            encoder,
            mask,
            samples,
            (&format!("ss mask ({which})"), timer),
        );
        let name = format!("{}, samples", shading.pass_name());
        shading.encode_as(&self.shading, encoder, Some(timer), &name);
        self.dispatch(
            encoder,
            resolve,
            self.size,
            (&format!("ss resolve ({which})"), timer),
        );
    }

    fn targets_size(&self) -> (u32, u32) {
        (self.targets.width, self.targets.height)
    }

    /// Reads back the samples each pixel took in the last frame (`m²` everywhere when full).
    pub(crate) fn read_counts(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
    ) -> Result<gbuffer::Image<u32>, RenderError> {
        if self.full() {
            let (w, h) = self.size;
            let n = self.config.samples();
            return Ok(gbuffer::Image::filled(w, h, n));
        }
        let n = self.config.samples();
        let counts = self.evaluation.read_counts(device, queue)?;
        Ok(counts.map(|c| c.clamp(1, n)))
    }
}
