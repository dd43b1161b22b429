//! Supersampling inside the frame (`GpuRenderer::set_ssaa`): against the adaptive-ssaa
//! crate's own renderer (tested against its CPU twin) where both apply, against the
//! path-traced pixel integral, and the rules the frame states — adaptive pixels of all samples
//! equal full supersampling, indirect light is the pixel's, shared by its samples.

use adaptive_ssaa::SsaaConfig;
use gbuffer::{Image, accuracy};
use glam::Vec3;
use instant_radiosity::{IndirectConfig, vpl};
use pipeline::gpu::GpuRenderer;
use scene::Scene;

mod scenes;

const SIZE: (u32, u32) = (64, 48);

fn lights() -> Vec<scene::Light> {
    [
        "point:0.5,2.5,0.5,8,1,0.9,0.8,2",
        "dir:0.4,-1,0.3,1,1,1,0.7",
    ]
    .iter()
    .map(|s| s.parse().expect("light"))
    .collect()
}

fn full(m: u32) -> SsaaConfig {
    SsaaConfig {
        m,
        min_samples: m * m,
        anisotropy: 1,
        ..Default::default()
    }
}

fn adaptive(m: u32) -> SsaaConfig {
    SsaaConfig {
        m,
        anisotropy: 1,
        ..Default::default()
    }
}

/// A frame of `scene` with `config`'s supersampling (and indirect light from `set`, if given):
/// radiance and samples per pixel.
fn frame(
    gpu: &gpu::Gpu,
    scene: &Scene,
    lights: &[scene::Light],
    ssaa: Option<&SsaaConfig>,
    indirect: Option<(&IndirectConfig, &vpl::VplSet)>,
    ambient: Vec3,
) -> (Image<[f32; 4]>, Option<Image<u32>>) {
    let (d, q) = (&gpu.device, &gpu.queue);
    let textures = gbuffer::TextureOptions { max_anisotropy: 1 };
    let mut r = GpuRenderer::new_with(d, q, scene, lights, SIZE, &textures).expect("renderer");
    if let Some((config, set)) = indirect {
        r.set_indirect(d, config, set).expect("indirect");
    }
    r.set_ssaa(d, q, ssaa).expect("ssaa");
    let image = r
        .render(d, q, &scene.camera_or_framed(), ambient)
        .expect("frame")
        .image;
    (image, r.ssaa_counts(d, q).expect("counts"))
}

fn max_difference(a: &[f32; 4], b: &[f32; 4]) -> f32 {
    (0..3).map(|k| (a[k] - b[k]).abs()).fold(0.0, f32::max)
}

/// Untextured spheres lit by a point and a directional light without shadows: the frame's
/// supersampling (tiled light accumulation on the masked samples, the composition per sample)
/// and the adaptive-ssaa renderer (every light per sample in its own kernels) shade the same
/// samples of the same G-buffer with the same BRDF, so full and adaptive images and the
/// adaptive sample counts agree.
#[test]
fn the_frame_supersamples_as_the_adaptive_ssaa_renderer() {
    let Some(gpu) = gpu::test_device(&pipeline::device_needs()) else {
        return;
    };
    let scene = scene::spheres_on_plane(5);
    let lights = lights();
    let camera = scene.camera_or_framed();
    let gpu_lights = tiled_shading::gpu_lights(&lights).expect("lights");
    for config in [full(4), adaptive(4), adaptive(2)] {
        let (image, counts) = frame(gpu, &scene, &lights, Some(&config), None, config.ambient);
        let expected =
            adaptive_ssaa::gpu::run(gpu, &scene, &camera, &gpu_lights, SIZE.0, SIZE.1, &config)
                .expect("adaptive-ssaa");
        let counts = counts.expect("counts");
        let n = config.samples();
        let same: Vec<bool> = counts
            .pixels()
            .iter()
            .zip(expected.counts.pixels())
            .map(|(a, b)| *a == (*b).clamp(1, n))
            .collect();
        let differing = same.iter().filter(|s| !**s).count();
        // The G-buffer stores albedo in 8 bits (the adaptive-ssaa renderer reads the
        // material's factor): up to half a step of 1/255, relative to the albedo; the shading
        // metric's thresholds see S through it, so a pixel at a threshold may take another
        // count (compared where the counts agree). The frame's S comes from the pixel grid
        // jittered onto the first samples, whose vertices the rasteriser snaps to 1/256 pixel
        // instead of 1/256 sample: a first sample within that of a silhouette may see the other
        // surface (a pixel or two of 3072).
        let relative: Vec<f32> = image
            .pixels()
            .iter()
            .zip(expected.image.pixels())
            .zip(&same)
            .filter(|(_, same)| **same)
            .map(|((a, b), _)| max_difference(a, b) / (1e-2 + b[0].max(b[1]).max(b[2])))
            .collect();
        let off = relative.iter().filter(|&&r| r >= 1e-2).count();
        let mean = counts.pixels().iter().sum::<u32>() as f32 / counts.pixels().len() as f32;
        println!(
            "m {} min {}: {off} pixels differ by 1 % or more, {differing} counts differ, {mean:.2} samples per pixel",
            config.m, config.min_samples
        );
        assert!(
            differing * 100 <= same.len(),
            "sample counts differ at {differing} pixels"
        );
        assert!(off <= 3, "{off} pixels differ by 1 % or more");
        if config.min_samples == 1 {
            assert!(
                mean > 1.0 && mean < 0.5 * n as f32,
                "adaptive: {mean} samples per pixel"
            );
        }
    }
}

/// The adaptive path (first samples, evaluation, the rest) gives a pixel it supersamples
/// fully exactly the full path's average, and a pixel of one sample its first sample.
#[test]
fn adaptive_pixels_of_every_sample_equal_full_supersampling() {
    let Some(gpu) = gpu::test_device(&pipeline::device_needs()) else {
        return;
    };
    let scene = scene::cornell_box();
    let ambient = pipeline::DEFAULT_AMBIENT;
    let (full_image, _) = frame(gpu, &scene, &scene.lights, Some(&full(4)), None, ambient);
    let (image, counts) = frame(
        gpu,
        &scene,
        &scene.lights,
        Some(&adaptive(4)),
        None,
        ambient,
    );
    let counts = counts.expect("counts");
    let mut compared = 0;
    for ((a, b), &k) in image
        .pixels()
        .iter()
        .zip(full_image.pixels())
        .zip(counts.pixels())
    {
        if k == 16 {
            assert!(max_difference(a, b) < 1e-5, "{a:?} vs {b:?}");
            compared += 1;
        }
    }
    assert!(compared > 20, "only {compared} pixels of 16 samples");
}

/// Indirect light is shaded once per pixel and shared by its samples. The pixels adaptive
/// supersampling gives one sample show the first sample (S), lit by the first sample's
/// indirect light; full supersampling composes every sample with that same pixel light, so
/// where a pixel's samples see one surface (the adaptive pixels of one sample, with and
/// without indirect light) both gain exactly the same indirect light.
#[test]
fn supersampled_pixels_share_their_indirect_light() {
    let Some(gpu) = gpu::test_device(&pipeline::device_needs()) else {
        return;
    };
    let scene = scene::cornell_box();
    let config = IndirectConfig::new(scene.bounds());
    let set = scenes::vpls(&scene, &config);
    let lit = |ssaa: &SsaaConfig, indirect| {
        frame(gpu, &scene, &scene.lights, Some(ssaa), indirect, Vec3::ZERO)
    };
    let gain = |ssaa: &SsaaConfig| {
        let (with, with_counts) = lit(ssaa, Some((&config, &set)));
        let (without, without_counts) = lit(ssaa, None);
        let gains: Vec<[f32; 4]> = with
            .pixels()
            .iter()
            .zip(without.pixels())
            .map(|(a, b)| std::array::from_fn(|k| a[k] - b[k]))
            .collect();
        let ones: Vec<bool> = with_counts
            .expect("counts")
            .pixels()
            .iter()
            .zip(without_counts.expect("counts").pixels())
            .map(|(a, b)| *a == 1 && *b == 1)
            .collect();
        (gains, ones)
    };
    let (full_gain, _) = gain(&full(4));
    let (first_gain, ones) = gain(&adaptive(4));
    let (mut single, mut equal) = (0, 0);
    for ((a, b), one) in full_gain.iter().zip(&first_gain).zip(&ones) {
        let scale = b.iter().take(3).fold(0.0f32, |m, v| m.max(v.abs()));
        if *one && scale > 1e-3 {
            single += 1;
            if max_difference(a, b) <= 1e-4 * scale {
                equal += 1;
            }
        }
    }
    let share = equal as f32 / single as f32;
    println!(
        "{single} lit pixels of one sample; {:.1} % of them gain the same indirect light in full supersampling",
        100.0 * share
    );
    assert!(
        single * 8 > full_gain.len(),
        "{single} lit pixels of one sample"
    );
    // The others have a sample on another surface than the first (an edge the metrics missed).
    assert!(share > 0.97, "{share}");
}

/// Against the path tracer's pixel integral (rays jittered over each pixel) of delta lights
/// with exact shadows: supersampling removes most of the one-sample frame's silhouette error.
#[test]
fn supersampling_approaches_the_path_traced_pixel_integral() {
    let Some(gpu) = gpu::test_device(&pipeline::device_needs()) else {
        return;
    };
    let (d, q) = (&gpu.device, &gpu.queue);
    let scene = scene::spheres_on_plane(5);
    let lights = lights();
    let camera = scene.camera_or_framed();
    let config = scene::reference::ReferenceConfig {
        max_bounces: 0,
        jitter: true,
        ..Default::default()
    };
    let truth = bench::path_traced(&scene, &lights, camera, SIZE, config, 256).expect("truth");
    let render = |ssaa: Option<&SsaaConfig>| {
        let mut r = GpuRenderer::new(d, q, &scene, &lights, SIZE.0, SIZE.1).expect("renderer");
        r.set_ray_shadows(d, q, Some(&scene)).expect("rays");
        r.set_ssaa(d, q, ssaa).expect("ssaa");
        let image = r.render(d, q, &camera, Vec3::ZERO).expect("frame").image;
        accuracy(&truth, &image, 10.0)
    };
    let one = render(None);
    let supersampled = render(Some(&full(4)));
    let adaptive = render(Some(&adaptive(4)));
    println!(
        "against the pixel integral: one sample {one:?}, full 4x4 {supersampled:?}, adaptive 4x4 {adaptive:?}"
    );
    assert!(
        supersampled.rms < 0.6 * one.rms,
        "{supersampled:?} vs {one:?}"
    );
    assert!(adaptive.rms < 0.8 * one.rms, "{adaptive:?} vs {one:?}");
}

/// A resize rebuilds the supersampling stage's targets around its compiled kernels: the
/// resized renderer's frame equals a new renderer's at that size, adaptive sample counts too.
#[test]
fn a_resized_renderer_supersamples_as_a_new_one() {
    let Some(gpu) = gpu::test_device(&pipeline::device_needs()) else {
        return;
    };
    let (d, q) = (&gpu.device, &gpu.queue);
    let scene = scenes::cesium_room();
    let textures = gbuffer::TextureOptions { max_anisotropy: 1 };
    let camera = scene.camera_or_framed();
    let config = adaptive(2);
    let make = |size: (u32, u32)| {
        let mut r =
            GpuRenderer::new_with(d, q, &scene, &lights(), size, &textures).expect("renderer");
        r.set_ssaa(d, q, Some(&config)).expect("ssaa");
        r
    };
    let mut resized = make((32, 24));
    resized
        .render(d, q, &camera, Vec3::splat(0.1))
        .expect("frame");
    resized.resize(d, q, SIZE.0, SIZE.1).expect("resize");
    let got = resized
        .render(d, q, &camera, Vec3::splat(0.1))
        .expect("frame");
    let mut fresh = make(SIZE);
    let expected = fresh
        .render(d, q, &camera, Vec3::splat(0.1))
        .expect("frame");
    assert_eq!(got.image.pixels(), expected.image.pixels());
    let counts = |r: &GpuRenderer| r.ssaa_counts(d, q).expect("counts").expect("adaptive");
    assert_eq!(counts(&resized).pixels(), counts(&fresh).pixels());
}
