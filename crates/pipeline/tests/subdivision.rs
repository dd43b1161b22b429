//! Subdivision per frame (`pipeline::subdivision`, `GpuRenderer::set_subdivision`): the GPU
//! frame of a skinned, subdivided character against its CPU twin (the rig posed and the
//! control mesh subdivided on the CPU, rendered still), and the stencils' invariant for the
//! attributes evaluated through them.

use glam::{Vec2, Vec3};
use pipeline::gpu::GpuRenderer;
use pipeline::subdivision::{self, SubdivisionPlan, Tessellation};
use scene::Scene;

mod scenes;

const SIZE: (u32, u32) = (96, 72);

fn tables() -> subdiv_bft::BftSet {
    subdiv_bft::BftSet::build(2, subdiv_bft::MAX_VALENCE).expect("tables")
}

/// CesiumMan in the Cornell box, its meshes subdivided to surface `level` as `tessellation`
/// says.
fn subdivided_room(level: u32, tessellation: Tessellation) -> (Scene, SubdivisionPlan) {
    let room = scenes::cesium_room();
    let moved: Vec<usize> = room
        .rig
        .as_ref()
        .expect("rig")
        .deformers
        .iter()
        .map(|d| d.mesh as usize)
        .collect();
    subdivision::prepare(&room, &moved, (level, tessellation), tables()).expect("prepared")
}

fn render(gpu: &gpu::Gpu, r: &mut GpuRenderer, scene: &Scene) -> gbuffer::Image<[f32; 4]> {
    r.render(
        &gpu.device,
        &gpu.queue,
        &scene.camera_or_framed(),
        pipeline::DEFAULT_AMBIENT,
    )
    .expect("frame")
    .image
}

fn still(gpu: &gpu::Gpu, scene: &Scene) -> gbuffer::Image<[f32; 4]> {
    let textures = gbuffer::TextureOptions { max_anisotropy: 1 };
    let (d, q) = (&gpu.device, &gpu.queue);
    let mut r = GpuRenderer::new_with(d, q, scene, &scene.lights, SIZE, &textures).expect("still");
    render(gpu, &mut r, scene)
}

#[test]
fn a_skinned_subdivided_character_matches_its_cpu_twin() {
    let Some(gpu) = gpu::test_device(&pipeline::device_needs()) else {
        return;
    };
    let (d, q) = (&gpu.device, &gpu.queue);
    let (prepared, plan) = subdivided_room(2, Tessellation::Uniform);
    let rig = prepared.rig.clone().expect("rig");
    let textures = gbuffer::TextureOptions { max_anisotropy: 1 };
    let mut r = GpuRenderer::new_with(d, q, &prepared, &prepared.lights, SIZE, &textures)
        .expect("renderer");
    r.set_subdivision(d, q, &plan).expect("subdivision");
    // The rest pose: the GPU's evaluation equals the CPU's at set-up.
    let rest = render(gpu, &mut r, &prepared);
    let expected = still(gpu, &plan.drawn(&prepared));
    let db = pipeline::psnr(&expected, &rest);
    assert!(db >= 50.0, "rest pose: PSNR {db:.1} dB");
    // Posed by the skinning, then subdivided, every frame.
    r.set_animation(d, q, Some(&rig)).expect("animation");
    for t in [0.4, 1.3] {
        let pose = rig.pose(Some(0), t);
        r.set_pose(q, &pose).expect("pose");
        let frame = render(gpu, &mut r, &prepared);
        let mut posed = prepared.clone();
        rig.apply(&pose, &mut posed.meshes);
        plan.refine_cpu(&mut posed, &prepared.camera_or_framed(), SIZE)
            .expect("cpu subdivision");
        let expected = still(gpu, &plan.drawn(&posed));
        let db = pipeline::psnr(&expected, &frame);
        println!("t {t}: PSNR {db:.1} dB against the CPU-posed, CPU-subdivided scene");
        assert!(db >= 45.0, "t {t}: PSNR {db:.1} dB");
        let moved = pipeline::psnr(&rest, &frame);
        assert!(
            moved < db - 5.0,
            "t {t}: the pose changes the frame ({moved:.1} dB)"
        );
    }
}

/// Adaptive tessellation every frame (§2.4): the factors for the frame's camera, the patches
/// tessellated and their triangles drawn from the scene's index buffer — against the CPU's
/// factors and tessellation of the posed control mesh, rendered still.
#[test]
fn adaptive_subdivision_per_frame_matches_its_cpu_twin() {
    let needs = pipeline::device_needs().and(&subdiv_bft::adaptive_device_needs());
    let Some(gpu) = gpu::test_device(&needs) else {
        return;
    };
    let (d, q) = (&gpu.device, &gpu.queue);
    let adaptive = Tessellation::Adaptive { target_pixels: 0.5 };
    let (prepared, plan) = subdivided_room(3, adaptive);
    let rig = prepared.rig.clone().expect("rig");
    let camera = prepared.camera_or_framed();
    let textures = gbuffer::TextureOptions { max_anisotropy: 1 };
    let mut r = GpuRenderer::new_with(d, q, &prepared, &prepared.lights, SIZE, &textures)
        .expect("renderer");
    r.set_subdivision(d, q, &plan).expect("subdivision");
    r.set_animation(d, q, Some(&rig)).expect("animation");
    let pose = rig.pose(Some(0), 0.9);
    r.set_pose(q, &pose).expect("pose");
    let frame = render(gpu, &mut r, &prepared);
    let mut posed = prepared.clone();
    rig.apply(&pose, &mut posed.meshes);
    plan.refine_cpu(&mut posed, &camera, SIZE)
        .expect("cpu subdivision");
    let drawn = plan.drawn(&posed);
    let capacity = prepared.meshes.last().expect("refined").indices.len();
    let kept = drawn.meshes.last().expect("refined").indices.len();
    assert_eq!(
        posed.meshes.last().expect("refined").indices.len(),
        capacity,
        "the prepared scene keeps every slot (the upload's size)"
    );
    println!("adaptive: {} of {} triangle slots", kept / 3, capacity / 3);
    // Level 3 has 16 triangles a patch: more than 1/16 of the slots means some patches were
    // split, fewer than half that most were not (the character is small on screen).
    assert!(
        kept > capacity / 16 && kept < capacity / 2,
        "{kept} of {capacity} indices"
    );
    let expected = still(gpu, &drawn);
    let db = pipeline::psnr(&expected, &frame);
    println!("adaptive, posed: PSNR {db:.1} dB against the CPU twin");
    assert!(db >= 40.0, "PSNR {db:.1} dB");
}

/// The visibility buffer (issue 29) reads the skinned, subdivided vertices where the hardware
/// path reads them — the scene's buffers the skinning and the subdivision write, no copy — and
/// is bound again when the subdivision hides the control meshes: the posed frame through it
/// within 40 dB of the hardware path's, uniform and adaptive (whose slots past each frame's
/// count are degenerate triangles).
#[test]
fn the_visibility_buffer_draws_the_skinned_subdivided_character() {
    let needs = pipeline::device_needs()
        .and(&subdiv_bft::adaptive_device_needs())
        .and(&gbuffer::gpu::visibility::device_needs());
    let Some(gpu) = gpu::test_device(&needs) else {
        return;
    };
    let (d, q) = (&gpu.device, &gpu.queue);
    let adaptive = Tessellation::Adaptive { target_pixels: 0.5 };
    for (level, tessellation) in [(2, Tessellation::Uniform), (3, adaptive)] {
        let (prepared, plan) = subdivided_room(level, tessellation);
        let rig = prepared.rig.clone().expect("rig");
        let textures = gbuffer::TextureOptions { max_anisotropy: 1 };
        let mut r = GpuRenderer::new_with(d, q, &prepared, &prepared.lights, SIZE, &textures)
            .expect("renderer");
        // On before the subdivision: its hiding of the control meshes rebinds the path.
        r.set_visibility(d, true).expect("visibility");
        r.set_subdivision(d, q, &plan).expect("subdivision");
        r.set_animation(d, q, Some(&rig)).expect("animation");
        r.set_pose(q, &rig.pose(Some(0), 0.9)).expect("pose");
        assert!(r.visibility(), "still on after the subdivision");
        let camera = prepared.camera_or_framed();
        let frame = r
            .render(d, q, &camera, pipeline::DEFAULT_AMBIENT)
            .expect("frame");
        if gpu.has_timestamps() {
            assert!(
                frame.timings.iter().any(|t| t.name == "visibility")
                    && !frame.timings.iter().any(|t| t.name == "gbuffer"),
                "drawn through the visibility buffer"
            );
        }
        let visible = frame.image;
        r.set_visibility(d, false).expect("hardware");
        let hardware = render(gpu, &mut r, &prepared);
        let db = pipeline::psnr(&hardware, &visible);
        let differ = hardware
            .pixels()
            .iter()
            .zip(visible.pixels())
            .filter(|(a, b)| (0..3).any(|c| (a[c] - b[c]).abs() > 1e-3))
            .count();
        println!(
            "level {level} {tessellation:?}: PSNR {db:.1} dB between the two paths, {differ} pixels differ"
        );
        // A pixel on an edge may go to the neighbouring triangle; the control mesh drawn in the
        // refined mesh's place (the path not rebound) differs in ~80 of these 6 912 pixels.
        assert!(
            db >= 40.0 && differ <= 20,
            "level {level}: PSNR {db:.1} dB, {differ} pixels differ"
        );
    }
}

/// Texture coordinates go through the positions' stencils, whose weights sum to one: on a flat
/// grid whose coordinates are an affine function of the position, every refined vertex keeps
/// that function (the limit surface of a plane is the plane; the same combination of control
/// values gives both).
#[test]
fn attributes_through_the_stencils_keep_an_affine_map() {
    let n = 6;
    let mut mesh = scene::Mesh {
        name: "grid".into(),
        material: 0,
        ..Default::default()
    };
    let uv_of = |p: Vec3| Vec2::new(0.3 * p.x + 0.1 * p.z + 0.2, -0.2 * p.x + 0.7 * p.z + 0.5);
    for j in 0..=n {
        for i in 0..=n {
            // A slightly irregular grid: the map still holds.
            let p = Vec3::new(
                i as f32 + 0.2 * ((i * j) % 3) as f32,
                0.0,
                j as f32 - 0.15 * ((i + 2 * j) % 2) as f32,
            );
            mesh.positions.push(p);
            mesh.normals.push(Vec3::Y);
            mesh.uvs.push(uv_of(p));
        }
    }
    for j in 0..n {
        for i in 0..n {
            let v = j * (n + 1) + i;
            mesh.indices
                .extend([v, v + n + 1, v + 1, v + 1, v + n + 1, v + n + 2].map(|k| k as u32));
        }
    }
    let mut scene = Scene::default();
    scene.materials.push(scene::Material::default());
    scene.meshes.push(mesh);
    let (prepared, plan) =
        subdivision::prepare(&scene, &[0], (3, Tessellation::Uniform), tables()).expect("prepared");
    assert_eq!(plan.level(), 3);
    let refined = &prepared.meshes[1];
    assert!(refined.positions.len() > 4 * scene.meshes[0].positions.len());
    let worst = refined
        .positions
        .iter()
        .zip(&refined.uvs)
        .map(|(&p, &uv)| (uv_of(p) - uv).abs().max_element())
        .fold(0.0f32, f32::max);
    assert!(worst < 1e-5, "largest deviation {worst}");
    assert!(
        refined.positions.iter().all(|p| p.y.abs() < 1e-6),
        "the limit surface of a plane is the plane"
    );
}

#[test]
fn bad_plans_are_refused_by_name() {
    let scene = scene::cornell_box();
    let e = subdivision::prepare(&scene, &[99], (2, Tessellation::Uniform), tables())
        .expect_err("no mesh 99");
    assert!(e.to_string().contains("mesh 99"), "{e}");
    let e = subdivision::prepare(&scene, &[0, 0], (2, Tessellation::Uniform), tables())
        .expect_err("twice");
    assert!(e.to_string().contains("twice"), "{e}");
    let e = subdivision::prepare(&scene, &[0], (9, Tessellation::Uniform), tables())
        .expect_err("level 9");
    assert!(e.to_string().contains("level"), "{e}");
}
