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
//!
//! One module per kernel stage, named after its WGSL file: [`split`] (`one_pass.wgsl`,
//! `two_pass.wgsl`, `tiled.wgsl` over `texel.wgsl`), [`discontinuity`], [`blur`],
//! [`discontinuity_blur`] (both in one dispatch), [`shade`];
//! [`run`] has the upload → encode → read-back helpers for tests and examples.

use ::gpu::kernel::{self, Binding, Layout, Workgroups};
use ::gpu::wgpu;

pub mod blur;
pub mod discontinuity;
pub mod discontinuity_blur;
pub mod run;
pub mod shade;
pub mod split;

pub use blur::BlurPass;
pub use discontinuity::DiscontinuityPass;
pub use discontinuity_blur::DiscontinuityBlurPass;
pub use run::{
    Shading, download_image, run_blur, run_discontinuity, run_discontinuity_blur, run_gather,
    run_shading, run_split, to_f16_texels, upload_depth_normals, upload_image,
};
pub use shade::{SubsetShading, lights_per_subset};
pub use split::{SPLIT_FORMATS, Splitter, texel_format, texel_specialisation};

/// Every shader variant this crate can build: each split/gather file for each format, and the
/// one-dispatch discontinuity buffer + blur for each valid blur.
pub fn shader_variants() -> Vec<(&'static str, ::gpu::shader::Specialisation)> {
    let blurs = (5..=17).step_by(2).flat_map(|kernel| {
        [crate::BlurVariant::Plain, crate::BlurVariant::Fast]
            .map(|variant| crate::Blur { kernel, variant })
    });
    let fused = blurs.map(|b| {
        (
            "discontinuity_blur.wgsl",
            discontinuity_blur::specialisation(&b),
        )
    });
    split::shader_variants().into_iter().chain(fused).collect()
}

/// Format of irradiance textures (blur input and output, shading output): filterable and
/// writable from compute, 16 bits per channel like the paper's (§5.3).
pub const IRRADIANCE_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;
/// Format of the discontinuity buffer: red = normal edge, green = depth edge; filterable for
/// the fast blur's bilinear lookups.
pub const DISCONTINUITY_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;

const USAGE: wgpu::TextureUsages = ::gpu::transfer::STORAGE_ANY;

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
fn compute_kernel(
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

/// Checks a pass's G-buffer inputs: linear depth and normals of `size`, readable.
fn check_gbuffer(
    linear_depth: &wgpu::Texture,
    normals: &wgpu::Texture,
    size: (u32, u32),
) -> Result<(), crate::InterleaveError> {
    let depth_format = gbuffer::LINEAR_DEPTH_FORMAT;
    kernel::check_texture("linear depth", linear_depth, size, depth_format, READ)?;
    kernel::check_texture("normals", normals, size, gbuffer::NORMAL_FORMAT, READ)?;
    Ok(())
}

fn groups(size: (u32, u32), workgroup: u32) -> (u32, u32) {
    (size.0.div_ceil(workgroup), size.1.div_ceil(workgroup))
}
