//! Upload → encode → submit → read back, for tests, examples and pictures.

use ::gpu::{Gpu, transfer, wgpu};
use bytemuck::Pod;
use gbuffer::Image;

use super::{
    BlurPass, DISCONTINUITY_FORMAT, DiscontinuityBlurPass, DiscontinuityPass, IRRADIANCE_FORMAT,
    Passes, Splitter, SubsetShading, USAGE, split::texel_format,
};
use crate::cpu::SubsetLight;
use crate::{Blur, InterleaveError, SplitLayout, SplitVariant, Thresholds};

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

/// Uploads a G-buffer's linear depth and octahedral normals (same size) into textures of
/// the G-buffer's formats: what the discontinuity buffer and the subset shading read.
pub fn upload_depth_normals(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    linear_depth: &Image<f32>,
    normals: &Image<u32>,
) -> Result<[wgpu::Texture; 2], InterleaveError> {
    let (w, h) = (linear_depth.width(), linear_depth.height());
    crate::cpu::check_size("normal image", normals, w, h)?;
    Ok([
        upload_image(
            device,
            queue,
            "linear depth",
            linear_depth,
            gbuffer::LINEAR_DEPTH_FORMAT,
        )?,
        upload_image(device, queue, "normals", normals, gbuffer::NORMAL_FORMAT)?,
    ])
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
    let [depth, nrm] = upload_depth_normals(&gpu.device, &gpu.queue, linear_depth, normals)?;
    let pass = DiscontinuityPass::new(&gpu.device, thresholds)?;
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

/// Convenience for tests: the discontinuity buffer and two images blurred by it in one
/// dispatch ([`DiscontinuityBlurPass`]).
pub fn run_discontinuity_blur(
    gpu: &Gpu,
    (linear_depth, normals): (&Image<f32>, &Image<u32>),
    irradiance: [&Image<[f32; 4]>; 2],
    thresholds: &Thresholds,
    blur: &Blur,
) -> Result<(Image<[u8; 4]>, [Image<[f32; 4]>; 2]), InterleaveError> {
    let (w, h) = (linear_depth.width(), linear_depth.height());
    let device = &gpu.device;
    let pass = DiscontinuityBlurPass::new(device, thresholds, blur)?;
    let gbuffer = upload_depth_normals(device, &gpu.queue, linear_depth, normals)?;
    let mut images = Vec::new();
    for image in irradiance {
        crate::cpu::check_size("irradiance", image, w, h)?;
        let t = to_f16_texels(image);
        images.push(upload_image(
            device,
            &gpu.queue,
            "irradiance",
            &t,
            IRRADIANCE_FORMAT,
        )?);
    }
    let disc = transfer::texture_2d(device, "discontinuities", w, h, DISCONTINUITY_FORMAT, USAGE);
    let out: [_; 2] =
        std::array::from_fn(|_| BlurPass::irradiance_texture(device, "blurred", w, h));
    let images: [&wgpu::Texture; 2] = [&images[0], &images[1]];
    let gbuffer = (&gbuffer[0], &gbuffer[1]);
    submit(
        gpu,
        &pass.bind(device, gbuffer, images, &disc, out.each_ref())?,
    );
    let [a, b] = out.each_ref().map(|o| {
        download_image::<[half::f16; 4]>(device, &gpu.queue, o)
            .map(|i| i.map(|p| p.map(half::f16::to_f32)))
    });
    Ok((download_image(device, &gpu.queue, &disc)?, [a?, b?]))
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
    let (w, h) = (irradiance.width(), irradiance.height());
    crate::cpu::check_size("discontinuity buffer", discontinuities, w, h)?;
    let device = &gpu.device;
    let pass = BlurPass::new(device, blur)?;
    let disc = upload_image(
        device,
        &gpu.queue,
        "discontinuities",
        discontinuities,
        DISCONTINUITY_FORMAT,
    )?;
    let t = to_f16_texels(irradiance);
    let input = upload_image(device, &gpu.queue, "irradiance", &t, IRRADIANCE_FORMAT)?;
    let scratch = BlurPass::irradiance_texture(device, "blur scratch", w, h);
    let out = BlurPass::irradiance_texture(device, "blurred", w, h);
    submit(gpu, &pass.bind(device, &input, &disc, &scratch, &out)?);
    Ok(download_image::<[half::f16; 4]>(device, &gpu.queue, &out)?
        .map(|p| p.map(half::f16::to_f32)))
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
    let device = &gpu.device;
    let shade = SubsetShading::new(device, layout, lights)?;
    let [depth, nrm] = upload_depth_normals(device, &gpu.queue, linear_depth, normals)?;
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
