//! Each GPU estimator against its CPU twin on the same G-buffer: every method, whole and
//! separable, on the Cornell box and the spheres on a plane, kernels 5, 11, 21 and 31.

use ssao::cpu::{self, KernelConfig};
use ssao::gpu::run;
use ssao::{AoConfig, Estimator, Method, SsaoError};

const SIZE: (u32, u32) = (96, 72);

#[test]
fn gpu_estimators_match_their_cpu_twins() {
    let Some(gpu) = gpu::test_device(&ssao::device_needs()) else {
        return;
    };
    for scene in [scene::cornell_box(), scene::spheres_on_plane(4)] {
        let camera = scene.camera_or_framed();
        let g = gbuffer::cpu::rasterize(&scene, &camera, SIZE.0, SIZE.1)
            .expect("G-buffer")
            .gbuffer;
        let frame = gbuffer::Frame::new(&camera, SIZE.0, SIZE.1);
        let radius = 0.1 * scene.bounds().diagonal();
        // 5, 11 and 21 read workgroup tiles; 31 reads the textures.
        for size in [5, 11, 21, 31] {
            let config = KernelConfig {
                size,
                ao: AoConfig { radius },
            };
            for method in Method::ALL {
                for separable in [false, true] {
                    let e = Estimator::new(method, separable);
                    let unsmoothed = separable.then(|| e.without_smoothing());
                    let variants = [Some(e), Some(e.at_half_resolution()), unsmoothed];
                    for estimator in variants.into_iter().flatten() {
                        let expected = cpu::estimate(&g, &frame, &config, estimator).expect("cpu");
                        let got = run(gpu, &g, &frame, &config, estimator).expect("gpu");
                        let differences: Vec<f32> = got
                            .pixels()
                            .iter()
                            .zip(expected.pixels())
                            .map(|(a, b)| (a - b).abs())
                            .collect();
                        // GTAO's acos and cos are looser on GPUs (Vulkan lets acos err by 4096 ULP
                        // of atan): 1e-3 there.
                        let tolerance = if method == Method::Gtao { 1e-3 } else { 1e-4 };
                        let off = differences.iter().filter(|&&d| d > tolerance).count();
                        let worst = differences.iter().copied().fold(0.0f32, f32::max);
                        println!(
                            "{estimator} k {size}: {off} pixels off by more than {tolerance:e}, worst {worst:.2e}"
                        );
                        // Rounding may put a neighbour on the other side of the radius or a surface test:
                        // at most 0.5 % of the pixels.
                        assert!(
                            off * 200 <= differences.len(),
                            "{estimator} k {size}: {off} pixels off"
                        );
                    }
                }
            }
        }
    }
}

#[test]
fn bad_bindings_are_refused() {
    let Some(gpu) = gpu::test_device(&ssao::device_needs()) else {
        return;
    };
    let scene = scene::cornell_box();
    let camera = scene.camera_or_framed();
    let g = gbuffer::cpu::rasterize(&scene, &camera, 32, 24)
        .expect("G-buffer")
        .gbuffer;
    let frame = gbuffer::Frame::new(&camera, 32, 24);
    let even = KernelConfig {
        size: 4,
        ao: AoConfig { radius: 1.0 },
    };
    let separable: Estimator = "filter-separable".parse().expect("name");
    let e = run(gpu, &g, &frame, &even, separable).expect_err("even kernel");
    assert!(matches!(e, SsaoError::InvalidKernel(4)), "{e}");
    let other = gbuffer::Frame::new(&camera, 16, 12);
    let fine = KernelConfig { size: 5, ..even };
    let e = run(gpu, &g, &other, &fine, separable).expect_err("size");
    assert!(matches!(e, SsaoError::SizeMismatch { .. }), "{e}");
}
