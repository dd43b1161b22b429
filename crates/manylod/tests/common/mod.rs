//! The test scene shared by the CPU and GPU tests.
#![allow(dead_code)] // each test binary uses part of the shared scene

use glam::Vec3;
use manylod::{Bsh, CutProblem, NodeView, View, surfels};

/// A bumpy sphere above a ground quad: closed and open parts, all orientations.
pub fn scene() -> (Vec<Vec3>, Vec<u32>) {
    let (rings, segments) = (24u32, 48u32);
    let mut p = Vec::new();
    let mut idx = Vec::new();
    for r in 0..=rings {
        let th = std::f32::consts::PI * r as f32 / rings as f32;
        for s in 0..segments {
            let ph = std::f32::consts::TAU * s as f32 / segments as f32;
            let bump = 1.0 + 0.1 * (3.0 * ph).sin() * (4.0 * th).sin();
            p.push(
                Vec3::new(th.sin() * ph.cos(), th.cos(), th.sin() * ph.sin()) * bump
                    + Vec3::Y * 1.5,
            );
        }
    }
    for r in 0..rings {
        for s in 0..segments {
            let a = r * segments + s;
            let b = r * segments + (s + 1) % segments;
            let (c, d) = (a + segments, b + segments);
            idx.extend([a, c, b, b, c, d]);
        }
    }
    let g = p.len() as u32;
    p.extend([
        Vec3::new(-4.0, 0.0, -4.0),
        Vec3::new(4.0, 0.0, -4.0),
        Vec3::new(4.0, 0.0, 4.0),
        Vec3::new(-4.0, 0.0, 4.0),
    ]);
    idx.extend([g, g + 2, g + 1, g, g + 3, g + 2]);
    (p, idx)
}

pub fn tree(count: usize) -> (Bsh, Vec<Vec3>, Vec<Vec3>) {
    let (p, i) = scene();
    let s = surfels::sample(&p, &i, count, 7).expect("surfels");
    let (pts, nrm) = surfels::evaluate(&s, &p, &i);
    let bsh = Bsh::build(&pts, &nrm, surfels::disc_radius(&p, &i, count)).expect("tree");
    (bsh, pts, nrm)
}

/// VPL-like hemispherical views scattered over the ground and the sphere, plus two cameras.
pub fn views(angle: f32) -> Vec<View> {
    views_in_tiles(angle, None)
}

/// [`views`], every one `tile × tile` pixels when `tile` is given (for an atlas).
pub fn views_in_tiles(angle: f32, tile: Option<u32>) -> Vec<View> {
    let mut v = Vec::new();
    for k in 0..24 {
        let a = angle + k as f32 * 0.7;
        let position = Vec3::new(3.0 * a.cos(), 0.05 + 0.1 * (k % 3) as f32, 3.0 * a.sin());
        v.push(View::Paraboloid {
            position,
            normal: Vec3::Y,
            size: tile.unwrap_or(32),
        });
    }
    for (eye, size) in [
        (
            Vec3::new(5.0 * angle.cos(), 3.0, 5.0 * angle.sin()),
            (64, 48),
        ),
        (Vec3::new(0.3, 1.4, 3.0), (128, 128)),
    ] {
        let size = tile.map_or(size, |t| (t, t));
        let fov_y = 0.9f32;
        let proj = glam::camera::rh::proj::directx::perspective(
            fov_y,
            size.0 as f32 / size.1 as f32,
            0.1,
            50.0,
        );
        let view = glam::camera::rh::view::look_at_mat4(eye, Vec3::new(0.0, 1.2, 0.0), Vec3::Y);
        v.push(View::Perspective {
            eye,
            view_proj: proj * view,
            fov_y,
            size,
        });
    }
    v
}

/// Node-views in a canonical order, to compare cuts as sets.
pub fn sorted(mut v: Vec<NodeView>) -> Vec<NodeView> {
    v.sort_unstable();
    v
}

/// Every leaf of every view covered exactly once.
pub fn assert_partition(problem: &CutProblem, set: &[NodeView], frame: u32) {
    let n = problem.bsh.leaf_count();
    let mut cover = vec![vec![0u8; n]; problem.views.len()];
    for nv in set {
        let (lo, hi) = problem.bsh.leaf_range(nv.node);
        for c in &mut cover[nv.view as usize][lo..hi] {
            *c += 1;
        }
    }
    for (v, c) in cover.iter().enumerate() {
        let bad = c.iter().filter(|&&c| c != 1).count();
        assert_eq!(
            bad, 0,
            "frame {frame} view {v}: {bad} leaves not covered once"
        );
    }
}
