//! The invariants of tiled light culling (Ishmukhametov 2013 §2.4.1, chapter 4): every
//! culled method gives the brute-force image, on the CPU and on the GPU; CPU and GPU tile
//! lists are the same sets (up to decisions within float rounding of a threshold); normal cones never change the image and, in front of a wall,
//! remove exactly the lights behind it.

use std::collections::BTreeSet;

use gbuffer::{Frame, GBuffer, Image};
use glam::Vec3;
use scene::{Camera, Light, Scene};
use tiled_shading::{
    GpuLight, LightSearch, Method, ShadingConfig, ShadingError,
    cpu::{self, Shaded},
    gpu,
};

/// Tolerance of images that sum the same non-zero terms in the same order up to lights that
/// contribute exactly zero (CPU culled vs CPU brute force), relative to the image's maximum.
const SAME_TERMS: f32 = 1e-6;
/// Tolerance of GPU vs CPU images (another summation order, fused multiply-adds, GPU
/// transcendental functions; GGX peaks of smooth spheres are the most sensitive: 4e-4 seen on
/// llvmpipe), relative per pixel, plus 1e-5 of the image's maximum.
const GPU_RELATIVE: f32 = 2e-3;

struct Case {
    gb: GBuffer,
    frame: Frame,
    camera: Camera,
    lights: Vec<GpuLight>,
}

impl Case {
    /// The GPU light accumulation of this case with `config`, without shadows.
    fn run_gpu(&self, g: &::gpu::Gpu, config: &ShadingConfig) -> Shaded {
        gpu::run(
            g,
            &self.gb,
            &self.frame,
            &self.camera,
            &self.lights,
            config,
            Default::default(),
        )
        .expect("gpu run")
    }
}

fn case(scene: &Scene, camera: Camera, lights: &[Light], width: u32, height: u32) -> Case {
    Case {
        gb: gbuffer::cpu::rasterize(scene, &camera, width, height)
            .expect("rasterize")
            .gbuffer,
        frame: Frame::new(&camera, width, height),
        camera,
        lights: tiled_shading::gpu_lights(lights).expect("valid lights"),
    }
}

/// Spheres on a plane under scattered point lights plus a spot, a hemispherical and a
/// directional light.
fn spheres(width: u32, height: u32, count: usize) -> Case {
    let scene = scene::spheres_on_plane(5);
    let mut lights = scene::scatter_point_lights(scene.bounds(), count, 5);
    lights.extend([
        "spot:0,3,0,0,-1,0,6,20,35".parse::<Light>().expect("spot"),
        "hemi:1,0.5,1,0,1,0,3".parse().expect("hemi"),
        "dir:0.3,-1,0.2,1,1,1,0.5".parse().expect("dir"),
    ]);
    case(&scene, scene.camera_or_framed(), &lights, width, height)
}

fn walls(behind: u32, width: u32, height: u32) -> Case {
    let scene = scene::thesis_walls(behind);
    let camera = scene.camera.expect("camera");
    case(&scene, camera, &scene.lights, width, height)
}

fn config(method: Method, tile_size: u32) -> ShadingConfig {
    ShadingConfig {
        method,
        tile_size,
        ..Default::default()
    }
}

fn shade_cpu(c: &Case, config: &ShadingConfig) -> Shaded {
    cpu::shade(&c.gb, &c.frame, &c.camera, &c.lights, config, None).expect("cpu shade")
}

fn max_abs(img: &Image<Vec3>) -> f32 {
    img.pixels()
        .iter()
        .map(|p| p.max_element())
        .fold(0.0, f32::max)
}

/// Largest per-pixel error of `test` against `reference` beyond `rel·|ref| + abs·max(ref)`.
fn compare(what: &str, reference: &Shaded, test: &Shaded, rel: f32, abs: f32) {
    for (name, r, t) in [
        ("diffuse", &reference.diffuse, &test.diffuse),
        ("specular", &reference.specular, &test.specular),
    ] {
        let floor = abs * max_abs(r);
        let mut worst = (0.0f32, 0u32, 0u32);
        for y in 0..r.height() {
            for x in 0..r.width() {
                let (a, b) = (r.get(x, y), t.get(x, y));
                let excess = ((a - b).abs() - (a.abs() * rel + floor)).max_element();
                if excess > worst.0 {
                    worst = (excess, x, y);
                }
            }
        }
        assert!(
            worst.0 == 0.0,
            "{what} {name}: pixel ({}, {}) differs: {} vs {}",
            worst.1,
            worst.2,
            r.get(worst.1, worst.2),
            t.get(worst.1, worst.2)
        );
    }
}

fn sets(lists: &[Vec<(u32, u32)>]) -> Vec<BTreeSet<(u32, u32)>> {
    lists.iter().map(|l| l.iter().copied().collect()).collect()
}

/// Margin of the rule below: a GPU list may differ from the CPU list only by lights whose
/// sphere–plane test (distance + radius, relative to the radius) or normal-cone test
/// (ω − (π/2 + α + δ + ε), radians) the CPU decides within this of its threshold — decisions
/// that float rounding (fused multiply-adds, GPU `acos`) can flip. Culling stays conservative
/// either way: the cone test has `CONE_EPSILON` = 1e-3 rad of slack, and a sphere that misses
/// by rounding contributes an attenuation of order 1e-10.
const DECISION_MARGIN: f32 = 1e-4;

/// How close the CPU's decision for `light` in tile `t` is to a threshold (the smaller of the
/// sphere–plane and cone margins).
fn decision_margin(c: &Case, config: &ShadingConfig, t: usize, light: u32) -> f32 {
    let (w, h) = (c.gb.width(), c.gb.height());
    let (tx, _) = config.tiles(w, h);
    let rect = cpu::tile_pixels(config.tile_size, w, h, t as u32 % tx, t as u32 / tx);
    let samples: Vec<cpu::Sample> = (rect[2]..rect[3])
        .flat_map(|y| (rect[0]..rect[1]).map(move |x| (x, y)))
        .filter_map(|(x, y)| cpu::sample(&c.gb, &c.frame, x, y))
        .collect();
    let bounds = cpu::tile_bounds(&samples, &tiled_shading::Slicing::new(&c.camera));
    let frustum = cpu::tile_frustum(&c.frame, rect, bounds.min_depth, bounds.max_depth);
    let slicing = tiled_shading::Slicing::new(&c.camera);
    let open = samples.len() < ((rect[1] - rect[0]) * (rect[3] - rect[2])) as usize;
    let far = cpu::forward_far(&bounds, open, &slicing);
    let reach = cpu::tile_frustum(&c.frame, rect, slicing.near, far);
    let l = &c.lights[light as usize];
    let p = Vec3::from(l.position);
    let planes = match config.method {
        Method::ForwardPlus => [frustum.planes, reach.planes].concat(),
        Method::Clustered => frustum.planes[..4].to_vec(),
        _ => frustum.planes.to_vec(),
    };
    let mut margin = planes
        .iter()
        .map(|q| (q.truncate().dot(p) + q.w + l.radius).abs() / l.radius)
        .fold(f32::INFINITY, f32::min);
    if matches!(config.method, Method::TiledSlices | Method::Clustered) {
        // The depth tests: the light's depth interval against each slice's ends (tiled
        // slices) or each cluster's depth bounds (clustered).
        let depth = -c.frame.view.row(2).dot(p.extend(1.0));
        for k in 0..tiled_shading::CLUSTER_SLICES {
            let [z0, z1] = match config.method {
                Method::Clustered => bounds.cluster_depths[k as usize],
                _ => [slicing.start(k), slicing.start(k + 1)],
            };
            margin = margin
                .min((depth + l.radius - z0).abs() / l.radius)
                .min((depth - l.radius - z1).abs() / l.radius);
        }
    }
    if config.method == Method::TiledCones {
        if let Some((axis, cos_delta)) = cpu::light_cone(&frustum, p) {
            let (normal_axis, cos_alpha) = bounds.cone();
            let omega = axis.dot(normal_axis).clamp(-1.0, 1.0).acos();
            let threshold = std::f32::consts::FRAC_PI_2
                + cos_alpha.acos()
                + cos_delta.acos()
                + cpu::CONE_EPSILON;
            margin = margin.min((omega - threshold).abs());
        }
    }
    margin
}

/// GPU and CPU tile lists are equal as sets, up to lights decided within
/// [`DECISION_MARGIN`] of a threshold (reported); on failure, the first differing tile.
fn same_lists(what: &str, c: &Case, config: &ShadingConfig, gpu: &Shaded, cpu: &Shaded) {
    assert_eq!(gpu.lists.len(), cpu.lists.len());
    let mut marginal = 0;
    for (t, (g, k)) in sets(&gpu.lists).iter().zip(sets(&cpu.lists)).enumerate() {
        for &(light, _) in g.symmetric_difference(&k) {
            let margin = decision_margin(c, config, t, light);
            assert!(
                margin <= DECISION_MARGIN,
                "{what}: tile {t}: light {light}'s entries differ (GPU {:?}, CPU {:?}; its tests are {margin} from their thresholds)",
                g.iter().filter(|e| e.0 == light).collect::<Vec<_>>(),
                k.iter().filter(|e| e.0 == light).collect::<Vec<_>>(),
            );
            marginal += 1;
        }
    }
    if marginal > 0 {
        eprintln!("{what}: {marginal} marginal list differences (within {DECISION_MARGIN})");
    }
}

#[test]
fn culled_images_equal_brute_force_on_the_cpu() {
    for c in [spheres(96, 64, 300), walls(500, 128, 72)] {
        let brute = shade_cpu(&c, &config(Method::BruteForce, 16));
        assert!(max_abs(&brute.diffuse) > 0.0, "the scene is lit");
        let methods = [
            Method::Tiled,
            Method::TiledCones,
            Method::TiledSlices,
            Method::Clustered,
            Method::ForwardPlus,
        ];
        for method in methods {
            for tile in [8, 16, 32] {
                let culled = shade_cpu(&c, &config(method, tile));
                compare(
                    &format!("cpu {method} {tile}"),
                    &brute,
                    &culled,
                    0.0,
                    SAME_TERMS,
                );
                let evaluated: u32 = culled.counts.iter().sum();
                assert!(
                    evaluated < brute.counts.iter().sum(),
                    "{method} culls nothing"
                );
            }
        }
    }
}

#[test]
fn tile_bounds_hold_every_pixel() {
    let c = walls(100, 128, 72);
    let slicing = tiled_shading::Slicing::new(&c.camera);
    let tile = 16;
    let (tx, ty) = config(Method::Tiled, tile).tiles(128, 72);
    for t in 0..tx * ty {
        let rect = cpu::tile_pixels(tile, 128, 72, t % tx, t / tx);
        let samples: Vec<cpu::Sample> = (rect[2]..rect[3])
            .flat_map(|y| (rect[0]..rect[1]).map(move |x| (x, y)))
            .filter_map(|(x, y)| cpu::sample(&c.gb, &c.frame, x, y))
            .collect();
        let b = cpu::tile_bounds(&samples, &slicing);
        assert_eq!(b.is_empty(), samples.is_empty());
        let (axis, cos_alpha) = b.cone();
        let frustum = cpu::tile_frustum(&c.frame, rect, b.min_depth, b.max_depth);
        for s in &samples {
            assert!((b.min_depth..=b.max_depth).contains(&s.depth));
            assert!(
                axis.dot(s.normal) >= cos_alpha - 1e-6,
                "normal outside the cone"
            );
            assert!(b.slices >> slicing.slice(s.depth) & 1 == 1);
            assert!(
                cpu::sphere_meets(&frustum.planes, s.position, 1e-3 * s.depth),
                "pixel outside its tile frustum"
            );
        }
    }
}

#[test]
fn normal_cones_remove_exactly_the_lights_behind_a_wall() {
    let (front, behind) = (40, 60);
    let scene = scene::wall(front, behind);
    let c = case(
        &scene,
        scene.camera.expect("camera"),
        &scene.lights,
        160,
        120,
    );
    let tiled = shade_cpu(&c, &config(Method::Tiled, 16));
    let cones = shade_cpu(&c, &config(Method::TiledCones, 16));
    let mut removed_total = 0;
    for (t, c) in tiled.lists.iter().zip(&cones.lists) {
        let t: BTreeSet<u32> = t.iter().map(|e| e.0).collect();
        let c: BTreeSet<u32> = c.iter().map(|e| e.0).collect();
        let removed: BTreeSet<u32> = t.difference(&c).copied().collect();
        let behind_in_tile: BTreeSet<u32> = t.iter().copied().filter(|&i| i >= front).collect();
        assert!(c.is_subset(&t));
        assert_eq!(
            removed, behind_in_tile,
            "cones must remove exactly the lights behind"
        );
        removed_total += removed.len();
    }
    assert!(
        removed_total > 100,
        "the lights behind reach the wall's tiles ({removed_total})"
    );
    compare("cones vs tiled", &tiled, &cones, 0.0, 0.0);
    let Some(g) = ::gpu::test_device(&tiled_shading::device_needs()) else {
        return;
    };
    let cfg = config(Method::TiledCones, 16);
    let gpu_cones = c.run_gpu(g, &cfg);
    same_lists("wall cones", &c, &cfg, &gpu_cones, &cones);
}

#[test]
fn normal_cones_never_change_the_image() {
    for c in [walls(1000, 160, 90), spheres(96, 64, 200)] {
        let tiled = shade_cpu(&c, &config(Method::Tiled, 16));
        let cones = shade_cpu(&c, &config(Method::TiledCones, 16));
        compare("cpu cones vs tiled", &tiled, &cones, 0.0, SAME_TERMS);
        let Some(g) = ::gpu::test_device(&tiled_shading::device_needs()) else {
            continue;
        };
        let run = |m| c.run_gpu(g, &config(m, 16));
        compare(
            "gpu cones vs tiled",
            &run(Method::Tiled),
            &run(Method::TiledCones),
            GPU_RELATIVE,
            1e-5,
        );
    }
}

#[test]
fn gpu_matches_cpu_images_and_lists() {
    let Some(g) = ::gpu::test_device(&tiled_shading::device_needs()) else {
        return;
    };
    for c in [spheres(100, 70, 300), walls(500, 128, 72)] {
        let brute = shade_cpu(&c, &config(Method::BruteForce, 16));
        // Every method and tile size through the light hierarchy; at 16 × 16 also every light
        // per tile (the lists must be the same).
        let searches = [
            (LightSearch::Tree, [8, 16, 32].as_slice()),
            (LightSearch::Flat, &[16]),
        ];
        for method in Method::ALL {
            for (search, tile) in searches
                .iter()
                .flat_map(|(s, tiles)| tiles.iter().map(move |&t| (*s, t)))
            {
                let brute_like = matches!(method, Method::BruteForce | Method::LightVolumes);
                if brute_like && (tile != 16 || search == LightSearch::Flat) {
                    continue;
                }
                let cfg = ShadingConfig {
                    search,
                    ..config(method, tile)
                };
                let gpu_out = c.run_gpu(g, &cfg);
                // Forward+ only builds lists here: its images come from drawing the scene
                // (`pipeline`'s forward tests); the light pre-pass writes its light buffer
                // (compared with its CPU twin's).
                let prepass = (method == Method::LightPrePass).then(|| shade_cpu(&c, &cfg));
                if method != Method::ForwardPlus {
                    compare(
                        &format!("gpu {method} {tile} {search} vs brute"),
                        prepass.as_ref().unwrap_or(&brute),
                        &gpu_out,
                        GPU_RELATIVE,
                        1e-5,
                    );
                }
                if method != Method::BruteForce {
                    let cpu_out = shade_cpu(&c, &cfg);
                    same_lists(&format!("{method} {tile}"), &c, &cfg, &gpu_out, &cpu_out);
                }
            }
        }
    }
}

#[test]
fn lists_longer_than_workgroup_memory_are_shaded_in_flushes() {
    // 2500 lights that all reach every pixel: each tile's list (2500) exceeds the 1024
    // entries of workgroup memory, so the kernel must shade and restart the list.
    let scene = scene::spheres_on_plane(3);
    let mut c = case(&scene, scene.camera_or_framed(), &[], 48, 40);
    let center = scene.bounds().center();
    let lights: Vec<Light> = (0..2500)
        .map(|i| Light::Point {
            position: center + Vec3::new((i % 50) as f32 * 0.01, 2.0, (i / 50) as f32 * 0.01),
            color: Vec3::ONE,
            intensity: 0.01,
            radius: 100.0,
        })
        .collect();
    c.lights = tiled_shading::gpu_lights(&lights).expect("valid");
    let brute = shade_cpu(&c, &config(Method::BruteForce, 16));
    let Some(g) = ::gpu::test_device(&tiled_shading::device_needs()) else {
        return;
    };
    let methods = [
        Method::Tiled,
        Method::TiledCones,
        Method::TiledSlices,
        Method::Clustered,
    ];
    for method in methods {
        let out = c.run_gpu(g, &config(method, 16));
        let lit: Vec<u32> = out.counts.iter().copied().filter(|&n| n > 0).collect();
        assert!(!lit.is_empty());
        assert!(
            lit.iter().all(|&n| n == 2500),
            "{method}: every light in every list"
        );
        compare(
            &format!("gpu {method} with flushes"),
            &brute,
            &out,
            5e-4,
            1e-5,
        );
    }
}

#[test]
fn frustum_culling_keeps_every_light_that_lights_the_view() {
    let c = walls(100, 128, 72);
    let kept = tiled_shading::frustum_cull(&c.camera, 128.0 / 72.0, &c.lights);
    let expected = (scene::THESIS_VISIBLE_LIGHTS + 100) as usize;
    assert!(
        kept.len() >= 100 && kept.len() <= expected,
        "kept {}",
        kept.len()
    );
    let all = shade_cpu(&c, &config(Method::BruteForce, 16));
    let culled = Case {
        lights: kept.iter().map(|&i| c.lights[i as usize]).collect(),
        ..c
    };
    compare(
        "frustum culled",
        &all,
        &shade_cpu(&culled, &config(Method::BruteForce, 16)),
        1e-5,
        1e-6,
    );
}

#[test]
fn clusters_list_only_lights_of_their_tiles_lists() {
    // A cluster's explicit bounds lie within its tile's depth bounds: its lights are among the
    // tile's, and depth discontinuities make them fewer.
    let c = walls(500, 128, 72);
    let tiled = shade_cpu(&c, &config(Method::Tiled, 16));
    let clustered = shade_cpu(&c, &config(Method::Clustered, 16));
    for (t, (tile, clusters)) in sets(&tiled.lists)
        .iter()
        .zip(sets(&clustered.lists))
        .enumerate()
    {
        let lights: BTreeSet<u32> = tile.iter().map(|e| e.0).collect();
        assert!(
            clusters.iter().all(|e| lights.contains(&e.0)),
            "tile {t}: a cluster lists a light its tile does not"
        );
    }
    let sum = |counts: &[u32]| counts.iter().map(|&n| u64::from(n)).sum::<u64>();
    assert!(
        sum(&clustered.counts) < sum(&tiled.counts),
        "depth discontinuities leave some of a tile's lights in none of its clusters"
    );
}

#[test]
fn slice_masks_hold_only_occupied_slices() {
    let (w, h) = (128, 72);
    let c = walls(500, w, h);
    let slicing = tiled_shading::Slicing::new(&c.camera);
    for method in [Method::TiledSlices, Method::Clustered] {
        slice_masks_of(&c, &slicing, method, w, h);
    }
}

fn slice_masks_of(c: &Case, slicing: &tiled_shading::Slicing, method: Method, w: u32, h: u32) {
    let out = shade_cpu(c, &config(method, 16));
    let mut slices_used = 0u32;
    for (t, list) in out.lists.iter().enumerate() {
        let rect = cpu::tile_pixels(16, w, h, t as u32 % out.tiles.0, t as u32 / out.tiles.0);
        let samples: Vec<cpu::Sample> = (rect[2]..rect[3])
            .flat_map(|y| (rect[0]..rect[1]).map(move |x| (x, y)))
            .filter_map(|(x, y)| cpu::sample(&c.gb, &c.frame, x, y))
            .collect();
        let occupied = cpu::tile_bounds(&samples, slicing).slices;
        for &(_, mask) in list {
            assert_ne!(mask, 0, "{method}: an entry for no cluster");
            assert_eq!(
                mask & !occupied,
                0,
                "{method}: an entry for an empty cluster"
            );
            slices_used |= mask;
        }
    }
    assert!(
        slices_used.count_ones() > 2,
        "{method}: the view spans several depth slices"
    );
}

/// `c`'s G-buffer on the GPU, a 16 × 16 tiled stage and its outputs, bound for `capacity`
/// lights.
struct TiledStage {
    uploaded: gbuffer::gpu::UploadedGBuffer,
    stage: gpu::LightShading,
    outputs: [::gpu::wgpu::Texture; 2],
    bound: gpu::BoundShading,
}

fn tiled_stage(g: &::gpu::Gpu, c: &Case, capacity: usize) -> TiledStage {
    let uploaded =
        gbuffer::gpu::UploadedGBuffer::new(&g.device, &g.queue, &c.gb, &c.frame).expect("upload");
    let stage = gpu::LightShading::new(&g.device, &config(Method::Tiled, 16)).expect("stage");
    let outputs = gpu::LightShading::output_textures(&g.device, c.gb.width(), c.gb.height());
    let bound = stage
        .bind(
            &g.device,
            &uploaded.frame,
            uploaded.textures(),
            [&outputs[0], &outputs[1]],
            capacity,
            false,
        )
        .expect("bind");
    TiledStage {
        uploaded,
        stage,
        outputs,
        bound,
    }
}

#[test]
fn bad_input_is_an_error() {
    let c = spheres(32, 32, 4);
    assert!(matches!(
        cpu::shade(
            &c.gb,
            &c.frame,
            &c.camera,
            &c.lights,
            &config(Method::Tiled, 12),
            None
        ),
        Err(ShadingError::TileSize(12))
    ));
    let bad = Light::Point {
        position: Vec3::ZERO,
        color: Vec3::ONE,
        intensity: 1.0,
        radius: -1.0,
    };
    assert!(matches!(
        tiled_shading::gpu_lights(&[bad]),
        Err(ShadingError::InvalidLight { index: 0, .. })
    ));
    // The message names the light, the parameter and its value (no debug dump).
    let nan_colour = Light::Point {
        position: Vec3::ZERO,
        color: Vec3::new(1.0, f32::NAN, 0.0),
        intensity: 1.0,
        radius: 1.0,
    };
    for (light, why) in [
        (
            bad,
            "light 1: point light: radius -1 must be positive and finite",
        ),
        (
            nan_colour,
            "light 1: point light: colour × intensity [1.0, NaN, 0.0] must be finite",
        ),
    ] {
        let ok = Light::Directional {
            direction: Vec3::NEG_Y,
            color: Vec3::ONE,
            intensity: 1.0,
        };
        let e = tiled_shading::gpu_lights(&[ok, light])
            .expect_err(why)
            .to_string();
        assert!(e.contains(why), "{why}: {e}");
    }
    let Some(g) = ::gpu::test_device(&tiled_shading::device_needs()) else {
        return;
    };
    let TiledStage {
        uploaded,
        stage,
        outputs,
        mut bound,
    } = tiled_stage(g, &c, 2);
    let (w, h) = (c.gb.width(), c.gb.height());
    assert!(matches!(
        bound.set_lights(&g.queue, &c.lights),
        Err(ShadingError::TooManyLights {
            count: 7,
            capacity: 2
        })
    ));
    assert!(gpu::LightShading::new(&g.device, &config(Method::Tiled, 64)).is_err());
    // Outputs of the wrong size, format or usage are an error from `bind`, naming them.
    let small = gpu::LightShading::output_textures(&g.device, w / 2, h);
    let wrong_size = stage.bind(
        &g.device,
        &uploaded.frame,
        uploaded.textures(),
        [&small[0], &outputs[1]],
        2,
        false,
    );
    assert!(matches!(&wrong_size, Err(e) if e.to_string().contains("diffuse output")));
    let sampled_only = ::gpu::transfer::texture_2d(
        &g.device,
        "sampled only",
        w,
        h,
        gpu::ACCUMULATION_FORMAT,
        ::gpu::wgpu::TextureUsages::TEXTURE_BINDING,
    );
    let no_storage = stage.bind(
        &g.device,
        &uploaded.frame,
        uploaded.textures(),
        [&outputs[0], &sampled_only],
        2,
        false,
    );
    assert!(matches!(&no_storage, Err(e) if e.to_string().contains("specular output")));
}

/// Traditional deferred shading (thesis §4.1) on a G-buffer rendered on the GPU, its light
/// volumes depth-tested against the scene's depth buffer where the device can clamp their
/// depth: the brute-force image, with the eye inside a light's volume, volumes reaching past
/// the far plane, narrow spots (cones) and wide ones (spheres), hemispherical and directional
/// lights.
#[test]
fn light_volumes_equal_brute_force() {
    let Some(g) = ::gpu::test_device(&tiled_shading::device_needs()) else {
        return;
    };
    let (device, queue) = (&g.device, &g.queue);
    let scene = scene::spheres_on_plane(5);
    let mut camera = scene.camera_or_framed();
    let bounds = scene.bounds();
    let farthest = (0..8)
        .map(|i| {
            let pick = |bit, lo: f32, hi: f32| if i & bit == 0 { lo } else { hi };
            let corner = Vec3::new(
                pick(1, bounds.min.x, bounds.max.x),
                pick(2, bounds.min.y, bounds.max.y),
                pick(4, bounds.min.z, bounds.max.z),
            );
            (corner.distance(camera.eye), corner)
        })
        .fold((0.0, Vec3::ZERO), |a, b| if b.0 > a.0 { b } else { a });
    camera.far = farthest.0 * 1.01;
    let mut lights = scene::scatter_point_lights(bounds, 200, 11);
    let p = |v: Vec3| format!("{},{},{}", v.x, v.y, v.z);
    lights.extend(
        [
            // The eye inside the volume.
            format!("point:{},3,1,1,1,2", p(camera.eye)),
            // Past the far plane.
            format!("point:{},4,1,1,1,2", p(farthest.1)),
            "spot:0,3,0,0,-1,0,6,20,35".to_string(),
            "spot:1,2,1,0.3,-1,0,5,60,80".to_string(),
            "hemi:1,0.5,1,0,1,0,3".to_string(),
            "dir:0.3,-1,0.2,1,1,1,0.5".to_string(),
        ]
        .iter()
        .map(|s| s.parse::<Light>().expect("light")),
    );
    let lights = tiled_shading::gpu_lights(&lights).expect("valid lights");
    let (w, h) = (160, 112);
    let pass = gbuffer::gpu::GBufferPass::new(device).expect("gbuffer pass");
    let gpu_scene = gbuffer::gpu::GpuScene::upload(device, queue, &scene, &pass).expect("upload");
    let targets = gbuffer::gpu::GBufferTargets::new(device, w, h).expect("targets");
    pass.write_frame(queue, &Frame::new(&camera, w, h));
    let mut encoder = device.create_command_encoder(&Default::default());
    pass.encode(&mut encoder, &gpu_scene, &targets, None);
    queue.submit([encoder.finish()]);
    let shade = |method: Method, depth: bool| {
        let stage = gpu::LightShading::new(device, &config(method, 16)).expect("stage");
        let outputs = gpu::LightShading::output_textures(device, w, h);
        let outputs = [&outputs[0], &outputs[1]];
        let mut bound = stage
            .bind(
                device,
                pass.frame_buffer(),
                (&targets).into(),
                outputs,
                lights.len(),
                false,
            )
            .expect("bind");
        if depth {
            stage
                .bind_depth(&mut bound, &targets.depth)
                .expect("scene depth");
        }
        assert_eq!(
            stage.depth_tested(&bound),
            depth
                && device
                    .features()
                    .contains(::gpu::wgpu::Features::DEPTH_CLIP_CONTROL)
        );
        bound.set_lights(queue, &lights).expect("lights");
        let mut encoder = device.create_command_encoder(&Default::default());
        stage.encode(&bound, &mut encoder, None);
        queue.submit([encoder.finish()]);
        let [diffuse, specular] = gpu::read_outputs(device, queue, outputs).expect("read");
        Shaded {
            diffuse,
            specular,
            tiles: (0, 0),
            counts: Vec::new(),
            lists: Vec::new(),
        }
    };
    let brute = shade(Method::BruteForce, false);
    let lit = brute
        .diffuse
        .pixels()
        .iter()
        .filter(|v| v.max_element() > 0.0)
        .count();
    assert!(lit > (w * h / 2) as usize, "{lit} lit pixels");
    for depth in [true, false] {
        compare(
            &format!("volumes (scene depth {depth}) vs brute"),
            &brute,
            &shade(Method::LightVolumes, depth),
            GPU_RELATIVE,
            1e-5,
        );
    }
}

#[test]
fn forward_lists_hold_the_tiled_lists_and_every_light_in_front() {
    // Forward+ marks as opaque exactly the lights tiled shading lists (the same planes), and
    // lists besides every light that reaches the tile between the near plane and its far
    // bound: a surface in front of the opaque ones, or over the background, finds its lights.
    for c in [spheres(96, 64, 300), walls(500, 128, 72)] {
        let tiled = shade_cpu(&c, &config(Method::Tiled, 16));
        let forward = shade_cpu(&c, &config(Method::ForwardPlus, 16));
        let mut in_front = 0;
        for (t, (tiled, forward)) in tiled.lists.iter().zip(&forward.lists).enumerate() {
            let opaque: Vec<u32> = forward
                .iter()
                .filter(|e| e.1 & cpu::FORWARD_OPAQUE != 0)
                .map(|e| e.0)
                .collect();
            let listed: Vec<u32> = tiled.iter().map(|e| e.0).collect();
            assert_eq!(
                opaque, listed,
                "tile {t}: the opaque entries are tiled's list"
            );
            assert!(
                forward.iter().all(|e| e.1 & cpu::FORWARD_BLENDED != 0),
                "tile {t}: every entry serves blended surfaces"
            );
            in_front += forward.len() - opaque.len();
        }
        assert!(in_front > 0, "some lights reach only what lies in front");
    }
    // Over the background (a tile without any surface), the lights in front of the camera are
    // listed: the spheres seen from above, the plane's edge in view.
    let scene = scene::spheres_on_plane(3);
    let camera = Camera::look_at(Vec3::new(0.0, 3.0, 9.0), Vec3::new(0.0, 2.0, 0.0));
    let mut c = case(&scene, camera, &[], 64, 48);
    c.lights = tiled_shading::gpu_lights(&[Light::Point {
        position: Vec3::new(0.0, 2.0, 6.0),
        color: Vec3::ONE,
        intensity: 1.0,
        radius: 2.0,
    }])
    .expect("valid");
    let forward = shade_cpu(&c, &config(Method::ForwardPlus, 16));
    let (tx, _) = forward.tiles;
    let empty = |t: usize| {
        let rect = cpu::tile_pixels(16, 64, 48, t as u32 % tx, t as u32 / tx);
        (rect[2]..rect[3]).all(|y| (rect[0]..rect[1]).all(|x| c.gb.linear_depth.get(x, y) <= 0.0))
    };
    let background: Vec<usize> = (0..forward.lists.len()).filter(|&t| empty(t)).collect();
    assert!(!background.is_empty(), "the view shows background");
    assert!(
        background.iter().any(|&t| forward.counts[t] == 1),
        "the light in front of the camera is listed over the background"
    );
}

#[test]
fn the_light_buffer_holds_the_diffuse_light_and_monochrome_specular() {
    // The light pre-pass's lighting pass, on the CPU: its diffuse light is brute force's (the
    // same terms), and its specular is grey, the luminance of the specular light of a white
    // metal (F = 1) — brute force's where every surface is one.
    let mut c = spheres(96, 64, 300);
    let brute = shade_cpu(&c, &config(Method::BruteForce, 16));
    let prepass = shade_cpu(&c, &config(Method::LightPrePass, 16));
    let diffuse_only = |s: &Shaded| Shaded {
        specular: Image::filled(s.diffuse.width(), s.diffuse.height(), Vec3::ZERO),
        ..s.clone()
    };
    compare(
        "light buffer diffuse",
        &diffuse_only(&brute),
        &diffuse_only(&prepass),
        0.0,
        SAME_TERMS,
    );
    assert!(
        prepass
            .specular
            .pixels()
            .iter()
            .all(|s| s.x == s.y && s.y == s.z && s.x >= 0.0),
        "grey specular"
    );
    assert!(max_abs(&prepass.specular) > 0.0);
    // Every surface a white metal of its roughness: F = 1 everywhere.
    let (w, h) = (c.gb.width(), c.gb.height());
    for y in 0..h {
        for x in 0..w {
            let [.., specular] = c.gb.albedo.get(x, y);
            c.gb.albedo.set(x, y, [255, 255, 255, specular]);
            let (roughness, _, id) = gbuffer::unpack_material(c.gb.material.get(x, y));
            c.gb.material
                .set(x, y, gbuffer::pack_material(roughness, 1.0, id));
        }
    }
    let metal = shade_cpu(&c, &config(Method::BruteForce, 16));
    let grey = Shaded {
        specular: Image::from_vec(
            w,
            h,
            metal
                .specular
                .pixels()
                .iter()
                .map(|&s| Vec3::splat(scene::luminance(s)))
                .collect(),
        )
        .expect("w × h"),
        ..metal
    };
    compare("white metals", &grey, &prepass, 1e-5, SAME_TERMS);
}

#[test]
fn the_gpu_builds_the_light_hierarchy_of_its_cpu_twin() {
    // 3000 scattered lights, a directional one among them, over the spheres scene.
    let c = spheres(32, 32, 3000);
    let Some(g) = ::gpu::test_device(&tiled_shading::device_needs()) else {
        return;
    };
    let TiledStage {
        stage, mut bound, ..
    } = tiled_stage(g, &c, c.lights.len());
    // Built twice (the lights set twice): the second build starts from the state the first
    // left.
    for _ in 0..2 {
        bound.set_lights(&g.queue, &c.lights).expect("lights");
        let mut encoder = g.device.create_command_encoder(&Default::default());
        stage.encode(&bound, &mut encoder, None);
        g.queue.submit([encoder.finish()]);
    }
    let built = bound
        .read_light_groups(&g.device, &g.queue)
        .expect("read")
        .expect("a hierarchy");
    let twin = tiled_shading::LightGroups::new(&c.lights);
    let mut order = built.order.clone();
    order.sort_unstable();
    assert_eq!(order, (0..c.lights.len() as u32).collect::<Vec<_>>());
    assert_eq!(built.spheres.len(), twin.spheres.len());
    let directional = |i: u32| c.lights[i as usize].kind == tiled_shading::LIGHT_DIRECTIONAL;
    assert!(directional(built.order[0]), "directional lights first");
    assert_eq!(built.spheres[0][3], f32::MAX);
    for (g, sphere) in built.spheres.iter().enumerate().skip(1) {
        let (centre, radius) = (Vec3::new(sphere[0], sphere[1], sphere[2]), sphere[3]);
        let members = &built.order[g * tiled_shading::LIGHT_GROUP
            ..((g + 1) * tiled_shading::LIGHT_GROUP).min(c.lights.len())];
        for &i in members {
            let l = &c.lights[i as usize];
            assert!(
                centre.distance(Vec3::from(l.position)) + l.radius <= radius,
                "group {g} holds light {i}"
            );
        }
    }
    // The same buckets in the same order (within a bucket in any order): groups as tight as
    // the twin's, up to members swapped across a group's end within one bucket.
    let mean = |groups: &tiled_shading::LightGroups| {
        groups.spheres[1..].iter().map(|s| s[3]).sum::<f32>() / (groups.spheres.len() - 1) as f32
    };
    let (gpu_mean, cpu_mean) = (mean(&built), mean(&twin));
    assert!(
        gpu_mean <= cpu_mean * 1.1,
        "GPU groups' mean radius {gpu_mean} against the twin's {cpu_mean}"
    );
}
