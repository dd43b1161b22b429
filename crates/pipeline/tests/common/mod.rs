//! What the ground-truth tests share: the Cornell box of the shared fixtures and the path
//! tracer's image of it.

use gbuffer::Image;
use scene::reference::ReferenceConfig;

/// The test GPU, the Cornell box of the shared fixtures and its view; `None` (skipped, a
/// failure in CI) without a GPU or the fixtures.
pub fn cornell() -> Option<(&'static gpu::Gpu, scene::Scene, scene::Camera)> {
    let gpu = gpu::test_device(&pipeline::device_needs())?;
    let Some(fixtures) = scene::shared_fixtures() else {
        assert!(
            std::env::var_os("CI").is_none(),
            "CI needs ../shared/fixtures"
        );
        eprintln!("skipped: no ../shared/fixtures");
        return None;
    };
    let path = fixtures.join("cornell/CornellBox-Original.obj");
    let scene = scene::Scene::load(&path).expect("cornell");
    let camera = scene::preset_view(&path, &scene).expect("the Cornell view of views.json");
    Some((gpu, scene, camera))
}

/// The path tracer's image of `scene` (its lights and emissive triangles) with `bounces`
/// after the first surface at `spp`; `jitter: false` traces through pixel centres, where the
/// rasteriser samples (per-pixel RMS then compares like with like).
pub fn truth(
    scene: &scene::Scene,
    camera: scene::Camera,
    size: (u32, u32),
    (bounces, jitter): (u32, bool),
    spp: u32,
) -> Image<[f32; 4]> {
    let config = ReferenceConfig {
        max_bounces: bounces,
        jitter,
        ..ReferenceConfig::default()
    };
    bench::path_traced(scene, &scene.lights, camera, size, config, spp).expect("truth")
}
