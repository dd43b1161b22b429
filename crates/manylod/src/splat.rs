//! Splatting a multi-cut into one atlas of per-view tiles (§3.7.2): every drawn node-view is a
//! disc ([`View::splat`]) whose covered pixels (pixel centre inside the disc) take the minimum
//! of a 32-bit packed depth — the FreePipe encoding with the thesis's correction.
//!
//! [`pack_depth`]: the depth `d ∈ [0, 1]` is mapped to `m = 0.5 + d/2 ∈ [0.5, 1]`, whose IEEE
//! bits have sign 0 and exponent 126, so the 23 mantissa bits shifted left by 9 order like `d`;
//! the low 12 bits are left for colour. The thesis notes that `1.0` (exponent 127) breaks this
//! (it would pack to 0, the near plane); here `m` is clamped below 1 instead of neglected.
//! The atlas is cleared to `0xFFFFFFFF` (farther than any depth).

use rayon::prelude::*;

use crate::{ManyLodError, Node, NodeView, View, cut::CULLED};

/// Packed value of an empty pixel.
pub const CLEAR: u32 = 0xFFFF_FFFF;

/// The FreePipe depth word of `depth ∈ [0, 1]` with 12 bits of `colour` (0 for depth only).
pub fn pack_depth(depth: f32, colour: u32) -> u32 {
    let m = (0.5 + 0.5 * depth.clamp(0.0, 1.0)).min(f32::from_bits(0x3F7F_FFFF));
    ((m.to_bits() << 9) & 0xFFFF_F000) | (colour & 0xFFF)
}

/// Depth of a packed word (20 bits of precision; [`CLEAR`] unpacks to about 1).
pub fn unpack_depth(word: u32) -> f32 {
    (f32::from_bits(0x3F00_0000 | (word >> 9)) - 0.5) * 2.0
}

/// Where views' tiles lie in the atlas: `tile × tile` pixels each, `columns` per row, view `v`
/// in slot `s = first_view + v`, at column `s % columns`, row `s / columns`. A view smaller
/// than the tile (a 1920×1080 camera in a one-view atlas of 1920² pixels: single-view point
/// rendering, §3.6.1) fills the tile's top-left corner; nothing is splatted past its size.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AtlasLayout {
    /// Tile side in pixels.
    pub tile: u32,
    /// Tiles per atlas row.
    pub columns: u32,
    /// Tile rows.
    pub rows: u32,
    /// Distance mapped to depth 1 in paraboloid tiles.
    pub far: f32,
    /// The slot of this set's view 0: 0, unless the views are split into batches that splat
    /// into one shared atlas ([`AtlasLayout::batch`]).
    pub first_view: u32,
}

impl AtlasLayout {
    /// A square-ish layout for `views` tiles of `tile` pixels.
    pub fn new(views: usize, tile: u32, far: f32) -> Self {
        let columns = (views as f64).sqrt().ceil().max(1.0) as u32;
        Self {
            tile,
            columns,
            rows: (views as u32).div_ceil(columns).max(1),
            far,
            first_view: 0,
        }
    }

    /// This layout for the batch of views whose view 0 is the atlas's view `first_view`.
    pub fn batch(self, first_view: u32) -> Self {
        Self { first_view, ..self }
    }

    /// Atlas width and height in pixels.
    pub fn size(&self) -> (u32, u32) {
        (self.columns * self.tile, self.rows * self.tile)
    }

    /// Checks that every view fits a tile and has a slot, and `far` is positive.
    pub fn check(&self, views: &[View]) -> Result<(), ManyLodError> {
        let slots = (self.columns as usize) * (self.rows as usize);
        if self.tile == 0 || slots < self.first_view as usize + views.len() {
            return Err(ManyLodError::Mismatch(format!(
                "an atlas of {}×{} tiles of {} px cannot hold {} views from slot {}",
                self.columns,
                self.rows,
                self.tile,
                views.len(),
                self.first_view
            )));
        }
        if !(self.far.is_finite() && self.far > 0.0) {
            return Err(ManyLodError::Mismatch(format!("far distance {}", self.far)));
        }
        for (index, v) in views.iter().enumerate() {
            v.check(index)?;
            let (w, h) = v.size();
            if w > self.tile || h > self.tile {
                return Err(ManyLodError::View {
                    index,
                    problem: format!(
                        "size {w}×{h} does not fit an atlas of {} px tiles",
                        self.tile
                    ),
                });
            }
        }
        Ok(())
    }
}

/// The CPU reference splat: the node-views of `cut` over `nodes` (a hierarchy's, or the [`ism`]
/// points) into a cleared atlas, row-major `u32` packed depths; node-views flagged [`CULLED`]
/// are skipped (see [`crate::CutProblem::flag_culled`]). Tiles are filled in parallel.
pub fn splat(
    nodes: &[Node],
    views: &[View],
    cut: &[NodeView],
    layout: &AtlasLayout,
) -> Result<Vec<u32>, ManyLodError> {
    layout.check(views)?;
    let tile = layout.tile as usize;
    let mut per_view: Vec<Vec<u32>> = vec![Vec::new(); views.len()];
    for nv in cut {
        if nv.node & CULLED != 0 {
            continue;
        }
        let node = nv.node;
        if node as usize >= nodes.len() || nv.view as usize >= views.len() {
            return Err(ManyLodError::Mismatch(format!(
                "{nv:?} outside {} nodes × {} views",
                nodes.len(),
                views.len()
            )));
        }
        per_view[nv.view as usize].push(node);
    }
    let tiles: Vec<Vec<u32>> = per_view
        .par_iter()
        .zip(views)
        .map(|(indices, view)| {
            let mut t = vec![CLEAR; tile * tile];
            for &n in indices {
                cover(view, &nodes[n as usize], layout, |pixel, word| {
                    t[pixel] = t[pixel].min(word);
                });
            }
            t
        })
        .collect();
    let (w, h) = layout.size();
    let mut atlas = vec![CLEAR; (w * h) as usize];
    for (v, t) in tiles.iter().enumerate() {
        let slot = layout.first_view + v as u32;
        let (ox, oy) = (
            (slot % layout.columns) as usize * tile,
            (slot / layout.columns) as usize * tile,
        );
        for (y, row) in t.chunks_exact(tile).enumerate() {
            let start = (oy + y) * w as usize + ox;
            atlas[start..start + tile].copy_from_slice(row);
        }
    }
    Ok(atlas)
}

/// Calls `f(pixel, word)` for every pixel of `view`'s tile (row-major index) within the view
/// whose centre lies in `node`'s disc ([`View::splat`]), with the disc's packed depth.
fn cover(view: &View, node: &Node, layout: &AtlasLayout, mut f: impl FnMut(usize, u32)) {
    let tile = layout.tile as usize;
    let Some(s) = view.splat(node, layout.far) else {
        return;
    };
    let word = pack_depth(s.depth, 0);
    let (w, h) = view.size();
    let (lo_x, hi_x) = pixel_span(s.center.x, s.radius, w as usize);
    let (lo_y, hi_y) = pixel_span(s.center.y, s.radius, h as usize);
    for y in lo_y..hi_y {
        for x in lo_x..hi_x {
            let dx = x as f32 + 0.5 - s.center.x;
            let dy = y as f32 + 0.5 - s.center.y;
            if dx * dx + dy * dy <= s.radius * s.radius {
                f(y * tile + x, word);
            }
        }
    }
}

/// The nearest node of `drawn` at each pixel of `view`'s tile ([`NO_NODE`] where none
/// covers it): the splat of [`splat`] keeping which node won the depth test (the smaller
/// index among equal packed depths), for applications that look up what a node carries —
/// point-based GI's radiance (§3.6.1).
pub fn nearest_nodes(nodes: &[Node], view: &View, drawn: &[u32], layout: &AtlasLayout) -> Vec<u32> {
    let tile = layout.tile as usize;
    let mut best = vec![(CLEAR, NO_NODE); tile * tile];
    for &n in drawn {
        cover(view, &nodes[n as usize], layout, |pixel, word| {
            best[pixel] = best[pixel].min((word, n));
        });
    }
    best.into_iter().map(|(_, n)| n).collect()
}

/// [`nearest_nodes`]' value of a pixel no node covers.
pub const NO_NODE: u32 = u32::MAX;

/// Pixels `lo..hi` (clipped to `0..size`) whose centres may lie within `radius` of `c`.
fn pixel_span(c: f32, radius: f32, size: usize) -> (usize, usize) {
    let lo = (c - radius - 0.5).ceil().max(0.0);
    let hi = (c + radius - 0.5).floor() + 1.0;
    (lo as usize, (hi.max(0.0) as usize).min(size))
}

/// The imperfect-shadow-map baseline (Ritschel et al. 2008, the comparison of Table 3.1): every
/// view splats its own fixed random subset of `per_view` points, each a disc standing for
/// `n / per_view` leaves (radius grown by `√(n / per_view)`), with no hierarchy and no cut.
/// Returns the point nodes and the node-views to splat (the same for every frame).
pub fn ism(
    leaves: &[Node],
    views: usize,
    per_view: usize,
    seed: u64,
) -> Result<(Vec<Node>, Vec<NodeView>), ManyLodError> {
    if leaves.is_empty() || per_view == 0 || per_view > leaves.len() {
        return Err(ManyLodError::Mismatch(format!(
            "{per_view} points per view from {} points",
            leaves.len()
        )));
    }
    let grow = (leaves.len() as f32 / per_view as f32).sqrt();
    let nodes = leaves
        .iter()
        .map(|l| Node {
            radius: l.radius * grow,
            ..*l
        })
        .collect();
    let n = leaves.len() as u32;
    let node_views = (0..views as u32)
        .into_par_iter()
        .flat_map_iter(|view| {
            (0..per_view as u32).map(move |k| NodeView {
                node: pick(seed, view, k) % n,
                view,
            })
        })
        .collect();
    Ok((nodes, node_views))
}

/// A stateless 32-bit integer hash (Wellons' "lowbias32") of a view, a point and a seed.
fn pick(seed: u64, view: u32, k: u32) -> u32 {
    let mut x = (seed as u32) ^ view.wrapping_mul(0x9E37_79B1) ^ k.wrapping_mul(0x85EB_CA77);
    x ^= x >> 16;
    x = x.wrapping_mul(0x7FEB_352D);
    x ^= x >> 15;
    x = x.wrapping_mul(0x846C_A68B);
    x ^ (x >> 16)
}
