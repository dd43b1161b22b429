//! The BVH's hits against rays aimed at known points of triangles: the hit's barycentric
//! coordinates give back the point aimed at, whatever the triangle's size and shape.

use glam::{Vec2, Vec3};
use scene::{Bvh, Material, Mesh, Scene};

/// Triangles from thin slivers to large ones (doubled areas 10⁻⁴ to 10²), each alone in its
/// scene, hit by rays from random origins at random interior points.
#[test]
fn hit_barycentrics_give_the_point_aimed_at() {
    let mut state = 0x2545_f491_4f6c_dd1du64;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 40) as f32 / (1u64 << 24) as f32
    };
    let mut worst = 0.0f32;
    for k in 0..200 {
        let scale = 10f32.powf(-2.0 + 3.0 * next());
        let centre = Vec3::new(next(), next(), next()) * 20.0 - 10.0;
        let stretch = 10f32.powf(-2.0 * next());
        let v = [0, 1, 2].map(|_| {
            centre + Vec3::new(next() - 0.5, (next() - 0.5) * stretch, next() - 0.5) * scale
        });
        let mesh = Mesh {
            name: "triangle".into(),
            positions: v.to_vec(),
            normals: vec![Vec3::Y; 3],
            uvs: vec![Vec2::ZERO; 3],
            indices: vec![0, 1, 2],
            material: 0,
            ..Default::default()
        };
        let scene = Scene {
            meshes: vec![mesh],
            materials: vec![Material::default()],
            ..Default::default()
        };
        let bvh = Bvh::build(&scene);
        let (a, b) = (next(), next());
        let (a, b) = if a + b > 1.0 {
            (1.0 - a, 1.0 - b)
        } else {
            (a, b)
        };
        let target = v[0] * (1.0 - a - b) + v[1] * a + v[2] * b;
        let origin = centre + (Vec3::new(next(), next(), next()) - 0.5) * 8.0 * scale.max(1.0);
        let to = target - origin;
        let Some(hit) = bvh.closest_hit(origin, to.normalize(), 2.0 * to.length()) else {
            continue; // a ray nearly in the triangle's plane may miss it
        };
        let w = hit.barycentrics;
        let from_weights = v[0] * (1.0 - w.x - w.y) + v[1] * w.x + v[2] * w.y;
        let error = (from_weights - hit.position).length() / scale;
        worst = worst.max(error);
        assert!(
            error < 1e-3,
            "triangle {k} (scale {scale}): barycentrics {w} give {from_weights}, the hit is at {}, aimed at {target} ({a}, {b})",
            hit.position
        );
    }
    println!("largest error {worst} of the triangle's size");
}
