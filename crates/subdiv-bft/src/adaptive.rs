//! Adaptive tessellation (§2.2.3 "Adaptive Refinement", Figures 2.10/2.11): every M¹ edge has
//! its own tessellation factor, every patch is tessellated with the finest of its three edges,
//! and all vertices are still read from the same maximum-level tables (subsampled).
//!
//! A *factor* `f` is a level in log₂ segments, `0 ≤ f ≤ log₂ s_max`: an edge with factor `f`
//! has `2^⌈f⌉` segments, so all its vertices sit at dyadic positions the tables hold. The
//! fractional part drives the optional linear geomorph: a vertex that is new at `2^⌈f⌉`
//! segments moves from the midpoint of its two parents (the neighbours it splits) to its limit
//! position as `α = f − (⌈f⌉ − 1)` goes from 0 to 1 ("all vertices lying on a virtual mesh
//! subdivided at maximum level"), so an integer factor gives the limit surface exactly and the
//! surface changes continuously with `f`.
//!
//! Crack-free by the same argument as the uniform case: an edge's vertices depend only on the
//! edge's factor and are written once, by the edge's owner patch, into a vertex buffer laid out
//! for `s_max` segments ([`crate::patch::output_vertex`] at `s_max`). Inside a patch with `s`
//! segments, grid vertices on an edge with fewer segments `sₑ` are snapped to the nearest edge
//! vertex (rounding half up along the edge); the triangles that collapse are kept as degenerate
//! triangles (two equal indices), which rasterisers drop, so every patch writes exactly `s²`
//! triangles ([`Refined::without_collapsed`] removes them).

use glam::{Mat4, Vec3, Vec4Swizzles};
use rayon::prelude::*;

use crate::{
    Refined, SubdivError, Subdivider,
    bft::BftSet,
    mesh::Topology,
    patch::{Patches, padded_weights},
};

/// Segments and geomorph weight of a factor: `(2^⌈f⌉, f − (⌈f⌉ − 1))`, with `f` clamped to
/// `[0, log₂ max_segments]` (factor 0: one segment, weight 1). Mirrored by `split_factor` in
/// `evaluate.wgsl`.
pub fn split_factor(f: f32, max_segments: u32) -> (u32, f32) {
    let f = f.clamp(0.0, max_segments.ilog2() as f32);
    let c = f.ceil();
    if c == 0.0 {
        return (1, 1.0);
    }
    (1 << c as u32, f - (c - 1.0))
}

/// One patch's adaptive tessellation: segments of the patch and of its edges, geomorph weights.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PatchLevels {
    /// Segments of the patch grid: the largest of its edges'.
    pub segments: u32,
    /// Geomorph weight of the inner vertices (the finest edge's).
    pub alpha: f32,
    /// Segments of edge k (corner k → k + 1).
    pub edge_segments: [u32; 3],
    /// Geomorph weight of edge k's vertices.
    pub edge_alpha: [f32; 3],
}

impl PatchLevels {
    /// Levels of a patch from the factors of its edges.
    pub fn new(edge_factors: [f32; 3], max_segments: u32) -> Self {
        let split = edge_factors.map(|f| split_factor(f, max_segments));
        let (segments, alpha) = split_factor(
            edge_factors[0].max(edge_factors[1]).max(edge_factors[2]),
            max_segments,
        );
        Self {
            segments,
            alpha,
            edge_segments: split.map(|s| s.0),
            edge_alpha: split.map(|s| s.1),
        }
    }

    /// The edge a grid vertex lies on and its place along it (`t` from corner k), or `None`
    /// for corners and inner vertices.
    pub fn on_edge(&self, (i, j): (u32, u32)) -> Option<(usize, u32)> {
        let s = self.segments;
        if self.is_corner((i, j)) {
            return None;
        }
        match (i, j) {
            (_, 0) => Some((0, i)),
            _ if i + j == s => Some((1, j)),
            (0, _) => Some((2, s - j)),
            _ => None,
        }
    }

    /// Whether grid vertex `(i, j)` is one of the three corners.
    pub fn is_corner(&self, (i, j): (u32, u32)) -> bool {
        let s = self.segments;
        (i, j) == (0, 0) || (i, j) == (s, 0) || (i, j) == (0, s)
    }

    /// Grid vertex `t` segments along edge k from corner k.
    pub fn edge_point(&self, k: usize, t: u32) -> (u32, u32) {
        let s = self.segments;
        match k {
            0 => (t, 0),
            1 => (s - t, t),
            _ => (0, s - t),
        }
    }

    /// Grid steps between two vertices of edge k.
    fn edge_step(&self, k: usize) -> u32 {
        self.segments / self.edge_segments[k]
    }

    /// The vertex grid vertex `(i, j)` becomes: itself, or on a coarser edge the nearest edge
    /// vertex (half up along the edge).
    pub fn snap(&self, ij: (u32, u32)) -> (u32, u32) {
        match self.on_edge(ij) {
            Some((k, t)) => {
                let r = self.edge_step(k);
                self.edge_point(k, (t + r / 2) / r * r)
            }
            None => ij,
        }
    }

    /// Whether grid vertex `(i, j)` is a vertex of the tessellation (not snapped away).
    pub fn is_vertex(&self, ij: (u32, u32)) -> bool {
        self.on_edge(ij)
            .is_none_or(|(k, t)| t.is_multiple_of(self.edge_step(k)))
    }

    /// The geomorph of vertex `(i, j)`: its two parents (snapped) and weight, or `None` for a
    /// vertex that exists at the coarser level too.
    pub fn morph(&self, (i, j): (u32, u32)) -> Option<((u32, u32), (u32, u32), f32)> {
        if let Some((k, t)) = self.on_edge((i, j)) {
            let r = self.edge_step(k);
            return (self.edge_segments[k] > 1 && (t / r) % 2 == 1).then(|| {
                (
                    self.edge_point(k, t - r),
                    self.edge_point(k, t + r),
                    self.edge_alpha[k],
                )
            });
        }
        if self.is_corner((i, j)) {
            return None;
        }
        let (a, b) = match (i % 2, j % 2) {
            (0, 0) => return None,
            (1, 0) => ((i - 1, j), (i + 1, j)),
            (0, _) => ((i, j - 1), (i, j + 1)),
            // Both odd: the midpoint of a diagonal of the coarser grid (`(i + 1, j)` to
            // `(i, j + 1)` in `Patches::triangulate`).
            _ => ((i + 1, j - 1), (i - 1, j + 1)),
        };
        Some((self.snap(a), self.snap(b), self.alpha))
    }

    /// The `s²` triangles of the patch in grid coordinates, snapped (some collapse), in the
    /// order of [`Patches::triangulate`].
    pub fn triangles(&self) -> Vec<[(u32, u32); 3]> {
        let s = self.segments;
        let mut out = Vec::with_capacity((s * s) as usize);
        for j in 0..s {
            for i in 0..s - j {
                out.push([(i, j), (i + 1, j), (i, j + 1)].map(|v| self.snap(v)));
                if i + j + 1 < s {
                    out.push([(i + 1, j), (i + 1, j + 1), (i, j + 1)].map(|v| self.snap(v)));
                }
            }
        }
        out
    }
}

/// Checks a factor list: one finite factor per M¹ edge.
pub fn check_factors(factors: &[f32], edge_count: u32) -> Result<(), SubdivError> {
    if factors.len() != edge_count as usize {
        return Err(SubdivError::Factors(format!(
            "{} factors given, M¹ has {edge_count} edges",
            factors.len()
        )));
    }
    match factors.iter().position(|f| !f.is_finite()) {
        Some(e) => Err(SubdivError::Factors(format!(
            "factor of M¹ edge {e} is not finite"
        ))),
        None => Ok(()),
    }
}

/// The view the screen-space metric measures edges in.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScreenView {
    /// World → clip transform.
    pub view_proj: Mat4,
    /// Image size in pixels.
    pub viewport: (u32, u32),
    /// Wanted length of a fine edge in pixels (> 0).
    pub target_pixels: f32,
}

impl ScreenView {
    /// Checks the view: a finite matrix, a non-empty viewport, a positive finite target.
    pub fn check(&self) -> Result<(), SubdivError> {
        if !self.view_proj.is_finite()
            || self.viewport.0 == 0
            || self.viewport.1 == 0
            || !(self.target_pixels.is_finite() && self.target_pixels > 0.0)
        {
            return Err(SubdivError::Factors(format!(
                "the screen-space metric needs a finite matrix, a non-empty viewport and a positive \
                 target edge length (got {:?} pixels, target {})",
                self.viewport, self.target_pixels
            )));
        }
        Ok(())
    }

    /// Factor of an edge (§2.1.2's view-dependent metric): enough segments that its fine edges
    /// are about `target_pixels` long on screen, `f = log₂(projected length / target_pixels)`,
    /// clamped to `[0, log₂ max_segments]`. Entirely behind the eye: 0; crossing the eye plane:
    /// the maximum. Mirrored by `edge_factors` in `factors.wgsl`.
    pub fn factor(&self, ends: [Vec3; 2], max_segments: u32) -> f32 {
        let max = max_segments.ilog2() as f32;
        let [a, b] = ends.map(|p| self.view_proj * p.extend(1.0));
        if a.w <= 0.0 && b.w <= 0.0 {
            return 0.0;
        }
        if a.w <= 0.0 || b.w <= 0.0 {
            return max;
        }
        let half = glam::Vec2::new(self.viewport.0 as f32, self.viewport.1 as f32) * 0.5;
        let d = (a.xy() / a.w - b.xy() / b.w) * half;
        (d.length() / self.target_pixels).log2().clamp(0.0, max)
    }
}

/// Screen-space factors of every M¹ edge ([`ScreenView::factor`]).
pub fn screen_factors(
    m1: &Topology,
    m1_positions: &[Vec3],
    view: &ScreenView,
    max_segments: u32,
) -> Vec<f32> {
    m1.edges
        .par_iter()
        .map(|&h| {
            view.factor(
                [m1.origin(h), m1.dest(h)].map(|v| m1_positions[v as usize]),
                max_segments,
            )
        })
        .collect()
}

impl Patches {
    /// Levels of patch `p` from the per-edge factors.
    pub fn patch_levels(&self, p: usize, factors: &[f32], max_segments: u32) -> PatchLevels {
        let e = self.patches[p].edges;
        PatchLevels::new(
            [0, 1, 2].map(|k| factors[(e[k] & !crate::patch::REVERSED) as usize]),
            max_segments,
        )
    }

    /// Triangle list of the adaptive tessellation: `s²` triangles per patch (collapsed ones
    /// included, see the module docs), indices into the `max_segments` vertex layout.
    pub fn triangulate_adaptive(&self, factors: &[f32], max_segments: u32) -> Vec<u32> {
        (0..self.patches.len())
            .into_par_iter()
            .flat_map_iter(|p| {
                let levels = self.patch_levels(p, factors, max_segments);
                let m = max_segments / levels.segments;
                levels.triangles().into_iter().flat_map(move |t| {
                    t.map(|(i, j)| self.output_vertex(p, i * m, j * m, max_segments).0)
                })
            })
            .collect()
    }

    /// CPU mirror of `evaluate_adaptive` in `evaluate.wgsl`: every vertex of the adaptive
    /// tessellation (with geomorph), in a vertex buffer laid out for `max_segments`; slots of
    /// the layout that the tessellation does not use stay zero.
    pub fn evaluate_adaptive(
        &self,
        bft: &BftSet,
        factors: &[f32],
        max_segments: u32,
        m1_positions: &[Vec3],
        m1_normals: &[Vec3],
    ) -> (Vec<Vec3>, Vec<Vec3>) {
        let (weights, _) = padded_weights(bft);
        let per_patch: Vec<Vec<(u32, Vec3, Vec3)>> = (0..self.patches.len())
            .into_par_iter()
            .map(|p| {
                let levels = self.patch_levels(p, factors, max_segments);
                let s = levels.segments;
                let m = max_segments / s;
                let eval = |(i, j)| {
                    self.evaluate_at(bft, &weights, p, (i, j, s), m1_positions, m1_normals)
                };
                let mut out = Vec::new();
                for j in 0..=s {
                    for i in 0..=s - j {
                        if !levels.is_vertex((i, j)) {
                            continue;
                        }
                        let (o, owned) = self.output_vertex(p, i * m, j * m, max_segments);
                        if !owned {
                            continue;
                        }
                        let (mut pos, mut nrm) = eval((i, j));
                        if let Some((a, b, alpha)) =
                            levels.morph((i, j)).filter(|&(_, _, alpha)| alpha < 1.0)
                        {
                            let ((pa, na), (pb, nb)) = (eval(a), eval(b));
                            let (mp, mn) = (0.5 * (pa + pb), 0.5 * (na + nb));
                            pos = mp + alpha * (pos - mp);
                            nrm = (mn + alpha * (nrm - mn)).normalize_or_zero();
                        }
                        out.push((o, pos, nrm));
                    }
                }
                out
            })
            .collect();
        crate::patch::scatter(per_patch, self.output_vertex_count(max_segments))
    }
}

impl Subdivider {
    /// The whole adaptive pipeline on the CPU: initial step, then every patch with the
    /// per-M¹-edge `factors` (see the [module docs](self)), up to surface level `max_level`.
    pub fn evaluate_adaptive_cpu(
        &self,
        bft: &BftSet,
        m0_positions: &[Vec3],
        factors: &[f32],
        max_level: u32,
    ) -> Result<Refined, SubdivError> {
        let s = self.segments(max_level)?;
        check_factors(factors, self.patches.edge_count)?;
        let (p1, n1) = self.initial_step_f32(m0_positions)?;
        let (positions, normals) = self.patches.evaluate_adaptive(bft, factors, s, &p1, &n1);
        Ok(Refined {
            positions,
            normals,
            indices: self.patches.triangulate_adaptive(factors, s),
        })
    }
}

impl Refined {
    /// The mesh without the collapsed triangles of an adaptive tessellation and without the
    /// vertices no triangle uses (indices renumbered in first-use order).
    pub fn without_collapsed(&self) -> Refined {
        let mut map = vec![u32::MAX; self.positions.len()];
        let mut out = Refined::default();
        for t in self.indices.chunks_exact(3) {
            if t[0] == t[1] || t[1] == t[2] || t[2] == t[0] {
                continue;
            }
            for &v in t {
                if map[v as usize] == u32::MAX {
                    map[v as usize] = out.positions.len() as u32;
                    out.positions.push(self.positions[v as usize]);
                    out.normals.push(self.normals[v as usize]);
                }
                out.indices.push(map[v as usize]);
            }
        }
        out
    }
}
