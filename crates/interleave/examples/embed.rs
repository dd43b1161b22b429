//! `interleave` inside an application that owns its wgpu device: split a 4×4-interleaved
//! G-buffer channel on the GPU, in the application's own encoder, and check it against the CPU
//! reference.
//!
//! The application creates its own device: wgpu's default limits plus what the crate states
//! it needs (`device_needs()`).

use gbuffer::Image;
use interleave::{Pattern, SplitLayout, SplitVariant, gpu::Splitter};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let adapter =
        pollster::block_on(wgpu::Instance::default().request_adapter(&Default::default()))?;
    let (device, queue) =
        pollster::block_on(adapter.request_device(&interleave::device_needs().descriptor()))?;

    // Any size works, also sizes that are not multiples of the pattern.
    let (width, height) = (50, 37);
    let image = Image::from_vec(width, height, (0..width * height).collect::<Vec<u32>>())?;
    let layout = SplitLayout::new(width, height, Pattern::new(4, 4)?)?;
    let format = wgpu::TextureFormat::R32Uint;

    // new: pipelines once; bind: the caller's textures; encode: only records.
    let splitter = Splitter::new(&device, &layout, SplitVariant::Tiled, format)?;
    let input = interleave::gpu::upload_image(&device, &queue, "input", &image, format)?;
    let split = splitter.split_texture(&device, "split");
    let passes = splitter.split(&device, &input, &split)?;
    let mut encoder = device.create_command_encoder(&Default::default());
    passes.encode(&mut encoder, None);
    queue.submit([encoder.finish()]);

    let gpu: Image<u32> = interleave::gpu::download_image(&device, &queue, &split)?;
    let cpu = interleave::cpu::split(&image, &layout, SplitVariant::Tiled)?;
    assert!(gpu == cpu, "GPU split differs from the CPU reference");
    println!(
        "split {width}×{height} into 4×4 sub-buffers on {}: equal to the CPU reference",
        adapter.get_info().name
    );
    Ok(())
}
