//! Shadow maps of the direct lights: the GPU's maps against depth ray-cast through every
//! texel (ground truth of the rasterisation), the CPU lookup on the read-back maps against the
//! GPU's shading (CPU twin), the lookup against shadow rays through the BVH (ground truth of
//! visibility), and the invariants: shadows only remove light, and they do remove it.

use gbuffer::{Frame, GBuffer};
use glam::Vec3;
use scene::{Bvh, Camera, Light, Scene};
use tiled_shading::{
    GpuLight, Method, ShadingConfig,
    cpu::{self, Shaded},
    gpu,
    rays::RayShadows,
    shadows::{self, ShadowMapConfig, ShadowMaps},
};

/// Spheres on a plane under a point light (six cube faces), a narrow spot (one view), a
/// wide spot (five faces), a hemispherical light (five faces) and a directional light (four
/// cascades): every kind of view.
fn spheres() -> (Scene, Camera, Vec<GpuLight>) {
    let scene = scene::spheres_on_plane(5);
    let lights: Vec<Light> = [
        "point:0.5,2.5,0.5,8,1,0.9,0.8,2",
        "spot:-1,3,1,0.2,-1,-0.1,8,15,30,0.8,0.9,1,3",
        "spot:1.5,2,-1,0,-1,0,8,60,80,1,1,1,1",
        "hemi:0,3,0,0,-1,0,8,1,1,1,2",
        "dir:0.4,-1,0.3,1,1,1,0.7",
    ]
    .iter()
    .map(|s| s.parse().expect("light"))
    .collect();
    let camera = scene.camera_or_framed();
    (
        scene,
        camera,
        tiled_shading::gpu_lights(&lights).expect("lights"),
    )
}

fn gbuffer(scene: &Scene, camera: &Camera, w: u32, h: u32) -> (GBuffer, Frame) {
    let gb = gbuffer::cpu::rasterize(scene, camera, w, h)
        .expect("rasterize")
        .gbuffer;
    (gb, Frame::new(camera, w, h))
}

/// The test device (`None`: skipped), [`spheres`] and its G-buffer of `w × h`.
#[allow(clippy::type_complexity)]
fn setup(
    w: u32,
    h: u32,
) -> Option<(
    &'static ::gpu::Gpu,
    Scene,
    Camera,
    Vec<GpuLight>,
    (GBuffer, Frame),
)> {
    let g = ::gpu::test_device(&tiled_shading::device_needs())?;
    let (scene, camera, lights) = spheres();
    let view = gbuffer(&scene, &camera, w, h);
    Some((g, scene, camera, lights, view))
}

const CONFIG: ShadowMapConfig = ShadowMapConfig {
    resolution: 256,
    cascades: 4,
    max_distance: None,
    bias: 1.0,
    normal_offset: 1.5,
};

fn shaded_gpu(
    g: &::gpu::Gpu,
    scene: &Scene,
    (gb, frame): &(GBuffer, Frame),
    camera: &Camera,
    lights: &[GpuLight],
) -> (Shaded, ShadowMaps, Vec<GpuLight>) {
    let config = ShadingConfig {
        method: Method::Tiled,
        tile_size: 16,
        ..Default::default()
    };
    gpu::run_shadowed(g, scene, gb, frame, camera, lights, &config, &CONFIG).expect("shadowed")
}

#[test]
fn rasterised_maps_match_depth_ray_cast_through_every_texel() {
    let Some((g, scene, camera, lights, view)) = setup(64, 48) else {
        return;
    };
    let (_, maps, _) = shaded_gpu(g, &scene, &view, &camera, &lights);
    let truth = shadows::ray_cast_maps(&Bvh::build(&scene), &maps.views, &CONFIG);
    let texels = (CONFIG.resolution * CONFIG.resolution) as usize;
    for (k, v) in maps.views.iter().enumerate() {
        let layer = k * texels..(k + 1) * texels;
        let agree = maps.depth[layer.clone()]
            .iter()
            .zip(&truth.depth[layer])
            .filter(|&(&a, &b)| {
                (v.linear_depth(a) - v.linear_depth(b)).abs() <= 1e-3 * (v.far - v.near) + 1e-4
            })
            .count();
        // Texels whose centre ray grazes a silhouette may hit another surface than the
        // rasteriser's coverage rule gives them: a few per cent at 256².
        let fraction = agree as f64 / texels as f64;
        assert!(
            fraction >= 0.97,
            "view {k}: {:.2} % of texels agree",
            100.0 * fraction
        );
    }
}

#[test]
fn cpu_lookup_on_the_read_back_maps_equals_the_gpu_shading() {
    let Some((g, scene, camera, lights, view)) = setup(96, 64) else {
        return;
    };
    let (gpu_shaded, maps, lights) = shaded_gpu(g, &scene, &view, &camera, &lights);
    let config = ShadingConfig {
        method: Method::Tiled,
        tile_size: 16,
        ..Default::default()
    };
    let cpu_shaded =
        cpu::shade(&view.0, &view.1, &camera, &lights, &config, Some(&maps)).expect("cpu");
    // A comparison within rounding of its threshold may fall the other way on the GPU (one
    // of the 16 taps: 1/9 of a light's weight at most), so count pixels, not a maximum.
    assert_same_shading(&cpu_shaded, &gpu_shaded);
}

/// The sum of a shading's diffuse light.
fn total(s: &Shaded) -> f32 {
    s.diffuse.pixels().iter().map(|p| p.element_sum()).sum()
}

/// CPU shadows with no depth views: a ManyLoD atlas and/or rays.
fn without_views(
    atlas: Option<(Vec<u32>, manylod::lookup::AtlasParams)>,
    rays: Option<RayShadows>,
) -> ShadowMaps {
    ShadowMaps {
        views: Vec::new(),
        depth: Vec::new(),
        resolution: 1,
        bias: 0.0,
        normal_offset: 0.0,
        atlas,
        rays,
    }
}

/// At most 0.5 % of the pixels of `gpu`'s diffuse light differ from `cpu`'s by more than
/// 0.1 % of the peak.
fn assert_same_shading(cpu: &Shaded, gpu: &Shaded) {
    let peak = cpu
        .diffuse
        .pixels()
        .iter()
        .fold(0.0f32, |m, p| m.max(p.max_element()));
    let differ = cpu
        .diffuse
        .pixels()
        .iter()
        .zip(gpu.diffuse.pixels())
        .filter(|(a, b)| (**a - **b).abs().max_element() > 1e-3 * peak)
        .count();
    let pixels = cpu.diffuse.pixels().len();
    assert!(
        differ * 200 <= pixels,
        "{differ} of {pixels} pixels differ by more than 0.1 % of the peak"
    );
}

#[test]
fn lookup_agrees_with_shadow_rays_outside_the_penumbra() {
    let Some((g, scene, camera, lights, view)) = setup(96, 64) else {
        return;
    };
    let (_, maps, lights) = shaded_gpu(g, &scene, &view, &camera, &lights);
    let bvh = Bvh::build(&scene);
    let reach = 2.0 * scene.bounds().diagonal();
    let lift = 1e-3 * scene.bounds().diagonal();
    let (gb, frame) = &view;
    let a = shadows::ray_agreement(
        gb,
        frame,
        &lights,
        &bvh,
        (|_| lift, reach),
        |light, p, n| {
            let v = shadows::visibility(&maps, light, p, n);
            // The tent's weights sum to 1 within rounding.
            (v >= 1.0 - 1e-5 || v <= 1e-5).then_some(v > 0.5)
        },
        |_, _| 0.0,
    );
    println!("{a}");
    assert!(a.occluded * 20 > a.pairs, "the scene casts shadows: {a}");
    assert!(a.fraction() >= 0.99, "{a}");
    // The band (partly lit by the 3-texel tent) stays a minority of the pairs.
    assert!(a.skipped * 4 < a.pairs, "{a}");
}

#[test]
fn shadows_only_remove_light_and_do_remove_it() {
    let Some((g, scene, camera, lights, view)) = setup(96, 64) else {
        return;
    };
    let config = ShadingConfig {
        method: Method::Tiled,
        tile_size: 16,
        ..Default::default()
    };
    let lit = gpu::run(
        g,
        &view.0,
        &view.1,
        &camera,
        &lights,
        &config,
        Default::default(),
    )
    .expect("unshadowed");
    let (shadowed, _, _) = shaded_gpu(g, &scene, &view, &camera, &lights);
    for (a, b) in lit.diffuse.pixels().iter().zip(shadowed.diffuse.pixels()) {
        assert!(
            b.cmple(*a * (1.0 + 1e-4) + Vec3::splat(1e-6)).all(),
            "{b} > {a}"
        );
    }
    let (t_lit, t_shadowed) = (total(&lit), total(&shadowed));
    assert!(
        t_shadowed < 0.95 * t_lit,
        "shadows removed only {:.1} % of the light",
        100.0 * (1.0 - t_shadowed / t_lit)
    );
}

#[test]
fn bad_shadow_settings_are_errors() {
    let (_, camera, lights) = spheres();
    let bounds = scene::spheres_on_plane(5).bounds();
    let all = vec![true; lights.len()];
    for (config, why) in [
        (
            ShadowMapConfig {
                resolution: 0,
                ..CONFIG
            },
            "resolution 0",
        ),
        (
            ShadowMapConfig {
                cascades: 9,
                ..CONFIG
            },
            "9 cascades",
        ),
        (
            ShadowMapConfig {
                bias: f32::NAN,
                ..CONFIG
            },
            "bias NaN",
        ),
    ] {
        let e = shadows::plan(&lights, &all, &camera, 1.0, bounds, &config, 256)
            .expect_err(why)
            .to_string();
        assert!(e.contains(why), "{e}");
    }
    let e = shadows::plan(&lights, &all, &camera, 1.0, bounds, &CONFIG, 8)
        .expect_err("too many views")
        .to_string();
    assert!(
        e.contains("21 shadow views") && e.contains("8 texture array layers"),
        "{e}"
    );
}

/// ManyLoD-style shadows (Holländer 2013 §3.6 for many lights) from an atlas ray-cast through
/// every texel of every light's paraboloid views: the GPU lookup equals the CPU twin, and it
/// agrees with shadow rays where the receiver is not within a texel of a shadow's edge.
#[test]
fn paraboloid_shadows_from_a_ray_cast_atlas() {
    let Some((g, scene, camera, lights, view)) = setup(96, 64) else {
        return;
    };
    let mut lights: Vec<GpuLight> = lights
        .into_iter()
        .filter(|l| l.kind != tiled_shading::LIGHT_DIRECTIONAL)
        .collect();
    let (views, plan) = shadows::paraboloid_plan(&lights, &vec![true; lights.len()]);
    assert_eq!(
        views.len(),
        2 + 1 + 1 + 1,
        "point 2, spots 1 each, hemispherical 1"
    );
    plan.assign(&mut lights);
    let bvh = Bvh::build(&scene);
    let diagonal = scene.bounds().diagonal();
    let layout = manylod::AtlasLayout::new(views.len(), 128, 2.0 * diagonal);
    let params = manylod::lookup::AtlasParams {
        enabled: 1,
        tile: layout.tile,
        columns: layout.columns,
        width: layout.size().0,
        far: layout.far,
        lift: 0.0,
        bias: 0.002,
        normal_offset: 1.0,
        slope: 0.0,
    };
    let atlas = shadows::ray_cast_atlas(&bvh, &views, &params);
    let upload = |label, bytes: &[u8], usage| {
        ::gpu::transfer::buffer_init(&g.device, label, bytes, usage).expect("upload")
    };
    let atlas_buffer = upload(
        "atlas",
        bytemuck::cast_slice(&atlas),
        wgpu::BufferUsages::STORAGE,
    );
    let params_buffer = upload(
        "atlas params",
        bytemuck::bytes_of(&params),
        wgpu::BufferUsages::UNIFORM,
    );
    let config = ShadingConfig {
        method: Method::Tiled,
        tile_size: 16,
        ..Default::default()
    };
    let inputs = gpu::shadows::ShadowInputs {
        maps: None,
        atlas: Some(gpu::shadows::AtlasBindings {
            atlas: &atlas_buffer,
            params: &params_buffer,
        }),
        rays: None,
    };
    let (gb, frame) = &view;
    let on_gpu = gpu::run(g, gb, frame, &camera, &lights, &config, inputs).expect("gpu");
    let maps = without_views(Some((atlas.clone(), params)), None);
    let on_cpu = cpu::shade(gb, frame, &camera, &lights, &config, Some(&maps)).expect("cpu");
    assert_same_shading(&on_cpu, &on_gpu);

    // Against shadow rays, outside the band where a point one texel away on the surface
    // answers otherwise.
    let lift = 1e-3 * diagonal;
    let a = shadows::ray_agreement(
        gb,
        frame,
        &lights,
        &bvh,
        (|_| lift, 0.0),
        |light, p, n| Some(shadows::visibility(&maps, light, p, n) > 0.5),
        |light, p| (p - Vec3::from(light.position)).length() * 4.0 / params.tile as f32,
    );
    println!("{a}");
    assert!(a.occluded * 20 > a.pairs, "the scene casts shadows: {a}");
    assert!(a.fraction() >= 0.98, "{a}");
}

#[test]
fn ray_shadows_equal_their_cpu_twin_and_the_shadow_rays_of_an_independent_bvh() {
    let Some((g, scene, camera, mut lights, view)) = setup(96, 64) else {
        return;
    };
    for l in &mut lights {
        l.shadow_first = 0;
        l.shadow_count = shadows::RAY_SHADOW;
    }
    let rays = RayShadows::new(&scene).expect("rays");
    let gpu_rays = gpu::shadows::GpuRays::new(&g.device, &rays.bvh, rays.params).expect("gpu rays");
    let config = ShadingConfig {
        method: Method::Tiled,
        tile_size: 16,
        ..Default::default()
    };
    let inputs = gpu::shadows::ShadowInputs {
        rays: Some(&gpu_rays),
        ..Default::default()
    };
    let (gb, frame) = &view;
    let on_gpu = gpu::run(g, gb, frame, &camera, &lights, &config, inputs).expect("gpu");
    let maps = without_views(None, Some(rays.clone()));
    let on_cpu = cpu::shade(gb, frame, &camera, &lights, &config, Some(&maps)).expect("cpu");
    assert_same_shading(&on_cpu, &on_gpu);
    // Against `scene::Bvh` (another builder and intersector) from the same lift: only pairs
    // whose ray grazes an edge may differ.
    let a = shadows::ray_agreement(
        gb,
        frame,
        &lights,
        &Bvh::build(&scene),
        (tiled_shading::rays::ray_lift, rays.params.reach),
        |light, p, n| Some(rays.visibility(light, p, n) > 0.5),
        |_, _| 0.0,
    );
    println!("{a}");
    assert!(a.occluded * 20 > a.pairs, "the scene casts shadows: {a}");
    assert_eq!(a.skipped, 0, "{a}");
    assert!(a.fraction() >= 0.999, "{a}");
    // Shadows by rays darken the frame as the maps do.
    let lit = gpu::run(g, gb, frame, &camera, &lights, &config, Default::default());
    assert!(total(&on_gpu) < 0.95 * total(&lit.expect("unshadowed")));
}
