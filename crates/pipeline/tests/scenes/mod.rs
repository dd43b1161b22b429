//! Scenes and VPLs the frame's composition tests share (each test file uses some of them).

use glam::Vec3;
use instant_radiosity::{IndirectConfig, vpl};
use scene::Scene;

/// The Cornell box with CesiumMan (animated, skinned) walking in it.
#[allow(dead_code)]
pub fn cesium_room() -> Scene {
    let man = scene::shared_fixtures()
        .expect("the tests need ../shared/fixtures")
        .join("animated/CesiumMan/CesiumMan.glb");
    let mut room = scene::cornell_box();
    let placement = glam::Mat4::from_scale_rotation_translation(
        Vec3::splat(0.25),
        glam::Quat::from_rotation_y(-std::f32::consts::FRAC_PI_2),
        Vec3::new(0.2, 0.0, 0.14),
    );
    room.insert(Scene::load(man).expect("CesiumMan"), placement)
        .expect("inserted");
    room
}

/// 64 VPLs from `scene`'s lights in `config`'s subsets (seed 3, one bounce).
#[allow(dead_code)]
pub fn vpls(scene: &Scene, config: &IndirectConfig) -> vpl::VplSet {
    vpl::generate(
        scene,
        &scene::Bvh::build(scene),
        &scene.lights,
        &vpl::VplConfig {
            count: 64,
            subsets: config.subsets(),
            seed: 3,
            emissive: false,
            bounces: 1,
        },
    )
    .expect("vpls")
}
