//! `adaptive-ssaa` inside an application that owns its wgpu device: render the textured
//! checkerboard with 4×4 adaptive supersampling in the application's own encoder, then with
//! full supersampling, and check that the adaptive image is close at fewer samples.
//!
//! The application creates its own device: wgpu's default limits plus what the crate states
//! it needs (`device_needs()`).

use adaptive_ssaa::{SsaaConfig, gpu::SsaaRenderer};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let adapter =
        pollster::block_on(wgpu::Instance::default().request_adapter(&Default::default()))?;
    let (device, queue) =
        pollster::block_on(adapter.request_device(&adaptive_ssaa::device_needs().descriptor()))?;

    let scene = scene::checkerboard();
    let lights = tiled_shading::gpu_lights(&scene.lights)?;
    let (w, h) = (160, 120);
    // new: upload and pipelines once; set_camera writes a buffer; encode only records.
    let mut ssaa =
        SsaaRenderer::new(&device, &queue, &scene, &lights, w, h, &SsaaConfig::default())?;
    ssaa.set_camera(&queue, &scene.camera_or_framed())?;
    let render = |full: bool| {
        let mut encoder = device.create_command_encoder(&Default::default());
        ssaa.encode_gbuffer(&mut encoder, None);
        if full {
            ssaa.ssaa.encode_full(&mut encoder, None)
        } else {
            ssaa.ssaa.encode(&mut encoder, None)
        }
        queue.submit([encoder.finish()]);
        ssaa.ssaa.read_output(&device, &queue)
    };
    let adaptive = render(false)?;
    let samples = ssaa.ssaa.read_counts(&device, &queue)?;
    let full = render(true)?;

    let share =
        samples.pixels().iter().map(|&c| f64::from(c)).sum::<f64>() / (16.0 * f64::from(w * h));
    let psnr = gbuffer::psnr(&full, &adaptive);
    assert!(share < 1.0 && psnr > 30.0, "{:.0} % of the samples, PSNR {psnr:.1} dB", share * 100.0);
    println!(
        "adaptive 4×4 on {}: {:.0} % of the samples, PSNR {psnr:.1} dB against full SSAA",
        adapter.get_info().name,
        share * 100.0
    );
    Ok(())
}
