//! CPU reference: recursive Loop subdivision with Loop's weights, boundary rules, limit masks
//! and limit normals (§2.1.1), and the one-step computational entries of §2.2.2.
//!
//! Every refinement is a [`Stencils`] matrix (rows of weights over the coarser vertices), so
//! the same code subdivides positions and the unit basis vectors of a configuration mesh
//! (the BFT construction of §2.2.1).

use std::f64::consts::PI;

use glam::DVec3;
use rayon::prelude::*;

use crate::mesh::{Fan, NONE, Topology, prev};

/// Sparse linear map from coarse to fine values: fine value `i` is
/// `Σ weights[k] · coarse[indices[k]]` for `k` in `offsets[i]..offsets[i + 1]`.
///
/// The stencils of the step M⁰ → M¹ are the paper's *computational entries* (§2.2.2).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Stencils {
    /// Row starts, one more than rows.
    pub offsets: Vec<u32>,
    /// Coarse vertex of each entry.
    pub indices: Vec<u32>,
    /// Weight of each entry.
    pub weights: Vec<f64>,
}

impl Stencils {
    fn with_rows(rows: impl IntoIterator<Item = Vec<(u32, f64)>>) -> Self {
        let mut s = Self {
            offsets: vec![0],
            ..Self::default()
        };
        for row in rows {
            for (i, w) in row {
                s.indices.push(i);
                s.weights.push(w);
            }
            s.offsets.push(s.indices.len() as u32);
        }
        s
    }

    /// Number of fine values.
    pub fn rows(&self) -> usize {
        self.offsets.len() - 1
    }

    /// One row as (coarse vertex, weight) pairs.
    pub fn row(&self, i: usize) -> impl Iterator<Item = (u32, f64)> + '_ {
        let r = self.offsets[i] as usize..self.offsets[i + 1] as usize;
        self.indices[r.clone()]
            .iter()
            .copied()
            .zip(self.weights[r].iter().copied())
    }

    /// Applies the stencils to values of `stride` numbers per vertex.
    pub fn apply_strided(&self, values: &[f64], stride: usize) -> Vec<f64> {
        let mut out = vec![0.0; self.rows() * stride];
        out.par_chunks_mut(stride.max(1))
            .enumerate()
            .for_each(|(i, o)| {
                for (j, w) in self.row(i) {
                    let src = &values[j as usize * stride..(j as usize + 1) * stride];
                    for (o, s) in o.iter_mut().zip(src) {
                        *o += w * s;
                    }
                }
            });
        out
    }

    /// Applies the stencils to positions.
    pub fn apply(&self, values: &[DVec3]) -> Vec<DVec3> {
        (0..self.rows())
            .into_par_iter()
            .map(|i| self.row(i).map(|(j, w)| w * values[j as usize]).sum())
            .collect()
    }
}

/// Loop's original vertex weight β(n) = (5/8 − (3/8 + ¼·cos(2π/n))²) / n, the one OpenSubdiv,
/// Hbr and trimesh use (not Warren's simplification).
pub fn loop_beta(n: usize) -> f64 {
    let c = 0.375 + 0.25 * (2.0 * PI / n as f64).cos();
    (0.625 - c * c) / n as f64
}

/// Vertex point of Loop's scheme: interior (1 − nβ)·v + β·Σ pᵢ; boundary ¾·v + ⅛·(p₀ + pₖ)
/// (boundary edges only: "edge only" boundary interpolation, no corners).
fn vertex_rule(v: u32, fan: &Fan) -> Vec<(u32, f64)> {
    let n = fan.valence();
    if n == 0 {
        vec![(v, 1.0)]
    } else if fan.boundary {
        vec![(v, 0.75), (fan.ring[0], 0.125), (fan.ring[n - 1], 0.125)]
    } else {
        let b = loop_beta(n);
        let mut row = vec![(v, 1.0 - n as f64 * b)];
        row.extend(fan.ring.iter().map(|&p| (p, b)));
        row
    }
}

/// One Loop step: the refined triangles and the stencils giving every fine vertex (old
/// vertices first, then one edge point per edge of [`Topology::edges`]).
///
/// Edge points: interior ⅜·(a + b) + ⅛·(c + d); boundary ½·(a + b). Triangle `f` becomes
/// `4f..4f + 4`: the three corner triangles, then the middle one.
pub fn loop_step(top: &Topology) -> (Vec<[u32; 3]>, Stencils) {
    let nv = top.vertex_count() as u32;
    let vertex_rows = (0..nv).into_par_iter().map(|v| vertex_rule(v, &top.fan(v)));
    let edge_rows = top.edges.par_iter().map(|&h| {
        let (a, b) = (top.origin(h), top.dest(h));
        let t = top.twin[h as usize];
        if t == NONE {
            vec![(a, 0.5), (b, 0.5)]
        } else {
            let c = top.origin(prev(h));
            let d = top.origin(prev(t));
            vec![(a, 0.375), (b, 0.375), (c, 0.125), (d, 0.125)]
        }
    });
    let rows: Vec<Vec<(u32, f64)>> = vertex_rows.chain(edge_rows).collect();
    let triangles = (0..top.triangles.len())
        .into_par_iter()
        .flat_map_iter(|f| {
            let [a, b, c] = top.triangles[f];
            let e = |i: usize| nv + top.edge_of[3 * f + i];
            let (ab, bc, ca) = (e(0), e(1), e(2));
            [[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]
        })
        .collect();
    (triangles, Stencils::with_rows(rows))
}

/// A triangle mesh: validated topology and positions.
#[derive(Clone, Debug, PartialEq)]
pub struct TriMesh {
    /// Connectivity.
    pub topology: Topology,
    /// One position per vertex.
    pub positions: Vec<DVec3>,
}

/// The most triangles [`TriMesh::subdivide`] produces: 2^26 (32 M vertices of `DVec3` plus
/// their topology, about 2 GiB).
pub const MAX_REFINED_TRIANGLES: usize = 1 << 26;

impl TriMesh {
    /// Validates `triangles` (see [`Topology::new`]) and the positions (finite).
    pub fn new(
        positions: Vec<DVec3>,
        triangles: Vec<[u32; 3]>,
    ) -> Result<Self, crate::SubdivError> {
        if let Some(i) = positions.iter().position(|p| !p.is_finite()) {
            return Err(crate::SubdivError::NonFinite { vertex: i });
        }
        Ok(Self {
            topology: Topology::new(positions.len(), triangles)?,
            positions,
        })
    }

    /// Diagonal of the bounding box.
    pub fn diagonal(&self) -> f64 {
        let (lo, hi) = self.positions.iter().fold(
            (DVec3::splat(f64::MAX), DVec3::splat(f64::MIN)),
            |(lo, hi), &p| (lo.min(p), hi.max(p)),
        );
        if self.positions.is_empty() {
            0.0
        } else {
            (hi - lo).length()
        }
    }

    /// One Loop step.
    pub fn step(&self) -> Result<Self, crate::SubdivError> {
        let (triangles, stencils) = loop_step(&self.topology);
        Ok(Self {
            topology: Topology::new(stencils.rows(), triangles)?,
            positions: stencils.apply(&self.positions),
        })
    }

    /// `levels` recursive Loop steps (the refined, not limit, mesh Mᵏ).
    pub fn subdivide(&self, levels: u32) -> Result<Self, crate::SubdivError> {
        let triangles = self.topology.triangles.len() as u128;
        if levels >= 32 || triangles << (2 * levels) > MAX_REFINED_TRIANGLES as u128 {
            return Err(crate::SubdivError::TooLarge(format!(
                "level {levels} of {triangles} triangles makes {triangles}·4^{levels}, more than \
                 the {MAX_REFINED_TRIANGLES} triangles of the CPU reference (about 2 GiB)"
            )));
        }
        let mut m = self.clone();
        for _ in 0..levels {
            m = m.step()?;
        }
        Ok(m)
    }

    /// Every vertex projected to its limit position ([`limit_stencils`]).
    pub fn limit_positions(&self) -> Vec<DVec3> {
        limit_stencils(&self.topology).apply(&self.positions)
    }

    /// Unit limit normals from the tangent masks ([`limit_normal`]).
    pub fn limit_normals(&self) -> Vec<DVec3> {
        (0..self.topology.vertex_count() as u32)
            .into_par_iter()
            .map(|v| {
                limit_normal(
                    self.positions[v as usize],
                    &self.topology.fan(v),
                    &self.positions,
                )
            })
            .collect()
    }
}

/// Limit-position masks: interior (1 − nχ)·v + χ·Σ pᵢ with χ = 1 / (3/(8β) + n); boundary
/// (the cubic B-spline of the boundary curve) ⅔·v + ⅙·(p₀ + pₖ).
pub fn limit_stencils(top: &Topology) -> Stencils {
    Stencils::with_rows(
        (0..top.vertex_count() as u32)
            .map(|v| {
                let fan = top.fan(v);
                let n = fan.valence();
                if n == 0 {
                    vec![(v, 1.0)]
                } else if fan.boundary {
                    vec![
                        (v, 2.0 / 3.0),
                        (fan.ring[0], 1.0 / 6.0),
                        (fan.ring[n - 1], 1.0 / 6.0),
                    ]
                } else {
                    let chi = 1.0 / (3.0 / (8.0 * loop_beta(n)) + n as f64);
                    let mut row = vec![(v, 1.0 - n as f64 * chi)];
                    row.extend(fan.ring.iter().map(|&p| (p, chi)));
                    row
                }
            })
            .collect::<Vec<_>>(),
    )
}

/// Unit limit normal of a vertex from Loop's tangent masks.
///
/// Interior: t₁ = Σ cos(2πi/n)·pᵢ, t₂ = Σ sin(2πi/n)·pᵢ, n = t₁ × t₂. Boundary (ring p₀ … pₖ
/// over k triangles, p₀ and pₖ on the boundary): along = p₀ − pₖ; across (into the surface)
/// is the left eigenvector of the local subdivision matrix of the standard rules for
/// λ = ⅜ + ¼·cos(π/k): Σ sin(iπ/k)·pᵢ + a·(p₀ + pₖ) + b·v with a, b solving its two boundary
/// equations (k = 2 gives p₁ − v as in Hoppe et al. 1994; k = 1: p₀ + p₁ − 2v);
/// n = along × across. Being eigenvectors, both masks give the same normal at every level.
/// Zero for an unused or flat-degenerate vertex.
pub fn limit_normal(v: DVec3, fan: &Fan, positions: &[DVec3]) -> DVec3 {
    let p = |i: usize| positions[fan.ring[i] as usize];
    let n = fan.valence();
    let normal = if n == 0 {
        DVec3::ZERO
    } else if fan.boundary {
        let k = n - 1;
        let along = p(0) - p(k);
        let across = if k == 1 {
            p(0) + p(1) - 2.0 * v
        } else {
            let t = PI / k as f64;
            let lambda = 0.375 + 0.25 * t.cos();
            let (mut inner, mut sum) = (DVec3::ZERO, 0.0);
            for i in 1..k {
                let w = (i as f64 * t).sin();
                inner += w * p(i);
                sum += w;
            }
            let a = (0.375 * sum + (lambda - 0.75) * t.sin())
                / (8.0 * (lambda - 0.75) * (lambda - 0.5) - 1.0);
            let b = 8.0 * (lambda - 0.5) * a - t.sin();
            inner + a * (p(0) + p(k)) + b * v
        };
        along.cross(across)
    } else {
        let (mut t1, mut t2) = (DVec3::ZERO, DVec3::ZERO);
        for i in 0..n {
            let a = 2.0 * PI * i as f64 / n as f64;
            t1 += a.cos() * p(i);
            t2 += a.sin() * p(i);
        }
        t1.cross(t2)
    };
    normal.normalize_or_zero()
}
