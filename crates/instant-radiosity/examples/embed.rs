//! `instant-radiosity` inside an application that owns its wgpu device: one-bounce indirect
//! light of the Cornell box from 256 VPLs, interleaved 4×4 and blurred, recorded into the
//! application's encoder over the application's G-buffer, checked against the CPU reference.
//!
//! The application creates its own device: wgpu's default limits plus what the crate states
//! it needs (`device_needs()`).

use instant_radiosity::{IndirectConfig, gpu::IndirectStage, vpl};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let adapter =
        pollster::block_on(wgpu::Instance::default().request_adapter(&Default::default()))?;
    let descriptor = instant_radiosity::device_needs().descriptor();
    let (device, queue) = pollster::block_on(adapter.request_device(&descriptor))?;

    // The application's G-buffer: here the Cornell box rasterized on the CPU and uploaded.
    let (scene, (width, height)) = (scene::cornell_box(), (96, 72));
    let camera = scene.camera_or_framed();
    let gb = gbuffer::cpu::rasterize(&scene, &camera, width, height)?.gbuffer;
    let frame = gbuffer::Frame::new(&camera, width, height);
    let uploaded = gbuffer::gpu::UploadedGBuffer::new(&device, &queue, &gb, &frame)?;
    let config = IndirectConfig::new(scene.bounds());
    let vpls = vpl::VplConfig {
        count: 256,
        subsets: config.subsets(),
        seed: 1,
        emissive: false,
        bounces: 1,
    };
    let set = vpl::generate(&scene, &scene::Bvh::build(&scene), &scene.lights, &vpls)?;

    // new: pipelines once; bind: the caller's G-buffer, VPLs and outputs; encode: only records.
    let stage = IndirectStage::new(&device, &config, (width, height))?;
    let outputs = stage.output_textures(&device);
    let textures = uploaded.textures();
    let bound = stage.bind(&device, &uploaded.frame, textures, &set, None, outputs.each_ref())?;
    let mut encoder = device.create_command_encoder(&Default::default());
    stage.encode(&bound, &mut encoder, None);
    queue.submit([encoder.finish()]);

    let gpu = bound.read(&device, &queue)?;
    let cpu = instant_radiosity::cpu::indirect(&gb, &frame, &set, &config)?;
    let db = gbuffer::psnr(cpu.result().0, gpu.result().0);
    assert!(db > 50.0, "GPU indirect light differs from the CPU reference: {db:.1} dB");
    println!("indirect light of 256 VPLs on {}: {db:.1} dB", adapter.get_info().name);
    Ok(())
}
