//! Screen-space ambient occlusion as a stage of the frame (`GpuRenderer::set_ssao`): it scales
//! the ambient light by each pixel's accessibility and leaves the direct and emitted light
//! alone.

use glam::Vec3;
use pipeline::gpu::GpuRenderer;
use ssao::cpu::KernelConfig;
use ssao::{Estimator, Method};

const SIZE: (u32, u32) = (64, 48);

#[test]
fn ssao_scales_the_ambient_light_and_not_the_direct_light() {
    let Some(gpu) = gpu::test_device(&pipeline::device_needs()) else {
        return;
    };
    let (d, q) = (&gpu.device, &gpu.queue);
    let scene = scene::cornell_box();
    let camera = scene.camera_or_framed();
    let config = KernelConfig {
        size: 11,
        ao: ssao::AoConfig {
            radius: 0.1 * scene.bounds().diagonal(),
        },
    };
    // The paper's separable filter and the two horizon methods, whole and separable.
    let estimators = [Method::Filter, Method::Hbao, Method::Gtao]
        .into_iter()
        .flat_map(|method| [false, true].map(|separable| Estimator::new(method, separable)));
    for estimator in estimators {
        // Ambient light only: every pixel's radiance is scaled by its accessibility.
        // (The ceiling light's emission is not ambient light: it is subtracted first.)
        let mut r = GpuRenderer::new(d, q, &scene, &[], SIZE.0, SIZE.1).expect("renderer");
        let emitted = r.render(d, q, &camera, Vec3::ZERO).expect("frame").image;
        let plain = r
            .render(d, q, &camera, Vec3::splat(0.5))
            .expect("frame")
            .image;
        r.set_ssao(d, q, Some((&config, estimator))).expect("ssao");
        let occluded = r
            .render(d, q, &camera, Vec3::splat(0.5))
            .expect("frame")
            .image;
        let a: Vec<f32> = gpu::transfer::read_pod(d, q, r.ssao_accessibility().expect("ssao"))
            .expect("accessibility");
        let mut darker = 0;
        let pixels = plain.pixels().iter().zip(occluded.pixels());
        for (((p, o), e), a) in pixels.zip(emitted.pixels()).zip(&a) {
            for k in 0..3 {
                assert!(
                    ((p[k] - e[k]) * a - (o[k] - e[k])).abs() <= 1e-5 + 1e-4 * p[k],
                    "{estimator}: {p:?} × {a} vs {o:?}"
                );
            }
            darker += usize::from(*a < 0.95);
        }
        assert!(darker > 50, "{estimator}: only {darker} pixels occluded");
        // Direct light only: unchanged.
        let mut r =
            GpuRenderer::new(d, q, &scene, &scene.lights, SIZE.0, SIZE.1).expect("renderer");
        let lit = r.render(d, q, &camera, Vec3::ZERO).expect("frame").image;
        r.set_ssao(d, q, Some((&config, estimator))).expect("ssao");
        let still_lit = r.render(d, q, &camera, Vec3::ZERO).expect("frame").image;
        assert_eq!(
            lit.pixels(),
            still_lit.pixels(),
            "{estimator}: direct light changed"
        );
    }
}
