//! Surfels (§3.5.3, pre-process): the scene's surface sampled uniformly by area into `2^d`
//! points, each stored as `(s, t, triangle)` — barycentric coordinates `(s, t, u = 1 − s − t)`
//! on a triangle — so that deforming the mesh moves the points with it.

use glam::Vec3;
use rayon::prelude::*;

use crate::ManyLodError;

/// A surface sample: `s·a + t·b + (1 − s − t)·c` on triangle `triangle` (corners a, b, c).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Surfel {
    /// Barycentric weight of the triangle's first corner.
    pub s: f32,
    /// Barycentric weight of the second corner.
    pub t: f32,
    /// Triangle index.
    pub triangle: u32,
}

/// Checks a triangle mesh: indices in range, a multiple of three, finite positions.
pub fn check_mesh(positions: &[Vec3], indices: &[u32]) -> Result<(), ManyLodError> {
    if indices.is_empty() || !indices.len().is_multiple_of(3) {
        return Err(ManyLodError::Mesh(format!(
            "{} indices: need a non-empty multiple of 3",
            indices.len()
        )));
    }
    if let Some(k) = indices.iter().position(|&i| i as usize >= positions.len()) {
        return Err(ManyLodError::Mesh(format!(
            "index {k} is {} but there are {} positions",
            indices[k],
            positions.len()
        )));
    }
    if let Some(index) = positions.iter().position(|p| !p.is_finite()) {
        return Err(ManyLodError::NonFinite {
            what: "position",
            index,
        });
    }
    Ok(())
}

/// The R₃ low-discrepancy sequence (generalised golden ratio), shifted by `seed`.
fn r3(i: u64, seed: u64) -> [f64; 3] {
    const G: f64 = 1.220_744_084_605_759_5; // root of x⁴ = x + 1
    let a = [1.0 / G, 1.0 / (G * G), 1.0 / (G * G * G)];
    let shift = (seed as f64 * 0.618_033_988_749_894_9).fract();
    a.map(|ak| (shift + 0.5 + ak * i as f64).fract())
}

/// `count` surfels uniform by area (stratified along the area CDF, R₃ within triangles), the
/// same for the same `seed`.
///
/// Errors: a bad mesh ([`check_mesh`]), no area, `count` not a power of two in `1..=2^26`.
pub fn sample(
    positions: &[Vec3],
    indices: &[u32],
    count: usize,
    seed: u64,
) -> Result<Vec<Surfel>, ManyLodError> {
    check_mesh(positions, indices)?;
    if !count.is_power_of_two() || count > 1 << 26 {
        return Err(ManyLodError::PointCount(count));
    }
    let mut cdf = Vec::with_capacity(indices.len() / 3);
    let mut total = 0.0f64;
    for t in indices.chunks_exact(3) {
        let [a, b, c] = [t[0], t[1], t[2]].map(|i| positions[i as usize].as_dvec3());
        total += 0.5 * (b - a).cross(c - a).length();
        cdf.push(total);
    }
    if total <= 0.0 || !total.is_finite() {
        return Err(ManyLodError::Mesh("the mesh has no area".into()));
    }
    Ok((0..count as u64)
        .into_par_iter()
        .map(|i| {
            let [x, y, z] = r3(i, seed);
            let u = (i as f64 + x) / count as f64 * total;
            let triangle = cdf.partition_point(|&c| c <= u).min(cdf.len() - 1);
            let r = y.sqrt();
            Surfel {
                s: (1.0 - r) as f32,
                t: (z * r) as f32,
                triangle: triangle as u32,
            }
        })
        .collect())
}

/// Positions and unit face normals of `surfels` on the (possibly deformed) mesh.
pub fn evaluate(surfels: &[Surfel], positions: &[Vec3], indices: &[u32]) -> (Vec<Vec3>, Vec<Vec3>) {
    surfels
        .par_iter()
        .map(|p| {
            let t = &indices[3 * p.triangle as usize..][..3];
            let [a, b, c] = [t[0], t[1], t[2]].map(|i| positions[i as usize]);
            (
                p.s * a + p.t * b + (1.0 - p.s - p.t) * c,
                (b - a).cross(c - a).normalize_or_zero(),
            )
        })
        .unzip()
}

/// Radius of a disc with a `1 / count` share of the area: the leaves' bounding spheres.
pub fn disc_radius(positions: &[Vec3], indices: &[u32], count: usize) -> f32 {
    (mesh_area(positions, indices) / (count as f32 * std::f32::consts::PI)).sqrt()
}

/// The total area of a triangle mesh.
pub fn mesh_area(positions: &[Vec3], indices: &[u32]) -> f32 {
    indices
        .chunks_exact(3)
        .map(|t| {
            let [a, b, c] = [t[0], t[1], t[2]].map(|i| positions[i as usize]);
            0.5 * (b - a).cross(c - a).length()
        })
        .sum()
}
