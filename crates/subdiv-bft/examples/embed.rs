//! `subdiv-bft` inside an application that owns its wgpu device: Loop-subdivide an octahedron
//! to level 3 on the GPU with basis-function tables, in the application's own encoder, and
//! check the vertices against the CPU reference.
//!
//! The application creates its own device: wgpu's default limits plus what the crate states
//! it needs (`device_needs()`).

use subdiv_bft::{BftSet, Subdivider, TriMesh, gpu::GpuSubdivider};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let adapter =
        pollster::block_on(wgpu::Instance::default().request_adapter(&Default::default()))?;
    let (device, queue) =
        pollster::block_on(adapter.request_device(&subdiv_bft::device_needs().descriptor()))?;

    // A control mesh and the tables (level 3, valences up to 8).
    let p = [
        [1.0, 0.0, 0.0],
        [-1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, -1.0, 0.0],
        [0.0, 0.0, 1.0],
        [0.0, 0.0, -1.0],
    ];
    let faces = [0, 2, 4, 2, 1, 4, 1, 3, 4, 3, 0, 4, 2, 0, 5, 1, 2, 5, 3, 1, 5, 0, 3, 5];
    let mesh = TriMesh::from_f32(&p, &faces)?;
    let bft = BftSet::build(3, 8)?;
    let sub = Subdivider::new(&mesh.topology, &bft)?;

    // new: pipelines and static data once; level: output buffers; encode: only records.
    let gpu = GpuSubdivider::new(&device, &sub, &bft)?;
    let level = gpu.level(&device, &sub, 3)?;
    gpu.set_positions(&queue, &mesh.positions_f32())?;
    let mut encoder = device.create_command_encoder(&Default::default());
    gpu.encode(&mut encoder, &level, None);
    queue.submit([encoder.finish()]);

    let got = gpu.read_level(&device, &queue, &level)?;
    let want = sub.evaluate_cpu(&bft, &mesh.positions_f32(), 3)?;
    let worst =
        got.positions.iter().zip(&want.positions).map(|(a, b)| a.distance(*b)).fold(0.0, f32::max);
    assert!(worst < 1e-5, "GPU vertices differ from the CPU reference by {worst}");
    println!(
        "level 3: {} triangles on {}, max vertex difference {worst:.1e}",
        got.indices.len() / 3,
        adapter.get_info().name
    );
    Ok(())
}
