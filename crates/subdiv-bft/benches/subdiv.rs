//! CPU reference benches: recursive Loop subdivision, one table's construction from its
//! configuration mesh, and the CPU mirror of the BFT evaluation (fandisk or a bipyramid when
//! the shared fixtures are absent).

#![allow(missing_docs)] // criterion_group! generates an undocumented function

use criterion::{Criterion, criterion_group, criterion_main};
use subdiv_bft::{BftSet, Corner, Subdivider, TriMesh, bft::build_table, obj::ObjMesh};

fn control_mesh() -> TriMesh {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/fixtures/subdiv/fandisk.obj");
    match ObjMesh::read(&path).and_then(ObjMesh::into_mesh) {
        Ok(m) => m,
        Err(_) => TriMesh::from_f32(
            &[
                [0.0, 0.0, 1.0],
                [0.0, 0.0, -1.0],
                [1.0, 0.0, 0.0],
                [0.0, 1.0, 0.0],
                [-1.0, 0.0, 0.0],
                [0.0, -1.0, 0.0],
            ],
            &[
                0, 2, 3, 0, 3, 4, 0, 4, 5, 0, 5, 2, 1, 3, 2, 1, 4, 3, 1, 5, 4, 1, 2, 5,
            ],
        )
        .expect("octahedron"),
    }
}

fn bench(c: &mut Criterion) {
    let mesh = control_mesh();
    let bft = BftSet::build(4, 18).expect("tables");
    let sub = Subdivider::new(&mesh.topology, &bft).expect("subdivider");
    let p = mesh.positions_f32();
    c.bench_function("recursive Loop, 3 levels", |b| {
        b.iter(|| mesh.subdivide(3).expect("subdivide"))
    });
    c.bench_function("BFT evaluation (CPU mirror), level 3", |b| {
        b.iter(|| sub.evaluate_cpu(&bft, &p, 3).expect("evaluate"))
    });
    c.bench_function("table construction, valence 7, level 5", |b| {
        b.iter(|| {
            build_table(
                [
                    Corner::Interior(7),
                    Corner::Interior(6),
                    Corner::Interior(6),
                ],
                5,
            )
            .expect("table")
        })
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
