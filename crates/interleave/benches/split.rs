//! CPU reference timings (criterion): split and gather of a 1920×1080 r32 image, pattern 4×4,
//! and the 7×7 blur. The GPU benchmarks are in `interleave-bench`.
#![allow(missing_docs)] // criterion_group! generates an undocumented function

use criterion::{Criterion, criterion_group, criterion_main};
use gbuffer::Image;
use interleave::{Block, Blur, BlurVariant, Pattern, SplitLayout, SplitVariant, Thresholds, cpu};

fn split_gather(c: &mut Criterion) {
    let (w, h) = (1920, 1080);
    let pattern = Pattern { n: 4, m: 4 };
    let layout = SplitLayout::new(w, h, pattern).expect("layout");
    let image = Image::from_vec(w, h, (0..w * h).collect::<Vec<u32>>()).expect("image");
    for variant in [
        SplitVariant::OnePass,
        SplitVariant::TwoPass(Block::default()),
        SplitVariant::Tiled,
    ] {
        c.bench_function(&format!("split {} 1080p 4x4", variant.name()), |b| {
            b.iter(|| cpu::split(&image, &layout, variant).expect("split"))
        });
        let split = cpu::split(&image, &layout, variant).expect("split");
        c.bench_function(&format!("gather {} 1080p 4x4", variant.name()), |b| {
            b.iter(|| cpu::gather(&split, &layout, variant).expect("gather"))
        });
    }
}

fn blur(c: &mut Criterion) {
    let scene = scene::spheres_on_plane(16);
    let gb = gbuffer::cpu::rasterize(&scene, &scene.camera_or_framed(), 640, 480)
        .expect("raster")
        .gbuffer;
    let disc =
        cpu::discontinuity(&gb.linear_depth, &gb.normal, &Thresholds::default()).expect("disc");
    let irradiance = Image::filled(640, 480, [0.5f32, 0.25, 0.125, 1.0]);
    for variant in [BlurVariant::Plain, BlurVariant::Fast] {
        let blur = Blur::new(7, variant).expect("blur");
        c.bench_function(&format!("blur 7x7 {variant:?} 640x480"), |b| {
            b.iter(|| cpu::blur(&irradiance, &disc, &blur).expect("blur"))
        });
    }
}

criterion_group!(benches, split_gather, blur);
criterion_main!(benches);
