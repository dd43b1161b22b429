//! The compute rasteriser's visibility buffer against the CPU rasteriser's triangle ids.
//!
//! Rule for pixels allowed to differ (as for the hardware G-buffer, `gpu_vs_cpu.rs`): only
//! where the CPU's triangle-id image is not constant over the pixel's 3 × 3 neighbourhood (a
//! silhouette or triangle edge, where the GPU's clip position or depth may come out one rounding
//! apart from the CPU's); every other pixel must hold the CPU's id, and at least 99.5 % of all
//! pixels must match.

mod common;

use gbuffer::{
    Frame, cpu,
    gpu::{
        GBufferPass, GpuScene,
        visibility::{self, Atomics, Capacity, NO_TRIANGLE, VisibilityPass},
    },
};
use proptest::prelude::*;
use scene::{AlphaMode, Camera, Scene};

/// The GPU visibility buffer's ids of the opaque `scene` through `camera`, the meshes
/// `hardware` drawn by the hardware rasteriser.
fn gpu_ids(
    gpu: &gpu::Gpu,
    scene: &Scene,
    camera: &Camera,
    size: (u32, u32),
    hardware: &[usize],
) -> Vec<u32> {
    let atomics = Atomics::best(&gpu.device);
    let vis = gpu_words(gpu, scene, camera, size, (atomics, hardware));
    visibility::triangle_ids(&vis)
}

/// The GPU visibility buffer's words of `scene` through `camera`, merged as `atomics` says,
/// the meshes `hardware` and the alpha-tested ones drawn by the hardware rasteriser with a
/// depth attachment of their own.
fn gpu_words(
    gpu: &gpu::Gpu,
    scene: &Scene,
    camera: &Camera,
    (w, h): (u32, u32),
    (atomics, hardware): (Atomics, &[usize]),
) -> Vec<u64> {
    let gpass = GBufferPass::new(&gpu.device).expect("pass");
    let uploaded = GpuScene::upload(&gpu.device, &gpu.queue, scene, &gpass).expect("upload");
    let pass = VisibilityPass::with(&gpu.device, &gpass, Capacity::default(), atomics)
        .expect("visibility");
    let buffer = VisibilityPass::buffer(&gpu.device, w, h).expect("buffer");
    let depth = gpu.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("alpha-tested draw's attachment"),
        size: wgpu::Extent3d {
            width: w,
            height: h,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: gbuffer::DEPTH_FORMAT,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
        view_formats: &[],
    });
    gpass.write_frame(&gpu.queue, &Frame::new(camera, w, h));
    let vis = pass
        .bind_split(
            &gpu.device,
            &uploaded,
            gpass.frame_buffer(),
            (w, h),
            &buffer,
            hardware,
        )
        .expect("bind");
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    vis.encode(&mut encoder, Some(&depth), None)
        .expect("encode");
    let bytes =
        ::gpu::transfer::read_after(&gpu.device, &gpu.queue, encoder, &buffer, 0..buffer.size())
            .expect("read back");
    assert_eq!(
        vis.overflow(&gpu.device, &gpu.queue).expect("counts"),
        0,
        "nothing lost"
    );
    bytemuck::pod_collect_to_vec::<u8, u64>(&bytes)
}

fn opaque(mut scene: Scene) -> Scene {
    for m in &mut scene.materials {
        m.alpha_mode = AlphaMode::Opaque;
    }
    scene
}

/// Compares, the meshes `hardware` drawn by the hardware rasteriser; returns the share of
/// matching pixels, or the first interior mismatch.
fn compare(
    scene: &Scene,
    camera: &Camera,
    (w, h): (u32, u32),
    hardware: &[usize],
) -> Result<f64, String> {
    let Some(gpu) = gpu::test_device(&visibility::device_needs()) else {
        return Ok(1.0);
    };
    let expected = cpu::rasterize(scene, camera, w, h)
        .map_err(|e| e.to_string())?
        .triangle_id;
    let got = gpu_ids(gpu, scene, camera, (w, h), hardware);
    let mut matched = 0u32;
    for y in 0..h {
        for x in 0..w {
            let (e, g) = (expected.get(x, y), got[(y * w + x) as usize]);
            if e == g {
                matched += 1;
            } else if !common::is_edge(&expected, x, y) {
                return Err(format!(
                    "pixel ({x}, {y}): CPU triangle {e}, visibility buffer {g}"
                ));
            }
        }
    }
    Ok(f64::from(matched) / f64::from(w * h))
}

#[test]
fn spheres_on_a_plane_match_the_cpu_rasteriser() {
    let scene = opaque(scene::spheres_on_plane(6));
    let camera = scene.camera_or_framed();
    let share = compare(&scene, &camera, (160, 120), &[]).unwrap();
    assert!(share >= 0.995, "{:.2} % of the pixels match", share * 100.0);
}

#[test]
fn a_camera_inside_the_scene_clips_and_matches() {
    // From between the spheres, close to the plane: triangles cross the near plane and the
    // guard band, and the plane's triangles cover far more than 64 pixels.
    let scene = opaque(scene::spheres_on_plane(6));
    let framed = scene.camera_or_framed();
    let camera = Camera {
        eye: framed.target + (framed.eye - framed.target) * 0.15,
        ..framed
    };
    let share = compare(&scene, &camera, (128, 96), &[]).unwrap();
    assert!(share >= 0.995, "{:.2} % of the pixels match", share * 100.0);
}

#[test]
fn an_empty_view_holds_no_triangle() {
    let Some(gpu) = gpu::test_device(&visibility::device_needs()) else {
        return;
    };
    let scene = opaque(scene::spheres_on_plane(2));
    let framed = scene.camera_or_framed();
    // Looking away from everything.
    let camera = Camera {
        target: framed.eye + (framed.eye - framed.target),
        ..framed
    };
    assert!(
        gpu_ids(gpu, &scene, &camera, (32, 24), &[])
            .iter()
            .all(|&id| id == NO_TRIANGLE)
    );
}

/// Meshes drawn into the buffer by the hardware rasteriser (`bind_split`) hold the CPU's ids
/// as the compute rasteriser's do: the ground alone, every other mesh, all of them; from the
/// framed camera and from among the spheres (triangles crossing the near plane).
#[test]
fn a_split_between_the_rasterisers_matches_the_cpu_rasteriser() {
    let scene = opaque(scene::spheres_on_plane(6));
    let framed = scene.camera_or_framed();
    let inside = Camera {
        eye: framed.target + (framed.eye - framed.target) * 0.15,
        ..framed
    };
    let all: Vec<usize> = (0..scene.meshes.len()).collect();
    let odd: Vec<usize> = all.iter().copied().filter(|m| m % 2 == 1).collect();
    for camera in [framed, inside] {
        for hardware in [&[0][..], &odd, &all] {
            let share = compare(&scene, &camera, (128, 96), hardware).unwrap();
            assert!(
                share >= 0.995,
                "meshes {hardware:?} by the hardware rasteriser: {:.2} % of the pixels match",
                share * 100.0
            );
        }
    }
}

#[test]
fn a_split_naming_a_missing_mesh_is_refused() {
    let Some(gpu) = gpu::test_device(&visibility::device_needs()) else {
        return;
    };
    let scene = opaque(scene::spheres_on_plane(2));
    let gpass = GBufferPass::new(&gpu.device).expect("pass");
    let uploaded = GpuScene::upload(&gpu.device, &gpu.queue, &scene, &gpass).expect("upload");
    let pass = VisibilityPass::new(&gpu.device, &gpass).expect("visibility");
    let buffer = VisibilityPass::buffer(&gpu.device, 16, 16).expect("buffer");
    let meshes = scene.meshes.len();
    let err = pass
        .bind_split(
            &gpu.device,
            &uploaded,
            gpass.frame_buffer(),
            (16, 16),
            &buffer,
            &[0, meshes],
        )
        .map(|_| ())
        .expect_err("a mesh past the scene's");
    let text = err.to_string();
    assert!(
        text.contains(&format!("mesh {meshes}")) && text.contains(&format!("{meshes} meshes")),
        "{text}"
    );
}

/// The estimate that ranks meshes for the split, against geometry: through a 90° vertical
/// field of view at distance 3 over 96 rows (16 pixels per unit at z = 0), a 4 × 4 grid of
/// half size 2 covers a 64 × 64-pixel square with 32 triangles, 128 pixels each; a single cell
/// larger than the view covers the 128 × 96 image with 2 triangles; a grid moved off the
/// image, nothing.
#[test]
fn pixels_per_triangle_measures_the_screen_box() {
    let Some(gpu) = gpu::test_device(&visibility::device_needs()) else {
        return;
    };
    let camera = Camera {
        fov_y: 90f32.to_radians(),
        ..Camera::look_at(glam::Vec3::new(0.0, 0.0, 3.0), glam::Vec3::ZERO)
    };
    let mut scene = grid(4, 2.0, glam::Vec2::ZERO, 0.0);
    for (n, half, offset) in [
        (1, 10.0, glam::Vec2::ZERO),
        (4, 2.0, glam::Vec2::new(20.0, 0.0)),
    ] {
        scene.meshes.extend(grid(n, half, offset, 0.0).meshes);
    }
    let gpass = GBufferPass::new(&gpu.device).expect("pass");
    let uploaded = GpuScene::upload(&gpu.device, &gpu.queue, &scene, &gpass).expect("upload");
    let got = uploaded.pixels_per_triangle(&Frame::new(&camera, 128, 96));
    let expected = [128.0, 128.0 * 96.0 / 2.0, 0.0];
    assert_eq!(got.len(), 3);
    for (g, e) in got.iter().zip(expected) {
        assert!(
            (g - e).abs() <= 1e-3 * e.max(1.0),
            "{got:?} against {expected:?}"
        );
    }
}

/// A closed grid of `n × n` cells over `[-half, half]²` moved by `offset`, in the plane z = 0,
/// facing +z, its inner vertices jittered by up to `jitter` of a cell, each cell cut along an
/// alternating diagonal.
fn grid(n: u32, half: f32, offset: glam::Vec2, jitter: f32) -> Scene {
    let mut state = u64::from(n);
    let mut random = move || {
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1);
        ((state >> 40) as f32 / (1u64 << 24) as f32 - 0.5) * 2.0 * jitter
    };
    let cell = 2.0 * half / n as f32;
    let mut mesh = scene::Mesh {
        name: "grid".into(),
        ..Default::default()
    };
    for j in 0..=n {
        for i in 0..=n {
            let inner = |k| k > 0 && k < n;
            let (dx, dy) = (random(), random());
            let x = -half + cell * (i as f32 + if inner(i) { dx } else { 0.0 }) + offset.x;
            let y = -half + cell * (j as f32 + if inner(j) { dy } else { 0.0 }) + offset.y;
            mesh.positions.push(glam::Vec3::new(x, y, 0.0));
            mesh.normals.push(glam::Vec3::Z);
            mesh.uvs.push(glam::Vec2::new(x, y));
        }
    }
    let v = |i: u32, j: u32| j * (n + 1) + i;
    for j in 0..n {
        for i in 0..n {
            let (a, b, c, d) = (v(i, j), v(i + 1, j), v(i + 1, j + 1), v(i, j + 1));
            if (i + j) % 2 == 0 {
                mesh.indices.extend([a, b, c, a, c, d]);
            } else {
                mesh.indices.extend([a, b, d, b, c, d]);
            }
        }
    }
    let mut scene = Scene::default();
    scene.materials.push(scene::Material::default());
    scene.meshes.push(mesh);
    scene
}

/// Watertightness: a closed grid filling the view leaves no pixel uncovered, whether its
/// triangles take the per-triangle path (cells of ~2 pixels) or the deferred blocks (~30).
#[test]
fn closed_jittered_grids_leave_no_hole() {
    let Some(gpu) = gpu::test_device(&visibility::device_needs()) else {
        return;
    };
    let camera = Camera {
        fov_y: 45f32.to_radians(),
        ..Camera::look_at(glam::Vec3::new(0.3, -0.4, 3.0), glam::Vec3::ZERO)
    };
    for n in [96, 8] {
        let mesh = grid(n, 2.0, glam::Vec2::ZERO, 0.3);
        let holes = gpu_ids(gpu, &mesh, &camera, (128, 96), &[])
            .iter()
            .filter(|&&id| id == NO_TRIANGLE)
            .count();
        assert_eq!(holes, 0, "{n} × {n} grid: {holes} pixels uncovered");
        let share = compare(&mesh, &camera, (128, 96), &[]).expect("compare");
        assert!(share >= 0.995, "{:.2} % of the pixels match", share * 100.0);
    }
}

/// Every pixel once: a grid whose vertices snap to pixel centres (16 pixels per unit, lines
/// half a pixel off the image centre), so that every edge, diagonals included, runs through
/// pixel centres and the top-left rule alone decides who owns them. A pixel covered twice
/// would hold the smaller id of the two; the CPU's owner must hold it, everywhere.
#[test]
fn shared_edges_through_pixel_centres_go_to_one_triangle() {
    let Some(gpu) = gpu::test_device(&visibility::device_needs()) else {
        return;
    };
    // 90° vertical field of view at distance 3 over 96 rows: 16 pixels per unit at z = 0.
    let camera = Camera {
        fov_y: 90f32.to_radians(),
        ..Camera::look_at(glam::Vec3::new(0.0, 0.0, 3.0), glam::Vec3::ZERO)
    };
    let (w, h) = (128, 96);
    let half_pixel = glam::Vec2::new(1.0, -1.0) / 32.0;
    // Cells of 4 pixels (the per-triangle path) and of 32 (the deferred blocks).
    for (n, half) in [(40, 5.0), (5, 5.0)] {
        let mesh = grid(n, half, half_pixel, 0.0);
        let expected = cpu::rasterize(&mesh, &camera, w, h)
            .expect("cpu")
            .triangle_id;
        let ids = gpu_ids(gpu, &mesh, &camera, (w, h), &[]);
        let differ: Vec<(u32, u32)> = (0..h)
            .flat_map(|y| (0..w).map(move |x| (x, y)))
            .filter(|&(x, y)| expected.get(x, y) != ids[(y * w + x) as usize])
            .collect();
        assert!(
            differ.is_empty(),
            "{n} × {n} grid: {} pixels hold another triangle than the CPU's, e.g. {:?}",
            differ.len(),
            differ.first()
        );
    }
}

/// The 32-bit fallback (depths by 32-bit `atomicMin`, then the ids at those depths) writes the
/// 64-bit merge's buffer bit for bit: random scenes and cameras (depth ties included where
/// triangles share edges), the camera among the spheres (clipped and deferred triangles), and
/// the material gallery with its masked and dithered blended spheres (the alpha-tested draw,
/// twice).
#[test]
fn the_32_bit_fallback_writes_the_64_bit_buffer() {
    let Some(gpu) = gpu::test_device(&visibility::device_needs()) else {
        return;
    };
    if Atomics::best(&gpu.device) != Atomics::Wide {
        eprintln!("no 64-bit atomics on this adapter: nothing to compare the fallback with");
        return;
    }
    let spheres = opaque(scene::spheres_on_plane(6));
    let framed = spheres.camera_or_framed();
    let inside = Camera {
        eye: framed.target + (framed.eye - framed.target) * 0.15,
        ..framed
    };
    let gallery = scene::material_gallery();
    let mut cases = vec![
        (spheres.clone(), inside, (128, 96)),
        (gallery.clone(), gallery.camera_or_framed(), (160, 120)),
    ];
    for seed in [3, 17, 2024] {
        cases.push((
            opaque(common::random_scene(seed, 40)),
            common::random_camera(seed * 7919),
            (96, 72),
        ));
    }
    for (k, (scene, camera, size)) in cases.iter().enumerate() {
        let wide = gpu_words(gpu, scene, camera, *size, (Atomics::Wide, &[]));
        let narrow = gpu_words(gpu, scene, camera, *size, (Atomics::Narrow, &[]));
        let covered = wide.iter().filter(|&&w| w as u32 != NO_TRIANGLE).count();
        assert!(covered > 0, "case {k}: nothing drawn");
        let differ = wide.iter().zip(&narrow).filter(|(a, b)| a != b).count();
        assert_eq!(differ, 0, "case {k}: {differ} words differ");
    }
}

/// The passes' timing names: per merge pass the compute passes, then the alpha-tested draw
/// where there are alpha-tested meshes, each under the given prefix.
#[test]
fn passes_are_named_per_merge_pass() {
    let Some(gpu) = gpu::test_device(&visibility::device_needs()) else {
        return;
    };
    let gpass = GBufferPass::new(&gpu.device).expect("pass");
    let buffer = VisibilityPass::buffer(&gpu.device, 32, 24).expect("buffer");
    for (scene, alpha) in [
        (scene::material_gallery(), true),
        (opaque(scene::material_gallery()), false),
    ] {
        let uploaded = GpuScene::upload(&gpu.device, &gpu.queue, &scene, &gpass).expect("upload");
        for atomics in [Atomics::Wide, Atomics::Narrow] {
            if atomics == Atomics::Wide && Atomics::best(&gpu.device) != Atomics::Wide {
                continue;
            }
            let pass = VisibilityPass::with(&gpu.device, &gpass, Capacity::default(), atomics)
                .expect("visibility");
            let vis = pass
                .bind(
                    &gpu.device,
                    &uploaded,
                    gpass.frame_buffer(),
                    (32, 24),
                    &buffer,
                )
                .expect("bind")
                .named("ss ");
            let mut expected = vec!["ss visibility"];
            if alpha {
                expected.push("ss visibility hardware");
            }
            if atomics == Atomics::Narrow {
                expected.push("ss visibility ids");
                if alpha {
                    expected.push("ss visibility hardware ids");
                }
            }
            assert_eq!(
                vis.pass_names(),
                expected,
                "{atomics:?}, alpha-tested {alpha}"
            );
        }
    }
}

/// Lists too small for the deferred triangles lose some and say how many entries did not fit.
#[test]
fn overflowing_lists_are_counted() {
    let Some(gpu) = gpu::test_device(&visibility::device_needs()) else {
        return;
    };
    let scene = opaque(scene::spheres_on_plane(6));
    let camera = scene.camera_or_framed();
    let gpass = GBufferPass::new(&gpu.device).expect("pass");
    let uploaded = GpuScene::upload(&gpu.device, &gpu.queue, &scene, &gpass).expect("upload");
    let tiny = Capacity {
        deferred: 1,
        setups: 1,
        blocks: 1,
    };
    let pass = VisibilityPass::with(&gpu.device, &gpass, tiny, Atomics::best(&gpu.device))
        .expect("visibility");
    let buffer = VisibilityPass::buffer(&gpu.device, 160, 120).expect("buffer");
    gpass.write_frame(&gpu.queue, &Frame::new(&camera, 160, 120));
    let frame = gpass.frame_buffer();
    let vis = pass
        .bind(&gpu.device, &uploaded, frame, (160, 120), &buffer)
        .expect("bind");
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    vis.encode(&mut encoder, None, None).expect("encode");
    gpu.queue.submit([encoder.finish()]);
    assert!(vis.overflow(&gpu.device, &gpu.queue).expect("counts") > 0);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(12))]

    #[test]
    fn random_scenes_match_the_cpu_rasteriser(seed in 0u64..1_000_000, cam in 0u64..1_000_000, tris in 1usize..40, w in 8u32..96, h in 8u32..96) {
        let scene = opaque(common::random_scene(seed, tris));
        let camera = common::random_camera(cam);
        let share = compare(&scene, &camera, (w, h), &[]).map_err(TestCaseError::fail)?;
        prop_assert!(share >= 0.995, "{:.2} % of the pixels match", share * 100.0);
    }
}
