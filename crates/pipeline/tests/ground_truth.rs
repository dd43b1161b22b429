//! The renderer against the path-traced ground truth (`scene::reference`) on the original
//! Cornell box (`../shared/fixtures/cornell`), lit by its ceiling lamp: what a feature must do
//! to the error, for physical reasons independent of the code — VPLs without visibility leak
//! light through the boxes (too bright), and VPL visibility removes most of that leak. The
//! measured errors are in docs/ground-truth.md.

use gbuffer::{Image, accuracy};
use instant_radiosity::{
    IndirectConfig,
    shadows::{ShadowConfig, VplShadows},
    vpl,
};
use pipeline::gpu::GpuRenderer;
use scene::reference::{PathTracer, ReferenceConfig};

#[test]
fn vpl_visibility_brings_the_frame_closer_to_the_path_tracer() {
    let Some(gpu) = gpu::test_device(&pipeline::device_needs()) else {
        return;
    };
    let (d, q) = (&gpu.device, &gpu.queue);
    let Some(fixtures) = scene::shared_fixtures() else {
        assert!(
            std::env::var_os("CI").is_none(),
            "CI needs ../shared/fixtures"
        );
        eprintln!("skipped: no ../shared/fixtures");
        return;
    };
    let path = fixtures.join("cornell/CornellBox-Original.obj");
    let scene = scene::Scene::load(&path).expect("cornell");
    let camera = scene::preset_view(&path, &scene).expect("the Cornell view of views.json");
    let (w, h) = (64, 64);
    // Direct light plus one bounce, as the VPLs approximate.
    let mut pt = PathTracer::new(
        &scene,
        camera,
        w,
        h,
        &scene.lights,
        ReferenceConfig::default(),
    );
    pt.add_samples(1024);
    let truth = Image::from_vec(
        w,
        h,
        pt.image().iter().map(|c| [c.x, c.y, c.z, 1.0]).collect(),
    )
    .expect("truth");
    let (lights, _, _) = vpl::primary_lights(&scene);
    let config = IndirectConfig::new(scene.bounds());
    let bvh = scene::Bvh::build(&scene);
    let set = vpl::generate_from_primary(&scene, &bvh, 1024, config.subsets(), 1).expect("vpls");
    let frame = |shadows: Option<VplShadows>| {
        let mut r = GpuRenderer::new(d, q, &scene, &lights, w, h).expect("renderer");
        match shadows {
            Some(mode) => r
                .set_vpl_shadows(
                    d,
                    &scene,
                    mode,
                    &ShadowConfig {
                        points_log2: 16,
                        ..Default::default()
                    },
                    &config,
                    &set,
                )
                .expect("shadows"),
            None => r.set_indirect(d, &config, &set).expect("indirect"),
        }
        let image = r
            .render(d, q, &camera, glam::Vec3::ZERO)
            .expect("frame")
            .image;
        accuracy(&truth, &image, 10.0)
    };
    let leaking = frame(None);
    let visible = frame(Some(VplShadows::ManyLod));
    println!("against the path tracer: no VPL visibility {leaking:?}, ManyLoD {visible:?}");
    assert!(leaking.pixels > (w * h / 2) as usize);
    assert!(
        leaking.bias > 0.1,
        "light leaking through the boxes should brighten: {leaking:?}"
    );
    assert!(
        visible.error < leaking.error && visible.bias < leaking.bias - 0.05,
        "visibility should remove the leak: {visible:?} vs {leaking:?}"
    );
}
