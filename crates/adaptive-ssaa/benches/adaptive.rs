//! CPU reference timings of the adaptive supersampling stages (the GPU numbers come from
//! `ssaa-bench`).

#![allow(missing_docs)] // criterion_group! generates an undocumented function

use adaptive_ssaa::cpu::{self, ShadingInputs, SsGBuffer};
use adaptive_ssaa::{ArrayLayers, SsaaConfig, SsaaMaterial, TextureArray};
use criterion::{Criterion, criterion_group, criterion_main};

/// A supersampled G-buffer of the checkerboard scene from the GPU when one is present.
fn inputs() -> Option<(
    SsGBuffer,
    gbuffer::Frame,
    f32,
    TextureArray,
    Vec<SsaaMaterial>,
    Vec<tiled_shading::GpuLight>,
)> {
    let gpu = gpu::Gpu::from_env().ok()?;
    let scene = scene::checkerboard();
    let camera = scene.camera_or_framed();
    let config = SsaaConfig::default();
    let (w, h) = (160, 120);
    let lights = tiled_shading::gpu_lights(&scene.lights).ok()?;
    let mut r = adaptive_ssaa::gpu::SsaaRenderer::new(
        &gpu.device,
        &gpu.queue,
        &scene,
        &lights,
        w,
        h,
        &config,
    )
    .ok()?;
    r.set_camera(&gpu.queue, &camera).ok()?;
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    r.encode_gbuffer(&mut encoder, None);
    gpu.queue.submit([encoder.finish()]);
    let gb = r.targets.read(&gpu.device, &gpu.queue).ok()?;
    let frame = gbuffer::Frame::new(&camera, w * config.m, h * config.m);
    Some((
        gb,
        frame,
        camera.far,
        r.textures.read(&gpu.device, &gpu.queue).ok()?,
        SsaaMaterial::of_scene(&scene, &ArrayLayers::new(&scene)),
        lights,
    ))
}

fn bench(c: &mut Criterion) {
    let Some((gb, frame, far, textures, materials, lights)) = inputs() else {
        eprintln!("no GPU adapter to build the G-buffer; skipping");
        return;
    };
    let inp = ShadingInputs {
        gbuffer: &gb,
        frame: &frame,
        far,
        textures: &textures,
        materials: &materials,
        lights: &lights,
    };
    let config = SsaaConfig::default();
    let first = cpu::shade_first(&inp, &config).expect("valid inputs");
    c.bench_function("cpu evaluate ND+shading 4x4 160x120", |b| {
        b.iter(|| cpu::evaluate(&inp, &config, &first).expect("valid inputs"))
    });
    c.bench_function("cpu adaptive 4x4 160x120", |b| {
        b.iter(|| cpu::render(&inp, &config).expect("valid inputs"))
    });
    c.bench_function("cpu full 4x4 160x120", |b| {
        b.iter(|| cpu::shade_full(&inp, &config).expect("valid inputs"))
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
