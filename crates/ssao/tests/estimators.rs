//! The screen-space estimators: their invariants, and their error against the ray-traced
//! reference.

use glam::{Vec2, Vec3};
use scene::{Camera, Scene};
use ssao::cpu::{self, KernelConfig};
use ssao::{AoConfig, reference};

const SIZE: (u32, u32) = (96, 72);

fn gbuffer(scene: &Scene, camera: &Camera) -> (gbuffer::GBuffer, gbuffer::Frame) {
    let g = gbuffer::cpu::rasterize(scene, camera, SIZE.0, SIZE.1)
        .expect("G-buffer")
        .gbuffer;
    (g, gbuffer::Frame::new(camera, SIZE.0, SIZE.1))
}

fn config(size: u32, radius: f32) -> KernelConfig {
    KernelConfig {
        size,
        ao: AoConfig { radius },
    }
}

#[test]
fn an_open_plane_has_no_occlusion() {
    let mut scene = Scene::default();
    scene.materials.push(scene::Material::default());
    scene.meshes.push(scene::Mesh {
        name: "plane".into(),
        positions: [(-5.0, -5.0), (5.0, -5.0), (5.0, 5.0), (-5.0, 5.0)]
            .map(|(x, z)| Vec3::new(x, 0.0, z))
            .to_vec(),
        normals: vec![Vec3::Y; 4],
        uvs: vec![Vec2::ZERO; 4],
        indices: vec![0, 2, 1, 0, 3, 2],
        material: 0,
        ..Default::default()
    });
    let camera = Camera {
        eye: Vec3::new(0.3, 2.0, 2.0),
        target: Vec3::ZERO,
        ..scene.camera_or_framed()
    };
    let (g, frame) = gbuffer(&scene, &camera);
    for k in [5, 11] {
        for image in [
            cpu::kernel_2d(&g, &frame, &config(k, 1.0)).expect("2D"),
            cpu::separable(&g, &frame, &config(k, 1.0)).expect("separable"),
        ] {
            let least = image.pixels().iter().copied().fold(1.0f32, f32::min);
            assert!(least > 0.999, "k {k}: A {least} on an open plane");
        }
    }
}

#[test]
fn occlusion_is_monotone_in_the_radius() {
    let scene = scene::cornell_box();
    let (g, frame) = gbuffer(&scene, &scene.camera_or_framed());
    let small = cpu::kernel_2d(&g, &frame, &config(11, 0.1)).expect("small");
    let large = cpu::kernel_2d(&g, &frame, &config(11, 0.4)).expect("large");
    assert!(
        small
            .pixels()
            .iter()
            .zip(large.pixels())
            .all(|(a, b)| b <= a),
        "a larger radius never unoccludes"
    );
    assert!(large.pixels().iter().sum::<f32>() < small.pixels().iter().sum::<f32>());
}

/// Pass 1 along the image's x axis is eq. 7.1 restricted to the pixel's row.
#[test]
fn pass_1d_along_x_is_the_row_of_the_2d_kernel() {
    let scene = scene::cornell_box();
    let (g, frame) = gbuffer(&scene, &scene.camera_or_framed());
    let c = config(7, 0.3);
    let row = cpu::pass_1d(&g, &frame, &c, |_, _| Vec2::X).expect("pass 1");
    let position = |x: u32, y: u32| {
        let d = g.linear_depth.get(x, y);
        (d > 0.0).then(|| gbuffer::position::from_view_ray(&frame, x, y, d))
    };
    for (x, y) in [(40u32, 30u32), (10, 60), (80, 20), (48, 36)] {
        let Some(p) = position(x, y) else { continue };
        let n = gbuffer::normal::unpack_octahedral(g.normal.get(x, y));
        let mut sum = 0.0;
        for dx in [-3i32, -2, -1, 1, 2, 3] {
            let qx = x as i32 + dx;
            if qx < 0 || qx >= SIZE.0 as i32 {
                continue;
            }
            if let Some(q) = position(qx as u32, y) {
                let v = q - p;
                let d = v.length();
                if d > 0.0 && d < 0.3 {
                    sum += (n.dot(v) / d).max(0.0);
                }
            }
        }
        let expected = sum / 6.0;
        assert!(
            (row.get(x, y) - expected).abs() < 1e-6,
            "({x}, {y}): {} vs {expected}",
            row.get(x, y)
        );
    }
}

/// Against ray-traced AO (same radius, same falloff) on the Cornell box: the separable
/// approximation stays close to its non-separable counterpart (the target: within
/// 25 % of its error).
#[test]
fn the_separable_approximation_is_close_to_the_2d_kernel_against_ray_traced_ao() {
    let scene = scene::cornell_box();
    let camera = scene.camera_or_framed();
    let (g, frame) = gbuffer(&scene, &camera);
    let bvh = scene::Bvh::build(&scene);
    for (k, radius) in [(11, 0.15f32), (21, 0.25)] {
        let c = config(k, radius);
        let truth = reference::ray_traced(&bvh, &g, &frame, &c.ao, 256).expect("truth");
        let error = |image: &gbuffer::Image<f32>| {
            let surfaces = g.linear_depth.pixels().iter().filter(|&&d| d > 0.0).count();
            image
                .pixels()
                .iter()
                .zip(truth.pixels())
                .zip(g.linear_depth.pixels())
                .filter(|(_, d)| **d > 0.0)
                .map(|((a, t), _)| (a - t).abs())
                .sum::<f32>()
                / surfaces as f32
        };
        let full = error(&cpu::kernel_2d(&g, &frame, &c).expect("2D"));
        let separable = error(&cpu::separable(&g, &frame, &c).expect("separable"));
        println!(
            "k {k}, r {radius}: mean absolute error against ray-traced AO: 2D {full:.4}, separable {separable:.4}"
        );
        assert!(separable <= 1.25 * full, "k {k}: {separable} vs {full}");
    }
}
