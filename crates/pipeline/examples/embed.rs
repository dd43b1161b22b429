//! The renderer inside an application that owns its wgpu device: render the Cornell box into
//! the renderer's output texture with the application's own encoder, copy it into a texture
//! of the application, and check that the box is lit.
//!
//! The application creates its own device: wgpu's default limits plus what the crate states
//! it needs (`device_needs()`).

use pipeline::gpu::{GpuRenderer, RADIANCE_FORMAT, read_radiance};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    // The application's device: wgpu's default limits plus what the renderer states it needs.
    let adapter =
        pollster::block_on(wgpu::Instance::default().request_adapter(&Default::default()))?;
    let (device, queue) =
        pollster::block_on(adapter.request_device(&pipeline::device_needs().descriptor()))?;

    // new: upload and pipelines once; set_camera and resize only rebind; encode only records.
    let scene = scene::cornell_box();
    let mut renderer = GpuRenderer::new(&device, &queue, &scene, &scene.lights, 320, 240)?;
    renderer.set_camera(&queue, &scene.camera_or_framed())?;
    renderer.resize(&device, &queue, 256, 256)?;
    let mine = device.create_texture(&wgpu::TextureDescriptor {
        label: Some("application's copy"),
        size: wgpu::Extent3d { width: 256, height: 256, depth_or_array_layers: 1 },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: RADIANCE_FORMAT,
        usage: wgpu::TextureUsages::COPY_DST | wgpu::TextureUsages::COPY_SRC,
        view_formats: &[],
    });
    let mut encoder = device.create_command_encoder(&Default::default());
    renderer.encode(&mut encoder);
    let (from, to) = (renderer.output().as_image_copy(), mine.as_image_copy());
    encoder.copy_texture_to_texture(from, to, mine.size());
    queue.submit([encoder.finish()]);

    let image = read_radiance(&device, &queue, &mine)?;
    let lit = image.pixels().iter().filter(|p| p[0] + p[1] + p[2] > 0.05).count();
    let total = image.pixels().len();
    assert!(lit * 2 > total, "only {lit} of {total} pixels are lit");
    for t in renderer.timings(&device, &queue)? {
        println!("{:>24}: {:.3} ms", t.name, t.ms);
    }
    println!("Cornell box at 256×256 on {}: {lit} lit pixels", adapter.get_info().name);
    Ok(())
}
