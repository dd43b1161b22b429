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
    // Trilinear filtering: anisotropic filters are implementation-defined (the G-buffer's
    // tests compare them with supersampling).
    let textures = gbuffer::TextureOptions { max_anisotropy: 1 };
    let expected = cpu::render(
        &FrameInputs::new(scene, &camera, lights, (w, h), DEFAULT_AMBIENT).with_textures(textures),
    )
    .expect("cpu");
    let mut renderer =
        GpuRenderer::new_with(&gpu.device, &gpu.queue, scene, lights, (w, h), &textures)
            .expect("gpu renderer");
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
        for stage in ["SNSM", "DB + B"] {
            assert!(names.contains(&stage), "{stage} not timed: {names:?}");
        }
    }
}

#[test]
fn material_gallery_gpu_matches_cpu() {
    let s = scene::material_gallery();
    check("gallery", &s, &s.lights, 160, 100);
}

/// A quad facing the camera with an occlusion texture (R = 64: ao = 0.251 at strength 1) and
/// an emissive texture (sRGB 128: 0.2158) times the factor (1, 2, 3).
fn occluded_emitting_quad(occlusion: bool) -> scene::Scene {
    use scene::{Material, Mesh, Scene, Texture, TextureRef};
    let texel = |name: &str, v: u8| Texture {
        name: name.into(),
        width: 1,
        height: 1,
        rgba8: vec![v, v, v, 255],
        sampler: Default::default(),
    };
    let corners =
        [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)].map(|(x, y)| Vec3::new(x, y, 0.0));
    let mut mesh = Mesh::quad("quad", corners, 0);
    mesh.uvs = vec![glam::Vec2::ZERO; 4];
    let s = Scene {
        meshes: vec![mesh],
        materials: vec![Material {
            base_color: glam::Vec4::new(0.5, 0.5, 0.5, 1.0),
            specular: 0.0,
            roughness: 1.0,
            occlusion_texture: occlusion.then(|| TextureRef::new(0)),
            emissive_texture: Some(TextureRef::new(1)),
            emissive: Vec3::new(1.0, 2.0, 3.0),
            ..Default::default()
        }],
        textures: vec![texel("occlusion", 64), texel("emission", 128)],
        camera: Some(scene::Camera {
            eye: Vec3::new(0.0, 0.0, 3.0),
            target: Vec3::ZERO,
            up: Vec3::Y,
            fov_y: 0.8,
            near: 0.1,
            far: 10.0,
        }),
        ..Default::default()
    };
    s.validate().expect("valid");
    s
}

/// glTF §3.9.4–3.9.5 in the composition, on the CPU and the GPU: the occlusion texture scales
/// the ambient light only (a directional light's contribution is the same with and without
/// it), and the emissive texture × factor is added.
#[test]
fn occlusion_scales_only_ambient_and_emission_adds() {
    let ambient = Vec3::splat(0.2);
    let ao = 64.0 / 255.0;
    let emission = Vec3::new(1.0, 2.0, 3.0) * scene::srgb_to_linear(128.0 / 255.0);
    let sun: Light = "directional:0,0,-1,1,1,1,1".parse().expect("light");
    let gpu = gpu::test_device(&pipeline::device_needs());
    let centre = |s: &scene::Scene, lights: &[Light], ambient: Vec3| -> Vec<Vec3> {
        let camera = s.camera.expect("camera");
        let pixel = |image: &gbuffer::Image<[f32; 4]>| {
            let p = image.get(16, 16);
            Vec3::new(p[0], p[1], p[2])
        };
        let mut out = vec![pixel(
            &cpu::render(&FrameInputs::new(s, &camera, lights, (32, 32), ambient))
                .expect("cpu")
                .image,
        )];
        if let Some(gpu) = gpu {
            let mut r = GpuRenderer::new(&gpu.device, &gpu.queue, s, lights, 32, 32).expect("gpu");
            out.push(pixel(
                &r.render(&gpu.device, &gpu.queue, &camera, ambient)
                    .expect("gpu")
                    .image,
            ));
        }
        out
    };
    let (occluded, open) = (occluded_emitting_quad(true), occluded_emitting_quad(false));
    for got in centre(&occluded, &[], ambient) {
        // Albedo 128/255; GPUs may decode an sRGB texel within a third of its step (1.5 %
        // of the value at 128): 1 % of the value plus 0.002.
        let want = 128.0 / 255.0 * ambient * ao + emission;
        let tolerance = want * 0.01 + Vec3::splat(2e-3);
        assert!(
            (got - want).abs().cmple(tolerance).all(),
            "ambient: {got} vs {want}"
        );
    }
    for (a, b) in centre(&occluded, &[sun], Vec3::ZERO)
        .into_iter()
        .zip(centre(&open, &[sun], Vec3::ZERO))
    {
        assert!(a.x > emission.x + 0.05, "the light adds: {a}");
        assert!(
            (a - b).abs().max_element() < 1e-3,
            "direct light: {a} vs {b}"
        );
    }
}
