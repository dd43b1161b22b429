//! Criterion benches of the CPU reference rasterizer.

#![allow(missing_docs)] // criterion_group! generates an undocumented function

use criterion::{Criterion, criterion_group, criterion_main};

fn rasterize(c: &mut Criterion) {
    let cornell = scene::cornell_box();
    let camera = cornell.camera_or_framed();
    c.bench_function("cpu rasterize cornell 640x480", |b| {
        b.iter(|| gbuffer::cpu::rasterize(&cornell, &camera, 640, 480))
    });
    if let Some(dir) = scene::shared_fixtures()
        && let Ok(sponza) = scene::Scene::load(dir.join("sponza/dabrovic/sponza.gltf"))
    {
        let camera = scene::Camera {
            eye: glam::Vec3::new(-13.0, 2.0, 0.0),
            target: glam::Vec3::new(10.0, 5.0, 0.0),
            up: glam::Vec3::Y,
            fov_y: 60f32.to_radians(),
            near: 0.1,
            far: 60.0,
        };
        c.bench_function("cpu rasterize sponza 960x540", |b| {
            b.iter(|| gbuffer::cpu::rasterize(&sponza, &camera, 960, 540))
        });
    }
}

criterion_group!(benches, rasterize);
criterion_main!(benches);
