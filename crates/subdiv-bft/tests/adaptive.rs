//! Adaptive tessellation (§2.2.3 "Adaptive Refinement"): the snapped triangulation tiles each
//! patch, the output is a crack-free manifold for any factors, integer factors give the uniform
//! tessellation, geomorph starts on the coarser mesh, CPU == GPU.

mod common;

use common::*;
use glam::{DVec3, Mat4, Vec3};
use subdiv_bft::{
    Refined, Subdivider, TriMesh,
    adaptive::{PatchLevels, ScreenView, screen_factors},
    gpu::GpuSubdivider,
};

/// Deterministic factors in `[0, max]`, some integer, some fractional.
fn factors(n: usize, max: f32, seed: u32) -> Vec<f32> {
    let mut x = seed.wrapping_mul(2_654_435_761).max(1);
    (0..n)
        .map(|i| {
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            let f = (x % 10_000) as f32 / 10_000.0 * max;
            if i % 3 == 0 { f.round() } else { f }
        })
        .collect()
}

fn manifold(name: &str, out: &Refined) -> TriMesh {
    let clean = out.without_collapsed();
    TriMesh::new(
        clean.positions.iter().map(|p| p.as_dvec3()).collect(),
        clean
            .indices
            .chunks_exact(3)
            .map(|t| [t[0], t[1], t[2]])
            .collect(),
    )
    .unwrap_or_else(|e| panic!("{name}: adaptive output is not a manifold: {e}"))
}

fn boundary_edges(m: &TriMesh) -> usize {
    m.topology.twin.iter().filter(|&&t| t == u32::MAX).count()
}

/// Every combination of edge segments: the non-collapsed triangles have positive area, add up
/// to the patch, and their outline along edge k has exactly that edge's segments.
#[test]
fn snapped_triangulation_tiles_the_patch() {
    let max = 16u32;
    for a in 0..=4 {
        for b in 0..=4 {
            for c in 0..=4 {
                let l = PatchLevels::new([a, b, c].map(|f| f as f32), max);
                let s = l.segments as i64;
                assert_eq!(s, 1 << a.max(b).max(c));
                let mut area = 0;
                let mut directed = std::collections::HashSet::new();
                let tris = l.triangles();
                assert_eq!(tris.len() as i64, s * s);
                for t in tris {
                    if t[0] == t[1] || t[1] == t[2] || t[2] == t[0] {
                        continue;
                    }
                    let [p, q, r] = t.map(|(i, j)| (i as i64, j as i64));
                    let doubled = (q.0 - p.0) * (r.1 - p.1) - (q.1 - p.1) * (r.0 - p.0);
                    assert!(
                        doubled > 0,
                        "levels {a} {b} {c}: triangle {t:?} area {doubled}"
                    );
                    area += doubled;
                    for v in t {
                        assert!(l.is_vertex(v), "{v:?} is snapped away but used");
                    }
                    for e in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
                        assert!(directed.insert(e), "edge {e:?} used twice");
                    }
                }
                assert_eq!(area, s * s, "levels {a} {b} {c}: area");
                let mut outline = [0u32; 3];
                for &(u, v) in &directed {
                    if !directed.contains(&(v, u)) {
                        let on = |k: usize, (i, j): (u32, u32)| match k {
                            0 => j == 0,
                            1 => i + j == l.segments,
                            _ => i == 0,
                        };
                        let k = (0..3)
                            .find(|&k| on(k, u) && on(k, v))
                            .unwrap_or_else(|| panic!("outline edge {u:?}–{v:?} inside the patch"));
                        outline[k] += 1;
                    }
                }
                assert_eq!(outline, l.edge_segments, "levels {a} {b} {c}: outline");
            }
        }
    }
}

/// Random per-edge factors: the output of a closed mesh is a closed manifold with the control
/// mesh's Euler characteristic, an open one keeps exactly its edges' boundary segments.
#[test]
fn any_factors_give_a_crack_free_manifold() {
    let bft = tables();
    let max_level = bft.level + 1;
    for (name, mesh) in [
        ("bipyramid 5", bipyramid(5)),
        ("bipyramid 12", bipyramid(12)),
        ("disk 7", disk(7)),
        ("half disk 3", half_disk(3)),
    ] {
        let sub = Subdivider::new(&mesh.topology, bft).expect("subdivider");
        for seed in 1..=4 {
            let f = factors(sub.m1.edges.len(), max_level as f32, seed);
            let out = sub
                .evaluate_adaptive_cpu(bft, &mesh.positions_f32(), &f, max_level)
                .expect("adaptive");
            let fine = manifold(name, &out);
            let (v, t) = (
                fine.topology.vertex_count() as i64,
                fine.topology.triangles.len() as i64,
            );
            let e = fine.topology.edges.len() as i64;
            let (v0, t0) = (
                mesh.topology.vertex_count() as i64,
                mesh.topology.triangles.len() as i64,
            );
            let e0 = mesh.topology.edges.len() as i64;
            assert_eq!(
                v - e + t,
                v0 - e0 + t0,
                "{name} seed {seed}: Euler characteristic"
            );
            let s_max = 1 << (max_level - 1);
            let want: usize = sub
                .m1
                .edges
                .iter()
                .enumerate()
                .filter(|&(_, &h)| sub.m1.twin[h as usize] == u32::MAX)
                .map(|(k, _)| subdiv_bft::adaptive::split_factor(f[k], s_max).0 as usize)
                .sum();
            assert_eq!(boundary_edges(&fine), want, "{name} seed {seed}: boundary");
        }
    }
}

/// The adaptive tessellation of `mesh` with factors `f` (collapsed triangles dropped) and the
/// uniform one at `level`, both on the CPU.
fn adaptive_and_uniform(
    sub: &Subdivider,
    mesh: &TriMesh,
    f: &[f32],
    level: u32,
) -> (Refined, Refined) {
    let bft = tables();
    let adaptive = sub
        .evaluate_adaptive_cpu(bft, &mesh.positions_f32(), f, bft.level + 1)
        .expect("adaptive")
        .without_collapsed();
    let uniform = sub
        .evaluate_cpu(bft, &mesh.positions_f32(), level)
        .expect("uniform");
    (adaptive, uniform)
}

/// Integer factors n everywhere are the uniform tessellation at level n + 1 (same points, same
/// triangle count); with mixed factors every vertex still lies on the limit surface where no
/// geomorph is under way.
#[test]
fn integer_factors_equal_uniform_tessellation() {
    let bft = tables();
    let mesh = bipyramid(7);
    let sub = Subdivider::new(&mesh.topology, bft).expect("subdivider");
    for n in 0..=bft.level {
        let f = vec![n as f32; sub.m1.edges.len()];
        let (adaptive, uniform) = adaptive_and_uniform(&sub, &mesh, &f, n + 1);
        assert_eq!(adaptive.indices.len(), uniform.indices.len(), "level {n}");
        assert_eq!(
            adaptive.positions.len(),
            uniform.positions.len(),
            "level {n}"
        );
        let a: Vec<DVec3> = adaptive.positions.iter().map(|p| p.as_dvec3()).collect();
        let u: Vec<DVec3> = uniform.positions.iter().map(|p| p.as_dvec3()).collect();
        assert!(
            max_nearest(&a, &u) <= 1e-6 * mesh.diagonal(),
            "level {n}: points"
        );
    }
}

/// Geomorph: just above an integer factor n every new vertex sits on the level-(n + 1) mesh, at
/// the midpoint of one of its edges (the surface does not pop when a factor crosses n).
#[test]
fn geomorph_starts_on_the_coarser_mesh() {
    let bft = tables();
    let mesh = bipyramid(6);
    let sub = Subdivider::new(&mesh.topology, bft).expect("subdivider");
    for n in 1..bft.level {
        let f = vec![n as f32 + 1e-5; sub.m1.edges.len()];
        let (morphed, coarse) = adaptive_and_uniform(&sub, &mesh, &f, n + 1);
        let mut targets: Vec<DVec3> = coarse.positions.iter().map(|p| p.as_dvec3()).collect();
        for t in coarse.indices.chunks_exact(3) {
            for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
                targets.push(
                    0.5 * (coarse.positions[a as usize] + coarse.positions[b as usize]).as_dvec3(),
                );
            }
        }
        let got: Vec<DVec3> = morphed.positions.iter().map(|p| p.as_dvec3()).collect();
        assert_eq!(
            got.len(),
            4 * coarse.positions.len() - 6,
            "level {n}: closed mesh V"
        );
        let err = max_nearest(&got, &targets);
        assert!(
            err <= 1e-4 * mesh.diagonal(),
            "level {n}: morph start {err:e}"
        );
    }
}

#[test]
fn bad_factors_are_errors() {
    let bft = tables();
    let mesh = bipyramid(4);
    let sub = Subdivider::new(&mesh.topology, bft).expect("subdivider");
    let p = mesh.positions_f32();
    let n = sub.m1.edges.len();
    assert!(
        sub.evaluate_adaptive_cpu(bft, &p, &vec![1.0; n - 1], 3)
            .is_err()
    );
    let mut f = vec![1.0; n];
    f[3] = f32::NAN;
    let err = sub.evaluate_adaptive_cpu(bft, &p, &f, 3).unwrap_err();
    assert!(err.to_string().contains("edge 3"), "{err}");
    assert!(
        sub.evaluate_adaptive_cpu(bft, &p, &vec![1.0; n], 0)
            .is_err()
    );
}

/// The metric on a known projection: identity view-projection, a 200×100 viewport; an edge of
/// 0.5 NDC along x is 50 pixels.
#[test]
fn screen_factors_measure_pixels() {
    let m = TriMesh::from_f32(
        &[[0.0, 0.0, 0.5], [0.5, 0.0, 0.5], [0.0, 0.5, 0.5]],
        &[0, 1, 2],
    )
    .expect("triangle");
    let p = m.positions_f32();
    let view = |view_proj| ScreenView {
        view_proj,
        viewport: (200, 100),
        target_pixels: 5.0,
    };
    let f = screen_factors(&m.topology, &p, &view(Mat4::IDENTITY), 32);
    let mut want: Vec<f32> = m
        .topology
        .edges
        .iter()
        .map(|&h| {
            let (a, b) = (
                p[m.topology.origin(h) as usize],
                p[m.topology.dest(h) as usize],
            );
            let d = (a - b).truncate() * glam::Vec2::new(100.0, 50.0);
            (d.length() / 5.0).log2()
        })
        .collect();
    want.sort_by(f32::total_cmp);
    let mut got = f.clone();
    got.sort_by(f32::total_cmp);
    // 50 px along x, 25 px along y, √(50² + 25²) on the diagonal.
    assert!(
        (want[0] - 5f32.log2()).abs() < 1e-6 && (want[2] - (55.9017f32 / 5.0).log2()).abs() < 1e-4
    );
    for (g, w) in got.iter().zip(&want) {
        assert!((g - w).abs() < 1e-5, "{got:?} vs {want:?}");
    }
    let behind = Mat4::from_cols_array(&[
        1., 0., 0., 0., 0., 1., 0., 0., 0., 0., 1., -1., 0., 0., 0., 0.,
    ]);
    let all_behind = screen_factors(&m.topology, &p, &view(behind), 32);
    assert_eq!(all_behind, vec![0.0; 3], "w < 0 everywhere");
}

fn triangle_set(indices: &[u32]) -> Vec<[u32; 3]> {
    let mut v: Vec<[u32; 3]> = indices
        .chunks_exact(3)
        .map(|t| {
            let r = (0..3).min_by_key(|&k| t[k]).unwrap_or(0);
            [t[r], t[(r + 1) % 3], t[(r + 2) % 3]]
        })
        .collect();
    v.sort_unstable();
    v
}

/// GPU adaptive main step == CPU for factors from `seeds` up to `max_level`: the same triangles
/// (as sets; workgroups append in any order), the same vertices where triangles use them.
/// Returns the finest patch segments any seed used.
fn adaptive_matches_cpu(
    gpu: &gpu::Gpu,
    bft: &subdiv_bft::bft::BftSet,
    name: &str,
    mesh: &TriMesh,
    max_level: u32,
    seeds: std::ops::RangeInclusive<u32>,
) -> (Subdivider, GpuSubdivider, subdiv_bft::gpu::GpuAdaptive, u32) {
    let sub = Subdivider::new(&mesh.topology, bft).expect("subdivider");
    let g = GpuSubdivider::new(&gpu.device, &sub, bft).expect("gpu");
    let a = g.adaptive(&gpu.device, &sub, max_level).expect("adaptive");
    g.set_positions(&gpu.queue, &mesh.positions_f32())
        .expect("positions");
    let tol = (1e-5 * mesh.diagonal()) as f32;
    let s_max = 1 << (max_level - 1);
    let mut finest = 0;
    for seed in seeds {
        let f = factors(sub.m1.edges.len(), max_level as f32, seed);
        a.set_factors(&gpu.queue, &f).expect("factors");
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        g.encode_initial(&mut encoder, None);
        g.encode_adaptive(&mut encoder, &a, None);
        gpu.queue.submit([encoder.finish()]);
        let got = g.read_adaptive(&gpu.device, &gpu.queue, &a).expect("read");
        let (p1, n1) = g.read_m1(&gpu.device, &gpu.queue).expect("M1");
        let (cp, cn) = sub.patches.evaluate_adaptive(bft, &f, s_max, &p1, &n1);
        let want = sub.patches.triangulate_adaptive(&f, s_max);
        assert_eq!(
            triangle_set(&got.indices),
            triangle_set(&want),
            "{name} seed {seed}: triangles"
        );
        for &v in &want {
            let v = v as usize;
            let d = cp[v].distance(got.positions[v]);
            assert!(
                d <= tol,
                "{name} seed {seed}: vertex {v} CPU {} GPU {}",
                cp[v],
                got.positions[v]
            );
            let c = 1.0 - cn[v].dot(got.normals[v]);
            assert!(
                c <= 1e-5,
                "{name} seed {seed}: normal {v} CPU {} GPU {}",
                cn[v],
                got.normals[v]
            );
        }
        let levels =
            (0..sub.patches.patches.len()).map(|p| sub.patches.patch_levels(p, &f, s_max).segments);
        finest = finest.max(levels.max().unwrap_or(0));
    }
    (sub, g, a, finest)
}

/// CPU == GPU: the adaptive main step (above), and the factors of the GPU metric == the CPU
/// metric's.
#[test]
fn adaptive_cpu_equals_gpu() {
    let Some(gpu) = gpu::test_device(&subdiv_bft::adaptive_device_needs()) else {
        return;
    };
    let bft = tables();
    let max_level = bft.level + 1;
    for (name, mesh) in [("bipyramid 9", bipyramid(9)), ("half disk 5", half_disk(5))] {
        let (sub, g, a, _) = adaptive_matches_cpu(gpu, bft, name, &mesh, max_level, 1..=3);
        // The metric on the GPU.
        let view_proj = scene::Camera::look_at(Vec3::new(0.5, 0.8, 4.0), Vec3::ZERO)
            .view_projection(640.0 / 480.0);
        let view = ScreenView {
            view_proj,
            viewport: (640, 480),
            target_pixels: 4.0,
        };
        a.set_view(&gpu.queue, &view).expect("view");
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        g.encode_initial(&mut encoder, None);
        g.encode_screen_factors(&mut encoder, &a, None);
        gpu.queue.submit([encoder.finish()]);
        let (p1, _) = g.read_m1(&gpu.device, &gpu.queue).expect("M1");
        let want = screen_factors(&sub.m1, &p1, &view, 1 << (max_level - 1));
        let got = g
            .read_factors(&gpu.device, &gpu.queue, &a)
            .expect("factors");
        assert!(
            want.iter().any(|&f| f > 0.5 && f < max_level as f32 - 1.0),
            "{want:?}"
        );
        for (e, (w, f)) in want.iter().zip(&got).enumerate() {
            assert!((w - f).abs() <= 1e-4, "{name}: edge {e}: CPU {w} GPU {f}");
        }
    }
}

/// A patch of 32 segments (561 grid vertices, 1 024 triangles) spreads over several workgroups
/// of the GPU kernel, each a chunk of its vertices and triangles: CPU == GPU still, with
/// level-5 tables.
#[test]
fn fine_patches_span_several_workgroups() {
    let Some(gpu) = gpu::test_device(&subdiv_bft::adaptive_device_needs()) else {
        return;
    };
    let bft = subdiv_bft::bft::BftSet::build(5, 9).expect("level-5 tables");
    let (.., finest) = adaptive_matches_cpu(gpu, &bft, "bipyramid 7", &bipyramid(7), 6, 4..=5);
    assert_eq!(finest, 32, "no patch reached 32 segments");
}

/// 40 960 patches of up to 2 chunks: more workgroups than one row of a dispatch holds
/// (`Workgroups::linear`, 32 768), so the kernel's workgroup index spans rows; CPU == GPU still.
#[test]
fn many_patches_span_several_rows_of_workgroups() {
    let Some(gpu) = gpu::test_device(&subdiv_bft::adaptive_device_needs()) else {
        return;
    };
    let bft = tables();
    let mesh = torus(80, 64);
    assert_eq!(mesh.topology.triangles.len() * 4, 40_960);
    let (.., finest) = adaptive_matches_cpu(gpu, bft, "torus", &mesh, bft.level + 1, 6..=6);
    assert_eq!(finest, 16, "no patch reached 16 segments (two chunks)");
}
