//! `manylod` inside an application that owns its wgpu device: find the many-view cut of a
//! surfel hierarchy for 16 paraboloid views on the GPU, in the application's own encoder, and
//! check it against the CPU reference.
//!
//! The application creates its own device: wgpu's default limits plus what the crate states
//! it needs (`device_needs()`).

use glam::Vec3;
use manylod::{
    AtlasLayout, Bsh, CutProblem, View, cut,
    gpu::{CutKind, GpuManyLod},
    surfels,
};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let adapter =
        pollster::block_on(wgpu::Instance::default().request_adapter(&Default::default()))?;
    let (device, queue) =
        pollster::block_on(adapter.request_device(&manylod::device_needs().descriptor()))?;

    // A floor with a wall, 2^12 surfels, a hierarchy, and 16 views above the floor.
    #[rustfmt::skip]
    let corners = [-2., 0., -2., 2., 0., -2., 2., 0., 2., -2., 0., 2., -2., 2., 0., 2., 2., 0.];
    let p: Vec<Vec3> = corners.chunks(3).map(Vec3::from_slice).collect();
    let i = [0, 2, 1, 0, 3, 2, 0, 1, 5, 0, 5, 4];
    let s = surfels::sample(&p, &i, 1 << 12, 1)?;
    let (points, normals) = surfels::evaluate(&s, &p, &i);
    let bsh = Bsh::build(&points, &normals, surfels::disc_radius(&p, &i, 1 << 12))?;
    let view = |k: u32| View::Paraboloid {
        position: Vec3::new(k as f32 * 0.2 - 1.5, 0.5, 1.0),
        normal: Vec3::Y,
        size: 32,
    };
    let views: Vec<View> = (0..16).map(view).collect();
    let (epsilon, layout) = (2.0, AtlasLayout::new(views.len(), 32, 8.0));

    // new: upload and pipelines once; encode_cut: only records (indirect dispatch, no readback).
    let mut gpu = GpuManyLod::new(&device, &bsh, &views, epsilon, layout, 1 << 16, None)?;
    let mut encoder = device.create_command_encoder(&Default::default());
    gpu.encode_cut(&mut encoder, CutKind::Basic, None);
    queue.submit([encoder.finish()]);

    let mut got = gpu.read_cut(&device, &queue)?.node_views;
    let problem = CutProblem { bsh: &bsh, views: &views, epsilon };
    let mut want = cut::basic(&problem)?.node_views;
    (got.sort_unstable(), want.sort_unstable());
    // Hardware asin/atan2 may decide a few node-views at ε the other way (≤ 0.1 %).
    let differ = got.iter().filter(|nv| want.binary_search(nv).is_err()).count();
    assert!(differ * 1000 <= want.len(), "{differ} of {} node-views differ", want.len());
    let name = adapter.get_info().name;
    println!("cut of {} node-views, 16 views, on {name}: {differ} differ from the CPU", got.len());
    Ok(())
}
