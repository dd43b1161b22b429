//! An animated sequence rendered into the caller's texture: CesiumMan walking in the Cornell
//! box, skinned on the GPU each frame, on a fixed-step clock with an orbiting camera; the
//! frames' pass times gathered into a timeline (CSV, trace, plot).

use pipeline::gpu::{GpuRenderer, RADIANCE_FORMAT};
use pipeline::sequence::{CameraPath, Clock, Timeline, looped};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let adapter =
        pollster::block_on(wgpu::Instance::default().request_adapter(&Default::default()))?;
    // Timestamp queries where the adapter has them, for the pass times.
    let mut needs = pipeline::device_needs().descriptor();
    needs.required_features |= adapter.features() & wgpu::Features::TIMESTAMP_QUERY;
    let (device, queue) = pollster::block_on(adapter.request_device(&needs))?;
    let man = scene::shared_fixtures()
        .ok_or("no ../shared/fixtures")?
        .join("animated/CesiumMan/CesiumMan.glb");
    let mut room = scene::cornell_box();
    let place = glam::Mat4::from_scale_rotation_translation(
        glam::Vec3::splat(0.25),
        glam::Quat::IDENTITY,
        glam::Vec3::new(0.2, 0.0, 0.15),
    );
    room.insert(scene::Scene::load(man)?, place)?;
    let rig = room.rig.clone().ok_or("the room does not move")?;

    let mut renderer = GpuRenderer::new(&device, &queue, &room, &room.lights, 320, 240)?;
    renderer.set_animation(&device, &queue, Some(&rig))?;
    let target = device.create_texture(&wgpu::TextureDescriptor {
        label: Some("caller's frame"),
        size: renderer.output().size(),
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: RADIANCE_FORMAT,
        usage: wgpu::TextureUsages::COPY_DST | wgpu::TextureUsages::TEXTURE_BINDING,
        view_formats: &[],
    });
    let (clock, path, base) = (
        Clock::new(24.0)?,
        CameraPath::Orbit { degrees_per_second: 20.0 },
        room.camera_or_framed(),
    );
    let mut timeline = Timeline::default();
    for frame in 0..24 {
        let t = clock.time(frame);
        renderer.set_pose(&queue, &rig.pose(Some(0), looped(t, rig.clips[0].duration)))?;
        renderer.set_camera(&queue, &path.camera(&base, t))?;
        let mut encoder = device.create_command_encoder(&Default::default());
        renderer.encode(&mut encoder);
        encoder.copy_texture_to_texture(
            renderer.output().as_image_copy(),
            target.as_image_copy(),
            target.size(),
        );
        queue.submit([encoder.finish()]);
        timeline.push(frame, t, 0.0, renderer.pass_times(&device, &queue)?);
    }
    for s in timeline.summary() {
        println!("{:<28} median {:.3} ms, p99 {:.3} ms", s.name, s.median_ms, s.p99_ms);
    }
    Ok(())
}
