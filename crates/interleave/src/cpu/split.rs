//! Split and gather (Segovia 2006 §3): `one_pass.wgsl`, `two_pass.wgsl`, `tiled.wgsl`.

use gbuffer::Image;
use rayon::prelude::*;

use crate::{InterleaveError, SplitLayout, SplitVariant};

use super::{check_size, per_texel};

/// Splits `image` into the tiled sub-buffers of `layout` with `variant`.
pub fn split<T: Copy + Default + Send + Sync>(
    image: &Image<T>,
    layout: &SplitLayout,
    variant: SplitVariant,
) -> Result<Image<T>, InterleaveError> {
    check_size("image", image, layout.width, layout.height)?;
    let two_pass = [split_block_splitting, split_block_translation];
    by_variant(
        image,
        layout,
        variant,
        split_one_pass,
        two_pass,
        split_tiled,
    )
}

/// Gathers the sub-buffers of `split` back into an image of `layout`'s size with `variant`.
pub fn gather<T: Copy + Default + Send + Sync>(
    split: &Image<T>,
    layout: &SplitLayout,
    variant: SplitVariant,
) -> Result<Image<T>, InterleaveError> {
    let (w, h) = (layout.split_width(), layout.split_height());
    check_size("split image", split, w, h)?;
    let two_pass = [gather_block_translation, gather_block_gathering];
    by_variant(
        split,
        layout,
        variant,
        gather_one_pass,
        two_pass,
        gather_tiled,
    )
}

/// A pass with one pass, two passes through a block intermediate, or tiles.
type Pass<T, G> = fn(&Image<T>, &G) -> Image<T>;

/// Runs `variant` of a split or gather: its one pass, its two passes in order, or its tiled pass.
fn by_variant<T>(
    input: &Image<T>,
    layout: &SplitLayout,
    variant: SplitVariant,
    one_pass: Pass<T, SplitLayout>,
    two_pass: [Pass<T, BlockGeometry>; 2],
    tiled: Pass<T, SplitLayout>,
) -> Result<Image<T>, InterleaveError> {
    variant.validate(layout.pattern)?;
    Ok(match variant {
        SplitVariant::OnePass => one_pass(input, layout),
        SplitVariant::TwoPass(block) => {
            let geometry = BlockGeometry::new(layout, block);
            two_pass[1](&two_pass[0](input, &geometry), &geometry)
        }
        SplitVariant::Tiled => tiled(input, layout),
    })
}

/// §3.2 one-pass split (`split_one_pass` in `one_pass.wgsl`): every split texel finds its
/// pixel by index arithmetic; padding texels are zero.
pub fn split_one_pass<T: Copy + Default + Send + Sync>(
    image: &Image<T>,
    layout: &SplitLayout,
) -> Image<T> {
    per_texel(layout.split_width(), layout.split_height(), |sx, sy| {
        layout
            .source_pixel(sx, sy)
            .map_or_else(T::default, |(x, y)| image.get(x, y))
    })
}

/// §3.4 one-pass gather (`gather_one_pass`): every pixel reads its split texel.
pub fn gather_one_pass<T: Copy + Default + Send + Sync>(
    split: &Image<T>,
    layout: &SplitLayout,
) -> Image<T> {
    per_texel(layout.width, layout.height, |x, y| {
        let (sx, sy) = layout.split_texel(x, y);
        split.get(sx, sy)
    })
}

/// The two-pass split's intermediate layout (§3.3, Figure 2c): the image is cut into blocks of
/// p×q pixels, and inside each block the pixels of sub-buffer (i, j) form the sub-block
/// (i, j) of a×b texels, a = p/n, b = q/m. Blocks continue past the image edge up to whole
/// blocks of the sub-buffers (padding texels are zero).
#[derive(Clone, Copy, Debug)]
pub struct BlockGeometry {
    layout: SplitLayout,
    /// Sub-block width, p / n.
    pub a: u32,
    /// Sub-block height, q / m.
    pub b: u32,
    /// Blocks across, ceil(sub_width / a).
    pub blocks_x: u32,
    /// Blocks down, ceil(sub_height / b).
    pub blocks_y: u32,
}

impl BlockGeometry {
    /// The geometry of a validated block.
    pub fn new(layout: &SplitLayout, block: crate::Block) -> Self {
        let a = block.p / layout.pattern.n;
        let b = block.q / layout.pattern.m;
        Self {
            layout: *layout,
            a,
            b,
            blocks_x: layout.sub_width.div_ceil(a),
            blocks_y: layout.sub_height.div_ceil(b),
        }
    }

    /// Size of the intermediate texture (whole blocks).
    pub fn intermediate_size(&self) -> (u32, u32) {
        let crate::Pattern { n, m } = self.layout.pattern;
        (self.blocks_x * self.a * n, self.blocks_y * self.b * m)
    }

    /// Sub-buffer texel (i, u, j, v) stored at intermediate texel (bx, by).
    fn sub_texel_at(&self, bx: u32, by: u32) -> (u32, u32, u32, u32) {
        let (p, q) = (
            self.a * self.layout.pattern.n,
            self.b * self.layout.pattern.m,
        );
        let (lx, ly) = (bx % p, by % q);
        (
            lx / self.a,
            (bx / p) * self.a + lx % self.a,
            ly / self.b,
            (by / q) * self.b + ly % self.b,
        )
    }

    /// Intermediate texel of sub-buffer texel (u, v) of sub-buffer (i, j).
    fn intermediate_of(&self, i: u32, u: u32, j: u32, v: u32) -> (u32, u32) {
        let (p, q) = (
            self.a * self.layout.pattern.n,
            self.b * self.layout.pattern.m,
        );
        (
            (u / self.a) * p + i * self.a + u % self.a,
            (v / self.b) * q + j * self.b + v % self.b,
        )
    }
}

/// §3.3 pass 1, block splitting (`split_block_splitting` in `two_pass.wgsl`): image →
/// intermediate, each block split into its n×m sub-blocks.
pub fn split_block_splitting<T: Copy + Default + Send + Sync>(
    image: &Image<T>,
    g: &BlockGeometry,
) -> Image<T> {
    let crate::Pattern { n, m } = g.layout.pattern;
    let (width, height) = (g.layout.width, g.layout.height);
    fill_intermediate(image, g, |i, u, j, v| {
        let (x, y) = (u * n + i, v * m + j);
        (x < width && y < height).then_some((x, y))
    })
}

/// §3.3 pass 2, block translation (`split_block_translation`): intermediate → split, whole
/// sub-blocks moved to their sub-buffer.
pub fn split_block_translation<T: Copy + Default + Send + Sync>(
    intermediate: &Image<T>,
    g: &BlockGeometry,
) -> Image<T> {
    let l = &g.layout;
    per_texel(l.split_width(), l.split_height(), |sx, sy| {
        let (i, u) = (sx / l.sub_width, sx % l.sub_width);
        let (j, v) = (sy / l.sub_height, sy % l.sub_height);
        let (bx, by) = g.intermediate_of(i, u, j, v);
        intermediate.get(bx, by)
    })
}

/// §3.4 gather pass 1, block translation (`gather_block_translation`): split → intermediate.
pub fn gather_block_translation<T: Copy + Default + Send + Sync>(
    split: &Image<T>,
    g: &BlockGeometry,
) -> Image<T> {
    let (sub_width, sub_height) = (g.layout.sub_width, g.layout.sub_height);
    fill_intermediate(split, g, |i, u, j, v| {
        (u < sub_width && v < sub_height).then_some((i * sub_width + u, j * sub_height + v))
    })
}

/// The intermediate texture of `g`: texel (bx, by) holds sub-buffer texel (i, u, j, v), read
/// from `source` at `at(i, u, j, v)`, or zero where that is `None` (padding).
fn fill_intermediate<T: Copy + Default + Send + Sync>(
    source: &Image<T>,
    g: &BlockGeometry,
    at: impl Fn(u32, u32, u32, u32) -> Option<(u32, u32)> + Sync,
) -> Image<T> {
    let (w, h) = g.intermediate_size();
    per_texel(w, h, |bx, by| {
        let (i, u, j, v) = g.sub_texel_at(bx, by);
        at(i, u, j, v).map_or_else(T::default, |(x, y)| source.get(x, y))
    })
}

/// §3.4 gather pass 2, block gathering (`gather_block_gathering`): intermediate → image.
pub fn gather_block_gathering<T: Copy + Default + Send + Sync>(
    intermediate: &Image<T>,
    g: &BlockGeometry,
) -> Image<T> {
    let l = &g.layout;
    let crate::Pattern { n, m } = l.pattern;
    per_texel(l.width, l.height, |x, y| {
        let (bx, by) = g.intermediate_of(x % n, x / n, y % m, y / m);
        intermediate.get(bx, by)
    })
}

/// Position in the tile's workgroup memory of pixel (lx, ly) of the tile: sub-buffers one
/// after the other, each an a×b run in row order (`tile_slot` in `tiled.wgsl`).
fn tile_slot(lx: u32, ly: u32, n: u32, m: u32, a: u32, b: u32) -> u32 {
    let (i, u, j, v) = (lx % n, lx / n, ly % m, ly / m);
    ((j * n + i) * b + v) * a + u
}

/// Pixel (lx, ly) of the tile whose workgroup-memory slot is `k` (inverse of `tile_slot`).
fn tile_pixel(k: u32, n: u32, a: u32, b: u32) -> (u32, u32, u32, u32) {
    let (s, r) = (k / (a * b), k % (a * b));
    let (i, j) = (s % n, s / n);
    (i, r % a, j, r / a)
}

/// The tiled one-pass split (`split_tiled` in `tiled.wgsl`): a tile of a·n × b·m pixels is read
/// in row order into workgroup memory at its sub-buffer slot, then each sub-buffer's a×b run is
/// written in order.
pub fn split_tiled<T: Copy + Default + Send + Sync>(
    image: &Image<T>,
    layout: &SplitLayout,
) -> Image<T> {
    let crate::Pattern { n, m } = layout.pattern;
    let size = (layout.split_width(), layout.split_height());
    by_tiles(layout, size, |tu, tv, (a, b)| {
        let (x0, y0) = (tu * a * n, tv * b * m);
        let mut tile = vec![T::default(); (a * n * b * m) as usize];
        for k in 0..a * n * b * m {
            let (lx, ly) = (k % (a * n), k / (a * n));
            let (x, y) = (x0 + lx, y0 + ly);
            if x < layout.width && y < layout.height {
                tile[tile_slot(lx, ly, n, m, a, b) as usize] = image.get(x, y);
            }
        }
        (0..a * n * b * m).filter_map(move |k| {
            let (i, u, j, v) = tile_pixel(k, n, a, b);
            let (u, v) = (tu * a + u, tv * b + v);
            (u < layout.sub_width && v < layout.sub_height).then(|| {
                let (sx, sy) = layout.sub_buffer_origin(i, j);
                (sx + u, sy + v, tile[k as usize])
            })
        })
    })
}

/// The tiled one-pass gather (`gather_tiled`): each sub-buffer's a×b run is read in order into
/// workgroup memory, then the tile's pixels are written in row order.
pub fn gather_tiled<T: Copy + Default + Send + Sync>(
    split: &Image<T>,
    layout: &SplitLayout,
) -> Image<T> {
    let crate::Pattern { n, m } = layout.pattern;
    by_tiles(layout, (layout.width, layout.height), |tu, tv, (a, b)| {
        let mut tile = vec![T::default(); (a * n * b * m) as usize];
        for k in 0..a * n * b * m {
            let (i, u, j, v) = tile_pixel(k, n, a, b);
            let (u, v) = (tu * a + u, tv * b + v);
            if u < layout.sub_width && v < layout.sub_height {
                let (sx, sy) = layout.sub_buffer_origin(i, j);
                tile[k as usize] = split.get(sx + u, sy + v);
            }
        }
        let (x0, y0) = (tu * a * n, tv * b * m);
        (0..a * n * b * m).filter_map(move |k| {
            let (lx, ly) = (k % (a * n), k / (a * n));
            let (x, y) = (x0 + lx, y0 + ly);
            (x < layout.width && y < layout.height)
                .then(|| (x, y, tile[tile_slot(lx, ly, n, m, a, b) as usize]))
        })
    })
}

/// An image of `size` written tile by tile (the workgroups of `tiled.wgsl`, a×b texels of
/// every sub-buffer each): `tile(tu, tv, (a, b))` gives the (x, y, value) writes of tile
/// (tu, tv).
fn by_tiles<T, I>(
    layout: &SplitLayout,
    (width, height): (u32, u32),
    tile: impl Fn(u32, u32, (u32, u32)) -> I + Sync,
) -> Image<T>
where
    T: Copy + Default + Send + Sync,
    I: Iterator<Item = (u32, u32, T)>,
{
    let (a, b) = crate::tile(layout.pattern).unwrap_or((1, 1));
    let (tiles_x, tiles_y) = (layout.sub_width.div_ceil(a), layout.sub_height.div_ceil(b));
    let tile = &tile;
    let writes: Vec<(u32, u32, T)> = (0..tiles_y)
        .into_par_iter()
        .flat_map_iter(|tv| (0..tiles_x).flat_map(move |tu| tile(tu, tv, (a, b))))
        .collect();
    let mut out = Image::filled(width, height, T::default());
    for (x, y, t) in writes {
        out.set(x, y, t);
    }
    out
}
