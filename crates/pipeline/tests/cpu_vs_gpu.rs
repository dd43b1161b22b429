//! The GPU deferred renderer against the CPU reference, and invariants of the shading.

use glam::Vec3;
use pipeline::{
    DEFAULT_AMBIENT,
    cpu::{self, FrameInputs},
    gpu::GpuRenderer,
    psnr,
};
use scene::Light;

/// Expected, actual and difference images of a failed comparison, under cargo's test folder.
fn write_failure(
    name: &str,
    expected: &gbuffer::Image<[f32; 4]>,
    actual: &gbuffer::Image<[f32; 4]>,
) -> String {
    expected.write_comparison(
        actual,
        &std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join(name),
    )
}

fn check(name: &str, scene: &scene::Scene, lights: &[Light], w: u32, h: u32) {
    let Some(gpu) = gpu::test_device(&pipeline::device_needs()) else {
        return;
    };
    let camera = scene.camera_or_framed();
    let expected = cpu::render(&FrameInputs::new(
        scene,
        &camera,
        lights,
        (w, h),
        DEFAULT_AMBIENT,
    ))
    .expect("cpu");
    let mut renderer =
        GpuRenderer::new(&gpu.device, &gpu.queue, scene, lights, w, h).expect("gpu renderer");
    let actual = renderer
        .render(&gpu.device, &gpu.queue, &camera, DEFAULT_AMBIENT)
        .expect("gpu");
    let db = psnr(&expected.image, &actual.image);
    assert!(
        db >= 40.0,
        "{name}: PSNR {db:.1} dB < 40 dB; images in {}",
        write_failure(name, &expected.image, &actual.image)
    );
    assert_eq!(
        actual.timings.len(),
        if gpu.has_timestamps() { 4 } else { 0 }
    );
}

#[test]
fn cornell_box_gpu_matches_cpu() {
    let s = scene::cornell_box();
    check("cornell", &s, &s.lights, 128, 96);
}

#[test]
fn checkerboard_with_all_light_kinds_gpu_matches_cpu() {
    let s = scene::checkerboard();
    let mut lights = s.lights.clone();
    lights.push(
        "spot:0,3,0,0,-1,-0.3,8,15,30,1,1,0.8,6"
            .parse()
            .expect("spot"),
    );
    check("checkerboard", &s, &lights, 160, 90);
}

#[test]
fn many_lights_on_spheres_gpu_matches_cpu() {
    let s = scene::spheres_on_plane(4);
    let lights = scene::scatter_point_lights(s.bounds(), 64, 3);
    check("spheres", &s, &lights, 120, 80);
}

#[test]
fn attenuation_is_exactly_zero_at_and_beyond_the_radius() {
    for r in [0.5f32, 1.0, 7.0] {
        assert_eq!(cpu::distance_attenuation(r, r), 0.0);
        assert_eq!(cpu::distance_attenuation(r * 1.5, r), 0.0);
        assert!(cpu::distance_attenuation(r * 0.99, r) > 0.0);
    }
}

#[test]
fn no_lights_leaves_ambient_and_emission_only() {
    let s = scene::cornell_box();
    let camera = s.camera.expect("camera");
    let out =
        cpu::render(&FrameInputs::new(&s, &camera, &[], (64, 64), Vec3::ZERO)).expect("render");
    // Without lights or ambient, only the emissive light opening is non-black.
    let lit = out.image.pixels().iter().filter(|p| p[0] > 0.0).count();
    let emissive = s
        .materials
        .iter()
        .find(|m| m.name == "light")
        .expect("light")
        .emissive;
    assert!(
        lit > 0
            && out
                .image
                .pixels()
                .iter()
                .all(|p| p[0] == 0.0 || (p[0] - emissive.x).abs() < 1e-6)
    );
}

#[test]
fn energy_is_additive_over_lights() {
    // Rendering lights A and B together equals the sum of A alone and B alone (minus one ambient).
    let s = scene::cornell_box();
    let camera = s.camera.expect("camera");
    let a: Light = "point:0.2,0.4,0.2,1.0,1,0.5,0.2,0.05".parse().expect("a");
    let b: Light = "point:0.4,0.3,0.4,0.8,0.2,0.5,1,0.05".parse().expect("b");
    let render = |l: &[Light]| {
        cpu::render(&FrameInputs::new(&s, &camera, l, (48, 48), Vec3::ZERO))
            .expect("render")
            .image
    };
    let (both, only_a, only_b, none) = (render(&[a, b]), render(&[a]), render(&[b]), render(&[]));
    for i in 0..both.pixels().len() {
        for c in 0..3 {
            let sum = only_a.pixels()[i][c] + only_b.pixels()[i][c] - none.pixels()[i][c];
            assert!(
                (both.pixels()[i][c] - sum).abs() <= 1e-5 * (1.0 + sum.abs()),
                "pixel {i}"
            );
        }
    }
}

/// The whole frame with one-bounce indirect light (fused 4×4, fast 5×5 blur) on the GPU
/// against the CPU frame: ≥ 40 dB, and the indirect passes are timed under their names.
#[test]
fn cornell_box_with_indirect_light_gpu_matches_cpu() {
    use instant_radiosity::{IndirectConfig, vpl};
    let Some(gpu) = gpu::test_device(&pipeline::device_needs()) else {
        return;
    };
    let s = scene::cornell_box();
    let camera = s.camera_or_framed();
    let (w, h) = (96, 72);
    let config = IndirectConfig::new(s.bounds());
    let set = vpl::generate(
        &s,
        &scene::Bvh::build(&s),
        &s.lights,
        &vpl::VplConfig {
            count: 256,
            subsets: config.subsets(),
            seed: 4,
            emissive: false,
            bounces: 1,
        },
    )
    .expect("vpls");
    let inputs = FrameInputs::new(&s, &camera, &s.lights, (w, h), Vec3::ZERO);
    let (expected, _) = cpu::render_indirect(
        &inputs,
        &pipeline::ShadingConfig::default(),
        Some((&config, &set)),
    )
    .expect("cpu");
    let direct_only = cpu::render(&inputs).expect("cpu");
    let mut renderer =
        GpuRenderer::new(&gpu.device, &gpu.queue, &s, &s.lights, w, h).expect("gpu renderer");
    renderer
        .set_indirect(&gpu.device, &config, &set)
        .expect("indirect");
    let actual = renderer
        .render(&gpu.device, &gpu.queue, &camera, Vec3::ZERO)
        .expect("gpu");
    let db = psnr(&expected.image, &actual.image);
    assert!(
        db >= 40.0,
        "PSNR {db:.1} dB < 40 dB; images in {}",
        write_failure("cornell-indirect", &expected.image, &actual.image)
    );
    assert!(
        psnr(&direct_only.image, &actual.image) < 35.0,
        "the indirect light must change the image"
    );
    if gpu.has_timestamps() {
        let names: Vec<&str> = actual.timings.iter().map(|t| t.name.as_str()).collect();
        for stage in ["SNSM", "DB", "B"] {
            assert!(names.contains(&stage), "{stage} not timed: {names:?}");
        }
    }
}
