//! The renderer against the path-traced ground truth (`scene::reference`) on the original
//! Cornell box (`../shared/fixtures/cornell`), lit by its ceiling lamp: what a feature must do
//! to the error, for physical reasons independent of the code — VPLs without visibility leak
//! light through the boxes (too bright), and VPL visibility removes most of that leak. The
//! measured errors are in docs/ground-truth.md.

use gbuffer::accuracy;
use instant_radiosity::{
    IndirectConfig,
    shadows::{ShadowConfig, VplShadows},
    vpl,
};
use pipeline::gpu::GpuRenderer;
use tiled_shading::shadows::ShadowMapConfig;

mod common;

use common::cornell;

#[test]
fn shadowed_area_light_samples_match_the_path_traced_direct_light() {
    let Some((gpu, scene, camera)) = cornell() else {
        return;
    };
    let (d, q) = (&gpu.device, &gpu.queue);
    let size = (64, 64);
    let truth = common::truth(&scene, camera, size, (0, true), 1024);
    let frame = |samples: u32, shadows: Option<&ShadowMapConfig>| {
        let (lights, _, _) = vpl::primary_lights_sampled(&scene, samples);
        let mut r = GpuRenderer::new(d, q, &scene, &lights, size.0, size.1).expect("renderer");
        r.set_shadows(d, q, shadows).expect("shadows");
        let image = r
            .render(d, q, &camera, glam::Vec3::ZERO)
            .expect("frame")
            .image;
        accuracy(&truth, &image, 10.0)
    };
    let shadows = ShadowMapConfig {
        resolution: 256,
        ..ShadowMapConfig::default()
    };
    let unshadowed = frame(1, None);
    let hard = frame(1, Some(&shadows));
    let soft = frame(16, Some(&shadows));
    println!(
        "direct light against the path tracer: one unshadowed point {unshadowed:?}, one shadowed point {hard:?}, 16 shadowed samples {soft:?}"
    );
    assert!(
        hard.error < unshadowed.error,
        "shadows lower the error: {hard:?} vs {unshadowed:?}"
    );
    assert!(
        soft.error < hard.error,
        "penumbrae lower it further: {soft:?} vs {hard:?}"
    );
    // 0.056 measured at 64² against 1024 spp (2026-12-02) (the issue's ≤ 0.05 is for 256² against 4096
    // spp, where silhouettes weigh less: the accuracy bench measures it).
    assert!(soft.error <= 0.07, "{soft:?}");
}

/// Direct light (16 shadowed samples of the lamp) plus 1024 VPLs 4×4 against the path-traced
/// one-bounce image: without visibility the VPLs light what the boxes hide (brighter); ManyLoD
/// visibility removes that leak, and the frame stays within the stated error of the truth.
#[test]
fn vpl_visibility_removes_the_leak_through_the_boxes() {
    let Some((gpu, scene, camera)) = cornell() else {
        return;
    };
    let (d, q) = (&gpu.device, &gpu.queue);
    let (w, h) = (64, 64);
    // Direct light plus one bounce, as the VPLs approximate.
    let truth = common::truth(&scene, camera, (w, h), (1, true), 1024);
    let (lights, _, _) = vpl::primary_lights_sampled(&scene, 16);
    let config = IndirectConfig::new(scene.bounds());
    let bvh = scene::Bvh::build(&scene);
    let set = vpl::generate_from_primary(&scene, &bvh, 1024, config.subsets(), 1).expect("vpls");
    let direct_shadows = ShadowMapConfig {
        resolution: 256,
        ..ShadowMapConfig::default()
    };
    let frame = |shadows: Option<VplShadows>| {
        let mut r = GpuRenderer::new(d, q, &scene, &lights, w, h).expect("renderer");
        r.set_shadows(d, q, Some(&direct_shadows)).expect("shadows");
        match shadows {
            Some(mode) => r
                .set_vpl_shadows(
                    d,
                    &scene,
                    mode,
                    &ShadowConfig {
                        points_log2: 16,
                        ..ShadowConfig::for_mode(mode)
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
    // Measured 2026-12-02 (64², 1024 spp truth, the box Lambertian as its MTL says): bias
    // +4.3 % without visibility, −2.9 % with ManyLoD (its 32×32 maps also shadow some visible
    // pairs); error 0.095 and 0.085.
    assert!(
        visible.bias < leaking.bias - 0.04,
        "visibility should remove the leak through the boxes: {visible:?} vs {leaking:?}"
    );
    for a in [leaking, visible] {
        assert!(a.error <= 0.12 && a.bias.abs() <= 0.08, "{a:?}");
    }
}

/// A point light and the sun over spheres on a plane, direct light only, against the path
/// tracer through pixel centres: a delta light's direct light has no noise there, so the
/// renderer's exact shadows (a ray per pixel and light) leave only rounding and the odd
/// pixel where the two rays graze an edge differently; the shadow maps also miss by their
/// filter's penumbra and their texels.
#[test]
fn ray_shadows_give_the_path_tracers_direct_light() {
    let Some(gpu) = gpu::test_device(&pipeline::device_needs()) else {
        return;
    };
    let (d, q) = (&gpu.device, &gpu.queue);
    let scene = scene::spheres_on_plane(5);
    let lights: Vec<scene::Light> = [
        "point:0.5,2.5,0.5,8,1,0.9,0.8,2",
        "dir:0.4,-1,0.3,1,1,1,0.7",
    ]
    .iter()
    .map(|s| s.parse().expect("light"))
    .collect();
    let camera = scene.camera_or_framed();
    let size = (96, 64);
    let config = scene::reference::ReferenceConfig {
        max_bounces: 0,
        jitter: false,
        ..Default::default()
    };
    let truth = bench::path_traced(&scene, &lights, camera, size, config, 4).expect("truth");
    let frame = |rays: bool| {
        let mut r = GpuRenderer::new(d, q, &scene, &lights, size.0, size.1).expect("renderer");
        r.set_shadows(d, q, Some(&ShadowMapConfig::default()))
            .expect("maps");
        if rays {
            r.set_ray_shadows(d, q, Some(&scene)).expect("rays");
        }
        let image = r
            .render(d, q, &camera, glam::Vec3::ZERO)
            .expect("frame")
            .image;
        accuracy(&truth, &image, 10.0)
    };
    let (maps, rays) = (frame(false), frame(true));
    println!("direct light of delta lights against the path tracer: maps {maps:?}, rays {rays:?}");
    // Measured 2026-12-02 (llvmpipe; the image does not depend on the adapter): maps error
    // 0.0036, RMS 0.032; rays 0.00065, RMS 0.0042 (with rays lifted by 10⁻⁴ of the
    // diagonal instead of the path tracer's `ray_lift`: 0.0014 and 0.022, one pixel whose
    // ray passed an occluder the path tracer's met).
    assert!(rays.error <= 0.002 && rays.rms <= 0.01, "{rays:?}");
    assert!(
        rays.error < 0.5 * maps.error,
        "rays {rays:?}, maps {maps:?}"
    );
    assert!(rays.rms < maps.rms, "rays {rays:?}, maps {maps:?}");
}

/// Direct light (16 shadowed samples of the lamp) plus point-based GI's one bounce (every 4th
/// pixel's receiver gathering 2^16 lit surfels through 16² paraboloid texels at ε = 2,
/// upsampled) against the path-traced one-bounce image: PBGI sees the boxes (its views are
/// rasterised cuts), so it must stay within the bounds the VPLs with visibility meet, and
/// without it the frame lacks the bounce (much darker).
#[test]
fn pbgi_adds_the_bounce_the_path_tracer_sees() {
    let Some((gpu, scene, camera)) = cornell() else {
        return;
    };
    let (d, q) = (&gpu.device, &gpu.queue);
    let (w, h) = (64, 64);
    let truth = common::truth(&scene, camera, (w, h), (1, true), 1024);
    let (lights, _, _) = vpl::primary_lights_sampled(&scene, 16);
    let gpu_lights: Vec<tiled_shading::GpuLight> =
        lights.iter().map(tiled_shading::GpuLight::from).collect();
    let config = instant_radiosity::pbgi::PbgiConfig {
        tile: 16,
        epsilon: 2.0,
        points_log2: 16,
    };
    let lit =
        instant_radiosity::pbgi::LitPoints::new(&scene, &gpu_lights, &config).expect("surfels");
    let frame = |pbgi: bool| {
        let mut r = GpuRenderer::new(d, q, &scene, &lights, w, h).expect("renderer");
        r.set_shadows(d, q, Some(&ShadowMapConfig::default()))
            .expect("shadows");
        if pbgi {
            r.set_pbgi(d, Some((&lit, 4, &scene))).expect("pbgi");
        }
        let mut image = r
            .render(d, q, &camera, glam::Vec3::ZERO)
            .expect("frame")
            .image;
        if r.check_pbgi(d, q).expect("the cuts fit the largest lists") {
            image = r
                .render(d, q, &camera, glam::Vec3::ZERO)
                .expect("frame")
                .image;
        }
        assert!(
            !r.check_pbgi(d, q).expect("check"),
            "grown lists hold the cut"
        );
        accuracy(&truth, &image, 10.0)
    };
    let (direct, with_pbgi) = (frame(false), frame(true));
    println!("against the path tracer: direct only {direct:?}, with PBGI {with_pbgi:?}");
    assert!(
        direct.bias < -0.1,
        "the bounce is missing without it: {direct:?}"
    );
    assert!(
        with_pbgi.error <= 0.12 && with_pbgi.bias.abs() <= 0.08,
        "{with_pbgi:?}"
    );
}
