//! The ray-traced reference against what is known without it: an open plane is unoccluded; a
//! point under a parallel plane at height h sees A = (h/r)² (for cosine-weighted directions,
//! cos²θ is uniform, and the plane blocks cos θ ≥ h/r); occlusion grows with the radius.

use glam::{Vec2, Vec3};
use scene::{Camera, Mesh, Scene};
use ssao::{AoConfig, SsaoError, reference::ray_traced};

const SIZE: (u32, u32) = (48, 36);

/// A square of side 2·`half` at height `y`, its normal along `up`.
fn square(y: f32, half: f32, up: f32) -> Mesh {
    let corners = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)];
    let indices = if up > 0.0 {
        vec![0, 2, 1, 0, 3, 2]
    } else {
        vec![0, 1, 2, 0, 2, 3]
    };
    Mesh {
        name: format!("square at {y}"),
        positions: corners
            .iter()
            .map(|&(x, z)| Vec3::new(x * half, y, z * half))
            .collect(),
        normals: vec![Vec3::new(0.0, up, 0.0); 4],
        uvs: vec![Vec2::ZERO; 4],
        indices,
        material: 0,
        ..Default::default()
    }
}

/// A floor (and a ceiling at `ceiling`, if given), seen from above the floor's centre.
fn slab(ceiling: Option<f32>) -> (Scene, Camera) {
    let mut scene = Scene::default();
    scene.materials.push(scene::Material::default());
    scene.meshes.push(square(0.0, 50.0, 1.0));
    if let Some(h) = ceiling {
        scene.meshes.push(square(h, 50.0, -1.0));
    }
    let camera = Camera {
        eye: Vec3::new(0.0, 0.5, 0.0),
        target: Vec3::ZERO,
        up: Vec3::Z,
        fov_y: 60f32.to_radians(),
        near: 0.01,
        far: 10.0,
    };
    (scene, camera)
}

fn accessibility(scene: &Scene, camera: &Camera, radius: f32, samples: u32) -> Vec<f32> {
    let g = gbuffer::cpu::rasterize(scene, camera, SIZE.0, SIZE.1)
        .expect("G-buffer")
        .gbuffer;
    let frame = gbuffer::Frame::new(camera, SIZE.0, SIZE.1);
    let bvh = scene::Bvh::build(scene);
    ray_traced(&bvh, &g, &frame, &AoConfig { radius }, samples)
        .expect("reference")
        .pixels()
        .to_vec()
}

#[test]
fn an_open_plane_is_unoccluded() {
    let (scene, camera) = slab(None);
    let a = accessibility(&scene, &camera, 10.0, 64);
    assert!(a.iter().all(|&v| v == 1.0), "some pixel is occluded");
}

#[test]
fn a_parallel_plane_at_height_h_leaves_h_over_r_squared() {
    let h = 1.0;
    let (scene, camera) = slab(Some(h));
    for (radius, expected) in [(2.0f32, 0.25f32), (4.0, 1.0 / 16.0), (0.5, 1.0)] {
        let a = accessibility(&scene, &camera, radius, 256);
        let mean = a.iter().sum::<f32>() / a.len() as f32;
        let worst = a
            .iter()
            .map(|v| (v - expected).abs())
            .fold(0.0f32, f32::max);
        println!("r {radius}: mean {mean:.4} (exact {expected:.4}), worst pixel off by {worst:.4}");
        assert!((mean - expected).abs() < 0.005, "r {radius}: mean {mean}");
        // Stratified rays: every pixel within 3 % (independent rays: σ ≈ 0.027 at r = 2).
        assert!(worst < 0.03, "r {radius}: a pixel off by {worst}");
    }
}

#[test]
fn occlusion_grows_with_the_radius_and_repeats() {
    let scene = scene::cornell_box();
    let camera = scene.camera_or_framed();
    let radii = [0.05f32, 0.2, 1.0];
    let runs: Vec<Vec<f32>> = radii
        .iter()
        .map(|&r| accessibility(&scene, &camera, r, 64))
        .collect();
    for w in runs.windows(2) {
        // The same rays per pixel: a ray blocked within a radius is blocked within a larger one.
        assert!(w[0].iter().zip(&w[1]).all(|(a, b)| b <= a));
    }
    let mean = |v: &[f32]| v.iter().sum::<f32>() / v.len() as f32;
    assert!(
        mean(&runs[2]) < mean(&runs[0]),
        "a larger radius occludes more"
    );
    assert_eq!(
        runs[1],
        accessibility(&scene, &camera, radii[1], 64),
        "deterministic"
    );
}

#[test]
fn bad_inputs_are_refused() {
    let (scene, camera) = slab(None);
    let g = gbuffer::cpu::rasterize(&scene, &camera, SIZE.0, SIZE.1)
        .expect("G-buffer")
        .gbuffer;
    let bvh = scene::Bvh::build(&scene);
    let frame = gbuffer::Frame::new(&camera, SIZE.0, SIZE.1);
    for radius in [0.0, -1.0, f32::NAN, f32::INFINITY] {
        let e = ray_traced(&bvh, &g, &frame, &AoConfig { radius }, 4).expect_err("radius");
        assert!(matches!(e, SsaoError::InvalidRadius(_)), "{e}");
    }
    let e = ray_traced(&bvh, &g, &frame, &AoConfig { radius: 1.0 }, 0).expect_err("samples");
    assert!(matches!(e, SsaoError::InvalidSamples(0)), "{e}");
    let other = gbuffer::Frame::new(&camera, 40, 30);
    let e = ray_traced(&bvh, &g, &other, &AoConfig { radius: 1.0 }, 4).expect_err("size");
    assert!(e.to_string().contains("(40, 30)"), "{e}");
}
