//! The CPU reference against independent results and its own invariants: OpenSubdiv's Hbr
//! baseline, limit normals, bad input.

mod common;

use std::path::PathBuf;

use common::*;
use glam::DVec3;
use subdiv_bft::{SubdivError, TriMesh, obj::ObjMesh};

fn opensubdiv() -> Option<PathBuf> {
    let dir = scene::shared_fixtures()?.join("subdiv/opensubdiv");
    dir.is_dir().then_some(dir)
}

/// Hbr's refined (not limit) positions after 1–3 steps equal ours as point sets. Shapes with
/// crease/corner tags or a boundary rule other than "edge only" are refused by the reader and
/// skipped here (named in the output).
#[test]
fn refined_positions_match_opensubdiv_hbr() {
    let Some(dir) = opensubdiv() else {
        eprintln!("skipping: ../shared/fixtures not found");
        return;
    };
    let mut compared = 0;
    for shape in [
        "loop_cube",
        "loop_icosahedron",
        "loop_saddle_edgeonly",
        "loop_triangle_edgeonly",
        "loop_cube_creases0",
    ] {
        let control = ObjMesh::read(&dir.join(format!("shapes/{shape}.obj"))).expect("shape");
        let mesh = match control.into_mesh() {
            Ok(m) => m,
            Err(e) => {
                eprintln!("{shape}: skipped ({e})");
                continue;
            }
        };
        for level in 0..3 {
            let expected =
                ObjMesh::read(&dir.join(format!("hbr_baseline/{shape}_level{level}.obj")))
                    .expect("baseline");
            let ours = mesh.subdivide(level + 1).expect("subdivide");
            assert_eq!(
                ours.positions.len(),
                expected.positions.len(),
                "{shape} level {level}: vertex count"
            );
            assert_eq!(
                ours.topology.triangles.len(),
                expected.triangles.len(),
                "{shape} level {level}: triangle count"
            );
            let e = max_nearest(&ours.positions, &expected.positions)
                .max(max_nearest(&expected.positions, &ours.positions));
            // Hbr writes 9 significant digits.
            assert!(
                e < 1e-6 * mesh.diagonal(),
                "{shape} level {level}: point sets differ by {e:e}"
            );
            compared += 1;
        }
    }
    assert_eq!(
        compared, 9,
        "loop_cube, loop_icosahedron, loop_saddle_edgeonly at three levels"
    );
}

/// The limit normal is the same whatever level it is computed from, and agrees with the
/// normals of the finely subdivided surface around the vertex.
#[test]
fn limit_normals_are_consistent_across_levels() {
    for mesh in [
        bipyramid(5),
        disk(7),
        half_disk(1),
        half_disk(2),
        half_disk(5),
    ] {
        let n0 = mesh.limit_normals();
        let fine = mesh.subdivide(5).expect("subdivide");
        let nk = fine.limit_normals();
        let limit = fine.limit_positions();
        for v in 0..mesh.positions.len() {
            let d = n0[v].dot(nk[v]);
            assert!(
                d > 1.0 - 1e-9,
                "vertex {v}: normal at level 0 {} vs level 5 {}",
                n0[v],
                nk[v]
            );
            // Face normals of the limit-projected fine triangles around the vertex.
            let fan = fine.topology.fan(v as u32);
            let mut avg = DVec3::ZERO;
            let tris = fan.ring.len() - usize::from(fan.boundary);
            for j in 0..tris {
                let (a, b) = (fan.ring[j], fan.ring[(j + 1) % fan.ring.len()]);
                avg += (limit[a as usize] - limit[v])
                    .cross(limit[b as usize] - limit[v])
                    .normalize();
            }
            let cos = avg.normalize().dot(n0[v]);
            assert!(
                cos > 0.995,
                "vertex {v}: limit normal {} vs fine surface {}",
                n0[v],
                avg.normalize()
            );
        }
    }
}

#[test]
fn bad_input_is_an_error() {
    let p = vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z, DVec3::ONE];
    // Three triangles on one edge.
    let e = TriMesh::new(p.clone(), vec![[0, 1, 2], [1, 0, 3], [0, 1, 4]]);
    assert!(
        matches!(e, Err(SubdivError::NonManifoldEdge { .. })),
        "{e:?}"
    );
    // Inconsistent orientation.
    let e = TriMesh::new(p.clone(), vec![[0, 1, 2], [0, 1, 3]]);
    assert!(
        matches!(e, Err(SubdivError::NonManifoldEdge { .. })),
        "{e:?}"
    );
    // Two fans meeting at one vertex (bow tie).
    let mut q = p.clone();
    q.extend([DVec3::NEG_X, DVec3::NEG_Y]);
    let e = TriMesh::new(q, vec![[0, 1, 2], [0, 5, 6]]);
    assert!(
        matches!(e, Err(SubdivError::NonManifoldVertex { vertex: 0 })),
        "{e:?}"
    );
    // Degenerate, out of range, NaN.
    assert!(matches!(
        TriMesh::new(p.clone(), vec![[0, 0, 1]]),
        Err(SubdivError::Degenerate { .. })
    ));
    assert!(matches!(
        TriMesh::new(p.clone(), vec![[0, 1, 9]]),
        Err(SubdivError::IndexOutOfRange { .. })
    ));
    let mut nan = p.clone();
    nan[2].x = f64::NAN;
    assert!(matches!(
        TriMesh::new(nan, vec![[0, 1, 2]]),
        Err(SubdivError::NonFinite { vertex: 2 })
    ));
    // Garbage OBJ.
    assert!(ObjMesh::parse("v 1 2\n").is_err());
    assert!(ObjMesh::parse("v 0 0 0\nf 1 2 3\n").is_err());
    assert!(
        ObjMesh::parse("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nt crease 2/1/0 0 1 2.0\n")
            .expect("parses")
            .into_mesh()
            .is_err()
    );
}

/// A valence beyond the tables is an error naming it, not a panic.
#[test]
fn valence_beyond_tables_is_an_error() {
    let bft = subdiv_bft::BftSet::build(2, 8).expect("small tables");
    let e = subdiv_bft::Subdivider::new(&bipyramid(9).topology, &bft);
    assert!(
        matches!(e, Err(SubdivError::NoTable { valence: 9, .. })),
        "{:?}",
        e.err()
    );
}

/// MeshLab's Loop subdivision (checked against trimesh when generated; `cargo xtask
/// subdiv-fixtures`) of the shared closed meshes equals ours as point sets.
#[test]
fn refined_positions_match_meshlab_on_larger_meshes() {
    let Some(shared) = scene::shared_fixtures() else {
        eprintln!("skipping: ../shared/fixtures not found");
        return;
    };
    let ours_dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/subdiv");
    for (name, file, level) in [
        ("spot", "subdiv/spot/spot_triangulated.obj", 1),
        ("spot", "subdiv/spot/spot_triangulated.obj", 2),
        ("fandisk", "subdiv/fandisk.obj", 1),
    ] {
        let mesh = ObjMesh::read(&shared.join(file))
            .expect("mesh")
            .into_mesh()
            .expect("valid");
        let bytes =
            std::fs::read(ours_dir.join(format!("{name}_loop{level}.f32"))).expect("expected file");
        let expected: Vec<DVec3> = bytes
            .chunks_exact(12)
            .map(|c| {
                let f =
                    |k: usize| f64::from(f32::from_le_bytes([c[k], c[k + 1], c[k + 2], c[k + 3]]));
                DVec3::new(f(0), f(4), f(8))
            })
            .collect();
        let ours = mesh.subdivide(level).expect("subdivide");
        assert_eq!(
            ours.positions.len(),
            expected.len(),
            "{name} level {level}: vertex count"
        );
        let e =
            max_nearest(&ours.positions, &expected).max(max_nearest(&expected, &ours.positions));
        // The expected positions are stored as f32.
        assert!(
            e < 1e-6 * mesh.diagonal(),
            "{name} level {level}: point sets differ by {e:e}"
        );
    }
}

#[test]
fn table_file_round_trip_and_errors() {
    let set = subdiv_bft::BftSet::build(2, 7).expect("tables");
    let bytes = set.to_bytes();
    assert_eq!(
        subdiv_bft::BftSet::from_bytes(&bytes).expect("reads back"),
        set
    );
    for cut in [0, 7, 20, bytes.len() - 1] {
        assert!(
            subdiv_bft::BftSet::from_bytes(&bytes[..cut]).is_err(),
            "truncated at {cut}"
        );
    }
    let mut wrong_version = bytes.clone();
    wrong_version[8] = 9;
    let e = subdiv_bft::BftSet::from_bytes(&wrong_version).expect_err("version");
    assert!(e.to_string().contains("version"), "{e}");
}
