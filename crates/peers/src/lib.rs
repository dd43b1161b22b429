//! The toolkit beside the libraries users would pick instead, on the same meshes and device:
//! OpenSubdiv's Loop refinement through `opensubdiv-petite` ([`opensubdiv`]), MeshLab and Open3D
//! through Python where they are importable ([`python`]), and the point-set distance their
//! positions are compared with ([`max_nearest`]). The `peers-gpu` benchmark runs them.

pub mod opensubdiv;
pub mod python;

use glam::{DVec3, Vec3};

/// `f32` triples (OpenSubdiv's and the GPU's positions) as `f64` points for [`hausdorff`].
pub fn dvec3s(points: &[[f32; 3]]) -> Vec<DVec3> {
    points.iter().map(|&p| Vec3::from(p).as_dvec3()).collect()
}

/// The largest distance from a point of `a` to its nearest point of `b`, where it is below
/// `reach`; `f64::INFINITY` if some point of `a` has no point of `b` within `reach` (or `b` is
/// empty). A grid of cells of `reach` keeps this linear in the points, millions included.
pub fn max_nearest(a: &[DVec3], b: &[DVec3], reach: f64) -> f64 {
    let reach = reach.max(f64::MIN_POSITIVE);
    let key = |p: DVec3| (p / reach).floor().as_i64vec3();
    let mut grid: std::collections::HashMap<glam::I64Vec3, Vec<u32>> = Default::default();
    for (i, &p) in b.iter().enumerate() {
        grid.entry(key(p)).or_default().push(i as u32);
    }
    a.iter().fold(0.0, |worst: f64, &p| {
        let k = key(p);
        let mut best = f64::INFINITY;
        for dz in -1..=1 {
            for dy in -1..=1 {
                for dx in -1..=1 {
                    for &i in grid
                        .get(&(k + glam::I64Vec3::new(dx, dy, dz)))
                        .into_iter()
                        .flatten()
                    {
                        best = best.min(p.distance(b[i as usize]));
                    }
                }
            }
        }
        worst.max(if best <= reach { best } else { f64::INFINITY })
    })
}

/// The positions of the vertices some triangle uses (`indices`: three per triangle), in order:
/// the surface's points. Isolated vertices are left out — the Stanford bunny's file has 1 113,
/// which OpenSubdiv and the recursive reference carry along unchanged and the basis-function
/// tables' output leaves at the origin (no patch owns them).
pub fn surface_points(positions: &[DVec3], indices: &[u32]) -> Vec<DVec3> {
    let mut used = vec![false; positions.len()];
    for &i in indices {
        if let Some(u) = used.get_mut(i as usize) {
            *u = true;
        }
    }
    positions
        .iter()
        .zip(used)
        .filter_map(|(&p, u)| u.then_some(p))
        .collect()
}

/// [`max_nearest`] both ways: the Hausdorff distance of two point sets, where below `reach`.
pub fn hausdorff(a: &[DVec3], b: &[DVec3], reach: f64) -> f64 {
    max_nearest(a, b, reach).max(max_nearest(b, a, reach))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nearest_points_within_reach_and_beyond() {
        let a = [DVec3::ZERO, DVec3::new(1.0, 0.0, 0.0)];
        let b = [DVec3::new(0.0, 0.01, 0.0), DVec3::new(1.0, 0.0, 0.02)];
        assert!((max_nearest(&a, &b, 0.1) - 0.02).abs() < 1e-12);
        // Each point's nearest, not any: swapping b's points changes nothing.
        assert!((max_nearest(&a, &[b[1], b[0]], 0.1) - 0.02).abs() < 1e-12);
        // A point with nothing within reach makes the distance infinite.
        assert_eq!(max_nearest(&a, &b, 0.015), f64::INFINITY);
        assert_eq!(max_nearest(&a, &[], 1.0), f64::INFINITY);
        // Across cell borders: reach 0.1, points 0.05 apart either side of x = 0.
        let c = [DVec3::new(-0.025, 0.0, 0.0)];
        let d = [DVec3::new(0.025, 0.0, 0.0)];
        assert!((hausdorff(&c, &d, 0.1) - 0.05).abs() < 1e-12);
    }

    #[test]
    fn surface_points_leave_isolated_vertices_out() {
        let p = [DVec3::X, DVec3::Y, DVec3::Z, DVec3::ONE, DVec3::NEG_X];
        let s = surface_points(&p, &[0, 2, 3, 3, 2, 0, 9]);
        assert_eq!(s, vec![DVec3::X, DVec3::Z, DVec3::ONE]);
    }
}
