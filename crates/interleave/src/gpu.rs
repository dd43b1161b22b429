//! GPU kernels (WGSL in `shaders/interleave/`). Pipelines are built once per configuration
//! (`Splitter::new`, ...); binding textures returns [`Passes`] — the dispatches with their bind
//! groups — which `encode` records into the caller's command encoder, any number of times.
//!
//! ```no_run
//! use interleave::{Pattern, SplitLayout, SplitVariant, gpu::Splitter};
//! # let gpu = gpu::Gpu::from_env()?;
//! let layout = SplitLayout::new(1920, 1080, Pattern::new(4, 4)?)?;
//! let format = gpu::wgpu::TextureFormat::R32Uint;
//! let splitter = Splitter::new(&gpu.device, &layout, SplitVariant::Tiled, format)?;
//! let normals = splitter.image_texture(&gpu.device, "normals");
//! let split = splitter.split_texture(&gpu.device, "split normals");
//! let passes = splitter.split(&gpu.device, &normals, &split)?;
//! let mut encoder = gpu.device.create_command_encoder(&Default::default());
//! passes.encode(&mut encoder, None);
//! gpu.queue.submit([encoder.finish()]);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use ::gpu::kernel::{self, Binding, Layout, Workgroups};
use ::gpu::shader::Specialisation;
use ::gpu::{Gpu, transfer, wgpu};
use bytemuck::Pod;
use gbuffer::Image;

use crate::cpu::{BlockGeometry, SubsetLight};
use crate::{Blur, BlurVariant, InterleaveError, Pattern, SplitLayout, SplitVariant, Thresholds};

/// Format of irradiance textures (blur input and output, shading output): filterable and
/// writable from compute, 16 bits per channel like the paper's (§5.3).
pub const IRRADIANCE_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;
/// Format of the discontinuity buffer: red = normal edge, green = depth edge; filterable for
/// the fast blur's bilinear lookups.
pub const DISCONTINUITY_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;

const USAGE: wgpu::TextureUsages = wgpu::TextureUsages::TEXTURE_BINDING
    .union(wgpu::TextureUsages::STORAGE_BINDING)
    .union(wgpu::TextureUsages::COPY_SRC)
    .union(wgpu::TextureUsages::COPY_DST);

pub use ::gpu::kernel::Passes;

/// A pass of one dispatch of `pipeline` with `resources` bound in order by `layout`.
fn pass(
    device: &wgpu::Device,
    name: &str,
    (pipeline, layout): &(wgpu::ComputePipeline, Layout),
    resources: &[wgpu::BindingResource<'_>],
    workgroups: (u32, u32),
) -> Passes {
    Passes::one(
        name,
        pipeline,
        vec![layout.bind(device, resources)],
        Workgroups::Direct([workgroups.0, workgroups.1, 1]),
    )
}

/// A compute pipeline of `entry` in `module` with one explicit bind group of `bindings`.
fn kernel(
    device: &wgpu::Device,
    module: &wgpu::ShaderModule,
    entry: &str,
    bindings: &[Binding],
    constants: &[(&str, f64)],
) -> (wgpu::ComputePipeline, Layout) {
    let layout = Layout::compute(device, entry, bindings);
    let pipeline = kernel::pipeline(device, module, entry, &[&layout], constants);
    (pipeline, layout)
}

fn view(t: &wgpu::Texture) -> wgpu::TextureView {
    t.create_view(&Default::default())
}

/// Usage of a texture a kernel reads.
const READ: wgpu::TextureUsages = wgpu::TextureUsages::TEXTURE_BINDING;
/// Usage of a texture a kernel writes.
const WRITE: wgpu::TextureUsages = wgpu::TextureUsages::STORAGE_BINDING;

fn groups(size: (u32, u32), workgroup: u32) -> (u32, u32) {
    (size.0.div_ceil(workgroup), size.1.div_ceil(workgroup))
}

/// WGSL storage format name and texel scalar type of a splittable format.
pub fn texel_format(
    format: wgpu::TextureFormat,
) -> Result<(&'static str, &'static str), InterleaveError> {
    use wgpu::TextureFormat as F;
    Ok(match format {
        F::R32Uint => ("r32uint", "u32"),
        F::Rg32Uint => ("rg32uint", "u32"),
        F::Rgba32Uint => ("rgba32uint", "u32"),
        F::Rgba16Uint => ("rgba16uint", "u32"),
        F::Rgba8Uint => ("rgba8uint", "u32"),
        F::R32Sint => ("r32sint", "i32"),
        F::Rg32Sint => ("rg32sint", "i32"),
        F::Rgba32Sint => ("rgba32sint", "i32"),
        F::Rgba16Sint => ("rgba16sint", "i32"),
        F::Rgba8Sint => ("rgba8sint", "i32"),
        F::R32Float => ("r32float", "f32"),
        F::Rg32Float => ("rg32float", "f32"),
        F::Rgba32Float => ("rgba32float", "f32"),
        F::Rgba16Float => ("rgba16float", "f32"),
        F::Rgba8Unorm => ("rgba8unorm", "f32"),
        other => return Err(InterleaveError::Format(other)),
    })
}

/// The specialisation of `texel.wgsl`'s `Texel`, `Source` and `Destination` declarations
/// for `format`, so one kernel moves any supported format bit for bit.
pub fn texel_specialisation(
    format: wgpu::TextureFormat,
) -> Result<Specialisation, InterleaveError> {
    let (storage, scalar) = texel_format(format)?;
    Ok(Specialisation::default()
        .set("Texel", format!("vec4<{scalar}>"))
        .set("Source", format!("texture_2d<{scalar}>"))
        .set(
            "Destination",
            format!("texture_storage_2d<{storage}, write>"),
        ))
}

/// The source texture's binding kind of a splittable format (read with `textureLoad` only).
fn texel_binding(format: wgpu::TextureFormat) -> Result<Binding, InterleaveError> {
    Ok(match texel_format(format)?.1 {
        "u32" => Binding::TextureUint,
        "i32" => Binding::TextureSint,
        _ => Binding::TextureUnfilterable,
    })
}

/// Every splittable format.
pub const SPLIT_FORMATS: [wgpu::TextureFormat; 15] = {
    use wgpu::TextureFormat as F;
    [
        F::R32Uint,
        F::Rg32Uint,
        F::Rgba32Uint,
        F::Rgba16Uint,
        F::Rgba8Uint,
        F::R32Sint,
        F::Rg32Sint,
        F::Rgba32Sint,
        F::Rgba16Sint,
        F::Rgba8Sint,
        F::R32Float,
        F::Rg32Float,
        F::Rgba32Float,
        F::Rgba16Float,
        F::Rgba8Unorm,
    ]
};

/// Every shader variant this crate can build: each split/gather file for each format.
pub fn shader_variants() -> Vec<(&'static str, Specialisation)> {
    ["one_pass.wgsl", "two_pass.wgsl", "tiled.wgsl"]
        .into_iter()
        .flat_map(|file| {
            SPLIT_FORMATS
                .iter()
                .filter_map(move |&f| texel_specialisation(f).ok().map(|s| (file, s)))
        })
        .collect()
}

/// Split and gather of one texture format for one [`SplitLayout`] and [`SplitVariant`].
pub struct Splitter {
    layout: SplitLayout,
    format: wgpu::TextureFormat,
    split_pipelines: Vec<(&'static str, (wgpu::ComputePipeline, Layout))>,
    gather_pipelines: Vec<(&'static str, (wgpu::ComputePipeline, Layout))>,
    /// Two-pass only: the block-split texture between the passes, and its geometry.
    intermediate: Option<(wgpu::Texture, BlockGeometry)>,
    tile: (u32, u32),
    variant: SplitVariant,
}

impl Splitter {
    /// Builds the pipelines (and the two-pass intermediate texture) for `format`.
    pub fn new(
        device: &wgpu::Device,
        layout: &SplitLayout,
        variant: SplitVariant,
        format: wgpu::TextureFormat,
    ) -> Result<Self, InterleaveError> {
        variant.validate(layout.pattern)?;
        transfer::check_texture_size(
            device,
            "split texture",
            layout.split_width(),
            layout.split_height(),
        )?;
        let Pattern { n, m } = layout.pattern;
        let (file, split_entries, gather_entries, (a, b)): (
            _,
            &[&'static str],
            &[&'static str],
            _,
        ) = match variant {
            SplitVariant::OnePass => (
                "one_pass.wgsl",
                &["split_one_pass"],
                &["gather_one_pass"],
                (1, 1),
            ),
            SplitVariant::TwoPass(block) => (
                "two_pass.wgsl",
                &["split_block_splitting", "split_block_translation"],
                &["gather_block_translation", "gather_block_gathering"],
                (block.p / n, block.q / m),
            ),
            SplitVariant::Tiled => (
                "tiled.wgsl",
                &["split_tiled"],
                &["gather_tiled"],
                crate::tile(layout.pattern)?,
            ),
        };
        let module = crate::SHADERS.module_with(device, file, &texel_specialisation(format)?)?;
        let bindings = [texel_binding(format)?, Binding::StorageTexture(format)];
        let constants = [
            ("width", f64::from(layout.width)),
            ("height", f64::from(layout.height)),
            ("n", f64::from(n)),
            ("m", f64::from(m)),
            ("sub_width", f64::from(layout.sub_width)),
            ("sub_height", f64::from(layout.sub_height)),
            ("a", f64::from(a)),
            ("b", f64::from(b)),
        ];
        let build = |entries: &[&'static str]| {
            entries
                .iter()
                .map(|e| (*e, kernel(device, &module, e, &bindings, &constants)))
                .collect()
        };
        let intermediate = match variant {
            SplitVariant::TwoPass(block) => {
                let g = BlockGeometry::new(layout, block);
                let (w, h) = g.intermediate_size();
                transfer::check_texture_size(device, "block-split texture", w, h)?;
                Some((
                    transfer::texture_2d(device, "block-split texture", w, h, format, USAGE),
                    g,
                ))
            }
            _ => None,
        };
        Ok(Self {
            layout: *layout,
            format,
            split_pipelines: build(split_entries),
            gather_pipelines: build(gather_entries),
            intermediate,
            tile: (a, b),
            variant,
        })
    }

    /// The layout.
    pub fn layout(&self) -> &SplitLayout {
        &self.layout
    }

    /// A texture of the image's size and this splitter's format, usable by every kernel.
    pub fn image_texture(&self, device: &wgpu::Device, label: &str) -> wgpu::Texture {
        transfer::texture_2d(
            device,
            label,
            self.layout.width,
            self.layout.height,
            self.format,
            USAGE,
        )
    }

    /// A texture of the split size and this splitter's format.
    pub fn split_texture(&self, device: &wgpu::Device, label: &str) -> wgpu::Texture {
        let l = &self.layout;
        transfer::texture_2d(
            device,
            label,
            l.split_width(),
            l.split_height(),
            self.format,
            USAGE,
        )
    }

    fn split_size(&self) -> (u32, u32) {
        (self.layout.split_width(), self.layout.split_height())
    }

    fn image_size(&self) -> (u32, u32) {
        (self.layout.width, self.layout.height)
    }

    fn tiles(&self) -> (u32, u32) {
        (
            self.layout.sub_width.div_ceil(self.tile.0),
            self.layout.sub_height.div_ceil(self.tile.1),
        )
    }

    /// Passes that split `image` into `split`.
    pub fn split(
        &self,
        device: &wgpu::Device,
        image: &wgpu::Texture,
        split: &wgpu::Texture,
    ) -> Result<Passes, InterleaveError> {
        kernel::check_texture("image", image, self.image_size(), self.format, READ)?;
        kernel::check_texture(
            "split texture",
            split,
            self.split_size(),
            self.format,
            WRITE,
        )?;
        self.passes(
            device,
            &self.split_pipelines,
            (image, split),
            self.split_size(),
        )
    }

    /// Passes that gather `split` back into `image`.
    pub fn gather(
        &self,
        device: &wgpu::Device,
        split: &wgpu::Texture,
        image: &wgpu::Texture,
    ) -> Result<Passes, InterleaveError> {
        kernel::check_texture("split texture", split, self.split_size(), self.format, READ)?;
        kernel::check_texture("image", image, self.image_size(), self.format, WRITE)?;
        self.passes(
            device,
            &self.gather_pipelines,
            (split, image),
            self.image_size(),
        )
    }

    /// The passes from `textures.0` to `textures.1`, whose size is `to_size`.
    fn passes(
        &self,
        device: &wgpu::Device,
        pipelines: &[(&'static str, (wgpu::ComputePipeline, Layout))],
        (from, to): (&wgpu::Texture, &wgpu::Texture),
        to_size: (u32, u32),
    ) -> Result<Passes, InterleaveError> {
        let res = wgpu::BindingResource::TextureView;
        let (from_view, to_view) = (view(from), view(to));
        let passes = match (self.variant, &self.intermediate, pipelines) {
            (SplitVariant::TwoPass(_), Some((mid, g)), [(first, p1), (second, p2)]) => {
                let mid_view = view(mid);
                pass(
                    device,
                    first,
                    p1,
                    &[res(&from_view), res(&mid_view)],
                    groups(g.intermediate_size(), 16),
                )
                .then(pass(
                    device,
                    second,
                    p2,
                    &[res(&mid_view), res(&to_view)],
                    groups(to_size, 16),
                ))
            }
            (SplitVariant::Tiled, _, [(name, p)]) => pass(
                device,
                name,
                p,
                &[res(&from_view), res(&to_view)],
                self.tiles(),
            ),
            (_, _, [(name, p)]) => pass(
                device,
                name,
                p,
                &[res(&from_view), res(&to_view)],
                groups(to_size, 16),
            ),
            _ => unreachable!("pipelines are built per variant in Splitter::new"),
        };
        Ok(passes)
    }
}

/// Uniform block of `discontinuity.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Pod, bytemuck::Zeroable)]
struct ThresholdsUniform {
    cos_squared: f32,
    cos_positive: u32,
    depth_factor: f32,
    _pad: u32,
}

/// The discontinuity buffer kernel (§4.5).
pub struct DiscontinuityPass {
    pipeline: (wgpu::ComputePipeline, Layout),
    thresholds: wgpu::Buffer,
}

impl DiscontinuityPass {
    /// Builds the pipeline with `thresholds` (change them with [`Self::set_thresholds`]).
    pub fn new(device: &wgpu::Device, thresholds: &Thresholds) -> Result<Self, InterleaveError> {
        let module = crate::SHADERS.module(device, "discontinuity.wgsl")?;
        let pipeline = kernel(
            device,
            &module,
            "discontinuity",
            &[
                Binding::TextureUnfilterable,
                Binding::TextureUint,
                Binding::StorageTexture(DISCONTINUITY_FORMAT),
                Binding::Uniform,
            ],
            &[],
        );
        let thresholds = transfer::buffer_init(
            device,
            "discontinuity thresholds",
            bytemuck::bytes_of(&Self::uniform(thresholds)?),
            wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        )?;
        Ok(Self {
            pipeline,
            thresholds,
        })
    }

    fn uniform(t: &Thresholds) -> Result<ThresholdsUniform, InterleaveError> {
        t.validate()?;
        let (cos_squared, positive) = t.cos_squared();
        Ok(ThresholdsUniform {
            cos_squared,
            cos_positive: u32::from(positive),
            depth_factor: t.depth_factor(),
            _pad: 0,
        })
    }

    /// New thresholds for the following submissions.
    pub fn set_thresholds(
        &self,
        queue: &wgpu::Queue,
        t: &Thresholds,
    ) -> Result<(), InterleaveError> {
        queue.write_buffer(&self.thresholds, 0, bytemuck::bytes_of(&Self::uniform(t)?));
        Ok(())
    }

    /// The pass writing `discontinuities` ([`DISCONTINUITY_FORMAT`]) from the G-buffer's linear
    /// depth and normal targets.
    pub fn bind(
        &self,
        device: &wgpu::Device,
        linear_depth: &wgpu::Texture,
        normals: &wgpu::Texture,
        discontinuities: &wgpu::Texture,
    ) -> Result<Passes, InterleaveError> {
        let size = (linear_depth.width(), linear_depth.height());
        kernel::check_texture(
            "linear depth",
            linear_depth,
            size,
            gbuffer::LINEAR_DEPTH_FORMAT,
            READ,
        )?;
        kernel::check_texture("normals", normals, size, gbuffer::NORMAL_FORMAT, READ)?;
        kernel::check_texture(
            "discontinuity buffer",
            discontinuities,
            size,
            DISCONTINUITY_FORMAT,
            WRITE,
        )?;
        let (d, nrm, out) = (view(linear_depth), view(normals), view(discontinuities));
        Ok(pass(
            device,
            "discontinuity buffer",
            &self.pipeline,
            &[
                wgpu::BindingResource::TextureView(&d),
                wgpu::BindingResource::TextureView(&nrm),
                wgpu::BindingResource::TextureView(&out),
                self.thresholds.as_entire_binding(),
            ],
            groups(size, 16),
        ))
    }
}

/// Uniform block of `blur.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Pod, bytemuck::Zeroable)]
struct BlurUniform {
    direction: [i32; 2],
    radius: i32,
    _pad: i32,
    weights: [f32; 12],
}

/// The edge-aware separable Gaussian blur (§4.5): a horizontal and a vertical pass.
pub struct BlurPass {
    blur: Blur,
    pipeline: (wgpu::ComputePipeline, Layout),
    params: [wgpu::Buffer; 2],
    sampler: wgpu::Sampler,
}

impl BlurPass {
    /// Builds the pipeline of `blur`'s variant.
    pub fn new(device: &wgpu::Device, blur: &Blur) -> Result<Self, InterleaveError> {
        blur.validate()?;
        let module = crate::SHADERS.module(device, "blur.wgsl")?;
        let storage = Binding::StorageTexture(IRRADIANCE_FORMAT);
        let pipeline = match blur.variant {
            BlurVariant::Plain => {
                let bindings = [Binding::TextureUnfilterable, Binding::TextureUnfilterable];
                let bindings = [&bindings[..], &[storage, Binding::Uniform]].concat();
                kernel(device, &module, "blur_plain", &bindings, &[])
            }
            BlurVariant::Fast => {
                let bindings = [Binding::Texture, Binding::Texture, storage];
                let bindings = [&bindings[..], &[Binding::Uniform, Binding::Sampler]].concat();
                kernel(device, &module, "blur_fast", &bindings, &[])
            }
        };
        let mut weights = [0.0; 12];
        for (w, v) in weights.iter_mut().zip(blur.weights()) {
            *w = v;
        }
        let params = [[1, 0], [0, 1]].map(|direction| {
            transfer::buffer_init(
                device,
                "blur params",
                bytemuck::bytes_of(&BlurUniform {
                    direction,
                    radius: blur.radius() as i32,
                    _pad: 0,
                    weights,
                }),
                wgpu::BufferUsages::UNIFORM,
            )
        });
        let [h, v] = params;
        let sampler = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("blur bilinear"),
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            ..Default::default()
        });
        Ok(Self {
            blur: *blur,
            pipeline,
            params: [h?, v?],
            sampler,
        })
    }

    /// An [`IRRADIANCE_FORMAT`] texture of `width × height` (blur input, scratch or output).
    pub fn irradiance_texture(
        device: &wgpu::Device,
        label: &str,
        width: u32,
        height: u32,
    ) -> wgpu::Texture {
        transfer::texture_2d(device, label, width, height, IRRADIANCE_FORMAT, USAGE)
    }

    /// Passes blurring `irradiance` into `output` through `scratch` (all [`IRRADIANCE_FORMAT`],
    /// same size), guided by `discontinuities`.
    pub fn bind(
        &self,
        device: &wgpu::Device,
        irradiance: &wgpu::Texture,
        discontinuities: &wgpu::Texture,
        scratch: &wgpu::Texture,
        output: &wgpu::Texture,
    ) -> Result<Passes, InterleaveError> {
        let size = (irradiance.width(), irradiance.height());
        kernel::check_texture("irradiance", irradiance, size, IRRADIANCE_FORMAT, READ)?;
        kernel::check_texture(
            "discontinuity buffer",
            discontinuities,
            size,
            DISCONTINUITY_FORMAT,
            READ,
        )?;
        kernel::check_texture("blur scratch", scratch, size, IRRADIANCE_FORMAT, READ)?;
        kernel::check_texture("blur scratch", scratch, size, IRRADIANCE_FORMAT, WRITE)?;
        kernel::check_texture("blur output", output, size, IRRADIANCE_FORMAT, WRITE)?;
        let disc = view(discontinuities);
        let [h, v] = &self.params;
        let one = |name: &str, from: &wgpu::Texture, to: &wgpu::Texture, params: &wgpu::Buffer| {
            let (from, to) = (view(from), view(to));
            let mut resources = vec![
                wgpu::BindingResource::TextureView(&from),
                wgpu::BindingResource::TextureView(&disc),
                wgpu::BindingResource::TextureView(&to),
                params.as_entire_binding(),
            ];
            if self.blur.variant == BlurVariant::Fast {
                resources.push(wgpu::BindingResource::Sampler(&self.sampler));
            }
            pass(device, name, &self.pipeline, &resources, groups(size, 16))
        };
        Ok(one("blur horizontal", irradiance, scratch, h).then(one(
            "blur vertical",
            scratch,
            output,
            v,
        )))
    }
}

/// Lights per sub-buffer subset: `count / (n·m)`, which must be a whole number ≥ 1.
pub fn lights_per_subset(count: usize, pattern: Pattern) -> Result<u32, InterleaveError> {
    let subsets = pattern.count();
    if count == 0
        || !count.is_multiple_of(subsets as usize)
        || count / subsets as usize > u32::MAX as usize
    {
        return Err(InterleaveError::Lights { count, subsets });
    }
    Ok((count / subsets as usize) as u32)
}

/// The probe shader of [`crate::cpu::shade_subsets`] on the GPU, on the split G-buffer (then
/// gathered) or fused with the split by strided addressing (§3.1's indirection).
pub struct SubsetShading {
    layout: SplitLayout,
    split_pipeline: (wgpu::ComputePipeline, Layout),
    fused_pipeline: (wgpu::ComputePipeline, Layout),
    lights: wgpu::Buffer,
}

impl SubsetShading {
    /// Uploads `lights` (n·m equal subsets) and builds both pipelines.
    pub fn new(
        device: &wgpu::Device,
        layout: &SplitLayout,
        lights: &[SubsetLight],
    ) -> Result<Self, InterleaveError> {
        let per_subset = lights_per_subset(lights.len(), layout.pattern)?;
        let module = crate::SHADERS.module(device, "shade.wgsl")?;
        let bindings = [
            Binding::TextureUnfilterable,
            Binding::TextureUint,
            Binding::StorageRead,
            Binding::StorageTexture(IRRADIANCE_FORMAT),
        ];
        let constants = [
            ("width", f64::from(layout.width)),
            ("height", f64::from(layout.height)),
            ("n", f64::from(layout.pattern.n)),
            ("m", f64::from(layout.pattern.m)),
            ("sub_width", f64::from(layout.sub_width)),
            ("sub_height", f64::from(layout.sub_height)),
            ("per_subset", f64::from(per_subset)),
        ];
        let lights = transfer::buffer_init(
            device,
            "subset lights",
            bytemuck::cast_slice(lights),
            wgpu::BufferUsages::STORAGE,
        )?;
        Ok(Self {
            layout: *layout,
            split_pipeline: kernel(device, &module, "shade_split", &bindings, &constants),
            fused_pipeline: kernel(device, &module, "shade_fused", &bindings, &constants),
            lights,
        })
    }

    fn bind(
        &self,
        device: &wgpu::Device,
        name: &str,
        pipeline: &(wgpu::ComputePipeline, Layout),
        size: (u32, u32),
        textures: [&wgpu::Texture; 3],
    ) -> Result<Passes, InterleaveError> {
        let [depth, normals, irradiance] = textures;
        kernel::check_texture(
            "linear depth",
            depth,
            size,
            gbuffer::LINEAR_DEPTH_FORMAT,
            READ,
        )?;
        kernel::check_texture("normals", normals, size, gbuffer::NORMAL_FORMAT, READ)?;
        kernel::check_texture("irradiance", irradiance, size, IRRADIANCE_FORMAT, WRITE)?;
        let (d, nrm, out) = (view(depth), view(normals), view(irradiance));
        let l = &self.layout;
        Ok(pass(
            device,
            name,
            pipeline,
            &[
                wgpu::BindingResource::TextureView(&d),
                wgpu::BindingResource::TextureView(&nrm),
                self.lights.as_entire_binding(),
                wgpu::BindingResource::TextureView(&out),
            ],
            groups((l.split_width(), l.split_height()), 16),
        ))
    }

    /// Shades the split G-buffer (split size) into split irradiance.
    pub fn shade_split(
        &self,
        device: &wgpu::Device,
        split_depth: &wgpu::Texture,
        split_normals: &wgpu::Texture,
        split_irradiance: &wgpu::Texture,
    ) -> Result<Passes, InterleaveError> {
        let l = &self.layout;
        self.bind(
            device,
            "shade split",
            &self.split_pipeline,
            (l.split_width(), l.split_height()),
            [split_depth, split_normals, split_irradiance],
        )
    }

    /// Shades the interleaved G-buffer in sub-buffer order by strided addressing, writing the
    /// interleaved irradiance directly (no split, no gather).
    pub fn shade_fused(
        &self,
        device: &wgpu::Device,
        depth: &wgpu::Texture,
        normals: &wgpu::Texture,
        irradiance: &wgpu::Texture,
    ) -> Result<Passes, InterleaveError> {
        let l = &self.layout;
        self.bind(
            device,
            "shade fused",
            &self.fused_pipeline,
            (l.width, l.height),
            [depth, normals, irradiance],
        )
    }
}

fn texel_bytes(format: wgpu::TextureFormat) -> u32 {
    format.block_copy_size(None).unwrap_or(0)
}

fn check_texel<T>(format: wgpu::TextureFormat) -> Result<(), InterleaveError> {
    texel_format(format)?;
    if size_of::<T>() != texel_bytes(format) as usize {
        return Err(InterleaveError::TexelSize {
            cpu: size_of::<T>(),
            gpu: texel_bytes(format),
            format,
        });
    }
    Ok(())
}

/// Uploads `image` into a new texture of `format` (texels of the same size), usable by every
/// kernel of this crate.
pub fn upload_image<T: Pod>(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    label: &str,
    image: &Image<T>,
    format: wgpu::TextureFormat,
) -> Result<wgpu::Texture, InterleaveError> {
    Ok(transfer::texture_init(
        device,
        queue,
        label,
        image.width(),
        image.height(),
        format,
        USAGE,
        bytemuck::cast_slice(image.pixels()),
    )?)
}

/// Reads `texture` back into an image of texels `T` (of the format's texel size).
pub fn download_image<T: Pod>(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    texture: &wgpu::Texture,
) -> Result<Image<T>, InterleaveError> {
    let bytes = transfer::read_texture(device, queue, texture, wgpu::TextureAspect::All)?;
    Image::from_vec(
        texture.width(),
        texture.height(),
        bytemuck::pod_collect_to_vec(&bytes),
    )
    .map_err(|e| ::gpu::GpuError::Readback(e.to_string()).into())
}

fn submit(gpu: &Gpu, passes: &Passes) {
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    passes.encode(&mut encoder, None);
    gpu.queue.submit([encoder.finish()]);
}

/// Convenience for tests and examples: uploads `image` as `format` (texels of the same size),
/// splits it on the GPU and reads the split texture back.
pub fn run_split<T: Pod>(
    gpu: &Gpu,
    image: &Image<T>,
    format: wgpu::TextureFormat,
    layout: &SplitLayout,
    variant: SplitVariant,
) -> Result<Image<T>, InterleaveError> {
    check_texel::<T>(format)?;
    crate::cpu::check_size("image", image, layout.width, layout.height)?;
    let splitter = Splitter::new(&gpu.device, layout, variant, format)?;
    let source = upload_image(&gpu.device, &gpu.queue, "image", image, format)?;
    let split = splitter.split_texture(&gpu.device, "split");
    submit(gpu, &splitter.split(&gpu.device, &source, &split)?);
    download_image(&gpu.device, &gpu.queue, &split)
}

/// Convenience for tests and examples: gathers a split image on the GPU.
pub fn run_gather<T: Pod>(
    gpu: &Gpu,
    split: &Image<T>,
    format: wgpu::TextureFormat,
    layout: &SplitLayout,
    variant: SplitVariant,
) -> Result<Image<T>, InterleaveError> {
    check_texel::<T>(format)?;
    crate::cpu::check_size(
        "split image",
        split,
        layout.split_width(),
        layout.split_height(),
    )?;
    let splitter = Splitter::new(&gpu.device, layout, variant, format)?;
    let source = upload_image(&gpu.device, &gpu.queue, "split", split, format)?;
    let image = splitter.image_texture(&gpu.device, "gathered");
    submit(gpu, &splitter.gather(&gpu.device, &source, &image)?);
    download_image(&gpu.device, &gpu.queue, &image)
}

/// Convenience for tests and examples: the discontinuity buffer on the GPU.
pub fn run_discontinuity(
    gpu: &Gpu,
    linear_depth: &Image<f32>,
    normals: &Image<u32>,
    thresholds: &Thresholds,
) -> Result<Image<[u8; 4]>, InterleaveError> {
    crate::cpu::check_size(
        "normal image",
        normals,
        linear_depth.width(),
        linear_depth.height(),
    )?;
    let pass = DiscontinuityPass::new(&gpu.device, thresholds)?;
    let depth = upload_image(
        &gpu.device,
        &gpu.queue,
        "linear depth",
        linear_depth,
        gbuffer::LINEAR_DEPTH_FORMAT,
    )?;
    let nrm = upload_image(
        &gpu.device,
        &gpu.queue,
        "normals",
        normals,
        gbuffer::NORMAL_FORMAT,
    )?;
    let out = transfer::texture_2d(
        &gpu.device,
        "discontinuities",
        linear_depth.width(),
        linear_depth.height(),
        DISCONTINUITY_FORMAT,
        USAGE,
    );
    submit(gpu, &pass.bind(&gpu.device, &depth, &nrm, &out)?);
    download_image(&gpu.device, &gpu.queue, &out)
}

/// Linear RGBA as f16 texels of an [`IRRADIANCE_FORMAT`] texture.
pub fn to_f16_texels(image: &Image<[f32; 4]>) -> Image<[half::f16; 4]> {
    image.map(|p| p.map(half::f16::from_f32))
}

/// Convenience for tests and examples: the blur on the GPU (irradiance stored as f16).
pub fn run_blur(
    gpu: &Gpu,
    irradiance: &Image<[f32; 4]>,
    discontinuities: &Image<[u8; 4]>,
    blur: &Blur,
) -> Result<Image<[f32; 4]>, InterleaveError> {
    crate::cpu::check_size(
        "discontinuity buffer",
        discontinuities,
        irradiance.width(),
        irradiance.height(),
    )?;
    let pass = BlurPass::new(&gpu.device, blur)?;
    let (w, h) = (irradiance.width(), irradiance.height());
    let input = upload_image(
        &gpu.device,
        &gpu.queue,
        "irradiance",
        &to_f16_texels(irradiance),
        IRRADIANCE_FORMAT,
    )?;
    let disc = upload_image(
        &gpu.device,
        &gpu.queue,
        "discontinuities",
        discontinuities,
        DISCONTINUITY_FORMAT,
    )?;
    let scratch = BlurPass::irradiance_texture(&gpu.device, "blur scratch", w, h);
    let out = BlurPass::irradiance_texture(&gpu.device, "blurred", w, h);
    submit(gpu, &pass.bind(&gpu.device, &input, &disc, &scratch, &out)?);
    Ok(
        download_image::<[half::f16; 4]>(&gpu.device, &gpu.queue, &out)?
            .map(|p| p.map(half::f16::to_f32)),
    )
}

/// How [`run_shading`] reaches the sub-buffers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Shading {
    /// Split depth and normals, shade the split G-buffer, gather the irradiance.
    Split(SplitVariant),
    /// §3.1's indirection: shade the interleaved G-buffer in sub-buffer order.
    Fused,
}

/// Convenience for tests and examples: interleaved shading of a G-buffer's linear depth and
/// normals with `lights` on the GPU; returns the gathered irradiance.
pub fn run_shading(
    gpu: &Gpu,
    linear_depth: &Image<f32>,
    normals: &Image<u32>,
    lights: &[SubsetLight],
    layout: &SplitLayout,
    shading: Shading,
) -> Result<Image<[f32; 4]>, InterleaveError> {
    crate::cpu::check_size("linear depth", linear_depth, layout.width, layout.height)?;
    crate::cpu::check_size("normal image", normals, layout.width, layout.height)?;
    let device = &gpu.device;
    let shade = SubsetShading::new(device, layout, lights)?;
    let depth = upload_image(
        &gpu.device,
        &gpu.queue,
        "linear depth",
        linear_depth,
        gbuffer::LINEAR_DEPTH_FORMAT,
    )?;
    let nrm = upload_image(
        &gpu.device,
        &gpu.queue,
        "normals",
        normals,
        gbuffer::NORMAL_FORMAT,
    )?;
    let out = BlurPass::irradiance_texture(device, "irradiance", layout.width, layout.height);
    let passes = match shading {
        Shading::Fused => shade.shade_fused(device, &depth, &nrm, &out)?,
        Shading::Split(variant) => {
            let depth_split = Splitter::new(device, layout, variant, gbuffer::LINEAR_DEPTH_FORMAT)?;
            let normal_split = Splitter::new(device, layout, variant, gbuffer::NORMAL_FORMAT)?;
            let irradiance_split = Splitter::new(device, layout, variant, IRRADIANCE_FORMAT)?;
            let split_depth = depth_split.split_texture(device, "split depth");
            let split_normals = normal_split.split_texture(device, "split normals");
            let split_irradiance = irradiance_split.split_texture(device, "split irradiance");
            depth_split
                .split(device, &depth, &split_depth)?
                .then(normal_split.split(device, &nrm, &split_normals)?)
                .then(shade.shade_split(device, &split_depth, &split_normals, &split_irradiance)?)
                .then(irradiance_split.gather(device, &split_irradiance, &out)?)
        }
    };
    submit(gpu, &passes);
    Ok(
        download_image::<[half::f16; 4]>(&gpu.device, &gpu.queue, &out)?
            .map(|p| p.map(half::f16::to_f32)),
    )
}
