//! The frame's stages in combination (issue 23 item 5): a pairwise-covering sample of the
//! stage switches — light accumulation, direct shadows, indirect light, VPL visibility,
//! animation, near field, output transform, supersampling, subdivision per frame, SSAO —
//! rendered small on the test device. Every combination renders without error to finite radiance, and:
//! - light culling does not change the image (each culled method, Forward+ included, equals
//!   brute force; the light pre-pass, whose monochrome specular approximates, within 25 dB);
//! - interleaving with a 1×1 pattern equals the non-interleaved reference;
//! - the skinning stage at a pose equals the scene posed on the CPU and rendered still;
//! - where the CPU frame has the stages (shadow maps or none, no visibility, no near field,
//!   no supersampling, no SSAO), the CPU frame equals the GPU frame.
//! (Supersampling's own rules — adaptive pixels of every sample equal full supersampling,
//! indirect light shared per pixel — are tested in `supersampling.rs`.)

use instant_radiosity::{
    IndirectConfig, Interleaving,
    shadows::{ShadowConfig, VplShadows, scene_mesh},
};
use interleave::Pattern;
use pipeline::subdivision::{self, SubdivisionPlan, Tessellation};
use pipeline::{
    ShadingMethod,
    cpu::{self, FrameInputs},
    gpu::GpuRenderer,
    psnr,
};
use scene::Scene;
use tiled_shading::shadows::ShadowMapConfig;

mod scenes;

const SIZE: (u32, u32) = (64, 48);
const POSE_TIME: f32 = 0.7;

#[derive(Clone, Copy, Debug, PartialEq)]
enum Shadows {
    None,
    Maps,
    ManyLod,
    Rays,
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Indirect {
    None,
    Fused4x4,
    OneByOne,
    Reference,
}

#[derive(Clone, Copy, Debug, PartialEq)]
struct Combo {
    shading: ShadingMethod,
    shadows: Shadows,
    indirect: Indirect,
    visibility: Option<VplShadows>,
    posed: bool,
    near_field: bool,
    output: bool,
    ssaa: Ssaa,
    subdiv: bool,
    ssao: bool,
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Ssaa {
    None,
    Adaptive4x4,
    Full2x2,
}

impl Ssaa {
    fn config(self) -> Option<adaptive_ssaa::SsaaConfig> {
        let (m, min_samples) = match self {
            Ssaa::None => return None,
            Ssaa::Adaptive4x4 => (4, 1),
            Ssaa::Full2x2 => (2, 4),
        };
        Some(adaptive_ssaa::SsaaConfig {
            m,
            min_samples,
            anisotropy: 1,
            ..Default::default()
        })
    }
}

/// Levels of each switch.
const LEVELS: [usize; 10] = [8, 4, 4, 4, 2, 2, 2, 3, 2, 2];

/// Forward+ and the light pre-pass draw the scene again: supersampling, which shades
/// G-buffer samples, is off with them.
fn draws_again(method: ShadingMethod) -> bool {
    matches!(
        method,
        ShadingMethod::ForwardPlus | ShadingMethod::LightPrePass
    )
}

fn combo(levels: [usize; 10]) -> Combo {
    let shading = ShadingMethod::ALL[levels[0]];
    Combo {
        shading,
        shadows: [
            Shadows::None,
            Shadows::Maps,
            Shadows::ManyLod,
            Shadows::Rays,
        ][levels[1]],
        indirect: [
            Indirect::None,
            Indirect::Fused4x4,
            Indirect::OneByOne,
            Indirect::Reference,
        ][levels[2]],
        visibility: [
            None,
            Some(VplShadows::ManyLod),
            Some(VplShadows::Ism),
            Some(VplShadows::Rays),
        ][levels[3]],
        posed: levels[4] == 1,
        near_field: levels[5] == 1,
        output: levels[6] == 1,
        ssaa: if draws_again(shading) {
            Ssaa::None
        } else {
            [Ssaa::None, Ssaa::Adaptive4x4, Ssaa::Full2x2][levels[7]]
        },
        subdiv: levels[8] == 1,
        ssao: levels[9] == 1,
    }
}

/// A greedy pairwise covering of [`LEVELS`]: every level pair of every two switches appears in
/// some combination (deterministic).
fn pairwise() -> Vec<[usize; 10]> {
    let all: Vec<[usize; 10]> = (0..LEVELS.iter().product::<usize>())
        .map(|mut k| {
            std::array::from_fn(|i| {
                let l = k % LEVELS[i];
                k /= LEVELS[i];
                l
            })
        })
        .collect();
    let pairs = |c: &[usize; 10]| {
        let mut p = Vec::new();
        for i in 0..10 {
            for j in i + 1..10 {
                p.push((i, c[i], j, c[j]));
            }
        }
        p
    };
    let mut uncovered: std::collections::HashSet<_> = all.iter().flat_map(pairs).collect();
    let mut chosen = Vec::new();
    while !uncovered.is_empty() {
        let best = all
            .iter()
            .max_by_key(|c| pairs(c).iter().filter(|p| uncovered.contains(p)).count())
            .expect("combinations");
        for p in pairs(best) {
            uncovered.remove(&p);
        }
        chosen.push(*best);
    }
    chosen
}

fn indirect_config(scene: &Scene, indirect: Indirect) -> Option<IndirectConfig> {
    let defaults = IndirectConfig::new(scene.bounds());
    Some(match indirect {
        Indirect::None => return None,
        Indirect::Fused4x4 => defaults,
        Indirect::OneByOne => IndirectConfig {
            pattern: Pattern { n: 1, m: 1 },
            ..defaults
        },
        // One subset, so the VPLs are those of the 1×1 pattern.
        Indirect::Reference => IndirectConfig {
            pattern: Pattern { n: 1, m: 1 },
            interleaving: Interleaving::Reference,
            ..defaults
        },
    })
}

const MAPS: ShadowMapConfig = ShadowMapConfig {
    resolution: 64,
    cascades: 4,
    max_distance: None,
    bias: 1.5,
    normal_offset: 1.0,
};

fn surfels(mode: VplShadows, refit: bool) -> ShadowConfig {
    ShadowConfig {
        points_log2: 12,
        tile: 16,
        ism_points: 512,
        refit,
        ..ShadowConfig::for_mode(mode)
    }
}

/// `c` rendered on the GPU from `rest` (posed by the skinning stage when `c.posed` and
/// `animate`, else `scene` is rendered still as given): linear radiance.
/// The meshes CesiumMan's rig moves in [`room`] (the subdivided ones).
fn moved_meshes() -> Vec<usize> {
    let room = scenes::cesium_room();
    let rig = room.rig.as_ref().expect("rig");
    rig.deformers.iter().map(|d| d.mesh as usize).collect()
}

/// `scene` with the moved meshes subdivided to level 2 (their control meshes kept, the refined
/// ones appended) when `on`, and the plan.
fn subdivided(scene: &Scene, on: bool) -> (Scene, Option<SubdivisionPlan>) {
    if !on {
        return (scene.clone(), None);
    }
    static TABLES: std::sync::OnceLock<subdiv_bft::BftSet> = std::sync::OnceLock::new();
    let tables = TABLES
        .get_or_init(|| subdiv_bft::BftSet::build(2, subdiv_bft::MAX_VALENCE).expect("tables"));
    let (prepared, plan) = subdivision::prepare(
        scene,
        &moved_meshes(),
        (2, Tessellation::Uniform),
        tables.clone(),
    )
    .expect("subdivided");
    (prepared, Some(plan))
}

/// What is drawn of `scene` (without the subdivided control meshes).
fn drawn(scene: &Scene, plan: Option<&SubdivisionPlan>) -> Scene {
    plan.map_or_else(|| scene.clone(), |p| p.drawn(scene))
}

fn render_gpu(gpu: &gpu::Gpu, given: &Scene, c: &Combo, animate: bool) -> gbuffer::Image<[f32; 4]> {
    let (d, q) = (&gpu.device, &gpu.queue);
    let textures = gbuffer::TextureOptions { max_anisotropy: 1 };
    let (uploaded, plan) = subdivided(given, c.subdiv);
    let mut r = GpuRenderer::new_with(d, q, &uploaded, &uploaded.lights, SIZE, &textures)
        .expect("renderer");
    if let Some(plan) = &plan {
        r.set_subdivision(d, q, plan).expect("subdivision");
    }
    // What the CPU builds (surfels, BVHs, VPLs) sees what is drawn; the surfels refit where
    // meshes move.
    let scene = &drawn(&uploaded, plan.as_ref());
    let refit = uploaded.rig.is_some();
    r.set_shading(
        d,
        q,
        &pipeline::ShadingConfig {
            method: c.shading,
            tile_size: 16,
            ..Default::default()
        },
    )
    .expect("shading");
    match c.shadows {
        Shadows::None => {}
        Shadows::Maps => r.set_shadows(d, q, Some(&MAPS)).expect("maps"),
        Shadows::ManyLod => r
            .set_manylod_shadows(d, q, scene, Some(&surfels(VplShadows::ManyLod, refit)))
            .expect("manylod shadows"),
        Shadows::Rays => r.set_ray_shadows(d, q, Some(scene)).expect("rays"),
    }
    let animated = c.posed && animate;
    let rig = uploaded.rig.as_ref().filter(|_| animated);
    let pose = rig.map(|rig| rig.pose(Some(0), POSE_TIME));
    let mut posed = uploaded.clone();
    if let (Some(rig), Some(pose)) = (rig, &pose) {
        rig.apply(pose, &mut posed.meshes);
        if let Some(plan) = &plan {
            let camera = uploaded.camera_or_framed();
            plan.refine_cpu(&mut posed, &camera, SIZE)
                .expect("cpu subdivision");
        }
    }
    let posed = drawn(&posed, plan.as_ref());
    if let Some(config) = indirect_config(scene, c.indirect) {
        let set = scenes::vpls(scene, &config);
        match c.visibility {
            None => r.set_indirect(d, &config, &set).expect("indirect"),
            Some(mode) => r
                .set_vpl_shadows(d, scene, mode, &surfels(mode, refit), &config, &set)
                .expect("visibility"),
        }
        if c.near_field {
            r.set_near_field(d, Some(scene)).expect("near field");
        }
        if animated {
            r.set_vpls(q, &scenes::vpls(&posed, &config))
                .expect("posed vpls");
        }
    }
    if let (Some(rig), Some(pose)) = (rig, &pose) {
        r.set_animation(d, q, Some(rig)).expect("animation");
        r.set_pose(q, pose).expect("pose");
        r.set_scene_positions(q, &scene_mesh(&posed).0)
            .expect("refit");
    }
    if c.output {
        r.set_output(d, Some(pipeline::output::OutputTransform::default()))
            .expect("output");
    }
    r.set_ssaa(d, q, c.ssaa.config().as_ref()).expect("ssaa");
    if c.ssao {
        let config = ssao::cpu::KernelConfig {
            size: 5,
            ao: ssao::AoConfig {
                radius: 0.05 * uploaded.bounds().diagonal(),
            },
        };
        r.set_ssao(
            d,
            q,
            Some((&config, "filter-separable".parse().expect("estimator"))),
        )
        .expect("ssao");
    }
    let camera = scene.camera_or_framed();
    let out = r
        .render(d, q, &camera, pipeline::DEFAULT_AMBIENT)
        .expect("frame");
    if c.output {
        let display =
            pipeline::gpu::read_display(d, q, r.display().expect("display")).expect("display");
        assert!(
            display.pixels().iter().flatten().all(|v| v.is_finite()),
            "{c:?}: display"
        );
    }
    out.image
}

fn close(
    name: &str,
    c: &Combo,
    a: &gbuffer::Image<[f32; 4]>,
    b: &gbuffer::Image<[f32; 4]>,
    db: f64,
) {
    let got = psnr(a, b);
    assert!(
        got >= db,
        "{c:?}: {name}: PSNR {got:.1} dB < {db} dB; images in {}",
        a.write_comparison(
            b,
            &std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("combination-{name}"))
        )
    );
}

#[test]
fn every_sampled_combination_renders_and_keeps_the_invariants() {
    let Some(gpu) = gpu::test_device(&pipeline::device_needs()) else {
        return;
    };
    let rest = scenes::cesium_room();
    let rig = rest.rig.as_ref().expect("rig");
    let mut posed = rest.clone();
    rig.apply(&rig.pose(Some(0), POSE_TIME), &mut posed.meshes);
    posed.rig = None;
    let mut combos = pairwise();
    assert!(combos.len() >= 16, "{} combinations", combos.len());
    // And what the CPU frame has, across methods, indirect modes and poses.
    combos.extend([
        [1, 1, 1, 0, 1, 0, 0, 0, 0, 0],
        [3, 0, 3, 0, 0, 0, 1, 0, 1, 0],
        [2, 1, 2, 0, 1, 0, 0, 0, 1, 0],
        [0, 1, 1, 0, 0, 0, 0, 0, 0, 0],
        // Forward+ and the light pre-pass against the CPU frame (its twin of the materials pass).
        [5, 0, 1, 0, 1, 0, 0, 0, 0, 0],
        [6, 1, 0, 0, 0, 0, 0, 0, 1, 0],
    ]);
    let mut cpu_checked = 0;
    for levels in combos {
        let c = combo(levels);
        let mut checks = vec!["renders"];
        let image = render_gpu(gpu, &rest, &c, true);
        assert!(
            image.pixels().iter().flatten().all(|v| v.is_finite()),
            "{c:?}: non-finite radiance"
        );
        if c.shading != ShadingMethod::BruteForce {
            let brute = Combo {
                shading: ShadingMethod::BruteForce,
                ..c
            };
            // The light pre-pass's monochrome specular approximates (31 dB on this scene
            // with its direct light alone).
            let (name, db) = if c.shading == ShadingMethod::LightPrePass {
                ("light pre-pass", 25.0)
            } else {
                ("culling", 50.0)
            };
            close(name, &c, &render_gpu(gpu, &rest, &brute, true), &image, db);
            checks.push("= brute force");
        }
        if c.indirect == Indirect::OneByOne {
            let reference = Combo {
                indirect: Indirect::Reference,
                ..c
            };
            close(
                "1x1",
                &c,
                &render_gpu(gpu, &rest, &reference, true),
                &image,
                45.0,
            );
            checks.push("= reference");
        }
        // Structures built on the CPU (ray BVHs, the near field's BVH) keep the set-up pose
        // and refit ManyLoD/ISM trees cut slightly otherwise than fresh ones, so
        // the stages compared with a still posed scene are those that follow the skinning
        // exactly.
        let exact = matches!(c.shadows, Shadows::None | Shadows::Maps)
            && (c.indirect == Indirect::None || (c.visibility.is_none() && !c.near_field));
        if c.posed && exact {
            close(
                "skinning",
                &c,
                &render_gpu(gpu, &posed, &c, false),
                &image,
                45.0,
            );
            checks.push("= posed still");
        }
        let cpu_has = c.ssaa == Ssaa::None
            && !c.ssao
            && matches!(c.shadows, Shadows::None | Shadows::Maps)
            && (c.visibility.is_none() || c.indirect == Indirect::None)
            && (!c.near_field || c.indirect == Indirect::None);
        if cpu_has {
            let given = if c.posed { &posed } else { &rest };
            let (prepared, plan) = subdivided(given, c.subdiv);
            let scene = &drawn(&prepared, plan.as_ref());
            let camera = rest.camera_or_framed();
            let mut inputs = FrameInputs::new(
                scene,
                &camera,
                &scene.lights,
                SIZE,
                pipeline::DEFAULT_AMBIENT,
            )
            .with_textures(gbuffer::TextureOptions { max_anisotropy: 1 });
            if c.shadows == Shadows::Maps {
                inputs = inputs.with_shadows(MAPS);
            }
            let config = indirect_config(scene, c.indirect);
            let set = config.map(|config| scenes::vpls(scene, &config));
            let indirect = config.as_ref().zip(set.as_ref());
            let shading = pipeline::ShadingConfig {
                method: c.shading,
                tile_size: 16,
                ..Default::default()
            };
            let (expected, _) =
                cpu::render_indirect(&inputs, &shading, indirect).expect("cpu frame");
            close("cpu", &c, &expected.image, &image, 40.0);
            cpu_checked += 1;
            checks.push("= CPU frame");
        }
        println!("{c:?}: {}", checks.join(", "));
    }
    assert!(
        cpu_checked >= 4,
        "only {cpu_checked} combinations compared with the CPU frame"
    );
}
