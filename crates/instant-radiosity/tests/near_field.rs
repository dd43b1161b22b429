//! The VPLs' near field (Kollig & Keller 2004's bias compensation): the GPU kernel against
//! its CPU twin, and the estimator's invariants. Its effect against the path tracer is tested
//! with the progressive mode (`pipeline/tests/progressive.rs`).

use gbuffer::{Frame, Image};
use glam::Vec3;
use half::f16;
use instant_radiosity::near_field::{
    NearField, NearFieldInputs, NearFieldParams, near_field, near_field_image, triangle_albedos,
};
use instant_radiosity::vpl;
use scene::Bvh;
use tiled_shading::{GpuLight, rays::RayBvh, rays::scene_mesh};

mod common;

fn luminance(p: &[f32; 4]) -> f64 {
    f64::from(0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2])
}

/// The Cornell box at 64×48 with 256 VPLs (64 light each hit) and a clamp of 10 % of its diagonal
/// (many receivers have a surface within it): GPU and CPU agree pixel for pixel, frame after
/// frame (each `set_vpls` draws another sample), and the near field lights the receivers
/// near another surface — the box's corners — not the open floor.
#[test]
fn gpu_near_field_matches_its_cpu_twin() {
    let Some(gpu) = gpu::test_device(&instant_radiosity::device_needs()) else {
        return;
    };
    let (d, q) = (&gpu.device, &gpu.queue);
    let (w, h) = (64, 48);
    let scene = scene::cornell_box();
    let camera = scene.camera_or_framed();
    let gb = gbuffer::cpu::rasterize(&scene, &camera, w, h)
        .expect("G-buffer")
        .gbuffer;
    let frame = Frame::new(&camera, w, h);
    let set = vpl::generate_from_primary(&scene, &Bvh::build(&scene), 256, 4, 3).expect("vpls");
    let lights: Vec<GpuLight> = scene.lights.iter().map(GpuLight::from).collect();
    assert!(!lights.is_empty(), "the Cornell box has a light");
    let clamp = 0.1 * scene.bounds().diagonal();

    let uploaded = gbuffer::gpu::UploadedGBuffer::new(d, q, &gb, &frame).expect("gb");
    let kernel = NearField::new(d, &scene).expect("near field");
    let output = gpu::transfer::texture_2d(
        d,
        "near field",
        w,
        h,
        interleave::gpu::IRRADIANCE_FORMAT,
        gpu::transfer::STORAGE_ANY,
    );
    let mut bound = kernel
        .bind(
            d,
            &uploaded.frame,
            uploaded.textures(),
            &lights,
            &set,
            clamp,
            &output,
        )
        .expect("bind");
    let (positions, indices) = scene_mesh(&scene);
    let bvh = RayBvh::new((&positions, &indices)).expect("bvh");
    let albedos = triangle_albedos(&scene);
    let gpu_vpls = set.gpu();
    for sample in 0..2 {
        if sample > 0 {
            bound.set_vpls(q, &set).expect("next sample");
        }
        let mut encoder = d.create_command_encoder(&Default::default());
        bound.encode(&mut encoder, None);
        q.submit([encoder.finish()]);
        let got: Image<[f32; 4]> = interleave::gpu::download_image::<[f16; 4]>(d, q, &output)
            .expect("read")
            .map(|p| p.map(f16::to_f32));
        let inputs = NearFieldInputs {
            bvh: &bvh,
            albedos: &albedos,
            lights: &lights,
            vpls: &gpu_vpls,
            params: bound.params(),
        };
        assert_eq!(inputs.params.seed, sample);
        let want = near_field_image(&gb, &frame, &inputs);
        // A ray through an edge, or a shadow ray grazing one, may go either way.
        let (g, c) = (got.pixels(), want.pixels());
        let close = common::agreeing_pixels(g, c);
        let lit = c.iter().filter(|p| luminance(p) > 0.0).count();
        println!(
            "sample {sample}: {close} of {} pixels agree, {lit} lit",
            g.len()
        );
        assert!(
            close as f64 >= 0.99 * g.len() as f64,
            "{close} of {}",
            g.len()
        );
        assert!(
            lit > g.len() / 50 && lit < g.len() / 2,
            "{lit} of {} lit",
            g.len()
        );
    }
}

/// Invariants of the estimator at one receiver: nothing without a clamp or without a surface
/// within it; with a wall at distance h ≪ c straight ahead, the mean of many samples
/// approaches what a Lambertian wall of radiance L gives: `L ∫ cos θ (1 − d²/c²) dω / π`
/// (d = h / cos θ), computed here by quadrature.
#[test]
fn near_field_integrates_the_clamped_away_light() {
    // A floor lit by a directional light (irradiance 1) and a receiver facing it from h.
    let mut scene = scene::Scene::default();
    let s = 10.0;
    scene.meshes.push(scene::Mesh::quad(
        "floor",
        [
            Vec3::new(-s, 0.0, -s),
            Vec3::new(-s, 0.0, s),
            Vec3::new(s, 0.0, s),
            Vec3::new(s, 0.0, -s),
        ],
        0,
    ));
    scene.materials.push(scene::Material {
        base_color: glam::Vec4::new(0.5, 0.5, 0.5, 1.0),
        ..Default::default()
    });
    let (positions, indices) = scene_mesh(&scene);
    let bvh = RayBvh::new((&positions, &indices)).expect("bvh");
    let albedos = triangle_albedos(&scene);
    let sun = GpuLight::from(&scene::Light::Directional {
        direction: Vec3::NEG_Y,
        color: Vec3::ONE,
        intensity: 1.0,
    });
    let no_vpl = vpl::GpuVpl::from(&vpl::Vpl {
        position: Vec3::new(0.0, -100.0, 0.0),
        normal: Vec3::NEG_Y,
        flux: Vec3::ZERO,
    });
    let (c, h) = (1.0f32, 0.1f32);
    let params = |seed, clamp: f32| NearFieldParams {
        clamp_squared: clamp * clamp,
        samples: 1,
        vpls: 1,
        seed,
        reach: 100.0,
        lights: 1,
        _pad: [0; 2],
    };
    let inputs = |seed, clamp| NearFieldInputs {
        bvh: &bvh,
        albedos: &albedos,
        lights: std::slice::from_ref(&sun),
        vpls: std::slice::from_ref(&no_vpl),
        params: params(seed, clamp),
    };
    let p = Vec3::new(0.0, h, 0.0);
    // No clamp, nothing taken away; facing away from the floor, nothing within reach.
    assert_eq!(
        near_field(&inputs(1, 0.0), p, Vec3::NEG_Y, (0, 0)),
        Vec3::ZERO
    );
    for seed in 0..64 {
        assert_eq!(near_field(&inputs(seed, c), p, Vec3::Y, (3, 5)), Vec3::ZERO);
    }
    // The floor's radiance: ρ/π · E, E = 1 (the sun straight above, the receiver's own
    // shadow aside: it has no geometry).
    let radiance = 0.5 / std::f64::consts::PI;
    // E_lost/π = L/π ∫ cos θ (1 − h²/(c² cos² θ))⁺ dω over θ < acos(h/c).
    let cos_min = f64::from(h / c);
    let steps = 100_000;
    let mut integral = 0.0;
    for i in 0..steps {
        let mu = cos_min + (1.0 - cos_min) * (i as f64 + 0.5) / steps as f64;
        integral += mu * (1.0 - f64::from(h * h) / (f64::from(c * c) * mu * mu));
    }
    integral *= 2.0 * std::f64::consts::PI * (1.0 - cos_min) / steps as f64;
    let want = radiance * integral / std::f64::consts::PI;
    let n = 40_000;
    let mean: f64 = (0..n)
        .map(|i| f64::from(near_field(&inputs(i, c), p, Vec3::NEG_Y, (i % 7, i / 7)).x))
        .sum::<f64>()
        / f64::from(n);
    println!("near field {mean:.5} vs quadrature {want:.5}");
    // 8-bit albedo and the sample mean's noise (≈ 0.5 %).
    assert!((mean / want - 1.0).abs() < 0.02, "{mean} vs {want}");
}

/// Ground truth on a corner: a black floor meeting a grey wall (both 40 units), a sun that
/// lights the wall; a floor point at h from the wall sees the wall over half its hemisphere, so
/// its one-bounce irradiance is exactly `L_wall · π/2` (whatever h, up to the walls' finite
/// size). The clamped VPL estimator (mean of many sets) falls short by about the near field;
/// with the near field added the mean is within a few per cent of the truth.
#[test]
fn clamped_vpls_plus_near_field_light_a_corner_as_the_analytic_truth() {
    let mut scene = scene::Scene::default();
    let s = 20.0;
    scene.meshes.push(scene::Mesh::quad(
        "floor",
        [
            Vec3::new(0.0, 0.0, -s),
            Vec3::new(0.0, 0.0, s),
            Vec3::new(2.0 * s, 0.0, s),
            Vec3::new(2.0 * s, 0.0, -s),
        ],
        0,
    ));
    scene.meshes.push(scene::Mesh::quad(
        "wall",
        [
            Vec3::new(0.0, 0.0, -s),
            Vec3::new(0.0, 2.0 * s, -s),
            Vec3::new(0.0, 2.0 * s, s),
            Vec3::new(0.0, 0.0, s),
        ],
        1,
    ));
    scene.materials.push(scene::Material {
        base_color: glam::Vec4::new(0.0, 0.0, 0.0, 1.0),
        ..Default::default()
    });
    scene.materials.push(scene::Material {
        base_color: glam::Vec4::new(0.5, 0.5, 0.5, 1.0),
        ..Default::default()
    });
    let sun_dir = Vec3::new(-1.0, -1.0, 0.0).normalize();
    scene.lights.push(scene::Light::Directional {
        direction: sun_dir,
        color: Vec3::ONE,
        intensity: 1.0,
    });
    // The wall's radiance: ρ/π · E, E = cos 45°.
    let l_wall = 0.5 / std::f64::consts::PI * f64::from(-sun_dir.x);
    let want = l_wall * 0.5; // E/π at the floor point: L_wall · (π/2) / π.
    let bvh = Bvh::build(&scene);
    let (positions, indices) = scene_mesh(&scene);
    let rays = RayBvh::new((&positions, &indices)).expect("bvh");
    let albedos = triangle_albedos(&scene);
    let lights: Vec<GpuLight> = scene.lights.iter().map(GpuLight::from).collect();
    let (h, c) = (0.01f32, 0.5f32);
    let (p, n) = (Vec3::new(h, 0.0, 0.0), Vec3::Y);
    let (mut vpl_sum, mut near_sum) = (0.0, 0.0);
    let sets = 400;
    for seed in 0..sets {
        let set = vpl::generate(
            &scene,
            &bvh,
            &scene.lights,
            &vpl::VplConfig {
                count: 1024,
                subsets: 1,
                seed,
                emissive: false,
                bounces: 1,
            },
        )
        .expect("vpls");
        let gpu_vpls = set.gpu();
        for v in &gpu_vpls {
            let (intensity, l) = instant_radiosity::cpu::vpl_intensity(v, p, c * c);
            let q = (Vec3::from(v.position), Vec3::from(v.normal));
            let seen = instant_radiosity::rays::visibility(&rays, (p, n), q, 1.0);
            vpl_sum += f64::from((intensity * n.dot(l).max(0.0) * seen).x) / std::f64::consts::PI;
        }
        let inputs = NearFieldInputs {
            bvh: &rays,
            albedos: &albedos,
            lights: &lights,
            vpls: &gpu_vpls,
            params: NearFieldParams {
                clamp_squared: c * c,
                samples: 64,
                vpls: 1024,
                seed: seed as u32,
                reach: 200.0,
                lights: 1,
                _pad: [0; 2],
            },
        };
        for k in 0..64 {
            near_sum += f64::from(near_field(&inputs, p, n, (k, 0)).x) / 64.0;
        }
    }
    let (vpls, near) = (vpl_sum / sets as f64, near_sum / sets as f64);
    println!(
        "corner: truth {want:.5}; clamped VPLs {vpls:.5} ({:+.1} %), + near field {near:.5} → {:.5} ({:+.1} %)",
        100.0 * (vpls / want - 1.0),
        vpls + near,
        100.0 * ((vpls + near) / want - 1.0)
    );
    assert!(
        vpls < 0.9 * want,
        "the clamp takes light away: {vpls} vs {want}"
    );
    assert!(
        ((vpls + near) / want - 1.0).abs() < 0.05,
        "{} vs {want}",
        vpls + near
    );
}
