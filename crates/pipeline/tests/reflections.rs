//! Reflection maps in the frame (Holländer 2013 §3.6.1, Fig. 3.19;
//! `GpuRenderer::set_reflections`): mirror spheres in the Cornell box rendered with and
//! without them. The reflection pass is tested against its CPU twin and the maps against rays
//! in `instant-radiosity/tests/reflections.rs`; here, the composition adds it where it
//! belongs: only mirror pixels change, none gets darker, and many get brighter. The VPLs'
//! indirect light, which fills the same slot, is refused with it.

use instant_radiosity::{
    IndirectConfig,
    pbgi::{LitPoints, PbgiConfig},
    reflections::has_probes,
    vpl,
};
use pipeline::gpu::GpuRenderer;

#[test]
fn reflections_brighten_only_the_mirrors() {
    let Some(gpu) = gpu::test_device(&pipeline::device_needs()) else {
        return;
    };
    let (d, q) = (&gpu.device, &gpu.queue);
    let scene = scene::mirror_spheres(8);
    let camera = scene.camera_or_framed();
    let (w, h) = (64, 48);
    let config = PbgiConfig {
        tile: 16,
        epsilon: 1.0,
        points_log2: 14,
    };
    let lit = LitPoints::sampled(&scene, &config).expect("surfels");
    let frame = |reflections: bool| {
        let mut r = GpuRenderer::new(d, q, &scene, &scene.lights, w, h).expect("renderer");
        if reflections {
            r.set_reflections(d, Some((&lit, 16, &scene)))
                .expect("reflections");
        }
        let mut image = r
            .render(d, q, &camera, glam::Vec3::ZERO)
            .expect("frame")
            .image;
        if r.check_reflections(d, q)
            .expect("the cuts fit the largest lists")
        {
            image = r
                .render(d, q, &camera, glam::Vec3::ZERO)
                .expect("frame")
                .image;
        }
        let gbuffer = r.targets().read(d, q).expect("G-buffer");
        (image, gbuffer, r)
    };
    let (plain, gb, _) = frame(false);
    let (reflected, _, mut r) = frame(true);
    let (mut mirrors, mut brighter) = (0, 0);
    for y in 0..h {
        for x in 0..w {
            let word = gb.material.get(x, y);
            let mirror = word != u32::MAX
                && has_probes(&scene.materials[gbuffer::unpack_material(word).2 as usize]);
            let (a, b) = (plain.get(x, y), reflected.get(x, y));
            if mirror {
                mirrors += 1;
                assert!(
                    (0..3).all(|c| b[c] >= a[c]),
                    "({x}, {y}) got darker: {a:?} → {b:?}"
                );
                brighter += usize::from((0..3).any(|c| b[c] > a[c] + 1e-3));
            } else {
                assert_eq!(a, b, "({x}, {y}) is not a mirror but changed");
            }
        }
    }
    println!("{brighter} of {mirrors} mirror pixels brighter with reflections");
    assert!(mirrors > 50, "{mirrors} mirror pixels");
    assert!(brighter * 4 > mirrors, "{brighter} of {mirrors} brighter");

    // The VPLs' stage and the reflections share the indirect specular slot.
    let vpl_config = IndirectConfig::new(scene.bounds());
    let vpls = vpl::generate(
        &scene,
        &scene::Bvh::build(&scene),
        &scene.lights,
        &vpl::VplConfig {
            count: 64,
            subsets: vpl_config.subsets(),
            seed: 1,
            emissive: false,
            bounces: 1,
        },
    )
    .expect("VPLs");
    assert!(r.set_indirect(d, &vpl_config, &vpls).is_err());
    r.set_reflections(d, None).expect("removed");
    let mut r = GpuRenderer::new(d, q, &scene, &scene.lights, w, h).expect("renderer");
    r.set_indirect(d, &vpl_config, &vpls).expect("VPLs");
    assert!(r.set_reflections(d, Some((&lit, 16, &scene))).is_err());
}
