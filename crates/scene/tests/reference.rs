//! The path-traced ground truth against analytic answers: the furnace (a closed, uniformly
//! emitting Lambertian box), direct light from a point light, a shadow, convergence as
//! 1/√spp, and determinism.

use glam::{Vec3, Vec4};
use scene::reference::{PathTracer, ReferenceConfig};
use scene::{Camera, Light, Material, Mesh, Scene};

fn material(albedo: f32, emissive: f32) -> Material {
    Material {
        name: "m".into(),
        base_color: Vec4::new(albedo, albedo, albedo, 1.0),
        base_color_texture: None,
        roughness: 1.0,
        metallic: 0.0,
        emissive: Vec3::splat(emissive),
        specular: 1.0,
        ..Default::default()
    }
}

/// The six inward-facing faces of the cube [−1, 1]³.
fn closed_box(material: u32) -> Vec<Mesh> {
    let mut faces = Vec::new();
    for axis in 0..3 {
        for sign in [-1.0f32, 1.0] {
            let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
            let corner = |a: f32, b: f32| {
                let mut p = [0.0; 3];
                p[axis] = sign;
                p[u] = a;
                p[v] = b;
                Vec3::from(p)
            };
            let mut c = [
                corner(-1., -1.),
                corner(1., -1.),
                corner(1., 1.),
                corner(-1., 1.),
            ];
            // Inward: the winding's normal points to the centre.
            if (c[1] - c[0]).cross(c[2] - c[0]).dot(-c[0]) < 0.0 {
                c.reverse();
            }
            faces.push(Mesh::quad("wall", c, material));
        }
    }
    faces
}

fn mean(image: &[Vec3]) -> f32 {
    image.iter().map(|c| c.x).sum::<f32>() / image.len() as f32
}

#[test]
fn the_furnace_converges_to_the_geometric_series() {
    // Walls of albedo ρ emitting Le: with B bounces the eye sees Le·(1 + ρ + … + ρ^(B+1)),
    // and Le / (1 − ρ) without a limit.
    let (rho, le) = (0.5f32, 1.0f32);
    let scene = Scene {
        meshes: closed_box(0),
        materials: vec![material(rho, le)],
        ..Default::default()
    };
    let mut camera = Camera::look_at(Vec3::ZERO, Vec3::Z);
    camera.fov_y = 60f32.to_radians();
    for (bounces, expected) in [
        (0, 1.0 + rho),
        (2, 1.0 + rho + rho * rho + rho * rho * rho),
        (200, 1.0 / (1.0 - rho)),
    ] {
        let config = ReferenceConfig {
            max_bounces: bounces,
            specular: false,
            ..Default::default()
        };
        let mut pt = PathTracer::new(&scene, camera, 16, 16, &[], config);
        // Russian roulette beyond three bounces is noisier: more samples there.
        pt.add_samples(if bounces > 2 { 256 } else { 64 });
        let image = pt.image();
        let m = mean(&image) * le;
        assert!(
            (m - expected).abs() / expected < 0.01,
            "{bounces} bounces: mean {m}, expected {expected}"
        );
        let worst = image
            .iter()
            .map(|c| (c.x - expected).abs() / expected)
            .fold(0.0, f32::max);
        assert!(worst < 0.12, "{bounces} bounces: a pixel is off by {worst}");
    }
}

/// A 20 × 20 floor (albedo 0.5) at y = 0, a point light at height 2, a camera at height 1
/// looking straight down with a 2° field of view; an optional occluder at height 1.5.
fn floor_scene(occluder: bool) -> (Scene, Camera, Light) {
    let e = 10.0;
    let mut meshes = vec![Mesh::quad(
        "floor",
        [
            Vec3::new(-e, 0.0, -e),
            Vec3::new(-e, 0.0, e),
            Vec3::new(e, 0.0, e),
            Vec3::new(e, 0.0, -e),
        ],
        0,
    )];
    if occluder {
        let o = 0.5;
        meshes.push(Mesh::quad(
            "occluder",
            [
                Vec3::new(-o, 1.5, -o),
                Vec3::new(-o, 1.5, o),
                Vec3::new(o, 1.5, o),
                Vec3::new(o, 1.5, -o),
            ],
            0,
        ));
    }
    let scene = Scene {
        meshes,
        materials: vec![material(0.5, 0.0)],
        ..Default::default()
    };
    let mut camera = Camera::look_at(Vec3::new(0.0, 1.0, 0.0), Vec3::ZERO);
    camera.fov_y = 2f32.to_radians();
    let light = Light::Point {
        position: Vec3::new(0.0, 2.0, 0.0),
        color: Vec3::ONE,
        intensity: 10.0,
        radius: 100.0,
    };
    (scene, camera, light)
}

#[test]
fn direct_light_from_a_point_light_is_the_analytic_value_and_is_shadowed() {
    let direct = ReferenceConfig {
        max_bounces: 0,
        specular: false,
        ..Default::default()
    };
    let (scene, camera, light) = floor_scene(false);
    let mut pt = PathTracer::new(&scene, camera, 8, 8, &[light], direct);
    pt.add_samples(4);
    // L = ρ/π · I · (1 − (d/r)⁴)² / d² · cos θ at the foot of the light (d = 2, cos θ ≈ 1).
    let window = (1.0f32 - (2.0f32 / 100.0).powi(4)).powi(2);
    let expected = 0.5 / std::f32::consts::PI * 10.0 * window / 4.0;
    let m = mean(&pt.image());
    assert!((m - expected).abs() / expected < 2e-3, "{m} vs {expected}");
    // The occluder between the light and the floor leaves it black (direct light only).
    let (scene, camera, light) = floor_scene(true);
    let mut camera = camera;
    camera.eye = Vec3::new(0.0, 1.0, 0.0);
    let mut pt = PathTracer::new(&scene, camera, 8, 8, &[light], direct);
    pt.add_samples(4);
    assert_eq!(mean(&pt.image()), 0.0, "the shadowed floor is lit");
    // One bounce: light the occluder's top reflects reaches nothing below it (its underside
    // is lit only by the floor, which is dark under it), but the floor around it lights the
    // occluder's underside, which lights the floor: no longer zero.
    let mut pt = PathTracer::new(
        &scene,
        camera,
        8,
        8,
        &[light],
        ReferenceConfig {
            max_bounces: 2,
            ..direct
        },
    );
    pt.add_samples(64);
    assert!(mean(&pt.image()) > 0.0);
}

fn rms(a: &[Vec3], b: &[Vec3]) -> f64 {
    let s: f64 = a
        .iter()
        .zip(b)
        .map(|(x, y)| f64::from((*x - *y).length_squared()))
        .sum();
    (s / a.len() as f64).sqrt()
}

#[test]
fn error_falls_as_one_over_the_square_root_of_the_samples() {
    let scene = scene::cornell_box();
    let camera = scene.camera_or_framed();
    let lights = scene.lights.clone();
    let run = |spp: u32, seed: u64| {
        let config = ReferenceConfig {
            seed,
            ..Default::default()
        };
        let mut pt = PathTracer::new(&scene, camera, 24, 24, &lights, config);
        pt.add_samples(spp);
        pt.image()
    };
    let truth = run(1024, 99);
    let (e16, e64) = (rms(&run(16, 1), &truth), rms(&run(64, 1), &truth));
    let ratio = e16 / e64;
    assert!(
        (1.6..2.6).contains(&ratio),
        "RMS 16 spp {e16}, 64 spp {e64}: ratio {ratio}"
    );
}

#[test]
fn the_same_seed_gives_the_same_image_progressively() {
    let scene = scene::cornell_box();
    let camera = scene.camera_or_framed();
    let config = ReferenceConfig::default();
    let mut once = PathTracer::new(&scene, camera, 16, 16, &scene.lights, config);
    once.add_samples(8);
    let mut twice = PathTracer::new(&scene, camera, 16, 16, &scene.lights, config);
    twice.add_samples(3);
    twice.add_samples(5);
    assert_eq!(once.image(), twice.image());
    assert_eq!(twice.samples(), 8);
    let mut other = PathTracer::new(
        &scene,
        camera,
        16,
        16,
        &scene.lights,
        ReferenceConfig { seed: 2, ..config },
    );
    other.add_samples(8);
    assert_ne!(once.image(), other.image());
}

/// `min_bounces` splits the image without changing the random sequence: with one seed, all
/// light up to one bounce is the direct light plus the one-bounce light alone, pixel for pixel
/// (up to the order of the f32 sums); the one-bounce part holds none of the lamp's own view.
#[test]
fn min_bounces_splits_direct_and_indirect_light() {
    let scene = scene::cornell_box();
    let camera = scene.camera_or_framed();
    let render = |min_bounces, max_bounces| {
        let config = ReferenceConfig {
            min_bounces,
            max_bounces,
            ..Default::default()
        };
        let mut pt = PathTracer::new(&scene, camera, 24, 24, &scene.lights, config);
        pt.add_samples(4);
        pt.image()
    };
    let (all, direct, indirect) = (render(0, 1), render(0, 0), render(1, 1));
    let mut brightest_direct = 0.0f32;
    for (i, ((a, d), n)) in all.iter().zip(&direct).zip(&indirect).enumerate() {
        let sum = *d + *n;
        assert!(
            (*a - sum).abs().max_element() <= 1e-4 * a.max_element().max(1.0),
            "pixel {i}: {a} vs {d} + {n}"
        );
        brightest_direct = brightest_direct.max(d.max_element());
    }
    let (mean_all, mean_indirect) = (mean(&all), mean(&indirect));
    assert!(
        mean_indirect > 0.05 * mean_all,
        "{mean_indirect} of {mean_all}"
    );
    // The lamp seen directly is the brightest thing in the direct image, absent from the
    // indirect one.
    let brightest_indirect = indirect.iter().map(|c| c.max_element()).fold(0.0, f32::max);
    assert!(
        brightest_indirect < 0.5 * brightest_direct,
        "{brightest_indirect} vs {brightest_direct}"
    );
}
