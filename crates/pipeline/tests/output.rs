//! The output transform (exposure, tone mapper) on the GPU against its CPU twin, and against
//! what its definitions say.

use pipeline::output::{DISPLAY_FORMAT, OutputPass, OutputTransform, ToneMapper, aces_fitted};

fn upload(gpu: &gpu::Gpu, image: &gbuffer::Image<[f32; 4]>) -> wgpu::Texture {
    gpu::transfer::texture_init(
        &gpu.device,
        &gpu.queue,
        "radiance",
        image.width(),
        image.height(),
        pipeline::gpu::RADIANCE_FORMAT,
        wgpu::TextureUsages::TEXTURE_BINDING,
        bytemuck::cast_slice(image.pixels()),
    )
    .expect("upload")
}

/// Runs `OutputPass` (new → bind → encode) over `image`.
fn on_gpu(
    gpu: &gpu::Gpu,
    image: &gbuffer::Image<[f32; 4]>,
    t: &OutputTransform,
) -> gbuffer::Image<[f32; 4]> {
    let radiance = upload(gpu, image);
    let display = gpu::transfer::texture_2d(
        &gpu.device,
        "display",
        image.width(),
        image.height(),
        DISPLAY_FORMAT,
        gpu::transfer::STORAGE_OUTPUT,
    );
    let pass = OutputPass::new(&gpu.device).expect("pass");
    let bound = pass
        .bind(&gpu.device, &radiance, &display, t)
        .expect("bind");
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    bound.encode(&mut encoder, None);
    gpu.queue.submit([encoder.finish()]);
    pipeline::gpu::read_display(&gpu.device, &gpu.queue, &display).expect("read")
}

/// Reinhard et al.'s automatic exposure: an image whose lit pixels hold luminances L₁ and L₂
/// (half each, plus black pixels, which do not count) is scaled by 0.18 / exp(mean log(δ + L)),
/// so with the clamp curve a grey pixel of L reads L × that.
#[test]
fn auto_exposure_maps_the_log_average_to_the_key() {
    let (l1, l2) = (0.02f32, 2.0f32);
    let pixels: Vec<[f32; 4]> = (0..64)
        .map(|i| match i % 3 {
            0 => [l1, l1, l1, 1.0],
            1 => [l2, l2, l2, 1.0],
            _ => [0.0, 0.0, 0.0, 1.0],
        })
        .collect();
    let image = gbuffer::Image::from_vec(8, 8, pixels).expect("image");
    let t = OutputTransform {
        exposure_ev: -1.0,
        auto_exposure: true,
        tone_mapper: ToneMapper::Clamp,
    };
    // 22 pixels of L1 and 21 of L2 (i % 3 over 0..64).
    let mean_log = (22.0 * (1e-4 + l1).ln() + 21.0 * (1e-4 + l2).ln()) / 43.0;
    let scale = 0.5 * 0.18 / mean_log.exp();
    assert!((t.exposure(&image) / scale - 1.0).abs() < 1e-5);
    let cpu = t.apply(&image);
    assert!((cpu.get(0, 0)[0] - l1 * scale).abs() < 1e-6);
    if let Some(gpu) = gpu::test_device(&pipeline::device_needs()) {
        let got = on_gpu(gpu, &image, &t);
        for (a, b) in got.pixels().iter().zip(cpu.pixels()) {
            assert!(
                (a[0] - b[0]).abs() <= 1e-3 * b[0].max(1.0),
                "{a:?} vs {b:?}"
            );
        }
    }
}

/// Hill's fitted ACES: black stays black, the curve rises monotonically and saturates at 1
/// (the ODT's white), and mid-grey lands near 0.8 × itself (the RRT's filmic toe/shoulder).
#[test]
fn aces_fitted_is_a_monotone_curve_to_white() {
    let grey = |v: f32| aces_fitted(glam::Vec3::splat(v)).x;
    assert!(grey(0.0).abs() < 1e-3);
    let mut last = grey(0.0);
    for i in 1..200 {
        let v = grey(i as f32 * 0.1);
        assert!(v >= last, "not monotone at {}", i as f32 * 0.1);
        last = v;
    }
    assert!((grey(1000.0) - 1.0).abs() < 0.02, "{}", grey(1000.0));
    assert!((0.1..0.2).contains(&grey(0.18)), "{}", grey(0.18));
}

/// A rendered frame (the material gallery, lit and emitting) through the renderer's output
/// stage equals the CPU twin applied to the same radiance: half-float display, f32 sums of
/// the log-luminance in another order.
#[test]
fn renderer_output_matches_the_cpu_twin() {
    let Some(gpu) = gpu::test_device(&pipeline::device_needs()) else {
        return;
    };
    let s = scene::material_gallery();
    let camera = s.camera.expect("camera");
    let mut r = pipeline::gpu::GpuRenderer::new(&gpu.device, &gpu.queue, &s, &s.lights, 96, 64)
        .expect("renderer");
    for t in [
        OutputTransform::default(),
        OutputTransform {
            exposure_ev: 0.5,
            auto_exposure: true,
            tone_mapper: ToneMapper::AcesFitted,
        },
        OutputTransform {
            exposure_ev: -2.0,
            auto_exposure: false,
            tone_mapper: ToneMapper::Clamp,
        },
    ] {
        r.set_output(&gpu.device, Some(t)).expect("output");
        let radiance = r
            .render(&gpu.device, &gpu.queue, &camera, pipeline::DEFAULT_AMBIENT)
            .expect("render")
            .image;
        let display =
            pipeline::gpu::read_display(&gpu.device, &gpu.queue, r.display().expect("display"))
                .expect("read");
        let want = t.apply(&radiance);
        let worst = display
            .pixels()
            .iter()
            .zip(want.pixels())
            .flat_map(|(a, b)| (0..3).map(move |k| (a[k] - b[k]).abs()))
            .fold(0.0f32, f32::max);
        assert!(worst <= 2e-3, "{t:?}: off by {worst}");
    }
}
