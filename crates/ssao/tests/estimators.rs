//! The screen-space estimators: their invariants, and their error against the ray-traced
//! reference.

use glam::{Vec2, Vec3};
use scene::{Camera, Scene};
use ssao::cpu::{self, KernelConfig};
use ssao::{AoConfig, Estimator, Method, reference};

const SIZE: (u32, u32) = (96, 72);

fn gbuffer(scene: &Scene, camera: &Camera) -> (gbuffer::GBuffer, gbuffer::Frame) {
    gbuffer_sized(scene, camera, SIZE)
}

fn gbuffer_sized(
    scene: &Scene,
    camera: &Camera,
    (w, h): (u32, u32),
) -> (gbuffer::GBuffer, gbuffer::Frame) {
    let g = gbuffer::cpu::rasterize(scene, camera, w, h)
        .expect("G-buffer")
        .gbuffer;
    (g, gbuffer::Frame::new(camera, w, h))
}

/// Every method, whole, separable and separable without the smoothing, at full and half
/// resolution.
fn estimators() -> impl Iterator<Item = Estimator> {
    Method::ALL.into_iter().flat_map(|method| {
        [
            Estimator::new(method, false),
            Estimator::new(method, true),
            Estimator::new(method, true).without_smoothing(),
        ]
        .into_iter()
        .flat_map(|e| [e, e.at_half_resolution()])
    })
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
        for estimator in estimators() {
            let image = cpu::estimate(&g, &frame, &config(k, 1.0), estimator).expect("A");
            let least = image.pixels().iter().copied().fold(1.0f32, f32::min);
            println!("{estimator} k {k}: least A {least}");
            assert!(
                least > 0.999,
                "{estimator} k {k}: A {least} on an open plane"
            );
        }
    }
}

/// The filter and the horizon methods measure a fixed hemisphere: a larger radius only adds
/// occluders. (Crytek and VO measure a fraction of a sphere that grows with the radius: a thin
/// occluder near p fills less of a larger sphere, so they are not monotone.)
#[test]
fn occlusion_is_monotone_in_the_radius() {
    let scene = scene::cornell_box();
    let (g, frame) = gbuffer(&scene, &scene.camera_or_framed());
    for estimator in
        estimators().filter(|e| matches!(e.method, Method::Filter | Method::Hbao | Method::Gtao))
    {
        let small = cpu::estimate(&g, &frame, &config(11, 0.1), estimator).expect("small");
        let large = cpu::estimate(&g, &frame, &config(11, 0.4), estimator).expect("large");
        assert!(
            small
                .pixels()
                .iter()
                .zip(large.pixels())
                .all(|(a, b)| *b <= a + 1e-6),
            "{estimator}: a larger radius never unoccludes"
        );
        assert!(large.pixels().iter().sum::<f32>() < small.pixels().iter().sum::<f32>());
    }
}

/// Pass 1 along the image's x axis is eq. 7.1 restricted to the pixel's row.
#[test]
fn pass_1d_along_x_is_the_row_of_the_2d_kernel() {
    let scene = scene::cornell_box();
    let (g, frame) = gbuffer(&scene, &scene.camera_or_framed());
    let c = config(7, 0.3);
    let row = cpu::pass_1d(&g, &frame, &c, Method::Filter, |_, _| Vec2::X).expect("pass 1");
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
        let expected = 1.0 - 2.0 * sum / 6.0;
        assert!(
            (row.get(x, y)[0] - expected).abs() < 1e-6 && row.get(x, y)[1] == 1.0,
            "({x}, {y}): {:?} vs {expected}",
            row.get(x, y)
        );
    }
}

/// Against ray-traced AO (same radius, same falloff) on the Cornell box: the separable
/// approximation stays close to its non-separable counterpart (the target: within
/// 25 % of its error); half resolution, with the kernel reaching as far, within 10 % of full.
#[test]
fn the_separable_approximation_is_close_to_the_2d_kernel_against_ray_traced_ao() {
    let scene = scene::cornell_box();
    let camera = scene.camera_or_framed();
    // Twice the other tests' size: the smoothing's k × k box should not span a fifth of the
    // image.
    let (g, frame) = gbuffer_sized(&scene, &camera, (2 * SIZE.0, 2 * SIZE.1));
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
        for method in Method::ALL {
            let estimate = |separable| {
                let image = cpu::estimate(&g, &frame, &c, Estimator::new(method, separable));
                error(&image.expect("A"))
            };
            let (full, separable) = (estimate(false), estimate(true));
            println!(
                "{} k {k}, r {radius}: mean absolute error against ray-traced AO: k×k {full:.4}, separable {separable:.4}",
                method.name()
            );
            if method == Method::Filter {
                assert!(separable <= 1.25 * full, "k {k}: {separable} vs {full}");
            }
            // Half resolution with the kernel reaching about as far: k' = (k + 1)/2, made odd,
            // steps of two pixels.
            let half_config = config(k.div_ceil(2) | 1, radius);
            let half = |separable| {
                let e = Estimator::new(method, separable).at_half_resolution();
                error(&cpu::estimate(&g, &frame, &half_config, e).expect("A"))
            };
            let (half_full, half_separable) = (half(false), half(true));
            println!(
                "{} half resolution, k {}: k×k {half_full:.4}, separable {half_separable:.4}",
                method.name(),
                half_config.size
            );
            // A varies slowly: a quarter of the estimates loses at most 10 % in accuracy.
            assert!(half_full <= 1.1 * full && half_separable <= 1.1 * separable);
        }
    }
}

/// A quad through four corners (counter-clockwise seen from its front), facing `normal`.
fn quad(corners: [Vec3; 4], normal: Vec3) -> scene::Mesh {
    scene::Mesh {
        name: "quad".into(),
        positions: corners.to_vec(),
        normals: vec![normal; 4],
        uvs: vec![Vec2::ZERO; 4],
        indices: vec![0, 1, 2, 0, 2, 3],
        material: 0,
        ..Default::default()
    }
}

/// Ground truth at the foot of a wall (a floor meeting a wall at a right angle, seen from two
/// sides, the kernel reaching past the radius): GTAO, which integrates the cosine-weighted
/// visible arc of each slice exactly, matches ray-traced AO within 0.04 on average where the
/// wall occludes; every other estimator's error is printed for the record.
#[test]
fn gtao_matches_ray_traced_ao_at_the_foot_of_a_wall() {
    let mut scene = Scene::default();
    scene.materials.push(scene::Material::default());
    let f = 5.0;
    let floor = [(-f, -f), (-f, f), (f, f), (f, -f)].map(|(x, z)| Vec3::new(x, 0.0, z));
    let wall = [(0.0, -f), (f, -f), (f, f), (0.0, f)].map(|(y, z)| Vec3::new(0.0, y, z));
    scene.meshes.push(quad(floor, Vec3::Y));
    scene.meshes.push(quad(wall, Vec3::X));
    let bvh = scene::Bvh::build(&scene);
    let c = config(31, 0.3);
    for eye in [Vec3::new(2.0, 1.5, 0.3), Vec3::new(1.5, 2.5, 2.0)] {
        let camera = Camera {
            eye,
            target: Vec3::ZERO,
            up: Vec3::Y,
            fov_y: 60f32.to_radians(),
            near: 0.01,
            far: 50.0,
        };
        let (g, frame) = gbuffer(&scene, &camera);
        let truth = reference::ray_traced(&bvh, &g, &frame, &c.ao, 512).expect("truth");
        for estimator in estimators() {
            let image = cpu::estimate(&g, &frame, &c, estimator).expect("A");
            let errors: Vec<f32> = image
                .pixels()
                .iter()
                .zip(truth.pixels())
                .filter(|(_, t)| **t < 0.98)
                .map(|(a, t)| a - t)
                .collect();
            let n = errors.len() as f32;
            let bias = errors.iter().sum::<f32>() / n;
            let mae = errors.iter().map(|e| e.abs()).sum::<f32>() / n;
            println!(
                "eye {eye}, {estimator}: {n} occluded pixels, bias {bias:+.4}, mean absolute error {mae:.4}"
            );
            if estimator == (Estimator::new(Method::Gtao, false)) {
                assert!(mae <= 0.04, "GTAO at the foot of a wall: {mae}");
            }
        }
    }
}

/// Temporal stability: the interleaved pattern is fixed to the screen (no per-frame noise, no
/// history), so a still camera gives identical frames and a moving camera changes A only as
/// the surfaces move under it. Over a slow pan (a quarter pixel a frame), each separable
/// estimator's mean frame-to-frame change stays within twice the ray-traced reference's (whose
/// own change is the geometry's plus its sampling noise) plus 0.002.
#[test]
fn a_moving_camera_changes_a_no_more_than_the_geometry_does() {
    let scene = scene::cornell_box();
    let start = scene.camera_or_framed();
    let bvh = scene::Bvh::build(&scene);
    let c = config(11, 0.15);
    let right = (start.target - start.eye).cross(start.up).normalize();
    let step = 0.25 * 2.0 * (start.fov_y * 0.5).tan() * (start.target - start.eye).length()
        / SIZE.1 as f32;
    let frames: Vec<(gbuffer::GBuffer, gbuffer::Frame)> = (0..4)
        .map(|i| {
            let shift = right * step * i as f32;
            let camera = Camera {
                eye: start.eye + shift,
                target: start.target + shift,
                ..start
            };
            gbuffer(&scene, &camera)
        })
        .collect();
    let change = |images: &[gbuffer::Image<f32>]| {
        let pairs = images.windows(2).map(|w| {
            let d: f32 = w[0]
                .pixels()
                .iter()
                .zip(w[1].pixels())
                .map(|(a, b)| (a - b).abs())
                .sum();
            d / w[0].pixels().len() as f32
        });
        pairs.sum::<f32>() / (images.len() - 1) as f32
    };
    let truth: Vec<_> = frames
        .iter()
        .map(|(g, f)| reference::ray_traced(&bvh, g, f, &c.ao, 512).expect("truth"))
        .collect();
    let truth_change = change(&truth);
    for method in Method::ALL {
        let e = Estimator::new(method, true);
        let images: Vec<_> = frames
            .iter()
            .map(|(g, f)| cpu::estimate(g, f, &c, e).expect("A"))
            .collect();
        let again = cpu::estimate(&frames[0].0, &frames[0].1, &c, e).expect("A");
        assert_eq!(again.pixels(), images[0].pixels(), "{e}: a still camera");
        let moving = change(&images);
        println!("{e}: mean frame-to-frame change {moving:.4} (ray-traced {truth_change:.4})");
        assert!(
            moving <= 2.0 * truth_change + 0.002,
            "{e}: {moving} vs {truth_change}"
        );
    }
}

/// Estimator names round-trip, and a name that is not `METHOD[-separable[-unsmoothed]][-half]`
/// is refused.
#[test]
fn estimator_names_round_trip() {
    for e in estimators() {
        assert_eq!(e.to_string().parse::<Estimator>().expect("name"), e);
    }
    for bad in ["filter-unsmoothed", "separable", "gtao-half-separable", ""] {
        assert!(bad.parse::<Estimator>().is_err(), "{bad}");
    }
}
