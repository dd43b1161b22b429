//! Instant radiosity with interleaved shading: VPL generation, the invariants of Segovia 2006
//! §4 (1×1 = reference, subset sums, unbiased mean) and the GPU stage against the CPU one.

use std::f64::consts::PI;

use gbuffer::{Frame, GBuffer, Image, normal::unpack_octahedral, position};
use glam::{Vec3, Vec4};
use instant_radiosity::{
    IndirectConfig, IndirectError, IndirectStages, Interleaving, cpu, gpu as igpu,
    vpl::{self, VplConfig, VplError, VplSet},
};
use interleave::{Block, Blur, BlurVariant, Pattern, SplitVariant};
use scene::{Bvh, Camera, Light, Material, Mesh, Scene};

fn material(name: &str, albedo: f32, roughness: f32) -> Material {
    Material {
        name: name.into(),
        base_color: Vec4::new(albedo, albedo, albedo, 1.0),
        base_color_texture: None,
        roughness,
        metallic: 0.0,
        emissive: Vec3::ZERO,
        specular: 1.0,
        ..Default::default()
    }
}

/// A 4×4 floor at y = 0 facing up, a ceiling at y = 1 facing down, a point light between
/// them, and a camera under the ceiling looking straight down at the floor.
fn plane_scene() -> Scene {
    // The square |x|, |z| ≤ 2 at height y, corners counter-clockwise seen from above.
    let square = |y: f32| {
        [(-2.0, -2.0), (-2.0, 2.0), (2.0, 2.0), (2.0, -2.0)].map(|(x, z)| Vec3::new(x, y, z))
    };
    let floor = Mesh::quad("floor", square(0.0), 0);
    let [p0, p1, p2, p3] = square(1.0);
    let ceiling = Mesh::quad("ceiling", [p0, p3, p2, p1], 1);
    Scene {
        meshes: vec![floor, ceiling],
        materials: vec![material("floor", 0.8, 1.0), material("ceiling", 0.7, 1.0)],
        textures: Vec::new(),
        rig: None,
        camera: Some(Camera {
            eye: Vec3::new(0.0, 0.9, 0.0),
            target: Vec3::ZERO,
            up: Vec3::NEG_Z,
            fov_y: 60f32.to_radians(),
            near: 0.01,
            far: 10.0,
        }),
        lights: vec![Light::Point {
            position: Vec3::new(0.3, 0.5, -0.2),
            color: Vec3::ONE,
            intensity: 1.0,
            radius: 100.0,
        }],
    }
}

fn vpls(scene: &Scene, count: usize, subsets: u32, seed: u64) -> VplSet {
    vpl::generate(
        scene,
        &Bvh::build(scene),
        &scene.lights,
        &VplConfig {
            count,
            subsets,
            seed,
            emissive: scene.lights.is_empty(),
            bounces: 1,
        },
    )
    .expect("vpls")
}

/// The frame and CPU G-buffer of `scene` from its camera at `w × h`.
fn frame_and_gbuffer(scene: &Scene, w: u32, h: u32) -> (Frame, GBuffer) {
    let camera = &scene.camera_or_framed();
    let gb = gbuffer::cpu::rasterize(scene, camera, w, h)
        .expect("rasterize")
        .gbuffer;
    (Frame::new(camera, w, h), gb)
}

fn config(
    scene: &Scene,
    pattern: (u32, u32),
    interleaving: Interleaving,
    blur: Option<Blur>,
) -> IndirectConfig {
    IndirectConfig {
        pattern: Pattern::new(pattern.0, pattern.1).expect("pattern"),
        interleaving,
        blur,
        ..IndirectConfig::new(scene.bounds())
    }
}

fn fast(kernel: u32) -> Option<Blur> {
    Some(Blur {
        kernel,
        variant: BlurVariant::Fast,
    })
}

/// Largest |a − b| / (|b| + floor) over RGB of two images.
fn max_relative(a: &Image<[f32; 4]>, b: &Image<[f32; 4]>, floor: f32) -> f32 {
    a.pixels()
        .iter()
        .zip(b.pixels())
        .flat_map(|(p, q)| (0..3).map(move |c| (p[c] - q[c]).abs() / (q[c].abs() + floor)))
        .fold(0.0, f32::max)
}

fn max_value(a: &Image<[f32; 4]>) -> f32 {
    a.pixels()
        .iter()
        .flat_map(|p| p[..3].iter().copied())
        .fold(0.0, f32::max)
}

#[test]
fn vpl_generation_is_deterministic_and_complete() {
    let s = scene::cornell_box();
    let a = vpls(&s, 480, 48, 3);
    let b = vpls(&s, 480, 48, 3);
    let c = vpls(&s, 480, 48, 4);
    assert_eq!(a, b, "same seed, same VPLs");
    assert_ne!(a.vpls, c.vpls, "another seed, other VPLs");
    assert_eq!((a.vpls.len(), a.per_subset, a.subsets), (480, 10, 48));
    assert_eq!(a.subset(47).len(), 10);
    for v in &a.vpls {
        assert!(v.flux.min_element() >= 0.0 && v.flux.max_element() > 0.0);
        assert!((v.normal.length() - 1.0).abs() < 1e-5);
        let b = s.bounds();
        let slack = Vec3::splat(1e-4);
        assert!(v.position.cmpge(b.min - slack).all() && v.position.cmple(b.max + slack).all());
    }
}

/// In a closed box with one albedo, every photon of a point light hits a wall, so the VPLs'
/// flux sums to albedo × the light's flux (4π·I, the window of a huge radius ≈ 1).
/// The Cornell box's lamp mesh and its area.
fn lamp_and_area(s: &Scene) -> (&Mesh, f32) {
    let lamp = s.meshes.iter().find(|m| m.name == "light").expect("lamp");
    let area = lamp
        .indices
        .chunks_exact(3)
        .map(|t| {
            let [a, b, c] = [0, 1, 2].map(|k| lamp.positions[t[k] as usize]);
            0.5 * (b - a).cross(c - a).length()
        })
        .sum();
    (lamp, area)
}

/// The Cornell box closed at the front, every surface of `albedo`, its lamp still emissive:
/// every photon hits it and reflects `albedo` of its flux.
fn closed_grey_box(albedo: f32) -> Scene {
    let mut s = scene::cornell_box();
    for m in &mut s.materials {
        m.base_color = Vec4::new(albedo, albedo, albedo, 1.0);
        m.base_color_texture = None;
    }
    let b = s.bounds();
    s.meshes.push(Mesh::quad(
        "front",
        [
            Vec3::new(b.min.x - 0.1, b.min.y - 0.1, b.min.z),
            Vec3::new(b.max.x + 0.1, b.min.y - 0.1, b.min.z),
            Vec3::new(b.max.x + 0.1, b.max.y + 0.1, b.min.z),
            Vec3::new(b.min.x - 0.1, b.max.y + 0.1, b.min.z),
        ],
        0,
    ));
    s
}

/// [`closed_grey_box`] lit only by a point light of `color` × `intensity` at its centre.
fn point_lit_grey_box(albedo: f32, color: Vec3, intensity: f32) -> Scene {
    let mut s = closed_grey_box(albedo);
    for m in &mut s.materials {
        m.emissive = Vec3::ZERO;
    }
    s.lights = vec![Light::Point {
        position: s.bounds().center(),
        color,
        intensity,
        radius: 1e4,
    }];
    s
}

/// Σ VPL flux against the flux reflected where photons of total flux `emitted` first land.
fn assert_reflected_flux(set: &VplSet, emitted: Vec3, albedo: f32) {
    let total: Vec3 = set.vpls.iter().map(|v| v.flux).sum();
    let expected = emitted * albedo;
    let photons: u64 = set.photons.iter().sum();
    assert_eq!(
        photons,
        set.vpls.len() as u64,
        "every photon hits the closed box"
    );
    assert!(
        ((total - expected).abs() / expected).max_element() < 1e-4,
        "{total} vs {expected}"
    );
}

#[test]
fn vpl_flux_sums_to_reflected_light_flux() {
    let albedo = 0.5;
    let s = point_lit_grey_box(albedo, Vec3::new(1.0, 0.5, 0.25), 2.0);
    let emitted = Vec3::new(1.0, 0.5, 0.25) * 2.0 * 4.0 * std::f32::consts::PI;
    assert_reflected_flux(&vpls(&s, 1024, 16, 9), emitted, albedo);
}

/// Multi-bounce VPLs (photons continue by Russian roulette): in the closed grey box of albedo
/// ρ = 1/2 the flux of all bounces sums to Φ·(ρ + ρ² + …) = Φ, within the roulette's noise
/// (about 1.6 % for ~2000 photon paths; 5 % allowed), where one bounce gives exactly ρ·Φ.
#[test]
fn multi_bounce_vpls_carry_every_bounce() {
    let albedo = 0.5;
    let s = point_lit_grey_box(albedo, Vec3::ONE, 1.0);
    let emitted = Vec3::ONE * 4.0 * std::f32::consts::PI;
    let config = VplConfig {
        count: 4096,
        subsets: 16,
        seed: 5,
        emissive: false,
        bounces: 64,
    };
    let set = vpl::generate(&s, &Bvh::build(&s), &s.lights, &config).expect("vpls");
    let total: Vec3 = set.vpls.iter().map(|v| v.flux).sum();
    let photons: u64 = set.photons.iter().sum();
    let geometric = emitted * albedo / (1.0 - albedo);
    assert!(
        ((total - geometric).abs() / geometric).max_element() < 0.05,
        "{total} vs {geometric} ({photons} photons for 4096 VPLs)"
    );
    // A path is 1/(1 − q) = 2 VPLs long on average (survival q = ρ).
    let per_path = 4096.0 / photons as f64;
    assert!((1.8..2.2).contains(&per_path), "{per_path} VPLs per photon");
}

/// A scene lit only by an emissive lamp: photons leave the lamp's triangles and carry its
/// flux π·L·A once, whether through `generate` or `generate_from_primary` (whose primary
/// lights are the lamp's hemispherical stand-ins for direct light).
#[test]
fn emissive_lamp_flux_is_counted_once() {
    let albedo = 0.5;
    let mut s = closed_grey_box(albedo);
    s.lights.clear();
    let (lamp, area) = lamp_and_area(&s);
    let emitted = s.materials[lamp.material as usize].emissive * std::f32::consts::PI * area;
    assert_reflected_flux(&vpls(&s, 1024, 16, 3), emitted, albedo);
    let bvh = Bvh::build(&s);
    let primary = vpl::generate_from_primary(&s, &bvh, 1024, 16, 3).expect("vpls");
    assert_reflected_flux(&primary, emitted, albedo);
}

/// The Cornell box's emissive quad is a primary light too, and its hemispherical stand-in
/// carries its flux π·L·A.
#[test]
fn emissive_area_lights_emit_photons() {
    let mut s = scene::cornell_box();
    s.lights.clear();
    let set = vpls(&s, 256, 16, 1);
    assert!(set.vpls.iter().all(|v| v.position.y < s.bounds().max.y));
    let lights = vpl::area_lights(&s, 1);
    assert_eq!(lights.len(), 1);
    let Light::Hemispherical {
        direction,
        intensity,
        color,
        ..
    } = lights[0]
    else {
        panic!("hemispherical light expected");
    };
    assert!(
        direction.y < -0.99,
        "the light opening faces down: {direction}"
    );
    let (lamp, area) = lamp_and_area(&s);
    let emissive = s.materials[lamp.material as usize].emissive;
    assert!(((color * intensity) - emissive * area).abs().max_element() < 1e-5);
}

/// The progressive mode's frames of area-light samples converge to the area light itself:
/// the irradiance their mean gives receivers near the Cornell box's lamp (grazing ones under
/// the ceiling, where a sample's placement matters most, and the floor) equals the lamp's
/// integral by a fine midpoint rule over its triangles within 0.2 % after 64 frames (frames
/// whose in-triangle coordinate continued one base-2 sequence were 4 % off at the grazing
/// receivers, samples lifted 10⁻⁴ of the light's reach off the lamp 0.7 %).
#[test]
fn area_light_frames_converge_to_the_area_light() {
    let mut s = scene::cornell_box();
    s.lights.clear();
    let (lamp, _) = lamp_and_area(&s);
    let radiance = f64::from(s.materials[lamp.material as usize].emissive.max_element());
    let b = s.bounds();
    let h = b.max.y - b.min.y;
    let centre = lamp.positions.iter().copied().sum::<Vec3>() / lamp.positions.len() as f32;
    let receivers = [
        (centre + Vec3::new(0.45, -0.05, 0.0) * h, -Vec3::X),
        (centre + Vec3::new(0.0, -0.05, -0.45) * h, Vec3::Z),
        (centre + Vec3::new(0.3, -0.5, 0.2) * h, -Vec3::X),
        (centre + Vec3::new(0.1, -0.95, 0.1) * h, Vec3::Y),
    ];
    // E = ∫ L cos θ_e cos θ_r / d² dA (lamp facing down), each triangle cut into n² pieces.
    let exact = |(p, n): (Vec3, Vec3)| -> f64 {
        let n_sub = 96;
        let mut e = 0.0;
        for t in lamp.indices.chunks_exact(3) {
            let [a, b, c] = [0, 1, 2].map(|k| lamp.positions[t[k] as usize].as_dvec3());
            let normal = (b - a).cross(c - a);
            let area = 0.5 * normal.length() / f64::from(n_sub * n_sub);
            let normal = normal.normalize();
            let normal = if normal.y > 0.0 { -normal } else { normal };
            for i in 0..n_sub {
                for j in 0..n_sub - i {
                    // The upright and (where it exists) the inverted piece of cell (i, j).
                    let mut pieces = vec![[(i, j), (i + 1, j), (i, j + 1)]];
                    if i + j + 1 < n_sub {
                        pieces.push([(i + 1, j), (i + 1, j + 1), (i, j + 1)]);
                    }
                    for piece in pieces {
                        let q = piece
                            .iter()
                            .map(|&(u, v)| {
                                let (u, v) = (
                                    f64::from(u) / f64::from(n_sub),
                                    f64::from(v) / f64::from(n_sub),
                                );
                                a + (b - a) * u + (c - a) * v
                            })
                            .sum::<glam::DVec3>()
                            / 3.0;
                        let to = p.as_dvec3() - q;
                        let d2 = to.length_squared();
                        let l = to / d2.sqrt();
                        let (ce, cr) = (normal.dot(l), -n.as_dvec3().dot(l));
                        if ce > 0.0 && cr > 0.0 {
                            e += radiance * ce * cr / d2 * area;
                        }
                    }
                }
            }
        }
        e
    };
    let frames = 64;
    for (k, &receiver) in receivers.iter().enumerate() {
        let (p, n) = receiver;
        let mut sum = 0.0;
        for f in 0..frames {
            for light in vpl::area_lights_frame(&s, 16, f) {
                let Light::Hemispherical {
                    position,
                    direction,
                    intensity,
                    ..
                } = light
                else {
                    panic!("hemispherical light expected");
                };
                let to = (p - position).as_dvec3();
                let d2 = to.length_squared();
                let l = to / d2.sqrt();
                let (ce, cr) = (direction.as_dvec3().dot(l), -n.as_dvec3().dot(l));
                if ce > 0.0 && cr > 0.0 {
                    sum += f64::from(intensity) * ce * cr / d2;
                }
            }
        }
        let (mean, want) = (sum / f64::from(frames), exact(receiver));
        assert!(
            (mean / want - 1.0).abs() < 2e-3,
            "receiver {k} at {p}: {mean} from the frames' samples, {want} from the lamp"
        );
    }
}

#[test]
fn bad_vpl_requests_are_errors() {
    let s = scene::cornell_box();
    let bvh = Bvh::build(&s);
    let ask = |count, subsets| {
        vpl::generate(
            &s,
            &bvh,
            &s.lights,
            &VplConfig {
                count,
                subsets,
                seed: 0,
                emissive: true,
                bounces: 1,
            },
        )
    };
    assert!(matches!(ask(100, 16), Err(VplError::Count { .. })));
    assert!(matches!(ask(8, 1), Err(VplError::Count { .. })));
    assert!(matches!(ask(32768, 1), Err(VplError::Count { .. })));
    let mut dark = scene::cornell_box();
    dark.lights.clear();
    for m in &mut dark.materials {
        m.emissive = Vec3::ZERO;
    }
    let r = vpl::generate(
        &dark,
        &bvh,
        &[],
        &VplConfig {
            count: 64,
            subsets: 1,
            seed: 0,
            emissive: true,
            bounces: 1,
        },
    );
    assert_eq!(r, Err(VplError::NoEmitter));
    // A spot light pointing away from everything places nothing.
    let away = Light::Spot {
        position: Vec3::new(0.0, 100.0, 0.0),
        direction: Vec3::Y,
        color: Vec3::ONE,
        intensity: 1.0,
        radius: 1.0,
        inner_angle: 0.1,
        outer_angle: 0.2,
    };
    let r = vpl::generate(
        &dark,
        &bvh,
        &[away],
        &VplConfig {
            count: 64,
            subsets: 1,
            seed: 0,
            emissive: true,
            bounces: 1,
        },
    );
    assert!(
        matches!(r, Err(VplError::TooFewHits { placed: 0, .. })),
        "{r:?}"
    );
    assert_eq!(vpl::per_subset(1024, 48), 21);
    assert_eq!(vpl::per_subset(480, 48), 10);
    assert_eq!(vpl::per_subset(3, 48), 1);
}

#[test]
fn bad_configurations_are_errors() {
    let s = scene::cornell_box();
    let (frame, gb) = frame_and_gbuffer(&s, 16, 12);
    let set = vpls(&s, 64, 16, 0);
    let mut c = config(&s, (4, 4), Interleaving::Fused, None);
    c.pattern = Pattern { n: 2, m: 2 };
    assert!(matches!(
        cpu::indirect(&gb, &frame, &set, &c),
        Err(IndirectError::Subsets {
            vpl_subsets: 16,
            sub_buffers: 4
        })
    ));
    let mut c = config(&s, (4, 4), Interleaving::Fused, None);
    c.clamp_distance = f32::NAN;
    assert!(matches!(
        cpu::indirect(&gb, &frame, &set, &c),
        Err(IndirectError::Clamp(_))
    ));
    let mut c = config(&s, (4, 4), Interleaving::Fused, None);
    c.blur = Some(Blur {
        kernel: 4,
        variant: BlurVariant::Plain,
    });
    assert!(matches!(
        cpu::indirect(&gb, &frame, &set, &c),
        Err(IndirectError::Interleave(_))
    ));
}

/// With a 1×1 pattern the interleaved frame is the reference: one subset, scale 1, the same
/// sums in the same order — equal bit for bit (CPU and GPU), blur off.
#[test]
fn pattern_1x1_is_the_reference() {
    let s = scene::cornell_box();
    let (frame, gb) = frame_and_gbuffer(&s, 40, 30);
    let set = vpls(&s, 64, 1, 5);
    let reference = config(&s, (1, 1), Interleaving::Reference, None);
    let expected = cpu::indirect(&gb, &frame, &set, &reference).expect("reference");
    for interleaving in [
        Interleaving::Split(SplitVariant::OnePass),
        Interleaving::Fused,
    ] {
        let c = config(&s, (1, 1), interleaving, None);
        let actual = cpu::indirect(&gb, &frame, &set, &c).expect("1x1");
        assert!(actual.diffuse == expected.diffuse && actual.specular == expected.specular);
        if let Some(gpu) = gpu::test_device(&instant_radiosity::device_needs()) {
            let g_ref = igpu::run(gpu, &gb, &frame, &set, &reference).expect("gpu reference");
            let g = igpu::run(gpu, &gb, &frame, &set, &c).expect("gpu 1x1");
            assert!(g.diffuse == g_ref.diffuse && g.specular == g_ref.specular);
        }
    }
}

/// Blur off: every pixel's diffuse light is n·m × the sum over its own VPL subset
/// (sub-buffer (x mod n, y mod m) ↔ subset (y mod m)·n + x mod n), computed here in f64 from
/// the G-buffer and the VPLs with the Lambert formula.
#[test]
fn each_pixel_sums_its_own_subset() {
    let s = scene::cornell_box();
    let (w, h) = (37, 29);
    let (frame, gb) = frame_and_gbuffer(&s, w, h);
    let (n, m) = (4u32, 3u32);
    let set = vpls(&s, 12 * 8, n * m, 11);
    let clamp = IndirectConfig::new(s.bounds()).clamp_distance as f64;
    let expected = |x: u32, y: u32| -> [f64; 3] {
        let depth = gb.linear_depth.get(x, y);
        if depth <= 0.0 {
            return [0.0; 3];
        }
        let p = position::from_view_ray(&frame, x, y, depth).as_dvec3();
        let nrm = unpack_octahedral(gb.normal.get(x, y)).as_dvec3();
        let subset = (y % m) * n + x % n;
        let mut e = [0.0; 3];
        for v in set.subset(subset) {
            let to = v.position.as_dvec3() - p;
            let d2 = to.length_squared();
            let l = to / d2.sqrt();
            let g = (-v.normal.as_dvec3().dot(l)).max(0.0) * nrm.dot(l).max(0.0)
                / d2.max(clamp * clamp);
            for (e, flux) in e.iter_mut().zip(v.flux.to_array()) {
                *e += f64::from(flux) / PI * g / PI * f64::from(n * m);
            }
        }
        e
    };
    let check = |what: &str, stages: &IndirectStages| {
        for y in 0..h {
            for x in 0..w {
                let got = stages.diffuse.get(x, y);
                let want = expected(x, y);
                for c in 0..3 {
                    let err = (f64::from(got[c]) - want[c]).abs();
                    assert!(
                        err <= want[c] * 2f64.powi(-9) + 1e-7,
                        "{what} ({x}, {y}) channel {c}: {} vs {}",
                        got[c],
                        want[c]
                    );
                }
            }
        }
    };
    for interleaving in [
        Interleaving::Split(SplitVariant::Tiled),
        Interleaving::Split(SplitVariant::TwoPass(Block { p: 8, q: 6 })),
        Interleaving::Fused,
    ] {
        let c = config(&s, (n, m), interleaving, None);
        check("cpu", &cpu::indirect(&gb, &frame, &set, &c).expect("cpu"));
        if let Some(gpu) = gpu::test_device(&instant_radiosity::device_needs()) {
            check("gpu", &igpu::run(gpu, &gb, &frame, &set, &c).expect("gpu"));
        }
    }
}

/// On a flat floor lit by VPLs on the ceiling, the mean interleaved light equals the mean of
/// the reference within 1 %, blur off and on (each subset is a representative sample).
#[test]
fn flat_plane_mean_matches_the_reference() {
    let s = plane_scene();
    let (frame, gb) = frame_and_gbuffer(&s, 96, 96);
    assert!(
        gb.linear_depth.pixels().iter().all(|&d| d > 0.0),
        "floor fills the view"
    );
    let mean = |img: &Image<[f32; 4]>| {
        img.pixels()
            .iter()
            .map(|p| f64::from(p[0] + p[1] + p[2]))
            .sum::<f64>()
            / img.pixels().len() as f64
    };
    for pattern in [(4, 4), (8, 6)] {
        let set = vpls(&s, 48 * 20, pattern.0 * pattern.1, 2);
        let reference = cpu::indirect(
            &gb,
            &frame,
            &set,
            &config(&s, pattern, Interleaving::Reference, None),
        )
        .expect("reference");
        let r = mean(&reference.diffuse);
        assert!(r > 0.0);
        for blur in [None, fast(5), fast(9)] {
            let c = config(&s, pattern, Interleaving::Fused, blur);
            let stages = cpu::indirect(&gb, &frame, &set, &c).expect("interleaved");
            let i = mean(stages.result().0);
            assert!(
                (i - r).abs() <= 0.01 * r,
                "{pattern:?} blur {blur:?}: mean {i} vs reference {r}"
            );
        }
    }
}

/// The whole indirect stage (split variants, fused, reference; plain and fast blur) on the
/// GPU against the CPU reference from the same G-buffer: every stage within 2⁻⁸ relative
/// (f16 storage, GPU `inverseSqrt` and fused multiply-adds) of the CPU's, with an absolute
/// floor of 2⁻¹² of the image's maximum.
#[test]
fn gpu_indirect_stage_matches_cpu() {
    let Some(gpu) = gpu::test_device(&instant_radiosity::device_needs()) else {
        return;
    };
    let mut s = scene::cornell_box();
    s.materials[1].roughness = 0.3; // a glossy wall
    let (frame, gb) = frame_and_gbuffer(&s, 67, 45);
    for (pattern, interleaving, blur) in [
        ((4, 4), Interleaving::Split(SplitVariant::Tiled), fast(5)),
        ((4, 4), Interleaving::Split(SplitVariant::OnePass), None),
        (
            (8, 6),
            Interleaving::Split(SplitVariant::TwoPass(Block { p: 16, q: 12 })),
            Some(Blur {
                kernel: 7,
                variant: BlurVariant::Plain,
            }),
        ),
        ((8, 6), Interleaving::Fused, fast(9)),
        ((4, 4), Interleaving::Reference, None),
    ] {
        let c = config(&s, pattern, interleaving, blur);
        let set = vpls(&s, (c.subsets() as usize * 4).max(16), c.subsets(), 21);
        let want = cpu::indirect(&gb, &frame, &set, &c).expect("cpu");
        let got = igpu::run(gpu, &gb, &frame, &set, &c).expect("gpu");
        assert_eq!(
            got.discontinuities, want.discontinuities,
            "{interleaving:?}"
        );
        assert_eq!(got.split_normal, want.split_normal, "{interleaving:?}");
        let pairs = [
            ("shaded", &got.shaded_diffuse, &want.shaded_diffuse),
            ("diffuse", &got.diffuse, &want.diffuse),
            ("specular", &got.specular, &want.specular),
            ("result diffuse", got.result().0, want.result().0),
            ("result specular", got.result().1, want.result().1),
        ];
        for (what, g, w) in pairs {
            let floor = max_value(w) * 2f32.powi(-12) + 1e-12;
            let err = max_relative(g, w, floor);
            assert!(
                err <= 2f32.powi(-8),
                "{interleaving:?} {what}: relative error {err}; images in {}",
                w.write_comparison(
                    g,
                    &std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
                        .join(format!("indirect-{what}"))
                )
            );
        }
    }
}

/// `bind` checks what the caller gives it: outputs of another size or format, a G-buffer of
/// another size and a VPL set of another subset count are errors naming the input, not wgpu
/// validation panics later.
#[test]
fn bind_rejects_mismatched_inputs() {
    let Some(gpu) = gpu::test_device(&instant_radiosity::device_needs()) else {
        return;
    };
    let d = &gpu.device;
    let s = scene::cornell_box();
    let (frame, gb) = frame_and_gbuffer(&s, 32, 24);
    let uploaded = gbuffer::gpu::UploadedGBuffer::new(d, &gpu.queue, &gb, &frame).expect("upload");
    let c = config(&s, (4, 4), Interleaving::Fused, fast(5));
    let set = vpls(&s, 64, 16, 0);
    let stage = igpu::IndirectStage::new(d, &c, (32, 24)).expect("stage");
    let good = stage.output_textures(d);
    let bind = |outputs: [&wgpu::Texture; 2], set: &VplSet| {
        stage
            .bind(d, &uploaded.frame, uploaded.textures(), set, None, outputs)
            .map(|_| ())
            .map_err(|e| e.to_string())
    };
    assert_eq!(bind(good.each_ref(), &set), Ok(()));
    let small = igpu::IndirectStage::new(d, &c, (16, 12))
        .expect("stage")
        .output_textures(d);
    let e = bind([&small[0], &good[1]], &set).expect_err("16×12 output");
    assert!(
        e.contains("indirect diffuse output") && e.contains("16×12"),
        "{e}"
    );
    let rgba8 = gpu::transfer::texture_2d(
        d,
        "rgba8",
        32,
        24,
        wgpu::TextureFormat::Rgba8Unorm,
        wgpu::TextureUsages::STORAGE_BINDING,
    );
    let e = bind([&good[0], &rgba8], &set).expect_err("Rgba8 output");
    assert!(
        e.contains("indirect specular output") && e.contains("format"),
        "{e}"
    );
    let e = bind(good.each_ref(), &vpls(&s, 64, 4, 0)).expect_err("4 subsets");
    assert!(e.contains("4 subsets"), "{e}");
    let other = igpu::IndirectStage::new(d, &c, (40, 24)).expect("stage");
    let outputs = other.output_textures(d);
    let e = other
        .bind(
            d,
            &uploaded.frame,
            uploaded.textures(),
            &set,
            None,
            outputs.each_ref(),
        )
        .map(|_| ())
        .expect_err("32×24 G-buffer for a 40×24 stage");
    assert!(e.to_string().contains("G-buffer linear depth"), "{e}");
}
