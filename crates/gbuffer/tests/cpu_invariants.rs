//! Invariants of the CPU reference: watertight, non-overlapping coverage (top-left rule),
//! position from depth both ways against ray casts, normal-encoding error bounds.

mod common;

use gbuffer::{Frame, GBufferError, cpu, normal::NormalEncoding, position};
use glam::{Vec2, Vec3};
use scene::{Camera, Material, Mesh, Scene};

/// A screen-filling grid of `n × n` quads (2 triangles each) at z = 0, seen head-on, wound
/// counter-clockwise seen from +z, with vertex normals `normal`.
fn grid_scene(n: u32, normal: Vec3) -> Scene {
    let mut mesh = Mesh {
        name: "grid".into(),
        ..Default::default()
    };
    for j in 0..=n {
        for i in 0..=n {
            // Irregular vertex positions so edges have arbitrary slopes.
            let jitter = if i > 0 && i < n && j > 0 && j < n {
                ((i * 7 + j * 13) % 5) as f32 * 0.03
            } else {
                0.0
            };
            mesh.positions.push(Vec3::new(
                i as f32 / n as f32 * 4.0 - 2.0 + jitter,
                j as f32 / n as f32 * 4.0 - 2.0 - jitter,
                0.0,
            ));
            mesh.normals.push(normal);
            mesh.uvs.push(Vec2::ZERO);
        }
    }
    for j in 0..n {
        for i in 0..n {
            let a = j * (n + 1) + i;
            mesh.indices
                .extend([a, a + 1, a + n + 2, a, a + n + 2, a + n + 1]);
        }
    }
    Scene {
        meshes: vec![mesh],
        materials: vec![Material::default()],
        ..Default::default()
    }
}

#[test]
fn coverage_is_watertight_and_never_doubled() {
    let scene = grid_scene(7, Vec3::Z);
    let camera = Camera {
        eye: Vec3::new(0.0, 0.0, 3.0),
        target: Vec3::ZERO,
        up: Vec3::Y,
        fov_y: 50f32.to_radians(),
        near: 0.5,
        far: 10.0,
    };
    let (w, h) = (61, 47);
    let full = cpu::rasterize(&scene, &camera, w, h).expect("raster");
    assert!(
        full.triangle_id.pixels().iter().all(|&t| t != u32::MAX),
        "gap in a closed grid"
    );
    // Each triangle alone: the coverage counts must sum to exactly one per pixel.
    let mut count = vec![0u32; (w * h) as usize];
    let mesh = &scene.meshes[0];
    for t in mesh.indices.chunks_exact(3) {
        let single = Scene {
            meshes: vec![Mesh {
                indices: t.to_vec(),
                ..mesh.clone()
            }],
            ..scene.clone()
        };
        let r = cpu::rasterize(&single, &camera, w, h).expect("raster");
        for (c, &id) in count.iter_mut().zip(r.triangle_id.pixels()) {
            *c += u32::from(id != u32::MAX);
        }
    }
    assert!(
        count.iter().all(|&c| c == 1),
        "pixels covered {:?} times",
        count.iter().filter(|&&c| c != 1).collect::<Vec<_>>()
    );
}

/// Surfaces are two-sided and shaded from the side they are seen from, as the path tracer
/// turns the shading normal to the side of the geometric normal that faces its ray: the
/// grid's normals face a camera in front of it and one behind it, whether the vertex normals
/// agree with the winding (+z, counter-clockwise seen from +z), oppose it (−z), or lean
/// beyond the plane on one side.
#[test]
fn normals_face_the_camera_side_of_their_triangle() {
    for normal in [Vec3::Z, -Vec3::Z, Vec3::new(0.3, 0.0, -0.2).normalize()] {
        let scene = grid_scene(3, normal);
        for (z, sign) in [(3.0, 1.0), (-3.0, -1.0)] {
            let camera = Camera {
                eye: Vec3::new(0.0, 0.0, z),
                target: Vec3::ZERO,
                up: Vec3::Y,
                fov_y: 50f32.to_radians(),
                near: 0.5,
                far: 10.0,
            };
            let r = cpu::rasterize(&scene, &camera, 32, 24).expect("raster");
            for (&word, &id) in r.gbuffer.normal.pixels().iter().zip(r.triangle_id.pixels()) {
                assert_ne!(id, u32::MAX, "the grid fills the view");
                let n = gbuffer::normal::unpack_octahedral(word);
                let want = normal * normal.z.signum() * sign;
                assert!(
                    n.dot(want) > 0.999,
                    "vertex normal {normal}, camera at z = {z}: normal {n}, want {want}"
                );
            }
        }
    }
}

#[test]
fn position_from_depth_both_ways_agrees_with_ray_casts() {
    let scene = scene::cornell_box();
    let camera = scene.camera.expect("camera");
    let (w, h) = (96, 96);
    let r = cpu::rasterize(&scene, &camera, w, h).expect("raster");
    let frame = Frame::new(&camera, w, h);
    let bvh = scene::Bvh::build(&scene);
    let mut checked = 0;
    for y in 0..h {
        for x in 0..w {
            let depth = r.gbuffer.depth.get(x, y);
            if depth >= 1.0 {
                continue;
            }
            let a = position::from_depth(&frame, x, y, depth);
            let b = position::from_view_ray(&frame, x, y, r.gbuffer.linear_depth.get(x, y));
            let scale = (a - camera.eye).length();
            assert!(
                (a - b).length() < 2e-4 * scale,
                "({x},{y}): inverse projection {a} vs view ray {b}"
            );
            let ray = b - camera.eye;
            if let Some(hit) = bvh.closest_hit(camera.eye, ray, 10.0) {
                // The ray through the pixel centre hits the rasterized surface unless the pixel
                // straddles an edge; compare where the triangle ids agree.
                let tri = r.triangle_id.get(x, y);
                let global: u32 = scene.meshes[..hit.mesh as usize]
                    .iter()
                    .map(|m| m.triangle_count() as u32)
                    .sum::<u32>()
                    + hit.triangle;
                if tri == global {
                    assert!(
                        (hit.position - a).length() < 1e-3 * scale,
                        "({x},{y}): ray {} vs depth {a}",
                        hit.position
                    );
                    checked += 1;
                }
            }
        }
    }
    assert!(
        checked > (w * h) as usize * 9 / 10,
        "only {checked} pixels compared"
    );
}

/// Documented bounds (docs/gbuffer.md) on the maximum angular error, in degrees, of each
/// encoding over its domain at 8 and 16 bits per value. Encodings without a singularity
/// (stereographic on its domain, octahedral) stay near the quantization step: one unorm step
/// s moves a normal by about s·(stretch) rad, ≈ 0.5° at 8 bits and 257 times less at 16.
/// Encodings that store z directly or take a square root near a pole (XY, spherical, sphere
/// map) turn a step s into about sqrt(4s) rad there: 7.2° at 8 bits, 0.45° at 16; the sphere
/// map's pole at z = −1 also quantizes the azimuth coarsely (bound 12° at 8 bits).
const MAX_ERROR_BOUNDS: [(NormalEncoding, f32, f32); 5] = [
    (NormalEncoding::XyReconstructZ, 7.2, 0.45),
    (NormalEncoding::Spherical, 7.2, 0.45),
    (NormalEncoding::SphereMap, 12.0, 0.45),
    (NormalEncoding::Stereographic, 1.2, 0.005),
    (NormalEncoding::Octahedral, 1.0, 0.004),
];

#[test]
fn normal_encodings_stay_within_documented_error_bounds() {
    for (enc, max8, max16) in MAX_ERROR_BOUNDS {
        let (m8, mean8) = gbuffer::normal::measure_error(enc, 8, 200_000);
        let (m16, mean16) = gbuffer::normal::measure_error(enc, 16, 200_000);
        eprintln!(
            "{:22} 8 bit: max {m8:.4}° mean {mean8:.4}°   16 bit: max {m16:.5}° mean {mean16:.5}°",
            enc.name()
        );
        assert!(
            m8 <= max8 && m16 <= max16 && m16 < m8 / 10.0,
            "{}: {m8}° / {m16}° above {max8}° / {max16}°",
            enc.name()
        );
        assert!(mean8 < m8 && mean16 < m16);
    }
}

#[test]
fn encodings_without_quantization_are_exact_on_their_domain() {
    for enc in NormalEncoding::ALL {
        for n in gbuffer::normal::fibonacci_sphere(5000).filter(|n| n.z >= enc.domain_min_z()) {
            let d = enc.decode(enc.encode(n));
            assert!(
                gbuffer::normal::angle_deg(n, d) < 0.05,
                "{}: {n} -> {d}",
                enc.name()
            );
        }
    }
}

#[test]
fn xy_encoding_loses_the_sign_of_z() {
    let n = Vec3::new(0.3, 0.4, -0.866).normalize();
    let d = NormalEncoding::XyReconstructZ.decode(NormalEncoding::XyReconstructZ.encode(n));
    assert!(d.z > 0.0, "the thesis notes the sign of z is lost");
}

#[test]
fn bad_sizes_and_cameras_are_errors() {
    let scene = scene::cornell_box();
    let camera = scene.camera.expect("camera");
    assert!(matches!(
        cpu::rasterize(&scene, &camera, 0, 10),
        Err(GBufferError::InvalidSize { .. })
    ));
    assert!(matches!(
        cpu::rasterize(&scene, &camera, 10, 100_000),
        Err(GBufferError::InvalidSize { .. })
    ));
    let mut bad = camera;
    bad.eye.x = f32::NAN;
    assert!(matches!(
        cpu::rasterize(&scene, &bad, 10, 10),
        Err(GBufferError::InvalidCamera(_))
    ));
    let mut bad = camera;
    bad.near = bad.far;
    assert!(matches!(
        cpu::rasterize(&scene, &bad, 10, 10),
        Err(GBufferError::InvalidCamera(_))
    ));
}

#[test]
fn triangles_behind_the_camera_and_crossing_the_near_plane_are_clipped() {
    // A large floor passing under and behind the eye: it must cover the lower half without
    // wrapping around (a w <= 0 vertex mishandled would fill the upper half too).
    let scene = common::random_scene(1, 0);
    let mut floor = Mesh {
        name: "floor".into(),
        ..Default::default()
    };
    for p in [
        Vec3::new(-50.0, -1.0, -50.0),
        Vec3::new(50.0, -1.0, -50.0),
        Vec3::new(50.0, -1.0, 50.0),
        Vec3::new(-50.0, -1.0, 50.0),
    ] {
        floor.positions.push(p);
        floor.normals.push(Vec3::Y);
        floor.uvs.push(Vec2::ZERO);
    }
    floor.indices = vec![0, 1, 2, 0, 2, 3];
    let scene = Scene {
        meshes: vec![floor],
        ..scene
    };
    let camera = Camera {
        eye: Vec3::ZERO,
        target: Vec3::new(0.0, 0.0, -1.0),
        up: Vec3::Y,
        fov_y: 60f32.to_radians(),
        near: 0.1,
        far: 100.0,
    };
    let r = cpu::rasterize(&scene, &camera, 64, 64).expect("raster");
    for x in 0..64 {
        assert_eq!(r.triangle_id.get(x, 2), u32::MAX, "sky covered at x={x}");
        assert_ne!(r.triangle_id.get(x, 60), u32::MAX, "floor missing at x={x}");
    }
}

/// Thesis §3.6's per-pixel view space: exact without quantization for every normal facing the
/// eye, including those whose plain view-space z is negative (near the image edges), where the
/// XY encoding loses the sign; quantized, it has XY's bounds (the same √ near the rim).
#[test]
fn per_pixel_view_space_keeps_normals_facing_the_eye() {
    use gbuffer::normal::{angle_deg, decode_per_pixel_view, encode_per_pixel_view};
    let to_eye = Vec3::new(0.6, 0.0, 0.8);
    let n = Vec3::new(1.0, 0.1, -0.2).normalize();
    assert!(n.z < 0.0 && n.dot(to_eye) > 0.0);
    let xy = NormalEncoding::XyReconstructZ;
    assert!(angle_deg(n, xy.decode(xy.encode(n))) > 10.0);
    assert!(
        angle_deg(
            n,
            decode_per_pixel_view(encode_per_pixel_view(n, to_eye), to_eye)
        ) < 0.01
    );
    for n in gbuffer::normal::fibonacci_sphere(5000).filter(|n| n.dot(to_eye) >= 0.0) {
        let d = decode_per_pixel_view(encode_per_pixel_view(n, to_eye), to_eye);
        assert!(angle_deg(n, d) < 0.05, "{n} -> {d}");
    }
    let (m8, mean8) = gbuffer::normal::measure_per_pixel_view_error(8, 20_000);
    let (m16, mean16) = gbuffer::normal::measure_per_pixel_view_error(16, 20_000);
    eprintln!(
        "per-pixel view space 8 bit: max {m8:.4}° mean {mean8:.4}°   16 bit: max {m16:.5}° mean {mean16:.5}°"
    );
    assert!(
        m8 <= 7.2 && m16 <= 0.45 && mean8 < m8 && mean16 < m16,
        "{m8} {m16}"
    );
}

/// Kaplanyan 2010's best fit (thesis §3.6): scaling the normal by its best length before
/// storing it in three unorm8 channels uses the cells off the unit sphere, so the mean error
/// falls to a third or less of storing the normalized normal (the thesis's banding) and the
/// worst one falls too, through a 512² table of the search; the lengths lie in (0, 1].
#[test]
fn best_fit_normals_beat_normalized_normals_in_three_bytes() {
    use gbuffer::normal::{BestFitTable, best_fit_length, measure_unorm8x3_error};
    let table = BestFitTable::new(512);
    for n in gbuffer::normal::fibonacci_sphere(2000) {
        let t = best_fit_length(n);
        assert!(t > 0.0 && t <= 1.0, "{n}: {t}");
    }
    let (plain_max, plain_mean) = measure_unorm8x3_error(None, 100_000);
    let (fit_max, fit_mean) = measure_unorm8x3_error(Some(&table), 100_000);
    eprintln!(
        "3 × unorm8: normalized max {plain_max:.4}° mean {plain_mean:.4}°; best fit (512² table) max {fit_max:.4}° mean {fit_mean:.4}°"
    );
    assert!(fit_max < plain_max && fit_mean < plain_mean / 3.0);
}
