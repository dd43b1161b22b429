//! `gbuffer` inside an application that owns its wgpu device: the G-buffer of the material
//! gallery through the visibility buffer (compute rasteriser, the hardware draw of its
//! alpha-tested spheres, the resolve), recorded into the application's own encoder, and checked
//! against the CPU rasteriser's G-buffer. `gbuffer-embed PICTURE.png` also writes a picture:
//! the triangle ids, the resolved albedo, and the pixels whose material word differs from the
//! CPU's (red).
//!
//! The application creates its own device: wgpu's default limits plus what the module states it
//! needs (`visibility::device_needs()`), and the 64-bit atomics where the adapter has them.

use gbuffer::gpu::visibility::{self, Atomics, ResolvePass, VisibilityPass};
use gbuffer::gpu::{GBufferPass, GBufferTargets, GpuScene};
use gbuffer::{Frame, Image, TextureOptions};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let adapter =
        pollster::block_on(wgpu::Instance::default().request_adapter(&Default::default()))?;
    let mut needs = visibility::device_needs();
    needs.features |= adapter.features() & visibility::WIDE_FEATURES;
    let (device, queue) = pollster::block_on(adapter.request_device(&needs.descriptor()))?;

    let scene = scene::material_gallery();
    let camera = scene.camera_or_framed();
    let (width, height) = (480, 320);
    let gpass = GBufferPass::new(&device)?;
    // Trilinear filtering, for the comparison: anisotropic filters are implementation-defined.
    let trilinear = TextureOptions { max_anisotropy: 1 };
    let uploaded = GpuScene::upload_with(&device, &queue, &scene, &gpass, &trilinear)?;
    gpass.write_frame(&queue, &Frame::new(&camera, width, height));
    let targets = GBufferTargets::new(&device, width, height)?;

    // new: pipelines once; bind: the caller's buffers and targets; encode: only records.
    let buffer = VisibilityPass::buffer(&device, width, height)?;
    let pass = VisibilityPass::new(&device, &gpass)?;
    let vis = pass.bind(&device, &uploaded, gpass.frame_buffer(), (width, height), &buffer)?;
    let resolve_pass = ResolvePass::new(&device, &gpass)?;
    let resolve = resolve_pass.bind(&device, &uploaded, gpass.frame_buffer(), &vis, &targets)?;
    let mut encoder = device.create_command_encoder(&Default::default());
    vis.encode(&mut encoder, Some(&targets.depth), None)?;
    resolve.passes.encode(&mut encoder, None);
    resolve_pass.encode_depth(&resolve, &mut encoder, &targets.depth, None);
    queue.submit([encoder.finish()]);

    let resolved = targets.read(&device, &queue)?;
    let words = gpu::transfer::read_buffer(&device, &queue, &buffer)?;
    let ids = visibility::triangle_ids(&bytemuck::pod_collect_to_vec::<u8, u64>(&words));
    let cpu = gbuffer::cpu::rasterize_with(&scene, &camera, (width, height), &trilinear)?.gbuffer;
    let differs: Vec<bool> =
        resolved.material.pixels().iter().zip(cpu.material.pixels()).map(|(g, c)| g != c).collect();
    let agree = differs.iter().filter(|&&d| !d).count() as f64 / differs.len() as f64;
    // Where the words differ: one roughness or metallic step apart (texture filtering rounding)
    // on the same material, or another material (or none) altogether.
    let one_step = resolved
        .material
        .pixels()
        .iter()
        .zip(cpu.material.pixels())
        .filter(|(g, c)| {
            let ((rg, mg, ig), (rc, mc, ic)) =
                (gbuffer::unpack_material(**g), gbuffer::unpack_material(**c));
            g != c && ig == ic && (rg - rc).abs() <= 1.5 / 255.0 && (mg - mc).abs() <= 1.5 / 255.0
        })
        .count();
    let elsewhere = differs.iter().filter(|&&d| d).count() - one_step;
    println!(
        "material gallery {width}×{height} on {} ({:?} atomics, meshes drawn by the hardware rasteriser {:?}): material words equal to the CPU rasteriser's on {:.2} % of the pixels; {one_step} differ by one roughness or metallic step, {elsewhere} hold another material or none",
        adapter.get_info().name,
        pass.atomics(),
        vis.hardware,
        agree * 100.0
    );
    assert!(pass.atomics() == Atomics::best(&device));

    if let Some(path) = std::env::args().nth(1) {
        let panel = |x: u32, y: u32, k: usize| -> [f32; 4] {
            let i = (y * width + x) as usize;
            match k {
                0 if ids[i] == visibility::NO_TRIANGLE => [0.0, 0.0, 0.0, 1.0],
                0 => {
                    let h = ids[i].wrapping_mul(0x9E37_79B9);
                    let c = |s: u32| ((h >> s) & 0xFF) as f32 / 255.0 * 0.8 + 0.1;
                    [c(8), c(16), c(24), 1.0]
                }
                _ => {
                    let a = resolved.albedo.get(x, y);
                    let linear = |v: u8| f32::from(v) / 255.0;
                    if k == 2 && differs[i] {
                        [1.0, 0.0, 0.0, 1.0]
                    } else if k == 2 {
                        let grey = 0.3 * (linear(a[0]) + linear(a[1]) + linear(a[2])) / 3.0;
                        [grey, grey, grey, 1.0]
                    } else {
                        [linear(a[0]), linear(a[1]), linear(a[2]), 1.0]
                    }
                }
            }
        };
        let picture = Image::from_vec(
            3 * width,
            height,
            (0..height)
                .flat_map(|y| (0..3 * width).map(move |x| (x, y)))
                .map(|(x, y)| panel(x % width, y, (x / width) as usize))
                .collect(),
        )?;
        picture.write_png(std::path::Path::new(&path))?;
        println!("wrote {path}");
    }
    Ok(())
}
