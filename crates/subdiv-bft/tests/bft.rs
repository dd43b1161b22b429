//! BFT evaluation == recursive subdivision + limit projection (the paper's invariant).

mod common;

use common::*;
use glam::DVec3;
use subdiv_bft::{Subdivider, TriMesh};

/// Maximum distance (relative to the bounding-box diagonal) between the BFT evaluation at
/// `level` and recursive subdivision to `level` followed by limit projection, as point sets,
/// with equal vertex counts.
fn bft_error(mesh: &TriMesh, level: u32) -> f64 {
    let bft = tables();
    let sub = Subdivider::new(&mesh.topology, bft).expect("subdivider");
    let out = sub
        .evaluate_cpu(bft, &mesh.positions_f32(), level)
        .expect("evaluate");
    let rec = mesh.subdivide(level).expect("recursive");
    let limit = rec.limit_positions();
    assert_eq!(out.positions.len(), limit.len(), "vertex count");
    assert_eq!(
        out.indices.len(),
        rec.topology.triangles.len() * 3,
        "triangle count"
    );
    let bft_points: Vec<DVec3> = out.positions.iter().map(|p| p.as_dvec3()).collect();
    max_nearest(&bft_points, &limit).max(max_nearest(&limit, &bft_points)) / mesh.diagonal()
}

#[test]
fn closed_valences_3_to_18() {
    for n in 3..=18 {
        for level in [1, 3, 5] {
            let e = bft_error(&bipyramid(n), level);
            assert!(
                e <= 1e-5,
                "bipyramid valence {n} level {level}: error {e:e}"
            );
        }
    }
}

#[test]
fn boundaries_valences_3_to_18() {
    for n in 3..=18 {
        for level in [2, 4] {
            let e = bft_error(&disk(n), level);
            assert!(e <= 1e-5, "disk valence {n} level {level}: error {e:e}");
        }
    }
    for faces in 1..=17 {
        for level in [2, 5] {
            let e = bft_error(&half_disk(faces), level);
            assert!(
                e <= 1e-5,
                "half disk with {faces} faces level {level}: error {e:e}"
            );
        }
    }
}
