//! CPU reference of every kernel. Each function mirrors the WGSL kernel of the same name
//! (in `shaders/interleave/`) loop for loop: the split and gather passes compute each
//! destination texel from its source by the same index arithmetic, the tiled variant stages a
//! tile the way the workgroup does. Rows (or tile rows) run in parallel with rayon.

use gbuffer::Image;
use rayon::prelude::*;

use crate::{Blur, BlurVariant, InterleaveError, SplitLayout, SplitVariant, Thresholds};

/// Splits `image` into the tiled sub-buffers of `layout` with `variant`.
pub fn split<T: Copy + Default + Send + Sync>(
    image: &Image<T>,
    layout: &SplitLayout,
    variant: SplitVariant,
) -> Result<Image<T>, InterleaveError> {
    check_size("image", image, layout.width, layout.height)?;
    variant.validate(layout.pattern)?;
    Ok(match variant {
        SplitVariant::OnePass => split_one_pass(image, layout),
        SplitVariant::TwoPass(block) => {
            let geometry = BlockGeometry::new(layout, block);
            split_block_translation(&split_block_splitting(image, &geometry), &geometry)
        }
        SplitVariant::Tiled => split_tiled(image, layout),
    })
}

/// Gathers the sub-buffers of `split` back into an image of `layout`'s size with `variant`.
pub fn gather<T: Copy + Default + Send + Sync>(
    split: &Image<T>,
    layout: &SplitLayout,
    variant: SplitVariant,
) -> Result<Image<T>, InterleaveError> {
    check_size(
        "split image",
        split,
        layout.split_width(),
        layout.split_height(),
    )?;
    variant.validate(layout.pattern)?;
    Ok(match variant {
        SplitVariant::OnePass => gather_one_pass(split, layout),
        SplitVariant::TwoPass(block) => {
            let geometry = BlockGeometry::new(layout, block);
            gather_block_gathering(&gather_block_translation(split, &geometry), &geometry)
        }
        SplitVariant::Tiled => gather_tiled(split, layout),
    })
}

pub(crate) fn check_size<T: Copy>(
    what: &'static str,
    image: &Image<T>,
    want_w: u32,
    want_h: u32,
) -> Result<(), InterleaveError> {
    if (image.width(), image.height()) == (want_w, want_h) {
        Ok(())
    } else {
        Err(InterleaveError::Mismatch {
            what,
            got_w: image.width(),
            got_h: image.height(),
            want_w,
            want_h,
        })
    }
}

/// An image whose texel (x, y) is `texel(x, y)`, rows in parallel (one GPU thread per texel).
fn per_texel<T: Copy + Send>(
    width: u32,
    height: u32,
    texel: impl Fn(u32, u32) -> T + Sync,
) -> Image<T> {
    let data: Vec<T> = (0..height)
        .into_par_iter()
        .flat_map_iter(|y| (0..width).map(move |x| (x, y)))
        .map(|(x, y)| texel(x, y))
        .collect();
    Image::from_vec(width, height, data).unwrap_or_else(|_| unreachable!("per_texel size"))
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
    let (w, h) = g.intermediate_size();
    let crate::Pattern { n, m } = g.layout.pattern;
    per_texel(w, h, |bx, by| {
        let (i, u, j, v) = g.sub_texel_at(bx, by);
        let (x, y) = (u * n + i, v * m + j);
        if x < g.layout.width && y < g.layout.height {
            image.get(x, y)
        } else {
            T::default()
        }
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
    let (w, h) = g.intermediate_size();
    let l = &g.layout;
    per_texel(w, h, |bx, by| {
        let (i, u, j, v) = g.sub_texel_at(bx, by);
        if u < l.sub_width && v < l.sub_height {
            split.get(i * l.sub_width + u, j * l.sub_height + v)
        } else {
            T::default()
        }
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
    let (a, b) = crate::tile(layout.pattern).unwrap_or((1, 1));
    let (tiles_x, tiles_y) = (layout.sub_width.div_ceil(a), layout.sub_height.div_ceil(b));
    let writes: Vec<(u32, u32, T)> = (0..tiles_y)
        .into_par_iter()
        .flat_map_iter(|tv| {
            (0..tiles_x).flat_map(move |tu| {
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
        })
        .collect();
    let mut out = Image::filled(layout.split_width(), layout.split_height(), T::default());
    for (x, y, t) in writes {
        out.set(x, y, t);
    }
    out
}

/// The tiled one-pass gather (`gather_tiled`): each sub-buffer's a×b run is read in order into
/// workgroup memory, then the tile's pixels are written in row order.
pub fn gather_tiled<T: Copy + Default + Send + Sync>(
    split: &Image<T>,
    layout: &SplitLayout,
) -> Image<T> {
    let crate::Pattern { n, m } = layout.pattern;
    let (a, b) = crate::tile(layout.pattern).unwrap_or((1, 1));
    let (tiles_x, tiles_y) = (layout.sub_width.div_ceil(a), layout.sub_height.div_ceil(b));
    let writes: Vec<(u32, u32, T)> = (0..tiles_y)
        .into_par_iter()
        .flat_map_iter(|tv| {
            (0..tiles_x).flat_map(move |tu| {
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
        })
        .collect();
    let mut out = Image::filled(layout.width, layout.height, T::default());
    for (x, y, t) in writes {
        out.set(x, y, t);
    }
    out
}

/// Octahedral normal word (two snorm16, `gbuffer::normal::pack_octahedral`) decoded to an
/// unnormalised integer vector of 11-bit components (`octahedral_integer` in
/// `discontinuity.wgsl`). Integer arithmetic, so CPU and GPU agree exactly.
pub fn octahedral_integer(word: u32) -> [i32; 3] {
    const ONE: i32 = 32767;
    let x = i32::from(word as u16 as i16).max(-ONE);
    let y = i32::from((word >> 16) as u16 as i16).max(-ONE);
    let z = ONE - x.abs() - y.abs();
    let sign = |v: i32| if v >= 0 { 1 } else { -1 };
    let (x, y) = if z < 0 {
        ((ONE - y.abs()) * sign(x), (ONE - x.abs()) * sign(y))
    } else {
        (x, y)
    };
    [x >> 4, y >> 4, z >> 4]
}

/// Whether two packed normals are more than the threshold angle apart (`normals_differ`).
///
/// With integer vectors v0, v1 (components < 2¹¹, so dot products < 2²⁴ are exact in f32):
/// the angle exceeds θ ⇔ v0·v1 < cos θ |v0||v1|, tested squared as
/// (v0·v1)² vs (cos²θ · |v0|²) · |v1|² — three single multiplications, each correctly rounded
/// in IEEE f32 on CPU and GPU alike.
pub fn normals_differ(a: u32, b: u32, cos_squared: f32, cos_positive: bool) -> bool {
    let (v0, v1) = (octahedral_integer(a), octahedral_integer(b));
    let d = |p: [i32; 3], q: [i32; 3]| p[0] * q[0] + p[1] * q[1] + p[2] * q[2];
    let (dot, n0, n1) = (d(v0, v1), d(v0, v0), d(v1, v1));
    let dot2 = dot as f32 * dot as f32;
    let bound = cos_squared * n0 as f32 * n1 as f32;
    if cos_positive {
        dot <= 0 || dot2 < bound
    } else {
        dot < 0 && dot2 > bound
    }
}

/// Whether two view depths are further apart than the factor 1 + depth_ratio allows
/// (`depths_differ`): max > min · factor, one correctly rounded multiplication.
pub fn depths_differ(a: f32, b: f32, factor: f32) -> bool {
    a.max(b) > a.min(b) * factor
}

/// §4.5 discontinuity buffer (`discontinuity.wgsl`): each pixel compared with its positive
/// neighbours (x+1, y), (x, y+1), (x+1, y+1) that exist. Red = 255 where a normal test fails,
/// green = 255 where a depth test fails, alpha 255.
pub fn discontinuity(
    linear_depth: &Image<f32>,
    normal: &Image<u32>,
    thresholds: &Thresholds,
) -> Result<Image<[u8; 4]>, InterleaveError> {
    thresholds.validate()?;
    check_size(
        "normal image",
        normal,
        linear_depth.width(),
        linear_depth.height(),
    )?;
    let (w, h) = (linear_depth.width(), linear_depth.height());
    let (cos2, cos_positive) = thresholds.cos_squared();
    let factor = thresholds.depth_factor();
    Ok(per_texel(w, h, |x, y| {
        let (mut normal_edge, mut depth_edge) = (false, false);
        for (nx, ny) in [(x + 1, y), (x, y + 1), (x + 1, y + 1)] {
            if nx < w && ny < h {
                normal_edge |=
                    normals_differ(normal.get(x, y), normal.get(nx, ny), cos2, cos_positive);
                depth_edge |=
                    depths_differ(linear_depth.get(x, y), linear_depth.get(nx, ny), factor);
            }
        }
        [
            u8::from(normal_edge) * 255,
            u8::from(depth_edge) * 255,
            0,
            255,
        ]
    }))
}

/// Whether a discontinuity-buffer texel marks a discontinuity.
fn on_discontinuity(texel: [u8; 4]) -> bool {
    texel[0] > 0 || texel[1] > 0
}

/// Rounds to the nearest f16, as storing into an `Rgba16Float` texture does.
pub fn to_f16(v: [f32; 4]) -> [f32; 4] {
    v.map(|c| half::f16::from_f32(c).to_f32())
}

/// §4.5 edge-aware separable Gaussian blur (`blur.wgsl`): a horizontal then a vertical pass,
/// each rounded to f16 like the GPU's `Rgba16Float` targets.
///
/// Per direction: a pixel not on a discontinuity blends its neighbours in the + direction until
/// one is on a discontinuity (that one is still blended: it is similar to the previous one) or
/// the radius is reached; in the − direction it blends neighbours until one is on a
/// discontinuity (that one is not: it differs from its + neighbour) — so a pixel on a
/// discontinuity explores only the − direction. The average is accumulated as the centre plus
/// the weighted mean of the differences to it, so a constant image stays exactly constant
/// whatever the rounding of the sums. The fast variant fetches taps in pairs between
/// two texel centres and stops at the first pair whose filtered discontinuity value is > 0.
pub fn blur(
    irradiance: &Image<[f32; 4]>,
    discontinuities: &Image<[u8; 4]>,
    blur: &Blur,
) -> Result<Image<[f32; 4]>, InterleaveError> {
    blur.validate()?;
    check_size(
        "discontinuity buffer",
        discontinuities,
        irradiance.width(),
        irradiance.height(),
    )?;
    let horizontal = blur_pass(irradiance, discontinuities, blur, (1, 0));
    Ok(blur_pass(&horizontal, discontinuities, blur, (0, 1)))
}

/// One direction of [`blur`] (`blur_plain` / `blur_fast` in `blur.wgsl`).
pub fn blur_pass(
    image: &Image<[f32; 4]>,
    disc: &Image<[u8; 4]>,
    blur: &Blur,
    direction: (i32, i32),
) -> Image<[f32; 4]> {
    let weights = blur.weights();
    let r = blur.radius() as i32;
    let (w, h) = (image.width() as i32, image.height() as i32);
    let inside = |x: i32, y: i32| x >= 0 && y >= 0 && x < w && y < h;
    let at = |x: i32, y: i32| image.get(x as u32, y as u32);
    let disc_at = |x: i32, y: i32| on_discontinuity(disc.get(x as u32, y as u32));
    per_texel(image.width(), image.height(), |x, y| {
        let (x, y) = (x as i32, y as i32);
        let centre = at(x, y);
        let mut sum = [0.0f32; 4];
        let mut total = weights[0];
        let mut add = |v: [f32; 4], weight: f32| {
            for c in 0..4 {
                sum[c] += (v[c] - centre[c]) * weight;
            }
            total += weight;
        };
        for side in [1, -1] {
            if side == 1 && disc_at(x, y) {
                continue;
            }
            let (dx, dy) = (direction.0 * side, direction.1 * side);
            match blur.variant {
                BlurVariant::Plain => {
                    for k in 1..=r {
                        let (qx, qy) = (x + dx * k, y + dy * k);
                        if !inside(qx, qy) || (side == -1 && disc_at(qx, qy)) {
                            break;
                        }
                        add(at(qx, qy), weights[k as usize]);
                        if side == 1 && disc_at(qx, qy) {
                            break;
                        }
                    }
                }
                BlurVariant::Fast => {
                    let mut k = 1;
                    while k <= r {
                        let last = (k + 1).min(r);
                        let (ax, ay) = (x + dx * k, y + dy * k);
                        let (bx, by) = (x + dx * last, y + dy * last);
                        if !inside(bx, by) || disc_at(ax, ay) || disc_at(bx, by) {
                            break;
                        }
                        let (va, vb) = (at(ax, ay), at(bx, by));
                        let mean = std::array::from_fn(|c| 0.5 * (va[c] + vb[c]));
                        let weight = if last > k {
                            weights[k as usize] + weights[last as usize]
                        } else {
                            weights[k as usize]
                        };
                        add(mean, weight);
                        k += 2;
                    }
                }
            }
        }
        to_f16(std::array::from_fn(|c| centre[c] + sum[c] / total))
    })
}

/// One light of [`shade_subsets`]: a directional light (unit `direction` towards the light).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct SubsetLight {
    /// Unit vector towards the light (w unused).
    pub direction: [f32; 4],
    /// Irradiance at normal incidence (w unused).
    pub color: [f32; 4],
}

/// §4.3 shading of interleaved samples, the crate's probe shader (`shade.wgsl`): pixel (x, y)
/// receives only the lights of its sub-buffer's subset s = (y mod m)·n + (x mod n), lights
/// `s·k .. s·k + k` with k = lights.len() / (n·m): E = Σ max(0, n·l) · colour. Pixels with no
/// surface (linear depth 0) get 0. Returns the gathered (interleaved) irradiance, rounded to f16.
pub fn shade_subsets(
    linear_depth: &Image<f32>,
    normal: &Image<u32>,
    lights: &[SubsetLight],
    layout: &SplitLayout,
) -> Result<Image<[f32; 4]>, InterleaveError> {
    check_size("linear depth", linear_depth, layout.width, layout.height)?;
    check_size("normal image", normal, layout.width, layout.height)?;
    let per_subset = crate::gpu::lights_per_subset(lights.len(), layout.pattern)?;
    Ok(per_texel(layout.width, layout.height, |x, y| {
        if linear_depth.get(x, y) == 0.0 {
            return [0.0; 4];
        }
        let nrm = gbuffer::normal::unpack_octahedral(normal.get(x, y));
        let (i, j) = layout.sub_buffer_of(x, y);
        let first = ((j * layout.pattern.n + i) * per_subset) as usize;
        let mut e = [0.0f32, 0.0, 0.0, 1.0];
        for light in &lights[first..first + per_subset as usize] {
            let d = glam::Vec3::from_slice(&light.direction[..3]);
            let cos = nrm.dot(d).max(0.0);
            for (e, c) in e.iter_mut().zip(&light.color[..3]) {
                *e += cos * c;
            }
        }
        to_f16(e)
    }))
}
