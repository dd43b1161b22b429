//! The renderer's direct-light shadows: a directional light's cascades follow the camera
//! (a frame after `set_camera` equals a frame of a renderer made for that camera), and the
//! shadows darken the frame.

use glam::Vec3;
use pipeline::gpu::GpuRenderer;
use scene::{Camera, Light};
use tiled_shading::shadows::ShadowMapConfig;

fn luminance(image: &gbuffer::Image<[f32; 4]>) -> f32 {
    image.pixels().iter().map(|p| p[0] + p[1] + p[2]).sum()
}

#[test]
fn cascades_follow_the_camera_and_shadows_darken() {
    let Some(gpu) = gpu::test_device(&pipeline::device_needs()) else {
        return;
    };
    let (d, q) = (&gpu.device, &gpu.queue);
    let scene = scene::spheres_on_plane(5);
    let sun: Light = "dir:0.4,-1,0.3,1,1,1,2".parse().expect("light");
    let first = scene.camera_or_framed();
    let second = Camera {
        eye: first.eye + Vec3::new(2.0, 1.0, -1.0),
        ..first
    };
    let config = ShadowMapConfig {
        resolution: 512,
        ..Default::default()
    };
    let renderer = |camera: &Camera, shadows: bool| {
        let mut r = GpuRenderer::new(d, q, &scene, &[sun], 96, 64).expect("renderer");
        r.set_camera(q, camera).expect("camera");
        r.set_shadows(d, q, shadows.then_some(&config))
            .expect("shadows");
        r
    };
    let mut moved = renderer(&first, true);
    let after_move = moved
        .render(d, q, &second, Vec3::ZERO)
        .expect("frame")
        .image;
    let fresh = renderer(&second, true)
        .render(d, q, &second, Vec3::ZERO)
        .expect("frame")
        .image;
    assert_eq!(
        after_move.pixels(),
        fresh.pixels(),
        "the cascades did not follow the camera"
    );
    let lit = renderer(&second, false)
        .render(d, q, &second, Vec3::ZERO)
        .expect("frame")
        .image;
    assert!(
        luminance(&fresh) < 0.97 * luminance(&lit),
        "the spheres' shadows darken the frame: {} vs {}",
        luminance(&fresh),
        luminance(&lit)
    );
}
