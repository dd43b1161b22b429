//! CPU reference timings (criterion): the light accumulation of every method on the thesis's
//! test 3 scene (2000 lights, 500 behind the wall) at 320×180. The GPU benchmarks are in
//! `tiled-bench`.
#![allow(missing_docs)] // criterion_group! generates an undocumented function

use criterion::{Criterion, criterion_group, criterion_main};
use tiled_shading::{Method, ShadingConfig, cpu};

fn shade(c: &mut Criterion) {
    let scene = scene::thesis_walls(500);
    let camera = scene.camera.expect("camera");
    let (w, h) = (320, 180);
    let gb = gbuffer::cpu::rasterize(&scene, &camera, w, h)
        .expect("raster")
        .gbuffer;
    let frame = gbuffer::Frame::new(&camera, w, h);
    let lights = tiled_shading::gpu_lights(&scene.lights).expect("lights");
    for method in Method::ALL {
        let config = ShadingConfig {
            method,
            tile_size: 16,
            ..Default::default()
        };
        c.bench_function(&format!("shade {method} test 3 320x180"), |b| {
            b.iter(|| cpu::shade(&gb, &frame, &camera, &lights, &config, None).expect("shade"))
        });
    }
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(10);
    targets = shade
}
criterion_main!(benches);
