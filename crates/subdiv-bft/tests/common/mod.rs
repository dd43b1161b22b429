//! Test meshes with vertices of every valence, closed and with boundaries.
#![allow(dead_code)]

use std::f64::consts::PI;
use std::sync::OnceLock;

use glam::DVec3;
use subdiv_bft::{BftSet, TriMesh};

/// Tables shared by the tests of one process (level 4, valences up to 18).
pub fn tables() -> &'static BftSet {
    static T: OnceLock<BftSet> = OnceLock::new();
    T.get_or_init(|| BftSet::build(4, 18).expect("tables"))
}

/// Closed bipyramid over an n-gon, apexes of valence n, wobbled so nothing is symmetric.
pub fn bipyramid(n: u32) -> TriMesh {
    let mut p = vec![DVec3::new(0.1, 0.2, 1.3), DVec3::new(-0.1, 0.05, -1.1)];
    for i in 0..n {
        let a = 2.0 * PI * f64::from(i) / f64::from(n);
        let r = 1.0 + 0.2 * f64::from(i % 3);
        p.push(DVec3::new(r * a.cos(), r * a.sin(), 0.1 * f64::from(i % 2)));
    }
    let mut t = Vec::new();
    for i in 0..n {
        let (a, b) = (2 + i, 2 + (i + 1) % n);
        t.push([0, a, b]);
        t.push([1, b, a]);
    }
    TriMesh::new(p, t).expect("bipyramid")
}

/// Open fan: a centre of interior valence n with a boundary ring of n vertices.
pub fn disk(n: u32) -> TriMesh {
    let mut p = vec![DVec3::new(0.0, 0.0, 0.3)];
    for i in 0..n {
        let a = 2.0 * PI * f64::from(i) / f64::from(n);
        p.push(DVec3::new(a.cos(), a.sin(), 0.2 * f64::from(i % 2)));
    }
    let t = (0..n).map(|i| [0, 1 + i, 1 + (i + 1) % n]).collect();
    TriMesh::new(p, t).expect("disk")
}

/// Half-disk: a boundary centre with `faces` triangles (valence faces + 1) spanning 0.1π–0.9π
/// (never a straight angle, so no triangle is flat), plus a second row so the outer vertices
/// are not all corners.
pub fn half_disk(faces: u32) -> TriMesh {
    let mut p = vec![DVec3::ZERO];
    for i in 0..=faces {
        let a = PI * (0.1 + 0.8 * f64::from(i) / f64::from(faces));
        p.push(DVec3::new(a.cos(), a.sin(), 0.15 * f64::from(i % 2)));
    }
    for i in 0..=faces {
        let a = PI * (0.1 + 0.8 * f64::from(i) / f64::from(faces));
        p.push(DVec3::new(
            2.0 * a.cos(),
            2.0 * a.sin(),
            -0.1 * f64::from(i % 3),
        ));
    }
    let mut t: Vec<[u32; 3]> = (0..faces).map(|i| [0, 1 + i, 2 + i]).collect();
    let outer = faces + 2;
    for i in 0..faces {
        let (a, b, c, d) = (1 + i, 2 + i, outer + i, outer + i + 1);
        t.push([a, c, d]);
        t.push([a, d, b]);
    }
    TriMesh::new(p, t).expect("half disk")
}

/// Closed torus of `nu × nv` quads split into triangles (every vertex of valence 6), radii 1
/// and 0.4, wobbled so nothing is symmetric.
pub fn torus(nu: u32, nv: u32) -> TriMesh {
    let mut p = Vec::new();
    for j in 0..nv {
        for i in 0..nu {
            let (a, b) = (
                2.0 * PI * f64::from(i) / f64::from(nu),
                2.0 * PI * f64::from(j) / f64::from(nv),
            );
            let r = 1.0 + (0.4 + 0.02 * f64::from((i + j) % 3)) * b.cos();
            p.push(DVec3::new(r * a.cos(), r * a.sin(), 0.4 * b.sin()));
        }
    }
    let at = |i: u32, j: u32| (j % nv) * nu + i % nu;
    let mut t = Vec::new();
    for j in 0..nv {
        for i in 0..nu {
            t.push([at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
            t.push([at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
        }
    }
    TriMesh::new(p, t).expect("torus")
}

/// Nearest-neighbour distance from every point of `a` to the set `b`, maximum (brute force
/// through a uniform grid).
pub fn max_nearest(a: &[DVec3], b: &[DVec3]) -> f64 {
    let (lo, hi) = b.iter().fold(
        (DVec3::splat(f64::MAX), DVec3::splat(f64::MIN)),
        |(l, h), &p| (l.min(p), h.max(p)),
    );
    let cell = ((hi - lo).max_element() / 64.0).max(1e-9);
    let key = |p: DVec3| ((p - lo) / cell).floor().as_ivec3();
    let mut grid: std::collections::HashMap<glam::IVec3, Vec<usize>> = Default::default();
    for (i, &p) in b.iter().enumerate() {
        grid.entry(key(p)).or_default().push(i);
    }
    a.iter()
        .map(|&p| {
            let k = key(p);
            let mut best = f64::MAX;
            for dz in -1..=1 {
                for dy in -1..=1 {
                    for dx in -1..=1 {
                        if let Some(v) = grid.get(&(k + glam::IVec3::new(dx, dy, dz))) {
                            for &i in v {
                                best = best.min(p.distance(b[i]));
                            }
                        }
                    }
                }
            }
            if best == f64::MAX {
                b.iter().map(|&q| p.distance(q)).fold(f64::MAX, f64::min)
            } else {
                best
            }
        })
        .fold(0.0, f64::max)
}
