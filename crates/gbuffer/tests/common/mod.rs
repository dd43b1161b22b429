//! Helpers shared by the G-buffer tests: random scenes and failure images.

#![allow(dead_code)]

use std::path::PathBuf;

use glam::{Vec2, Vec3, Vec4};
use scene::{Camera, Material, Mesh, Scene, Texture};

/// Folder for expected/actual/difference images of failed tests.
pub fn test_output(name: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../target/test-output")
        .join(name);
    std::fs::create_dir_all(&dir).expect("test output dir");
    dir
}

/// Writes an RGBA8 image as PNG.
pub fn write_rgba8(path: PathBuf, width: u32, height: u32, pixels: &[[u8; 4]]) {
    let bytes: Vec<u8> = pixels.iter().flatten().copied().collect();
    let _ = image::save_buffer(path, &bytes, width, height, image::ExtendedColorType::Rgba8);
}

/// A deterministic random scene from a seed: `triangles` random triangles in [-1, 1]³ with
/// random unit normals and UVs, over three materials (one with a checker texture).
pub fn random_scene(seed: u64, triangles: usize) -> Scene {
    let mut s = seed;
    let mut next = move || {
        s = s.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = s;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 40) as f32 / (1u64 << 24) as f32
    };
    let mut scene = Scene::default();
    let checker: Vec<u8> = (0..16 * 16)
        .flat_map(|i| {
            if (i % 16 / 4 + i / 64) % 2 == 0 {
                [200, 60, 20, 255]
            } else {
                [20, 90, 220, 255]
            }
        })
        .collect();
    scene.textures.push(Texture {
        name: "checker".into(),
        width: 16,
        height: 16,
        rgba8: checker,
        sampler: Default::default(),
    });
    for k in 0..3 {
        scene.materials.push(Material {
            name: format!("m{k}"),
            base_color: Vec4::new(next(), next(), next(), 1.0),
            base_color_texture: (k == 2).then_some(scene::TextureRef::new(0)),
            roughness: next(),
            metallic: next(),
            emissive: Vec3::ZERO,
            specular: next(),
            ..Default::default()
        });
    }
    for k in 0..3u32 {
        let mut mesh = Mesh {
            name: format!("mesh{k}"),
            material: k,
            ..Default::default()
        };
        for _ in 0..triangles.div_ceil(3) {
            let c = Vec3::new(next(), next(), next()) * 2.0 - 1.0;
            for _ in 0..3 {
                mesh.indices.push(mesh.positions.len() as u32);
                mesh.positions
                    .push(c + (Vec3::new(next(), next(), next()) - 0.5) * 1.2);
                mesh.normals
                    .push((Vec3::new(next(), next(), next()) - 0.5).normalize_or(Vec3::Y));
                mesh.uvs.push(Vec2::new(next(), next()) * 3.0 - 1.0);
            }
        }
        scene.meshes.push(mesh);
    }
    scene
}

/// A camera on a sphere of radius 2.5–4 around the origin, looking at it.
pub fn random_camera(seed: u64) -> Camera {
    let t = (seed % 1000) as f32 / 1000.0;
    let u = ((seed / 1000) % 1000) as f32 / 1000.0;
    let dir = Vec3::new(
        (t * 6.283).cos() * (1.0 - u * u).sqrt(),
        u * 1.6 - 0.8,
        (t * 6.283).sin(),
    );
    let mut cam = Camera::look_at(dir.normalize() * (2.5 + 1.5 * u), Vec3::ZERO);
    cam.fov_y = (35.0 + 50.0 * t).to_radians();
    cam.near = 0.3 + u;
    cam.far = 8.0;
    cam
}

/// Whether the triangle-id image is not constant over the 3 × 3 neighbourhood of (x, y): a
/// silhouette or triangle edge, where rasterisers may hand the pixel to a neighbour.
pub fn is_edge(ids: &gbuffer::Image<u32>, x: u32, y: u32) -> bool {
    let id = ids.get(x, y);
    (-1i32..=1).any(|dy| {
        (-1i32..=1).any(|dx| {
            let (nx, ny) = (x as i32 + dx, y as i32 + dy);
            nx >= 0
                && ny >= 0
                && (nx as u32) < ids.width()
                && (ny as u32) < ids.height()
                && ids.get(nx as u32, ny as u32) != id
        })
    })
}
