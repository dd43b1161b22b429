//! The indirect stage on the GPU: pipelines and textures are built once for a G-buffer, a
//! configuration and a VPL count; [`IndirectStage::encode`] records BS → SNSM → BG → DB → B,
//! each pass timed under its Table 3 name, with no read-back in between.
//!
//! ```no_run
//! use pipeline::indirect::{IndirectConfig, gpu::run, vpl};
//! # let gpu = gpu::Gpu::from_env()?;
//! let scene = scene::cornell_box();
//! let camera = scene.camera_or_framed();
//! let gb = gbuffer::cpu::rasterize(&scene, &camera, 320, 240)?.gbuffer;
//! let frame = gbuffer::Frame::new(&camera, 320, 240);
//! let config = IndirectConfig::new(scene.bounds());
//! let set = vpl::generate(&scene, &scene::Bvh::build(&scene), &scene.lights, &vpl::VplConfig {
//!     count: 1024,
//!     subsets: config.subsets(),
//!     seed: 1,
//!     emissive: false,
//! })?;
//! let stages = run(&gpu, &gb, &frame, &set, &config)?;
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use ::gpu::kernel::{Binding, Kernel, Passes, Workgroups};
use ::gpu::{Gpu, PassTimer, transfer, wgpu};
use gbuffer::{
    Frame, GBuffer, Image,
    gpu::{GBUFFER_BINDINGS, GBufferTextures, UploadedGBuffer},
};
use half::f16;
use interleave::{
    SplitLayout,
    gpu::{
        BlurPass, DISCONTINUITY_FORMAT, DiscontinuityPass, IRRADIANCE_FORMAT, Splitter,
        download_image,
    },
};

use super::{
    IndirectConfig, IndirectStages, Interleaving,
    shadows::{VplShadowMaps, disabled_bindings},
    vpl::VplSet,
};
use crate::RenderError;

/// Uniform block of `vpl_shading.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct ShadingParams {
    per_subset: u32,
    scale: f32,
    clamp_squared: f32,
    _pad: u32,
}

const USAGE: wgpu::TextureUsages = wgpu::TextureUsages::TEXTURE_BINDING
    .union(wgpu::TextureUsages::STORAGE_BINDING)
    .union(wgpu::TextureUsages::COPY_SRC)
    .union(wgpu::TextureUsages::COPY_DST);

/// `vpl_shading.wgsl`: frame, params, VPLs; the G-buffer; diffuse and specular outputs;
/// shadow atlas and its parameters.
fn vpl_shading_bindings() -> Vec<Binding> {
    let mut bindings = vec![Binding::Uniform, Binding::Uniform, Binding::StorageRead];
    bindings.extend(GBUFFER_BINDINGS);
    bindings.extend([Binding::StorageTexture(IRRADIANCE_FORMAT); 2]);
    bindings.extend([Binding::StorageRead, Binding::Uniform]);
    bindings
}

fn irradiance(device: &wgpu::Device, label: &str, (w, h): (u32, u32)) -> wgpu::Texture {
    transfer::texture_2d(device, label, w, h, IRRADIANCE_FORMAT, USAGE)
}

fn view(t: &wgpu::Texture) -> wgpu::TextureView {
    t.create_view(&Default::default())
}

/// The indirect-light stage for one G-buffer.
pub struct IndirectStage {
    passes: Passes,
    vpls: wgpu::Buffer,
    params: wgpu::Buffer,
    config: IndirectConfig,
    vpl_count: usize,
    split_normal: Option<wgpu::Texture>,
    shaded_diffuse: wgpu::Texture,
    gathered: [wgpu::Texture; 2],
    discontinuities: Option<wgpu::Texture>,
    blurred: Option<[wgpu::Texture; 2]>,
}

impl IndirectStage {
    /// Builds the passes reading `gbuffer` and the camera uniform `frame` (a
    /// [`gbuffer::Frame`]), shading the VPLs of `set` as `config` says, with visibility from
    /// `shadows` (built for the same VPLs) if given.
    pub fn new(
        device: &wgpu::Device,
        frame: &wgpu::Buffer,
        gbuffer: GBufferTextures<'_>,
        config: &IndirectConfig,
        set: &VplSet,
        shadows: Option<&VplShadowMaps>,
    ) -> Result<Self, RenderError> {
        config.validate(set)?;
        let disabled;
        let (shadow_atlas, shadow_params) = match shadows {
            Some(s) => s.bindings(),
            None => {
                disabled = disabled_bindings(device)?;
                (&disabled.0, &disabled.1)
            }
        };
        let size = (gbuffer.linear_depth.width(), gbuffer.linear_depth.height());
        let layout = SplitLayout::new(size.0, size.1, config.shading_pattern())?;
        let split_size = (layout.split_width(), layout.split_height());
        let vpls = transfer::buffer_init(
            device,
            "vpls",
            bytemuck::cast_slice(&set.gpu()),
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
        )?;
        let params = transfer::buffer_init(
            device,
            "vpl shading params",
            bytemuck::bytes_of(&ShadingParams {
                per_subset: config.per_invocation(set),
                scale: config.scale(set),
                clamp_squared: config.clamp_distance * config.clamp_distance,
                _pad: 0,
            }),
            wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        )?;
        let module = crate::SHADERS.module(device, "vpl_shading.wgsl")?;
        let constants = [
            ("width", f64::from(size.0)),
            ("height", f64::from(size.1)),
            ("n", f64::from(layout.pattern.n)),
            ("m", f64::from(layout.pattern.m)),
            ("sub_width", f64::from(layout.sub_width)),
            ("sub_height", f64::from(layout.sub_height)),
        ];
        let entry = match config.interleaving {
            Interleaving::Fused => "shade_fused",
            _ => "shade_split",
        };
        let kernel = Kernel::new(device, &module, entry, &vpl_shading_bindings(), &constants);
        let shading = |name: &str, g: [&wgpu::Texture; 4], out: [&wgpu::Texture; 2]| {
            let views = g.map(view);
            let outs = out.map(view);
            let tv = wgpu::BindingResource::TextureView;
            let group = kernel.bind(
                device,
                &[
                    frame.as_entire_binding(),
                    params.as_entire_binding(),
                    vpls.as_entire_binding(),
                    tv(&views[0]),
                    tv(&views[1]),
                    tv(&views[2]),
                    tv(&views[3]),
                    tv(&outs[0]),
                    tv(&outs[1]),
                    shadow_atlas.as_entire_binding(),
                    shadow_params.as_entire_binding(),
                ],
            );
            let workgroups = Workgroups::covering(split_size.0, split_size.1, 8);
            Passes::one(name, &kernel.pipeline, vec![group], workgroups)
        };
        let gathered = [
            irradiance(device, "indirect diffuse", size),
            irradiance(device, "indirect specular", size),
        ];
        let g = [
            gbuffer.linear_depth,
            gbuffer.normal,
            gbuffer.albedo,
            gbuffer.material,
        ];
        let (mut passes, split_normal, shaded_diffuse) = match config.interleaving {
            Interleaving::Split(variant) => {
                let splitter = |format| Splitter::new(device, &layout, variant, format);
                let r32f = splitter(gbuffer::LINEAR_DEPTH_FORMAT)?;
                let r32u = splitter(gbuffer::NORMAL_FORMAT)?;
                let rgba8 = splitter(gbuffer::ALBEDO_FORMAT)?;
                let half = splitter(IRRADIANCE_FORMAT)?;
                let split = [
                    r32f.split_texture(device, "split linear depth"),
                    r32u.split_texture(device, "split normal"),
                    rgba8.split_texture(device, "split albedo"),
                    r32u.split_texture(device, "split material"),
                ];
                let shaded = [
                    half.split_texture(device, "split indirect diffuse"),
                    half.split_texture(device, "split indirect specular"),
                ];
                let bs = r32f
                    .split(device, g[0], &split[0])?
                    .then(r32u.split(device, g[1], &split[1])?)
                    .then(rgba8.split(device, g[2], &split[2])?)
                    .then(r32u.split(device, g[3], &split[3])?)
                    .named("BS");
                let snsm = shading("SNSM", split.each_ref(), shaded.each_ref());
                let bg = half
                    .gather(device, &shaded[0], &gathered[0])?
                    .then(half.gather(device, &shaded[1], &gathered[1])?)
                    .named("BG");
                let [_, normal, _, _] = split;
                let [diffuse, _] = shaded;
                (bs.then(snsm).then(bg), Some(normal), diffuse)
            }
            Interleaving::Fused | Interleaving::Reference => {
                let name = if config.interleaving == Interleaving::Fused {
                    "SNSM"
                } else {
                    "shading (reference)"
                };
                let passes = shading(name, g, gathered.each_ref());
                (passes, None, gathered[0].clone())
            }
        };
        let (discontinuities, blurred) = match config.applied_blur() {
            Some(blur) => {
                let db = transfer::texture_2d(
                    device,
                    "discontinuity buffer",
                    size.0,
                    size.1,
                    DISCONTINUITY_FORMAT,
                    USAGE,
                );
                let dbp = DiscontinuityPass::new(device, &config.thresholds)?;
                passes = passes.then(
                    dbp.bind(device, gbuffer.linear_depth, gbuffer.normal, &db)?
                        .named("DB"),
                );
                let bp = BlurPass::new(device, &blur)?;
                let scratch = irradiance(device, "blur scratch", size);
                let out = [
                    irradiance(device, "blurred indirect diffuse", size),
                    irradiance(device, "blurred indirect specular", size),
                ];
                passes = passes.then(
                    bp.bind(device, &gathered[0], &db, &scratch, &out[0])?
                        .then(bp.bind(device, &gathered[1], &db, &scratch, &out[1])?)
                        .named("B"),
                );
                (Some(db), Some(out))
            }
            None => (None, None),
        };
        Ok(Self {
            passes,
            vpls,
            params,
            config: *config,
            vpl_count: set.vpls.len(),
            split_normal,
            shaded_diffuse,
            gathered,
            discontinuities,
            blurred,
        })
    }

    /// Records the stage; with a timer, each pass is timed under its stage name (BS, SNSM,
    /// BG, DB, B, or "shading (reference)").
    pub fn encode(&self, encoder: &mut wgpu::CommandEncoder, timer: Option<&PassTimer>) {
        self.passes.encode(encoder, timer);
    }

    /// Replaces the VPLs by another set of the same size and subset count (e.g. after the
    /// lights moved).
    pub fn set_vpls(&self, queue: &wgpu::Queue, set: &VplSet) -> Result<(), RenderError> {
        self.config.validate(set)?;
        if set.vpls.len() != self.vpl_count {
            return Err(RenderError::Vpl(super::vpl::VplError::Count {
                count: set.vpls.len(),
                subsets: set.subsets,
            }));
        }
        queue.write_buffer(&self.vpls, 0, bytemuck::cast_slice(&set.gpu()));
        let params = ShadingParams {
            per_subset: self.config.per_invocation(set),
            scale: self.config.scale(set),
            clamp_squared: self.config.clamp_distance * self.config.clamp_distance,
            _pad: 0,
        };
        queue.write_buffer(&self.params, 0, bytemuck::bytes_of(&params));
        Ok(())
    }

    /// The diffuse and specular indirect light the composition reads (blurred if blurring).
    pub fn output(&self) -> [&wgpu::Texture; 2] {
        match &self.blurred {
            Some([d, s]) => [d, s],
            None => [&self.gathered[0], &self.gathered[1]],
        }
    }

    /// Reads every stage's texture back (after the encoded work was submitted).
    pub fn read(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
    ) -> Result<IndirectStages, RenderError> {
        let irr = |t: &wgpu::Texture| -> Result<Image<[f32; 4]>, RenderError> {
            Ok(download_image::<[f16; 4]>(device, queue, t)?.map(|p| p.map(f16::to_f32)))
        };
        Ok(IndirectStages {
            split_normal: self
                .split_normal
                .as_ref()
                .map(|t| download_image(device, queue, t))
                .transpose()?,
            shaded_diffuse: irr(&self.shaded_diffuse)?,
            diffuse: irr(&self.gathered[0])?,
            specular: irr(&self.gathered[1])?,
            discontinuities: self
                .discontinuities
                .as_ref()
                .map(|t| download_image(device, queue, t))
                .transpose()?,
            blurred: match &self.blurred {
                Some([d, s]) => Some([irr(d)?, irr(s)?]),
                None => None,
            },
            timings: Vec::new(),
        })
    }
}

/// Convenience for tests and examples: uploads a G-buffer and a frame, runs the stage once
/// and reads every stage back.
pub fn run(
    gpu: &Gpu,
    gb: &GBuffer,
    frame: &Frame,
    set: &VplSet,
    config: &IndirectConfig,
) -> Result<IndirectStages, RenderError> {
    let uploaded = UploadedGBuffer::new(&gpu.device, &gpu.queue, gb, frame)?;
    let stage = IndirectStage::new(
        &gpu.device,
        &uploaded.frame,
        uploaded.textures(),
        config,
        set,
        None,
    )?;
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    stage.encode(&mut encoder, None);
    gpu.queue.submit([encoder.finish()]);
    stage.read(&gpu.device, &gpu.queue)
}
