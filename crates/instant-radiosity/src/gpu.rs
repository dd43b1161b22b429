//! The indirect stage on the GPU in three phases: [`IndirectStage::new`] builds the pipelines
//! of a configuration and frame size, [`IndirectStage::bind`] binds them to the caller's
//! G-buffer, VPLs and output textures, [`IndirectStage::encode`] records BS → SNSM → BG → DB →
//! B into the caller's encoder, each pass timed under its Table 3 name, with no read-back in
//! between.
//!
//! ```no_run
//! use instant_radiosity::{IndirectConfig, gpu::run, vpl};
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
//!     bounces: 1,
//! })?;
//! let stages = run(&gpu, &gb, &frame, &set, &config)?;
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use ::gpu::kernel::{Binding, Kernel, Passes, Workgroups, check_texture};
use ::gpu::shader::Specialisation;
use ::gpu::{Gpu, PassTimer, transfer, wgpu};
use gbuffer::{
    Frame, GBuffer, Image,
    gpu::{GBUFFER_BINDINGS, GBufferTextures, UploadedGBuffer},
};
use half::f16;
use interleave::{
    SplitLayout,
    gpu::{
        DISCONTINUITY_FORMAT, DiscontinuityBlurPass, IRRADIANCE_FORMAT, Splitter, download_image,
    },
};

use crate::IndirectError;
use crate::{
    IndirectConfig, IndirectStages, Interleaving,
    shadows::{DisabledBindings, VplShadowMaps},
    vpl::VplSet,
};

/// Uniform block of `vpl_shading.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct ShadingParams {
    per_subset: u32,
    scale: f32,
    clamp_squared: f32,
    ray_offset: f32,
}

const USAGE: wgpu::TextureUsages = ::gpu::transfer::STORAGE_ANY;

/// `vpl_shading.wgsl`: frame, params, VPLs; the G-buffer; diffuse and specular outputs;
/// shadow atlas and its parameters; the rays' BVH nodes and triangles.
fn vpl_shading_bindings() -> Vec<Binding> {
    let mut bindings = vec![Binding::Uniform, Binding::Uniform, Binding::StorageRead];
    bindings.extend(GBUFFER_BINDINGS);
    bindings.extend([Binding::StorageTexture(IRRADIANCE_FORMAT); 2]);
    bindings.extend([Binding::StorageRead, Binding::Uniform]);
    bindings.extend([Binding::StorageRead; 2]);
    bindings
}

fn irradiance(device: &wgpu::Device, label: &str, (w, h): (u32, u32)) -> wgpu::Texture {
    transfer::texture_2d(device, label, w, h, IRRADIANCE_FORMAT, USAGE)
}

fn view(t: &wgpu::Texture) -> wgpu::TextureView {
    t.create_view(&Default::default())
}

/// The indirect-light stage's pipelines for one configuration and frame size (phase `new`).
pub struct IndirectStage {
    config: IndirectConfig,
    layout: SplitLayout,
    size: (u32, u32),
    shading: Kernel,
    /// Split/gather passes of the linear depth, normal, albedo and irradiance formats.
    splitters: Option<[Splitter; 4]>,
    /// The discontinuity buffer and blur, in one dispatch.
    discontinuity_blur: Option<DiscontinuityBlurPass>,
}

/// The stage bound to one G-buffer, VPL set and pair of output textures (phase `bind`): the
/// recorded passes, the VPL buffer and the intermediate textures.
pub struct BoundIndirect {
    passes: Passes,
    vpls: wgpu::Buffer,
    params: wgpu::Buffer,
    config: IndirectConfig,
    vpl_count: usize,
    ray_offset: f32,
    split_normal: Option<wgpu::Texture>,
    shaded_diffuse: wgpu::Texture,
    gathered: [wgpu::Texture; 2],
    discontinuities: Option<wgpu::Texture>,
    outputs: [wgpu::Texture; 2],
}

/// `vpl_shading.wgsl`'s specialisation: the BVH buffers of `rays.wgsl` at bindings 11 and 12
/// of its one group.
pub fn shading_rays() -> Specialisation {
    Specialisation::default()
        .set("RAY_GROUP", "0u")
        .set("RAY_NODES", "11u")
        .set("RAY_TRIANGLES", "12u")
}

impl IndirectStage {
    /// Builds the pipelines of `config` for frames of `size` (width, height). The VPL count
    /// is not part of the pipelines: any set of `config.subsets()` subsets binds.
    pub fn new(
        device: &wgpu::Device,
        config: &IndirectConfig,
        size: (u32, u32),
    ) -> Result<Self, IndirectError> {
        config.validate_alone()?;
        let layout = SplitLayout::new(size.0, size.1, config.shading_pattern())?;
        let module = crate::SHADERS.module_with(device, "vpl_shading.wgsl", &shading_rays())?;
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
        let shading = Kernel::new(device, &module, entry, &vpl_shading_bindings(), &constants);
        let splitters = match config.interleaving {
            Interleaving::Split(variant) => {
                let splitter = |format| Splitter::new(device, &layout, variant, format);
                Some([
                    splitter(gbuffer::LINEAR_DEPTH_FORMAT)?,
                    splitter(gbuffer::NORMAL_FORMAT)?,
                    splitter(gbuffer::ALBEDO_FORMAT)?,
                    splitter(IRRADIANCE_FORMAT)?,
                ])
            }
            Interleaving::Fused | Interleaving::Reference => None,
        };
        let discontinuity_blur = config
            .applied_blur()
            .map(|blur| DiscontinuityBlurPass::new(device, &config.thresholds, &blur))
            .transpose()?;
        Ok(Self {
            config: *config,
            layout,
            size,
            shading,
            splitters,
            discontinuity_blur,
        })
    }

    /// Two output textures the stage can write (diffuse, specular; [`IRRADIANCE_FORMAT`],
    /// sampled and copied from): the convenience beside [`IndirectStage::bind`]'s caller-owned
    /// outputs.
    pub fn output_textures(&self, device: &wgpu::Device) -> [wgpu::Texture; 2] {
        ["indirect diffuse", "indirect specular"].map(|label| irradiance(device, label, self.size))
    }

    /// Binds the stage to the camera uniform `frame` (a [`gbuffer::Frame`]), `gbuffer`, the
    /// VPLs of `set` (visible through `shadows`, built for the same VPLs, if given) and the
    /// caller's `outputs` (diffuse, specular: the stage's size, [`IRRADIANCE_FORMAT`], storage
    /// binding), allocating the intermediate textures. A G-buffer or output of another size
    /// or format, or a set of another subset count, is an `Err`.
    pub fn bind(
        &self,
        device: &wgpu::Device,
        frame: &wgpu::Buffer,
        gbuffer: GBufferTextures<'_>,
        set: &VplSet,
        shadows: Option<&VplShadowMaps>,
        outputs: [&wgpu::Texture; 2],
    ) -> Result<BoundIndirect, IndirectError> {
        let config = &self.config;
        config.validate(set)?;
        let size = self.size;
        check_texture(
            "G-buffer linear depth",
            gbuffer.linear_depth,
            size,
            gbuffer::LINEAR_DEPTH_FORMAT,
            wgpu::TextureUsages::TEXTURE_BINDING,
        )?;
        for (what, texture) in ["indirect diffuse output", "indirect specular output"]
            .into_iter()
            .zip(outputs)
        {
            check_texture(
                what,
                texture,
                size,
                IRRADIANCE_FORMAT,
                wgpu::TextureUsages::STORAGE_BINDING,
            )?;
        }
        let disabled;
        let visibility = match shadows {
            Some(s) => s.bindings(),
            None => {
                disabled = DisabledBindings::new(device)?;
                disabled.bindings()
            }
        };
        let layout = &self.layout;
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
            bytemuck::bytes_of(&shading_params(config, set, visibility.ray_offset)),
            wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        )?;
        let shading = |name: &str, g: [&wgpu::Texture; 4], out: [&wgpu::Texture; 2]| {
            let views = g.map(view);
            let outs = out.map(view);
            let tv = wgpu::BindingResource::TextureView;
            let group = self.shading.bind(
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
                    visibility.atlas.as_entire_binding(),
                    visibility.params.as_entire_binding(),
                    visibility.ray_nodes.as_entire_binding(),
                    visibility.ray_triangles.as_entire_binding(),
                ],
            );
            let workgroups = Workgroups::covering(split_size.0, split_size.1, 8);
            Passes::one(name, &self.shading.pipeline, vec![group], workgroups)
        };
        // Without a blur the gathered light is the output; with one, the blur writes it.
        let gathered = match self.discontinuity_blur {
            Some(_) => [
                irradiance(device, "indirect diffuse", size),
                irradiance(device, "indirect specular", size),
            ],
            None => outputs.map(Clone::clone),
        };
        let g = [
            gbuffer.linear_depth,
            gbuffer.normal,
            gbuffer.albedo,
            gbuffer.material,
        ];
        let (mut passes, split_normal, shaded_diffuse) = match &self.splitters {
            Some([r32f, r32u, rgba8, half]) => {
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
            None => {
                let name = if config.interleaving == Interleaving::Fused {
                    "SNSM"
                } else {
                    "shading (reference)"
                };
                let passes = shading(name, g, gathered.each_ref());
                (passes, None, gathered[0].clone())
            }
        };
        let discontinuities = match &self.discontinuity_blur {
            Some(pass) => {
                let db = transfer::texture_2d(
                    device,
                    "discontinuity buffer",
                    size.0,
                    size.1,
                    DISCONTINUITY_FORMAT,
                    USAGE,
                );
                // Diffuse and specular along one walk per pixel.
                let g = (gbuffer.linear_depth, gbuffer.normal);
                let fused = pass.bind(device, g, gathered.each_ref(), &db, outputs)?;
                passes = passes.then(fused.named("DB + B"));
                Some(db)
            }
            None => None,
        };
        Ok(BoundIndirect {
            passes,
            vpls,
            params,
            config: *config,
            vpl_count: set.vpls.len(),
            ray_offset: visibility.ray_offset,
            split_normal,
            shaded_diffuse,
            gathered,
            discontinuities,
            outputs: outputs.map(Clone::clone),
        })
    }

    /// Records the bound stage; with a timer, each pass is timed under its stage name (BS,
    /// SNSM, BG, DB, B, or "shading (reference)").
    pub fn encode(
        &self,
        bound: &BoundIndirect,
        encoder: &mut wgpu::CommandEncoder,
        timer: Option<&PassTimer>,
    ) {
        bound.passes.encode(encoder, timer);
    }
}

fn shading_params(config: &IndirectConfig, set: &VplSet, ray_offset: f32) -> ShadingParams {
    ShadingParams {
        per_subset: config.per_invocation(set),
        scale: config.scale(set),
        clamp_squared: config.clamp_distance * config.clamp_distance,
        ray_offset,
    }
}

impl BoundIndirect {
    /// Replaces the VPLs by another set of the same size and subset count (e.g. after the
    /// lights moved).
    pub fn set_vpls(&self, queue: &wgpu::Queue, set: &VplSet) -> Result<(), IndirectError> {
        self.config.validate(set)?;
        if set.vpls.len() != self.vpl_count {
            return Err(IndirectError::Vpl(crate::vpl::VplError::Count {
                count: set.vpls.len(),
                subsets: set.subsets,
            }));
        }
        queue.write_buffer(&self.vpls, 0, bytemuck::cast_slice(&set.gpu()));
        queue.write_buffer(
            &self.params,
            0,
            bytemuck::bytes_of(&shading_params(&self.config, set, self.ray_offset)),
        );
        Ok(())
    }

    /// Reads every stage's texture back (after the encoded work was submitted).
    pub fn read(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
    ) -> Result<IndirectStages, IndirectError> {
        let irr = |t: &wgpu::Texture| -> Result<Image<[f32; 4]>, IndirectError> {
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
            blurred: match self.discontinuities {
                Some(_) => Some([irr(&self.outputs[0])?, irr(&self.outputs[1])?]),
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
) -> Result<IndirectStages, IndirectError> {
    let uploaded = UploadedGBuffer::new(&gpu.device, &gpu.queue, gb, frame)?;
    let stage = IndirectStage::new(&gpu.device, config, (gb.width(), gb.height()))?;
    let outputs = stage.output_textures(&gpu.device);
    let bound = stage.bind(
        &gpu.device,
        &uploaded.frame,
        uploaded.textures(),
        set,
        None,
        outputs.each_ref(),
    )?;
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    stage.encode(&bound, &mut encoder, None);
    gpu.queue.submit([encoder.finish()]);
    bound.read(&gpu.device, &gpu.queue)
}
