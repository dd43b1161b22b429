//! Visibility by rays: the flattened BVH's traversal (the CPU twin of `rays.wgsl`) against
//! `scene::Bvh`, an independent BVH and intersector.

use glam::Vec3;
use scene::Bvh;
use tiled_shading::rays::{RayBvh, scene_mesh};

/// A deterministic point in the scene's box (xorshift).
fn point(state: &mut u64, lo: Vec3, hi: Vec3) -> Vec3 {
    let mut next = || {
        *state ^= *state << 13;
        *state ^= *state >> 7;
        *state ^= *state << 17;
        (*state >> 40) as f32 / (1u64 << 24) as f32
    };
    lo + (hi - lo) * Vec3::new(next(), next(), next())
}

#[test]
fn ray_bvh_agrees_with_the_scene_bvh() {
    for scene in [scene::cornell_box(), scene::spheres_on_plane(6)] {
        let mesh = scene_mesh(&scene);
        let rays = RayBvh::new((&mesh.0, &mesh.1)).expect("bvh");
        let reference = Bvh::build(&scene);
        let bounds = scene.bounds();
        let (mut state, mut agree, mut blocked) = (0x9e37_79b9_7f4a_7c15u64, 0, 0);
        let n = 20_000;
        for _ in 0..n {
            let a = point(&mut state, bounds.min, bounds.max);
            let b = point(&mut state, bounds.min, bounds.max);
            let got = rays.occluded(a, b - a);
            let want = reference.any_hit(a, b - a, 1.0);
            agree += usize::from(got == want);
            blocked += usize::from(want);
        }
        println!(
            "{} triangles: {agree} of {n} segments agree, {blocked} blocked",
            scene.triangle_count()
        );
        assert!(
            blocked > n / 10 && blocked < n * 9 / 10,
            "{blocked} of {n} blocked"
        );
        // Segments through an edge or a vertex may go either way.
        assert!(agree as f64 >= 0.999 * n as f64, "{agree} of {n}");
    }
}

/// The closest hit (`RayBvh::nearest`, the near field's traversal) finds the reference's
/// triangle at the reference's distance: mesh index = the global triangle index of
/// `scene_mesh`'s order.
#[test]
fn nearest_hit_agrees_with_the_scene_bvh() {
    for scene in [scene::cornell_box(), scene::spheres_on_plane(6)] {
        let mesh = scene_mesh(&scene);
        let rays = RayBvh::new((&mesh.0, &mesh.1)).expect("bvh");
        let reference = Bvh::build(&scene);
        let first: Vec<u32> = scene
            .meshes
            .iter()
            .scan(0, |start, m| {
                let s = *start;
                *start += (m.indices.len() / 3) as u32;
                Some(s)
            })
            .collect();
        let bounds = scene.bounds();
        let (mut state, mut agree, mut hits) = (0x2545_f491_4f6c_dd1du64, 0, 0);
        let n = 20_000;
        for _ in 0..n {
            let a = point(&mut state, bounds.min, bounds.max);
            let b = point(&mut state, bounds.min, bounds.max);
            let got = rays
                .nearest(a, b - a)
                .map(|(t, slot)| (t, rays.triangles[slot].index));
            let want = reference
                .closest_hit(a, b - a, 1.0)
                .map(|h| (h.t, first[h.mesh as usize] + h.triangle));
            hits += usize::from(want.is_some());
            agree += usize::from(match (got, want) {
                (Some((t, i)), Some((u, j))) => i == j && (t - u).abs() <= 1e-4,
                (None, None) => true,
                _ => false,
            });
        }
        println!("{agree} of {n} nearest hits agree, {hits} hit");
        assert!(hits > n / 10, "{hits} of {n} hit");
        // Segments through an edge or a vertex may go either way.
        assert!(agree as f64 >= 0.999 * n as f64, "{agree} of {n}");
    }
}

#[test]
fn an_empty_scene_is_an_error() {
    let err = RayBvh::new((&[], &[])).expect_err("no triangles");
    assert!(err.to_string().contains("no triangles"), "{err}");
}
