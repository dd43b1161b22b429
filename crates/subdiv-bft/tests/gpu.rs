//! CPU == GPU for the initial step and the main step; crack-free output; animation.

mod common;

use common::*;
use glam::{DVec3, Vec3};
use subdiv_bft::{Refined, Subdivider, TriMesh, gpu::GpuSubdivider, patch::padded_weights};

fn meshes() -> Vec<(String, TriMesh)> {
    let mut v: Vec<(String, TriMesh)> = [3, 5, 6, 7, 12, 18]
        .into_iter()
        .map(|n| (format!("bipyramid {n}"), bipyramid(n)))
        .collect();
    v.push(("disk 9".into(), disk(9)));
    v.push(("half disk 4".into(), half_disk(4)));
    v.push(("half disk 1".into(), half_disk(1)));
    v
}

/// Position tolerance: 1e-5 of the bounding-box diagonal (f32 sums of ≤ 24 terms, GPU
/// sin/cos and possible fused multiply-adds).
const POSITION_TOLERANCE: f64 = 1e-5;
/// Normal tolerance: 1 − cos(angle).
const NORMAL_TOLERANCE: f32 = 1e-5;

fn compare(what: &str, cpu: &[Vec3], gpu: &[Vec3], tolerance: f32, normals: bool) {
    assert_eq!(cpu.len(), gpu.len(), "{what}: counts");
    for (i, (c, g)) in cpu.iter().zip(gpu).enumerate() {
        let err = if normals {
            1.0 - c.dot(*g)
        } else {
            c.distance(*g)
        };
        assert!(
            err <= tolerance,
            "{what}: vertex {i}: CPU {c} GPU {g} (error {err:e} > {tolerance:e})"
        );
    }
}

/// [`compare`] of two levels' positions within [`POSITION_TOLERANCE`] of `mesh`'s diagonal.
fn compare_positions(what: &str, mesh: &TriMesh, cpu: &Refined, gpu: &Refined) {
    let tolerance = (POSITION_TOLERANCE * mesh.diagonal()) as f32;
    compare(what, &cpu.positions, &gpu.positions, tolerance, false);
}

#[test]
fn initial_and_main_step_cpu_equals_gpu() {
    let Some(gpu) = gpu::test_device(&subdiv_bft::device_needs()) else {
        return;
    };
    let bft = tables();
    let mut slots = std::collections::BTreeSet::new();
    for (name, mesh) in meshes() {
        let sub = Subdivider::new(&mesh.topology, bft).expect("subdivider");
        let diag = mesh.diagonal();
        let tol = (POSITION_TOLERANCE * diag) as f32;
        let g = GpuSubdivider::new(&gpu.device, &sub, bft).expect("gpu");
        g.set_positions(&gpu.queue, &mesh.positions_f32())
            .expect("positions");
        for level in 1..=bft.level + 1 {
            let out = g.level(&gpu.device, &sub, level).expect("level");
            let mut encoder = gpu.device.create_command_encoder(&Default::default());
            g.encode(&mut encoder, &out, None);
            gpu.queue.submit([encoder.finish()]);
            let (p1, n1) = g.read_m1(&gpu.device, &gpu.queue).expect("read M1");
            let (cp1, cn1) = sub.initial_step(&mesh.positions).expect("initial step");
            let cp1: Vec<Vec3> = cp1.iter().map(|p| p.as_vec3()).collect();
            let cn1: Vec<Vec3> = cn1.iter().map(|p| p.as_vec3()).collect();
            compare(&format!("{name}: M1 positions"), &cp1, &p1, tol, false);
            compare(
                &format!("{name}: M1 normals"),
                &cn1,
                &n1,
                NORMAL_TOLERANCE,
                true,
            );
            let got = g
                .read_level(&gpu.device, &gpu.queue, &out)
                .expect("read level");
            // Main step from the GPU's own M¹ (so only the evaluation is compared).
            let s = sub.segments(level).expect("segments");
            slots.insert(subdiv_bft::gpu::patch_slots(s));
            let (cp, cn) = sub.patches.evaluate(bft, s, &p1, &n1);
            compare(
                &format!("{name} level {level}: positions"),
                &cp,
                &got.positions,
                tol,
                false,
            );
            compare(
                &format!("{name} level {level}: normals"),
                &cn,
                &got.normals,
                NORMAL_TOLERANCE,
                true,
            );
            assert_eq!(got.indices, sub.patches.triangulate(s), "{name}: indices");
        }
    }
    // Both kernels: several patches per workgroup (levels 1–3) and one.
    assert_eq!(slots.into_iter().collect::<Vec<_>>(), [1, 4]);
}

/// Crack-free: shared edges are one set of vertices (the output of a closed mesh is a closed
/// manifold), and every patch's own table gives the owner's value on shared edges and corners.
#[test]
fn shared_edges_are_crack_free() {
    let bft = tables();
    let (weights, _) = padded_weights(bft);
    for (name, mesh) in meshes() {
        let sub = Subdivider::new(&mesh.topology, bft).expect("subdivider");
        let level = bft.level + 1;
        let out = sub
            .evaluate_cpu(bft, &mesh.positions_f32(), level)
            .expect("evaluate");
        let fine = TriMesh::new(
            out.positions.iter().map(|p| p.as_dvec3()).collect(),
            out.indices
                .chunks_exact(3)
                .map(|t| [t[0], t[1], t[2]])
                .collect(),
        )
        .expect("output is a valid manifold mesh");
        let coarse_boundary = mesh
            .topology
            .twin
            .iter()
            .filter(|&&t| t == u32::MAX)
            .count();
        let fine_boundary = fine
            .topology
            .twin
            .iter()
            .filter(|&&t| t == u32::MAX)
            .count();
        let s = sub.segments(level).expect("segments");
        assert_eq!(
            fine_boundary,
            coarse_boundary * 2 * s as usize,
            "{name}: boundary edges"
        );
        let p0: Vec<DVec3> = mesh.positions.clone();
        let (p1, n1) = sub.initial_step(&p0).expect("initial");
        let p1: Vec<Vec3> = p1.iter().map(|p| p.as_vec3()).collect();
        let n1: Vec<Vec3> = n1.iter().map(|p| p.as_vec3()).collect();
        let tol = (1e-6 * mesh.diagonal()) as f32;
        let mut checked = 0;
        for p in 0..sub.patches.patches.len() {
            for j in 0..=s {
                for i in 0..=s - j {
                    let (o, owned) = sub.patches.output_vertex(p, i, j, s);
                    if owned {
                        continue;
                    }
                    let (q, _) = sub
                        .patches
                        .evaluate_at(bft, &weights, p, (i, j, s), &p1, &n1);
                    let d = q.distance(out.positions[o as usize]);
                    assert!(
                        d <= tol,
                        "{name}: patch {p} ({i}, {j}) differs from the owner by {d:e}"
                    );
                    checked += 1;
                }
            }
        }
        assert!(checked > 0);
    }
}

/// Animation: new M⁰ positions go through the same buffers, entries and tables.
#[test]
fn animated_control_mesh_needs_no_rebuild() {
    let Some(gpu) = gpu::test_device(&subdiv_bft::device_needs()) else {
        return;
    };
    let bft = tables();
    let mesh = bipyramid(7);
    let sub = Subdivider::new(&mesh.topology, bft).expect("subdivider");
    let g = GpuSubdivider::new(&gpu.device, &sub, bft).expect("gpu");
    let out = g.level(&gpu.device, &sub, 3).expect("level");
    for frame in 0..3 {
        let t = frame as f32 * 0.7;
        let moved: Vec<Vec3> = mesh
            .positions_f32()
            .iter()
            .map(|p| {
                *p + Vec3::new(
                    (p.y * 3.0 + t).sin() * 0.2,
                    0.0,
                    (p.x * 2.0 + t).cos() * 0.1,
                )
            })
            .collect();
        g.set_positions(&gpu.queue, &moved).expect("positions");
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        g.encode(&mut encoder, &out, None);
        gpu.queue.submit([encoder.finish()]);
        let got = g.read_level(&gpu.device, &gpu.queue, &out).expect("read");
        let want = sub.evaluate_cpu(bft, &moved, 3).expect("cpu");
        compare_positions(&format!("frame {frame}"), &mesh, &want, &got);
    }
}

/// At `wgpu::Limits::default()` (8 storage buffers) the uniform evaluation works and adaptive
/// tessellation is refused with an error naming the limit, never a wgpu panic.
#[test]
fn default_limits_fall_back_to_uniform_evaluation() {
    let Some(gpu) = gpu::test_device(&subdiv_bft::device_needs()) else {
        return;
    };
    assert!(
        gpu.device.limits().max_storage_buffers_per_shader_stage
            < subdiv_bft::gpu::ADAPTIVE_STORAGE_BUFFERS
    );
    let bft = tables();
    let mesh = bipyramid(5);
    let sub = Subdivider::new(&mesh.topology, bft).expect("subdivider");
    let g =
        GpuSubdivider::new(&gpu.device, &sub, bft).expect("uniform pipelines at default limits");
    let err = g
        .adaptive(&gpu.device, &sub, 2)
        .err()
        .expect("adaptive refused");
    assert!(err.to_string().contains("storage buffers"), "{err}");
    let positions = mesh.positions_f32();
    let got = subdiv_bft::gpu::run(gpu, &sub, bft, &positions, 2).expect("uniform");
    let want = sub.evaluate_cpu(bft, &positions, 2).expect("cpu");
    compare_positions("default limits", &mesh, &want, &got);
}

/// The main step writes into the caller's vertex buffers (`bind_level`): the same vertices as
/// the buffers `level` allocates; buffers too small or without `STORAGE` are errors that name
/// the buffer, not wgpu validation panics.
#[test]
fn caller_owned_level_buffers_are_checked_and_written() {
    let Some(gpu) = gpu::test_device(&subdiv_bft::device_needs()) else {
        return;
    };
    let (device, bft, mesh) = (&gpu.device, tables(), bipyramid(6));
    let sub = Subdivider::new(&mesh.topology, bft).expect("subdivider");
    let g = GpuSubdivider::new(device, &sub, bft).expect("gpu");
    g.set_positions(&gpu.queue, &mesh.positions_f32())
        .expect("positions");
    let own = g.level(device, &sub, 2).expect("level");
    let buffer =
        |size, usage| gpu::transfer::buffer(device, "caller's", size, usage).expect("buffer");
    let usage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC;
    let bytes = u64::from(own.vertex_count) * 16;
    let (positions, normals) = (buffer(bytes, usage), buffer(bytes + 64, usage));
    let mine = g
        .bind_level(device, &sub, 2, &positions, &normals)
        .expect("bind");
    let mut encoder = device.create_command_encoder(&Default::default());
    g.encode(&mut encoder, &own, None);
    g.encode_evaluate(&mut encoder, &mine, None);
    gpu.queue.submit([encoder.finish()]);
    let (a, b) = (
        g.read_level(device, &gpu.queue, &own).expect("read"),
        g.read_level(device, &gpu.queue, &mine).expect("read"),
    );
    assert_eq!(a.positions, b.positions);
    assert_eq!(a.normals, b.normals);
    // Binding caller buffers that do not fit: the error names the buffer and what is wrong.
    let refused = |positions, normals, names: [&str; 2]| {
        let e = g
            .bind_level(device, &sub, 2, positions, normals)
            .err()
            .expect("refused")
            .to_string();
        assert!(names.iter().all(|n| e.contains(n)), "{names:?}: {e}");
    };
    let small = buffer(bytes - 16, usage);
    refused(&small, &normals, ["fine positions", "bytes"]);
    let vertex_only = buffer(bytes, wgpu::BufferUsages::VERTEX);
    refused(&positions, &vertex_only, ["fine normals", "STORAGE"]);
}
