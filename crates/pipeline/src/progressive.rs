//! Segovia 2006 §6.3's physically based mode: the view and the G-buffer stay, and every frame
//! brings a new set of VPLs (another seed of the photon paths, multi-bounce by Russian
//! roulette), new samples of the emissive meshes' direct light (their shadowed hemispherical
//! samples, [`instant_radiosity::vpl::area_lights_frame`]) and their shadow maps (exact,
//! rasterised per VPL: [`VplShadows::Rasterised`]), and the frames' radiance is averaged on
//! the GPU (`accumulate.wgsl`; CPU twin [`accumulate`]) until the mean is as close to the
//! path tracer as wanted — the paper's Table 5 times this to < 1 % RMS error.
//!
//! ```no_run
//! use pipeline::progressive::{Progressive, ProgressiveConfig};
//! # let gpu = gpu::Gpu::from_env()?;
//! let scene = scene::cornell_box();
//! let camera = scene.camera_or_framed();
//! let config = ProgressiveConfig::new(&scene);
//! let mut progressive = Progressive::new(&gpu.device, &gpu.queue, &scene, camera, (256, 256), &config)?;
//! for _ in 0..16 {
//!     progressive.frame(&gpu.device, &gpu.queue)?;
//! }
//! let mean = progressive.read(&gpu.device, &gpu.queue)?;
//! assert_eq!(mean.width(), 256);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use ::gpu::kernel::{Binding, Kernel, Passes, Workgroups};
use ::gpu::transfer;
use gbuffer::Image;
use glam::Vec3;
use instant_radiosity::{
    IndirectConfig,
    shadows::{ShadowConfig, VplShadows},
    vpl::{self, VplConfig},
};
use scene::{Bvh, Camera, Light, Scene};
use tiled_shading::shadows::ShadowMapConfig;

use crate::gpu::GpuRenderer;
use crate::{PassTiming, RenderError};

/// What every frame of a progressive render is made of.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProgressiveConfig {
    /// VPLs per frame (rounded to whole subsets of the pattern).
    pub vpls: usize,
    /// Bounces of the photon paths (Russian roulette after the first).
    pub bounces: u32,
    /// Shadowed hemispherical samples per emissive mesh per frame.
    pub area_samples: u32,
    /// The indirect stage: pattern and interleaving (the reference: no interleaving), blur,
    /// VPL clamp.
    pub indirect: IndirectConfig,
    /// VPL visibility (`None`: the VPLs light through walls).
    pub visibility: Option<VplShadows>,
    /// The VPL shadow maps' settings.
    pub vpl_maps: ShadowConfig,
    /// The direct lights' shadow maps.
    pub direct_maps: ShadowMapConfig,
    /// Exact direct shadows by a ray per pixel and light instead of the maps
    /// ([`GpuRenderer::set_ray_shadows`]).
    pub direct_rays: bool,
    /// The VPLs' near field: the light the clamp takes away, by a short ray per pixel and
    /// frame ([`GpuRenderer::set_near_field`], Kollig & Keller 2004).
    pub near_field: bool,
}

impl ProgressiveConfig {
    /// The paper's mode for a scene: 1024 VPLs a frame, 8 bounces, 16 area samples, 2×2
    /// interleaving (fused) with the 5×5 blur, exact rasterised VPL maps of 64×64, direct
    /// shadow maps of 1024², [`IndirectConfig::new`]'s VPL clamp (2 % of the diagonal) and the
    /// near field, which gives back what the clamp takes: the clamp then costs no bias and
    /// keeps the VPLs' noise down (on the Cornell box at 64², rays for both: < 1 % RMS after
    /// 112 frames; without the near field, a 0.5 % clamp: 1.20 % after 161, the 2 % clamp
    /// 2.3 %; docs/ground-truth.md).
    pub fn new(scene: &Scene) -> Self {
        let single = IndirectConfig::new(scene.bounds());
        let indirect = IndirectConfig {
            pattern: interleave::Pattern { n: 2, m: 2 },
            ..single
        };
        Self {
            vpls: 1024,
            bounces: 8,
            area_samples: 16,
            indirect,
            visibility: Some(VplShadows::Rasterised),
            vpl_maps: ShadowConfig {
                tile: 64,
                ..ShadowConfig::for_mode(VplShadows::Rasterised)
            },
            direct_maps: ShadowMapConfig::default(),
            direct_rays: false,
            near_field: true,
        }
    }
}

/// Uniform block `AccumulateParams` of `accumulate.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct AccumulateParams {
    count: u32,
    _pad: [u32; 3],
}

/// A progressive render on the GPU: the renderer with its indirect stage and shadow maps,
/// the scene's BVH for the photon paths, and the running mean of the frames.
pub struct Progressive<'s> {
    renderer: GpuRenderer,
    scene: &'s Scene,
    bvh: Bvh,
    config: ProgressiveConfig,
    emissive: bool,
    /// The lights photons leave besides the emissive triangles ([`vpl::photon_lights`]).
    photon_lights: Vec<Light>,
    frames: u32,
    accumulate: Kernel,
    group: wgpu::BindGroup,
    params: wgpu::Buffer,
    mean: wgpu::Buffer,
    size: (u32, u32),
}

impl<'s> Progressive<'s> {
    /// Sets the renderer up for `scene` from `camera` at `width × height` with frame 0's
    /// lights and VPLs (nothing rendered yet).
    pub fn new(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        scene: &'s Scene,
        camera: Camera,
        (width, height): (u32, u32),
        config: &ProgressiveConfig,
    ) -> Result<Self, RenderError> {
        let bvh = Bvh::build(scene);
        let (lights, emissive, _) = vpl::primary_lights_frame(scene, config.area_samples, 0);
        let mut renderer = GpuRenderer::new(device, queue, scene, &lights, width, height)?;
        if config.direct_rays {
            renderer.set_ray_shadows(device, queue, Some(scene))?;
        } else {
            renderer.set_shadows(device, queue, Some(&config.direct_maps))?;
        }
        renderer.set_camera(queue, &camera)?;
        renderer.set_ambient(queue, Vec3::ZERO);
        let photon_lights = vpl::photon_lights(&lights, emissive).to_vec();
        let set = vpl_set(scene, &bvh, config, (&photon_lights, emissive), 0)?;
        match config.visibility {
            Some(mode) => renderer.set_vpl_shadows(
                device,
                scene,
                mode,
                &config.vpl_maps,
                &config.indirect,
                &set,
            )?,
            None => renderer.set_indirect(device, &config.indirect, &set)?,
        }
        if config.near_field {
            renderer.set_near_field(device, Some(scene))?;
        }
        let module = crate::SHADERS.module(device, "accumulate.wgsl")?;
        use Binding::{Storage, TextureUnfilterable, Uniform};
        let accumulate = Kernel::new(
            device,
            &module,
            "accumulate",
            &[Uniform, TextureUnfilterable, Storage],
            &[],
        );
        let params = transfer::buffer(
            device,
            "accumulate params",
            size_of::<AccumulateParams>() as u64,
            wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        )?;
        let mean = transfer::buffer(
            device,
            "progressive mean",
            u64::from(width) * u64::from(height) * 16,
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        )?;
        let radiance = renderer.output().create_view(&Default::default());
        let group = accumulate.bind(
            device,
            &[
                params.as_entire_binding(),
                wgpu::BindingResource::TextureView(&radiance),
                mean.as_entire_binding(),
            ],
        );
        Ok(Self {
            renderer,
            scene,
            bvh,
            config: *config,
            emissive,
            photon_lights,
            frames: 0,
            accumulate,
            group,
            params,
            mean,
            size: (width, height),
        })
    }

    /// Renders the next frame (after the first: new light samples and VPLs, frame number as
    /// their seed) and adds it to the mean; returns the frame's GPU pass times (the
    /// accumulation, one read and write per pixel, is not among them).
    pub fn frame(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
    ) -> Result<Vec<PassTiming>, RenderError> {
        let f = self.frames;
        if f > 0 {
            if self.emissive {
                let (lights, _, _) =
                    vpl::primary_lights_frame(self.scene, self.config.area_samples, f);
                self.renderer.set_lights(device, queue, &lights)?;
            }
            let photons = (&self.photon_lights[..], self.emissive);
            let set = vpl_set(self.scene, &self.bvh, &self.config, photons, f)?;
            self.renderer.set_vpls(queue, &set)?;
        }
        let params = AccumulateParams {
            count: f + 1,
            _pad: [0; 3],
        };
        queue.write_buffer(&self.params, 0, bytemuck::bytes_of(&params));
        let mut encoder = device.create_command_encoder(&Default::default());
        self.renderer.encode(&mut encoder);
        let (w, h) = self.size;
        Passes::one(
            "accumulate",
            &self.accumulate.pipeline,
            vec![self.group.clone()],
            Workgroups::covering(w, h, 8),
        )
        .encode(&mut encoder, None);
        queue.submit([encoder.finish()]);
        self.frames += 1;
        self.renderer.timings(device, queue)
    }

    /// Frames in the mean.
    pub fn frames(&self) -> u32 {
        self.frames
    }

    /// The renderer (its last frame's output is [`GpuRenderer::output`]).
    pub fn renderer(&self) -> &GpuRenderer {
        &self.renderer
    }

    /// Reads the mean of the frames so far back (linear RGBA).
    pub fn read(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
    ) -> Result<Image<[f32; 4]>, RenderError> {
        let (w, h) = self.size;
        let pixels: Vec<[f32; 4]> = transfer::read_pod(device, queue, &self.mean)?;
        Ok(Image::from_vec(w, h, pixels).map_err(|e| ::gpu::GpuError::Readback(e.to_string()))?)
    }
}

/// Frame `frame`'s VPLs: seed `frame`, photons from `photon_lights` (and the emissive
/// triangles where `emissive`).
fn vpl_set(
    scene: &Scene,
    bvh: &Bvh,
    config: &ProgressiveConfig,
    (photon_lights, emissive): (&[Light], bool),
    frame: u32,
) -> Result<vpl::VplSet, RenderError> {
    let subsets = config.indirect.subsets();
    let vpl_config = VplConfig {
        count: vpl::per_subset(config.vpls, subsets) as usize * subsets as usize,
        subsets,
        seed: u64::from(frame),
        emissive,
        bounces: config.bounces,
    };
    Ok(vpl::generate(scene, bvh, photon_lights, &vpl_config)
        .map_err(instant_radiosity::IndirectError::from)?)
}

/// The CPU twin of `accumulate.wgsl`: adds `frame` (the `count`-th) to the running `mean`.
pub fn accumulate(mean: &mut [[f32; 4]], frame: &[[f32; 4]], count: u32) {
    for (m, x) in mean.iter_mut().zip(frame) {
        for c in 0..4 {
            m[c] = if count <= 1 {
                x[c]
            } else {
                m[c] + (x[c] - m[c]) / count as f32
            };
        }
    }
}
