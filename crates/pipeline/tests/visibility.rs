//! The renderer's G-buffer through the visibility buffer (`GpuRenderer::set_visibility`, issue
//! 29) against the hardware path: the same frame within 40 dB (the G-buffers agree within the
//! hardware pass's tolerances; edge pixels may go to a neighbouring triangle), alpha-tested
//! materials included, and the shading methods it cannot serve refused with errors that say why.

use gbuffer::gpu::visibility;
use glam::Vec3;
use pipeline::{ShadingConfig, ShadingMethod, gpu::GpuRenderer, psnr};

fn device() -> Option<&'static gpu::Gpu> {
    gpu::test_device(&pipeline::device_needs().and(&visibility::device_needs()))
}

#[test]
fn the_visibility_path_renders_the_hardware_frame() {
    let Some(gpu) = device() else { return };
    the_same_frame(gpu, &scene::cornell_box(), false);
}

/// The material gallery's masked and dithered blended spheres: their meshes take the hardware
/// draw into the visibility buffer.
#[test]
fn alpha_tested_materials_render_the_hardware_frame() {
    let Some(gpu) = device() else { return };
    the_same_frame(gpu, &scene::material_gallery(), true);
}

/// The frame of `s` through the visibility path within 40 dB of the hardware path's; the
/// passes timed (`alpha`: the alpha-tested draw among them); rebound after a resize.
/// Trilinear filtering: anisotropic filters are implementation-defined, and llvmpipe's
/// differs between implicit derivatives (the hardware path) and explicit ones (the resolve):
/// 22 dB on the gallery's textures with 16× anisotropy, opaque or not.
fn the_same_frame(gpu: &gpu::Gpu, s: &scene::Scene, alpha: bool) {
    let camera = s.camera_or_framed();
    let trilinear = gbuffer::TextureOptions { max_anisotropy: 1 };
    let (w, h) = (96, 72);
    let mut renderer =
        GpuRenderer::new_with(&gpu.device, &gpu.queue, s, &s.lights, (w, h), &trilinear)
            .expect("renderer");
    let hardware = renderer
        .render(&gpu.device, &gpu.queue, &camera, Vec3::splat(0.05))
        .expect("hardware frame");
    renderer
        .set_visibility(&gpu.device, true)
        .expect("visibility");
    assert!(renderer.visibility());
    let visible = renderer
        .render(&gpu.device, &gpu.queue, &camera, Vec3::splat(0.05))
        .expect("visibility frame");
    let db = psnr(&hardware.image, &visible.image);
    assert!(db >= 40.0, "PSNR {db:.1} dB between the two paths");
    if gpu.has_timestamps() {
        let names: Vec<&str> = visible.timings.iter().map(|t| t.name.as_str()).collect();
        for pass in ["visibility", "visibility resolve", "visibility depth"] {
            assert!(names.contains(&pass), "{pass} not timed: {names:?}");
        }
        assert_eq!(
            names.contains(&"visibility hardware"),
            alpha,
            "the alpha-tested draw: {names:?}"
        );
        assert!(
            !names.contains(&"gbuffer"),
            "the hardware G-buffer still drawn: {names:?}"
        );
    }
    // After a resize the path is bound to the new targets.
    renderer
        .resize(&gpu.device, &gpu.queue, 64, 48)
        .expect("resize");
    renderer
        .render(&gpu.device, &gpu.queue, &camera, Vec3::splat(0.05))
        .expect("resized frame");
}

/// With supersampling the supersampled G-buffer goes through the visibility buffer too: the
/// frame of every sample (full 2×2 supersampling) within 40 dB of the hardware path's.
#[test]
fn the_supersampled_gbuffer_goes_through_the_visibility_buffer() {
    let Some(gpu) = device() else { return };
    let s = scene::cornell_box();
    let camera = s.camera_or_framed();
    let (d, q) = (&gpu.device, &gpu.queue);
    let mut renderer = GpuRenderer::new(d, q, &s, &s.lights, 64, 48).expect("renderer");
    let full = adaptive_ssaa::SsaaConfig {
        m: 2,
        min_samples: 4,
        anisotropy: 1,
        ..Default::default()
    };
    renderer.set_ssaa(d, q, Some(&full)).expect("ssaa");
    let hardware = renderer
        .render(d, q, &camera, Vec3::splat(0.05))
        .expect("hardware frame");
    renderer.set_visibility(d, true).expect("visibility");
    let visible = renderer
        .render(d, q, &camera, Vec3::splat(0.05))
        .expect("visibility frame");
    let db = psnr(&hardware.image, &visible.image);
    assert!(db >= 40.0, "PSNR {db:.1} dB between the two paths");
    if gpu.has_timestamps() {
        let names: Vec<&str> = visible.timings.iter().map(|t| t.name.as_str()).collect();
        for pass in [
            "ss visibility",
            "ss visibility resolve",
            "ss visibility depth",
        ] {
            assert!(names.contains(&pass), "{pass} not timed: {names:?}");
        }
        assert!(
            !names.contains(&"ss gbuffer"),
            "the hardware path still drawn: {names:?}"
        );
    }
}

/// `choose_gbuffer_path` times both paths and keeps the faster, and says why where the
/// visibility path cannot run (Forward+ draws the scene again).
#[test]
fn the_faster_gbuffer_path_is_kept() {
    let Some(gpu) = device() else { return };
    let s = scene::cornell_box();
    let camera = s.camera_or_framed();
    let (d, q) = (&gpu.device, &gpu.queue);
    let mut renderer = GpuRenderer::new(d, q, &s, &s.lights, 64, 48).expect("renderer");
    if !gpu.has_timestamps() {
        let e = renderer
            .choose_gbuffer_path(d, q, &camera, 3)
            .expect_err("no timestamps");
        assert!(e.to_string().contains("timestamp"), "{e}");
        return;
    }
    let choice = renderer
        .choose_gbuffer_path(d, q, &camera, 3)
        .expect("choice");
    let visibility_ms = *choice
        .visibility_ms
        .as_ref()
        .expect("the visibility path runs");
    assert!(
        choice.hardware_ms > 0.0 && visibility_ms > 0.0,
        "{choice:?}"
    );
    assert_eq!(choice.visibility, visibility_ms < choice.hardware_ms);
    // Each split measured once, from none of the meshes by the hardware rasteriser to more;
    // the fastest is the visibility path's time, and is the split kept.
    assert!(
        choice.splits[0].hardware_meshes.is_empty(),
        "{:?}",
        choice.splits
    );
    for pair in choice.splits.windows(2) {
        assert!(
            pair[1].above_pixels < pair[0].above_pixels
                && pair[1].hardware_meshes.len() > pair[0].hardware_meshes.len()
                && pair[0]
                    .hardware_meshes
                    .iter()
                    .all(|m| pair[1].hardware_meshes.contains(m)),
            "{:?}",
            choice.splits
        );
    }
    eprintln!("{choice}");
    let fastest = choice.fastest_split().expect("a split");
    assert_eq!(fastest.ms, visibility_ms);
    assert!(choice.to_string().contains("splits tried"), "{choice}");
    if choice.visibility {
        assert_eq!(
            renderer.visibility_hardware_meshes(),
            Some(fastest.hardware_meshes.as_slice())
        );
    }
    assert_eq!(
        renderer.visibility(),
        choice.visibility,
        "the kept path is set"
    );
    renderer
        .render(d, q, &camera, Vec3::splat(0.05))
        .expect("a frame on the kept path");

    let forward = ShadingConfig {
        method: ShadingMethod::ForwardPlus,
        ..ShadingConfig::default()
    };
    renderer.set_shading(d, q, &forward).ok();
    if renderer.visibility() {
        // Forward+ is refused while the visibility path is on: switch it off first.
        renderer.set_visibility(d, false).expect("off");
        renderer.set_shading(d, q, &forward).expect("Forward+");
    }
    let choice = renderer
        .choose_gbuffer_path(d, q, &camera, 3)
        .expect("choice");
    let why = choice
        .visibility_ms
        .as_ref()
        .expect_err("Forward+ excludes it");
    assert!(why.contains("exclude each other"), "{why}");
    assert!(!choice.visibility && !renderer.visibility());
    assert!(
        choice.to_string().starts_with("hardware rasteriser"),
        "{choice}"
    );
}

/// Lists too small for a frame's deferred triangles lose some: `check_visibility` says so and
/// grows them, until the frame is the hardware path's again.
#[test]
fn overflowing_lists_grow_until_every_triangle_is_drawn() {
    let Some(gpu) = device() else { return };
    let s = scene::cornell_box();
    let camera = s.camera_or_framed();
    let (d, q) = (&gpu.device, &gpu.queue);
    let mut renderer = GpuRenderer::new(d, q, &s, &s.lights, 96, 72).expect("renderer");
    let hardware = renderer
        .render(d, q, &camera, Vec3::splat(0.05))
        .expect("hardware frame");
    let tiny = visibility::Capacity {
        deferred: 1,
        setups: 1,
        blocks: 1,
    };
    renderer.set_visibility_with(d, tiny).expect("visibility");
    let mut grown = 0;
    loop {
        let frame = renderer
            .render(d, q, &camera, Vec3::splat(0.05))
            .expect("visibility frame");
        if !renderer.check_visibility(d, q).expect("check") {
            let db = psnr(&hardware.image, &frame.image);
            assert!(db >= 40.0, "after {grown} growths: PSNR {db:.1} dB");
            break;
        }
        if grown == 0 {
            let db = psnr(&hardware.image, &frame.image);
            assert!(db < 30.0, "triangles lost, yet PSNR {db:.1} dB");
        }
        grown += 1;
        assert!(grown <= 10, "still overflowing after {grown} growths");
    }
    assert!(grown > 0, "the tiny lists overflowed");
}

/// Meshes handed to the hardware rasteriser (`set_visibility_split`) draw into the visibility
/// buffer, timed as such, and the frame stays the hardware path's; the split needs the path
/// on, and one naming a missing mesh is refused, the split before kept.
#[test]
fn a_split_between_the_rasterisers_renders_the_hardware_frame() {
    let Some(gpu) = device() else { return };
    let s = scene::cornell_box();
    let camera = s.camera_or_framed();
    let (d, q) = (&gpu.device, &gpu.queue);
    let mut renderer = GpuRenderer::new(d, q, &s, &s.lights, 96, 72).expect("renderer");
    let even: Vec<usize> = (0..s.meshes.len()).step_by(2).collect();
    let e = renderer
        .set_visibility_split(d, &even)
        .expect_err("the path is off");
    assert!(e.to_string().contains("set_visibility"), "{e}");
    let hardware = renderer
        .render(d, q, &camera, Vec3::splat(0.05))
        .expect("hardware frame");
    renderer.set_visibility(d, true).expect("visibility");
    renderer.set_visibility_split(d, &even).expect("split");
    assert_eq!(renderer.visibility_hardware_meshes(), Some(even.as_slice()));
    let split = renderer
        .render(d, q, &camera, Vec3::splat(0.05))
        .expect("split frame");
    let db = psnr(&hardware.image, &split.image);
    assert!(db >= 40.0, "PSNR {db:.1} dB between the two paths");
    if gpu.has_timestamps() {
        let names: Vec<&str> = split.timings.iter().map(|t| t.name.as_str()).collect();
        for pass in ["visibility", "visibility hardware", "visibility resolve"] {
            assert!(names.contains(&pass), "{pass} not timed: {names:?}");
        }
    }
    let missing = s.meshes.len();
    let e = renderer
        .set_visibility_split(d, &[missing])
        .expect_err("no such mesh");
    assert!(e.to_string().contains(&format!("mesh {missing}")), "{e}");
    assert_eq!(renderer.visibility_hardware_meshes(), Some(even.as_slice()));
    renderer
        .render(d, q, &camera, Vec3::splat(0.05))
        .expect("a frame with the split kept");
}

/// A split rule re-splits the meshes as the camera moves: meshes whose triangles cover more
/// than the threshold from the camera (measured here on the scene uploaded on its own) go to
/// the hardware rasteriser, frame by frame, and the frame stays the hardware path's; a split
/// by hand ends the rule, and a rule needs a camera and a number.
#[test]
fn a_split_rule_follows_the_camera() {
    let Some(gpu) = device() else { return };
    let s = scene::cornell_box();
    let (d, q) = (&gpu.device, &gpu.queue);
    let (w, h) = (96, 72);
    let mut renderer = GpuRenderer::new(d, q, &s, &s.lights, w, h).expect("renderer");
    renderer.set_visibility(d, true).expect("visibility");
    let e = renderer
        .set_visibility_split_rule(d, 64.0)
        .expect_err("no camera yet");
    assert!(e.to_string().contains("set_camera"), "{e}");
    let far = s.camera_or_framed();
    let near = scene::Camera {
        eye: far.eye + (far.target - far.eye) * 0.6,
        ..far
    };
    // The meshes above the threshold from each camera, measured apart from the renderer.
    let gpass = gbuffer::gpu::GBufferPass::new(d).expect("G-buffer pass");
    let uploaded = gbuffer::gpu::GpuScene::upload(d, q, &s, &gpass).expect("upload");
    let above = |camera: &scene::Camera, t: f32| -> Vec<usize> {
        let pixels = uploaded.pixels_per_triangle(&gbuffer::Frame::new(camera, w, h));
        (0..pixels.len()).filter(|&m| pixels[m] > t).collect()
    };
    // A threshold between the two views: some mesh crosses it as the camera comes near.
    let threshold = [16.0, 64.0, 256.0, 1024.0]
        .into_iter()
        .find(|&t| above(&far, t) != above(&near, t))
        .expect("a threshold some mesh crosses");
    renderer.set_camera(q, &far).expect("camera");
    renderer
        .set_visibility_split_rule(d, threshold)
        .expect("rule");
    assert_eq!(renderer.visibility_split_rule(), Some(threshold));
    for camera in [far, near, far] {
        let split = renderer
            .render(d, q, &camera, Vec3::splat(0.05))
            .expect("frame");
        let expected = above(&camera, threshold);
        assert_eq!(
            renderer.visibility_hardware_meshes(),
            Some(expected.as_slice()),
            "eye {:?}",
            camera.eye
        );
        assert!(
            !renderer.follow_visibility_split(d).expect("follow"),
            "already followed"
        );
        let mut hardware = GpuRenderer::new(d, q, &s, &s.lights, w, h).expect("renderer");
        let reference = hardware
            .render(d, q, &camera, Vec3::splat(0.05))
            .expect("hardware frame");
        let db = psnr(&reference.image, &split.image);
        assert!(db >= 40.0, "PSNR {db:.1} dB between the two paths");
    }
    renderer.set_visibility_split(d, &[0]).expect("by hand");
    assert_eq!(renderer.visibility_split_rule(), None);
    renderer.set_camera(q, &near).expect("camera");
    assert!(!renderer.follow_visibility_split(d).expect("no rule"));
    assert_eq!(renderer.visibility_hardware_meshes(), Some(&[0][..]));
    let e = renderer
        .set_visibility_split_rule(d, f32::NAN)
        .expect_err("not a number");
    assert!(e.to_string().contains("number"), "{e}");
}

#[test]
fn redrawing_methods_are_refused() {
    let Some(gpu) = device() else { return };
    let s = scene::cornell_box();
    let mut renderer =
        GpuRenderer::new(&gpu.device, &gpu.queue, &s, &s.lights, 32, 24).expect("renderer");
    let forward = ShadingConfig {
        method: ShadingMethod::ForwardPlus,
        ..ShadingConfig::default()
    };
    renderer
        .set_shading(&gpu.device, &gpu.queue, &forward)
        .expect("Forward+");
    let e = renderer
        .set_visibility(&gpu.device, true)
        .expect_err("Forward+");
    assert!(e.to_string().contains("exclude each other"), "{e}");
    assert!(!renderer.visibility(), "the hardware path stays");
}

/// The splits measured: one per threshold of `SPLIT_PIXELS` that moves a mesh, meshes above it.
#[test]
fn splits_are_distinct_thresholds_of_pixels_per_triangle() {
    let splits = pipeline::gpu::visibility_splits(&[10.0, 5000.0, 0.0]);
    assert_eq!(
        splits,
        vec![
            (f32::INFINITY, vec![]),
            (4096.0, vec![1]),
            (4.0, vec![0, 1]),
        ]
    );
}
