//! OpenSubdiv's Loop refinement against ours, as the `peers-gpu` benchmark compares them, with
//! its bound asserted: 1e-5 of the bounding-box diagonal.

use glam::{DVec3, Vec3};
use peers::opensubdiv::{GpuEvaluator, Refinement};
use subdiv_bft::{BftSet, DEFAULT_LEVEL, MAX_VALENCE, Subdivider, TriMesh, obj::ObjMesh};

/// The comparison's tolerance, a fraction of the diagonal.
const TOLERANCE: f64 = 1e-5;

fn spot() -> Option<TriMesh> {
    let Some(fixtures) = scene::shared_fixtures() else {
        eprintln!("skipping: ../shared/fixtures not found");
        return None;
    };
    let obj = ObjMesh::read(&fixtures.join("subdiv/spot/spot_triangulated.obj")).expect("spot");
    Some(obj.into_mesh().expect("spot mesh"))
}

/// OpenSubdiv's refined vertices are our recursive reference's, as point sets; its level
/// projected to the limit is our basis-function tables' output.
#[test]
fn opensubdiv_refines_as_our_reference_and_tables() {
    let Some(mesh) = spot() else { return };
    let d = mesh.diagonal();
    let control: Vec<[f32; 3]> = mesh.positions_f32().iter().map(|p| p.to_array()).collect();
    let bft = BftSet::cached(
        &BftSet::default_path(DEFAULT_LEVEL, MAX_VALENCE),
        DEFAULT_LEVEL,
        MAX_VALENCE,
    )
    .expect("tables");
    let sub = Subdivider::new(&mesh.topology, &bft).expect("subdivider");
    for level in 1..=2 {
        let osd = Refinement::new(&mesh, level).expect("OpenSubdiv");
        let refined = peers::dvec3s(&osd.evaluate_cpu(&control).expect("evaluate"));
        let triangles = osd.triangles().expect("triangles");
        let reference = mesh.subdivide(level).expect("reference");
        assert_eq!(
            refined.len(),
            reference.positions.len(),
            "level {level}: vertices"
        );
        assert_eq!(
            triangles.len(),
            3 * reference.topology.triangles.len(),
            "level {level}: triangles"
        );
        let e = peers::hausdorff(&refined, &reference.positions, 1e-3 * d) / d;
        assert!(
            e <= TOLERANCE,
            "level {level}: OpenSubdiv vs reference {e:e}"
        );
        let osd_mesh = TriMesh::new(
            refined,
            triangles
                .chunks_exact(3)
                .map(|t| [t[0], t[1], t[2]])
                .collect(),
        )
        .expect("OpenSubdiv's level");
        let ours = sub
            .evaluate_cpu(&bft, &mesh.positions_f32(), level)
            .expect("tables");
        let ours: Vec<DVec3> = ours.positions.iter().map(|p| p.as_dvec3()).collect();
        let e = peers::hausdorff(&osd_mesh.limit_positions(), &ours, 1e-3 * d) / d;
        assert!(e <= TOLERANCE, "level {level}: limit vs tables {e:e}");
    }
    // A wrong refinement is seen: one level off.
    let osd = Refinement::new(&mesh, 1).expect("OpenSubdiv");
    let refined = peers::dvec3s(&osd.evaluate_cpu(&control).expect("evaluate"));
    let two = mesh.subdivide(2).expect("reference");
    assert!(peers::hausdorff(&refined, &two.positions, 1e-3 * d) / d > TOLERANCE);
}

/// OpenSubdiv's GPU evaluator (wgpu 29, the toolkit's adapter) gives its CPU evaluator's
/// positions, in one dispatch or in batches, and its timing bracket measures something.
#[test]
fn opensubdiv_gpu_evaluator_matches_its_cpu_evaluator() {
    let Some(mesh) = spot() else { return };
    let Some(gpu) = gpu::test_device(&Default::default()) else {
        return;
    };
    let evaluator = match GpuEvaluator::new(&gpu.info.name) {
        Ok(e) => e,
        Err(e) if std::env::var_os("CI").is_some() => panic!("{e:#}"),
        Err(e) => return eprintln!("skipping: {e:#}"),
    };
    let control: Vec<[f32; 3]> = mesh.positions_f32().iter().map(|p| p.to_array()).collect();
    let osd = Refinement::new(&mesh, 2).expect("OpenSubdiv");
    let cpu = osd.evaluate_cpu(&control).expect("CPU");
    let bound = evaluator.bind(&osd, &control).expect("bind");
    let ms = evaluator.evaluate(&bound).expect("evaluate");
    assert!(ms > 0.0, "GPU time {ms}");
    let gpu = evaluator.read(&bound).expect("read");
    assert_eq!(gpu.len(), cpu.len());
    let d = mesh.diagonal();
    let worst = gpu
        .iter()
        .zip(&cpu)
        .map(|(g, c)| {
            Vec3::from(*g)
                .as_dvec3()
                .distance(Vec3::from(*c).as_dvec3())
        })
        .fold(0.0, f64::max);
    assert!(worst / d <= 1e-6, "GPU vs CPU {:e}", worst / d);
    // In batches (as tables past 4.2 M stencils run): the same positions, bit for bit.
    evaluator
        .evaluate_in_batches(&bound, 1000)
        .expect("batches");
    assert_eq!(evaluator.read(&bound).expect("read"), gpu);
    assert!(evaluator.evaluate_in_batches(&bound, 0).is_err());
}
