//! The main step (§2.2.3): per M¹ face a patch record (Listing 2.1's `BFTPatch`), uniform
//! tessellation of every patch by subsampling the level-L tables, and the CPU mirror of the
//! GPU evaluation.
//!
//! Output layout: one vertex per fine vertex of the whole mesh, shared by the patches that
//! touch it, so shared edges are crack-free by construction: first the M¹ vertices, then
//! `s − 1` vertices per M¹ edge (from its lower to its higher vertex index), then the
//! `(s − 1)(s − 2)/2` inner vertices of every patch. Each vertex is evaluated by exactly one
//! patch (its *owner*: the lowest-numbered face touching it).

use bytemuck::{Pod, Zeroable};
use glam::Vec3;
use rayon::prelude::*;

use crate::{
    SubdivError,
    bft::{BftSet, face_key, face_ring, grid_count, grid_index},
    mesh::{NONE, Topology},
};

/// Listing 2.1's `BFTPatch`, as the GPU reads it (mirrored in `evaluate.wgsl`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct GpuPatch {
    /// First entry of the patch's one-ring in the ring index list (`m_uiPoints`).
    pub ring_offset: u32,
    /// One-ring size (`m_uiOneRingSize`).
    pub ring_size: u32,
    /// Table (`m_uiIndexBFT`), as the offset of its first weight in vec4 units.
    pub table_offset: u32,
    /// Bits 0–2: the patch evaluates corner k; bits 3–5: it evaluates edge k.
    pub owned: u32,
    /// The three corners (M¹ vertex indices) in table order; w unused.
    pub corners: [u32; 4],
    /// Edge k (corner k → k + 1): M¹ edge index, bit 31 set when the edge runs from the
    /// higher to the lower vertex; w unused.
    pub edges: [u32; 4],
}

/// Patches of every M¹ face with the shared tables.
#[derive(Clone, Debug, PartialEq)]
pub struct Patches {
    /// One per M¹ triangle.
    pub patches: Vec<GpuPatch>,
    /// One-ring vertex indices of all patches (M¹ vertices).
    pub rings: Vec<u32>,
    /// Table index of each patch.
    pub tables: Vec<u32>,
    /// Number of M¹ vertices.
    pub vertex_count: u32,
    /// Number of M¹ edges.
    pub edge_count: u32,
}

/// Bit of [`GpuPatch::edges`] set when the edge runs from the higher to the lower vertex.
pub(crate) const REVERSED: u32 = 1 << 31;

/// Table weights padded to vec4 per grid vertex, and each table's offset in vec4 units.
pub fn padded_weights(bft: &BftSet) -> (Vec<f32>, Vec<u32>) {
    let mut out = Vec::new();
    let mut offsets = Vec::new();
    for t in &bft.tables {
        offsets.push((out.len() / 4) as u32);
        let r = t.ring_size as usize;
        for row in t.weights.chunks_exact(r.max(1)) {
            out.extend_from_slice(row);
            out.resize(out.len().next_multiple_of(4), 0.0);
        }
    }
    (out, offsets)
}

impl Patches {
    /// Patch records of every face of `m1` (the once-subdivided mesh).
    ///
    /// Errors: a face whose configuration has no table (a vertex of valence above the tables'
    /// maximum), or whose one-ring folds onto itself (a mesh too small for its configuration).
    pub fn new(m1: &Topology, bft: &BftSet) -> Result<Self, SubdivError> {
        let (_, table_offsets) = padded_weights(bft);
        let mut lowest_face = vec![u32::MAX; m1.vertex_count()];
        for (f, t) in m1.triangles.iter().enumerate() {
            for &v in t {
                lowest_face[v as usize] = lowest_face[v as usize].min(f as u32);
            }
        }
        let per_face = (0..m1.triangles.len() as u32)
            .into_par_iter()
            .map(|f| {
                let (key, r) = face_key(m1, f);
                let table = bft.find(&key).ok_or_else(|| SubdivError::NoTable {
                    face: f,
                    valence: key.iter().map(|c| c.valence()).max().unwrap_or(0),
                    boundary: key
                        .iter()
                        .any(|c| matches!(c, crate::bft::Corner::Boundary { .. })),
                })?;
                let ring = face_ring(m1, f, r);
                if ring.len() != bft.tables[table as usize].ring_size as usize {
                    return Err(SubdivError::RingFolds { face: f });
                }
                let hs = [0, 1, 2].map(|i| 3 * f + (r + i) % 3);
                let corners = hs.map(|h| m1.origin(h));
                let mut owned = 0;
                let mut edges = [0u32; 4];
                for k in 0..3 {
                    if lowest_face[corners[k] as usize] == f {
                        owned |= 1 << k;
                    }
                    let t = m1.twin[hs[k] as usize];
                    if t == NONE || f < t / 3 {
                        owned |= 1 << (3 + k);
                    }
                    edges[k] = m1.edge_of[hs[k] as usize]
                        | if corners[k] > corners[(k + 1) % 3] {
                            REVERSED
                        } else {
                            0
                        };
                }
                let patch = GpuPatch {
                    ring_offset: 0,
                    ring_size: ring.len() as u32,
                    table_offset: table_offsets[table as usize],
                    owned,
                    corners: [corners[0], corners[1], corners[2], 0],
                    edges,
                };
                Ok((patch, ring, table))
            })
            .collect::<Result<Vec<_>, SubdivError>>()?;
        let mut patches = Vec::with_capacity(per_face.len());
        let mut rings = Vec::new();
        let mut tables = Vec::with_capacity(per_face.len());
        for (mut p, ring, t) in per_face {
            p.ring_offset = rings.len() as u32;
            rings.extend(ring);
            patches.push(p);
            tables.push(t);
        }
        Ok(Self {
            patches,
            rings,
            tables,
            vertex_count: m1.vertex_count() as u32,
            edge_count: m1.edges.len() as u32,
        })
    }

    /// Number of output vertices at `s` segments per patch edge.
    pub fn output_vertex_count(&self, s: u32) -> usize {
        self.vertex_count as usize
            + self.edge_count as usize * (s as usize - 1)
            + self.patches.len() * inner_count(s)
    }

    /// Output vertex of grid vertex `(i, j)` of patch `p` at `s` segments, and whether `p`
    /// evaluates it.
    pub fn output_vertex(&self, p: usize, i: u32, j: u32, s: u32) -> (u32, bool) {
        output_vertex(
            &self.patches[p],
            p as u32,
            i,
            j,
            s,
            self.vertex_count,
            self.edge_count,
        )
    }

    /// Triangle list of the uniform tessellation at `s` segments per patch edge.
    pub fn triangulate(&self, s: u32) -> Vec<u32> {
        (0..self.patches.len())
            .into_par_iter()
            .flat_map_iter(|p| {
                let mut out = Vec::with_capacity(3 * (s * s) as usize);
                let v = |i, j| self.output_vertex(p, i, j, s).0;
                for j in 0..s {
                    for i in 0..s - j {
                        out.extend([v(i, j), v(i + 1, j), v(i, j + 1)]);
                        if i + j + 1 < s {
                            out.extend([v(i + 1, j), v(i + 1, j + 1), v(i, j + 1)]);
                        }
                    }
                }
                out
            })
            .collect()
    }

    /// Position and normal of grid vertex `(i, j)` of patch `p` at `s` segments with that
    /// patch's table (f32, the shader's order of operations), whether or not it owns it.
    #[allow(clippy::too_many_arguments)]
    pub fn evaluate_at(
        &self,
        bft: &BftSet,
        weights: &[f32],
        p: usize,
        (i, j, s): (u32, u32, u32),
        m1_positions: &[Vec3],
        m1_normals: &[Vec3],
    ) -> (Vec3, Vec3) {
        let patch = &self.patches[p];
        let ring = &self.rings[patch.ring_offset as usize..][..patch.ring_size as usize];
        let stride = patch.ring_size.div_ceil(4) as usize * 4;
        let step = bft.segments() / s;
        let g = grid_index(i * step, j * step, bft.segments());
        let w = &weights[patch.table_offset as usize * 4 + g * stride..];
        let (mut pos, mut nrm) = (Vec3::ZERO, Vec3::ZERO);
        for (r, &v) in ring.iter().enumerate() {
            pos += w[r] * m1_positions[v as usize];
            nrm += w[r] * m1_normals[v as usize];
        }
        (pos, nrm.normalize_or_zero())
    }

    /// CPU mirror of `evaluate.wgsl`: every output vertex at `s` segments from the M¹ positions
    /// and normals, each evaluated by its owner patch.
    pub fn evaluate(
        &self,
        bft: &BftSet,
        s: u32,
        m1_positions: &[Vec3],
        m1_normals: &[Vec3],
    ) -> (Vec<Vec3>, Vec<Vec3>) {
        let (weights, _) = padded_weights(bft);
        let n = self.output_vertex_count(s);
        let per_patch: Vec<Vec<(u32, Vec3, Vec3)>> = (0..self.patches.len())
            .into_par_iter()
            .map(|p| {
                let mut out = Vec::new();
                for j in 0..=s {
                    for i in 0..=s - j {
                        let (o, owned) = self.output_vertex(p, i, j, s);
                        if owned {
                            let (pos, nrm) = self.evaluate_at(
                                bft,
                                &weights,
                                p,
                                (i, j, s),
                                m1_positions,
                                m1_normals,
                            );
                            out.push((o, pos, nrm));
                        }
                    }
                }
                out
            })
            .collect();
        scatter(per_patch, n)
    }
}

/// Inner vertices of a patch at `s` segments.
pub fn inner_count(s: u32) -> usize {
    if s < 3 {
        0
    } else {
        ((s - 1) * (s - 2) / 2) as usize
    }
}

/// See [`Patches::output_vertex`]; mirrored by `output_vertex` in `evaluate.wgsl`.
pub fn output_vertex(
    patch: &GpuPatch,
    p: u32,
    i: u32,
    j: u32,
    s: u32,
    vertex_count: u32,
    edge_count: u32,
) -> (u32, bool) {
    let corner = |k: usize| (patch.corners[k], patch.owned >> k & 1 == 1);
    let edge = |k: usize, t: u32| {
        let e = patch.edges[k];
        let along = if e & REVERSED != 0 { s - t } else { t };
        (
            vertex_count + (e & !REVERSED) * (s - 1) + along - 1,
            patch.owned >> (3 + k) & 1 == 1,
        )
    };
    match (i, j) {
        (0, 0) => corner(0),
        (_, 0) if i == s => corner(1),
        (0, _) if j == s => corner(2),
        (_, 0) => edge(0, i),
        _ if i + j == s => edge(1, j),
        (0, _) => edge(2, s - j),
        _ => {
            let row = (j - 1) * (s - 1) - (j - 1) * j / 2;
            let base = vertex_count + edge_count * (s - 1) + p * inner_count(s) as u32;
            (base + row + i - 1, true)
        }
    }
}

/// Grid coordinates `(i, j)` packed as `i | j << 16` in the order the GPU kernel walks them.
pub fn grid_walk(s: u32) -> Vec<u32> {
    let mut out = vec![0; grid_count(s)];
    for j in 0..=s {
        for i in 0..=s - j {
            out[grid_index(i, j, s)] = i | j << 16;
        }
    }
    out
}

/// Triangles of the `s`-segment grid in [`Patches::triangulate`] order, packed as
/// `i | j << 8 | down << 16` (down: the triangle `(i + 1, j), (i + 1, j + 1), (i, j + 1)`).
pub fn triangle_walk(s: u32) -> Vec<u32> {
    let mut out = Vec::with_capacity((s * s) as usize);
    for j in 0..s {
        for i in 0..s - j {
            out.push(i | j << 8);
            if i + j + 1 < s {
                out.push(i | j << 8 | 1 << 16);
            }
        }
    }
    out
}

/// The `n` output vertices from each patch's `(output index, position, normal)` list (shared
/// vertices are written by every patch that holds them, with the same values).
pub(crate) fn scatter(per_patch: Vec<Vec<(u32, Vec3, Vec3)>>, n: usize) -> (Vec<Vec3>, Vec<Vec3>) {
    let mut positions = vec![Vec3::ZERO; n];
    let mut normals = vec![Vec3::ZERO; n];
    for (o, p, q) in per_patch.into_iter().flatten() {
        positions[o as usize] = p;
        normals[o as usize] = q;
    }
    (positions, normals)
}
