//! `tiled-shading` inside an application that owns its wgpu device: accumulate 256 point
//! lights over a G-buffer with tiled normal-cone culling into the application's own output
//! textures, and check the result against the CPU reference.
//!
//! The application creates its own device: wgpu's default limits plus what the crate states
//! it needs (`device_needs()`).

use gbuffer::gpu::UploadedGBuffer;
use tiled_shading::{Method, ShadingConfig, gpu::LightShading};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let adapter =
        pollster::block_on(wgpu::Instance::default().request_adapter(&Default::default()))?;
    let (device, queue) =
        pollster::block_on(adapter.request_device(&tiled_shading::device_needs().descriptor()))?;

    // A G-buffer (here from the CPU rasteriser) and lights.
    let scene = scene::spheres_on_plane(3);
    let camera = scene.camera_or_framed();
    let (w, h) = (160, 120);
    let gb = gbuffer::cpu::rasterize(&scene, &camera, w, h)?.gbuffer;
    let frame = gbuffer::Frame::new(&camera, w, h);
    let lights = tiled_shading::gpu_lights(&scene::scatter_point_lights(scene.bounds(), 256, 7))?;
    let uploaded = UploadedGBuffer::new(&device, &queue, &gb, &frame)?;

    // new: the pipeline once; bind: G-buffer, the caller's outputs, a light buffer; encode.
    let config = ShadingConfig { method: Method::TiledCones, ..Default::default() };
    let shading = LightShading::new(&device, &config)?;
    let outputs = LightShading::output_textures(&device, w, h);
    let outputs = [&outputs[0], &outputs[1]];
    let (frame_uniform, textures) = (&uploaded.frame, uploaded.textures());
    let mut bound = shading.bind(&device, frame_uniform, textures, outputs, lights.len(), false)?;
    bound.set_lights(&queue, &lights)?;
    bound.set_camera(&queue, &camera);
    let mut encoder = device.create_command_encoder(&Default::default());
    shading.encode(&bound, &mut encoder, None);
    queue.submit([encoder.finish()]);

    let [diffuse, _] = tiled_shading::gpu::read_outputs(&device, &queue, outputs)?;
    let cpu = tiled_shading::cpu::shade(&gb, &frame, &camera, &lights, &config, None)?;
    let pairs = diffuse.pixels().iter().zip(cpu.diffuse.pixels());
    let worst = pairs.map(|(g, c)| (*g - *c).abs().max_element()).fold(0.0, f32::max);
    assert!(worst < 1e-3, "GPU differs from the CPU reference by {worst}");
    let name = adapter.get_info().name;
    println!("{} lights, tiled with normal cones on {name}: max error {worst:.1e}", lights.len());
    Ok(())
}
