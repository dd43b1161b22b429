//! Interleaved sampling by G-buffer splitting (Segovia, Iehl, Mitanchey, Péroche 2006,
//! "Non-interleaved Deferred Shading of Interleaved Sample Patterns").
//!
//! An n×m interleave [`Pattern`] gives every pixel of an n×m cell its own set of light
//! samples. Shading interleaved pixels directly is incoherent, so the G-buffer is **split**
//! (§3.2–3.3): pixel (x, y) goes to texel (x div n, y div m) of **sub-buffer** (x mod n, y mod m),
//! and the n·m sub-buffers are tiled in one texture. Each sub-buffer is then shaded as an
//! ordinary small G-buffer, the results are **gathered** back (§3.4), and an edge-aware
//! separable Gaussian blur guided by a **discontinuity buffer** (§4.5) blends the neighbouring
//! pixels' uncorrelated results.
//!
//! # Sizes that are not multiples of the pattern
//!
//! Every sub-buffer has the same size, `sub_width = ceil(width / n)` × `sub_height =
//! ceil(height / m)`, and the split texture is `n·sub_width × m·sub_height` (see
//! [`SplitLayout`]). When the image size is not a multiple of the pattern, the last column
//! and/or row of some sub-buffers has no source pixel: those **padding texels are written as
//! zero** by every split variant and ignored by every gather. No pixel is ever dropped, and
//! gather(split(image)) == image bit for bit.
//!
//! # Variants
//!
//! Each has a CPU twin in [`cpu`] and a WGSL kernel driven by [`gpu`]:
//!
//! - [`SplitVariant::OnePass`]: §3.2, one pass of index arithmetic per destination texel;
//! - [`SplitVariant::TwoPass`]: §3.3, block splitting then block translation with a tunable
//!   block of p×q pixels ([`Block`]);
//! - [`SplitVariant::Tiled`]: one pass that reads a tile of the image coalesced, transposes it
//!   through workgroup memory and writes each sub-buffer's run coalesced;
//! - the "fused" indirection baseline of §3.1 has no split at all: [`gpu::SubsetShading`] can
//!   shade the interleaved G-buffer in sub-buffer order through strided addressing.
//!
//! ```
//! use interleave::{Pattern, SplitLayout, SplitVariant, cpu};
//! let image = gbuffer::Image::from_vec(5, 3, (0..15u32).collect())?;
//! let layout = SplitLayout::new(5, 3, Pattern::new(2, 2)?)?;
//! let split = cpu::split(&image, &layout, SplitVariant::OnePass)?;
//! assert_eq!((split.width(), split.height()), (6, 4)); // two 3×2 sub-buffers per row
//! assert_eq!(split.get(0, 0), 0); // sub-buffer (0, 0) starts with pixel (0, 0)
//! assert_eq!(split.get(3, 0), 1); // sub-buffer (1, 0) starts with pixel (1, 0)
//! assert_eq!(cpu::gather(&split, &layout, SplitVariant::OnePass)?, image);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

pub mod cpu;
mod filter;
pub mod gpu;

pub use filter::{Blur, BlurVariant, Thresholds};

use ::gpu::GpuError;

/// This crate's WGSL (`shaders/interleave/`, carried into the package by the `shaders` link).
pub static SHADERS: ::gpu::shader::Library = ::gpu::shader_library!(
    "interleave",
    imports: [gbuffer::SHADERS],
    files: [
        "blur.wgsl",
        "blur_params.wgsl",
        "discontinuity.wgsl",
        "discontinuity_blur.wgsl",
        "one_pass.wgsl",
        "pattern.wgsl",
        "shade.wgsl",
        "texel.wgsl",
        "tiled.wgsl",
        "two_pass.wgsl",
    ],
);

/// What this crate's kernels need of a device: wgpu's default limits suffice.
pub fn device_needs() -> ::gpu::DeviceNeeds {
    ::gpu::DeviceNeeds::default()
}

/// Largest pattern side accepted (a 256×256 pattern already leaves 1 texel per sub-buffer at 4K).
pub const MAX_PATTERN: u32 = 256;
/// Largest image side accepted.
pub const MAX_SIZE: u32 = 16384;
/// Texels of one tile of the [`SplitVariant::Tiled`] kernel (its workgroup-memory capacity).
pub const TILE_TEXELS: u32 = 512;

/// Everything that can go wrong in this crate.
#[derive(Debug, thiserror::Error)]
pub enum InterleaveError {
    /// A pattern side is 0 or larger than [`MAX_PATTERN`].
    #[error(
        "interleave pattern {n}×{m} is invalid: both sides must be between 1 and {MAX_PATTERN}"
    )]
    Pattern {
        /// Columns.
        n: u32,
        /// Rows.
        m: u32,
    },
    /// A pattern string is not of the form `NxM`.
    #[error("cannot read interleave pattern {0:?}: expected NxM, e.g. 4x4")]
    PatternSyntax(String),
    /// An image side is 0 or larger than [`MAX_SIZE`].
    #[error("image size {width}×{height} is invalid: both sides must be between 1 and {MAX_SIZE}")]
    Size {
        /// Width.
        width: u32,
        /// Height.
        height: u32,
    },
    /// An input image does not have the size the layout expects.
    #[error("{what} is {got_w}×{got_h} but {want_w}×{want_h} is expected")]
    Mismatch {
        /// Which input.
        what: &'static str,
        /// Its width.
        got_w: u32,
        /// Its height.
        got_h: u32,
        /// Expected width.
        want_w: u32,
        /// Expected height.
        want_h: u32,
    },
    /// The two-pass block is not a multiple of the pattern.
    #[error(
        "block {p}×{q} does not fit pattern {n}×{m}: p must be a multiple of n and q of m (at most {MAX_SIZE})"
    )]
    Block {
        /// Block width in pixels.
        p: u32,
        /// Block height in pixels.
        q: u32,
        /// Pattern columns.
        n: u32,
        /// Pattern rows.
        m: u32,
    },
    /// The tiled variant needs one whole pattern cell in workgroup memory.
    #[error(
        "the tiled split holds {TILE_TEXELS} texels per workgroup; pattern {n}×{m} needs {} (use the one-pass or two-pass variant)",
        n * m
    )]
    TileTooSmall {
        /// Pattern columns.
        n: u32,
        /// Pattern rows.
        m: u32,
    },
    /// The texture format cannot be split on the GPU.
    #[error(
        "format {0:?} cannot be split on the GPU: supported are r32uint/sint/float, rg32uint/sint/float, rgba32uint/sint/float, rgba16uint/sint/float and rgba8unorm/uint/sint"
    )]
    Format(wgpu::TextureFormat),
    /// The CPU texel type does not have the GPU format's size.
    #[error("texels of {cpu} bytes do not match format {format:?} ({gpu} bytes)")]
    TexelSize {
        /// `size_of` the CPU texel.
        cpu: usize,
        /// The format's bytes per texel.
        gpu: u32,
        /// The format.
        format: wgpu::TextureFormat,
    },
    /// A blur kernel size outside 5..=17 or even.
    #[error("blur kernel {0} is invalid: use an odd size from 5 to 17")]
    Kernel(u32),
    /// A threshold is negative or not finite.
    #[error("discontinuity threshold {what} = {value} is invalid: {why}")]
    Threshold {
        /// Which threshold.
        what: &'static str,
        /// Its value.
        value: f32,
        /// The rule.
        why: &'static str,
    },
    /// The light list does not divide into one equal subset per sub-buffer.
    #[error(
        "{count} lights cannot be split into {subsets} equal, non-empty subsets (one per sub-buffer)"
    )]
    Lights {
        /// Lights given.
        count: usize,
        /// Sub-buffers, n·m.
        subsets: u32,
    },
    /// GPU failure.
    #[error(transparent)]
    Gpu(#[from] GpuError),
}

/// An n×m interleave pattern: n columns, m rows of sub-buffers.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Pattern {
    /// Columns (sub-buffers across).
    pub n: u32,
    /// Rows (sub-buffers down).
    pub m: u32,
}

impl Pattern {
    /// A pattern with both sides in 1..=[`MAX_PATTERN`].
    pub fn new(n: u32, m: u32) -> Result<Self, InterleaveError> {
        if !(1..=MAX_PATTERN).contains(&n) || !(1..=MAX_PATTERN).contains(&m) {
            return Err(InterleaveError::Pattern { n, m });
        }
        Ok(Self { n, m })
    }

    /// Number of sub-buffers, n·m.
    pub fn count(self) -> u32 {
        self.n * self.m
    }
}

impl std::fmt::Display for Pattern {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}x{}", self.n, self.m)
    }
}

impl std::str::FromStr for Pattern {
    type Err = InterleaveError;

    /// Reads `NxM` (also `N×M`), e.g. `4x4` or `8x6`.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let bad = || InterleaveError::PatternSyntax(s.to_owned());
        let (n, m) = s.split_once(['x', 'X', '×']).ok_or_else(bad)?;
        let n = n.trim().parse().map_err(|_| bad())?;
        let m = m.trim().parse().map_err(|_| bad())?;
        Self::new(n, m)
    }
}

/// Where every pixel of a `width × height` image lives in the split texture of a [`Pattern`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SplitLayout {
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// The pattern.
    pub pattern: Pattern,
    /// Width of every sub-buffer, ceil(width / n).
    pub sub_width: u32,
    /// Height of every sub-buffer, ceil(height / m).
    pub sub_height: u32,
}

impl SplitLayout {
    /// The layout of a `width × height` image (sides in 1..=[`MAX_SIZE`]).
    pub fn new(width: u32, height: u32, pattern: Pattern) -> Result<Self, InterleaveError> {
        if !(1..=MAX_SIZE).contains(&width) || !(1..=MAX_SIZE).contains(&height) {
            return Err(InterleaveError::Size { width, height });
        }
        Ok(Self {
            width,
            height,
            pattern,
            sub_width: width.div_ceil(pattern.n),
            sub_height: height.div_ceil(pattern.m),
        })
    }

    /// Width of the split texture, n · sub_width (≥ width).
    pub fn split_width(&self) -> u32 {
        self.pattern.n * self.sub_width
    }

    /// Height of the split texture, m · sub_height (≥ height).
    pub fn split_height(&self) -> u32 {
        self.pattern.m * self.sub_height
    }

    /// Top-left texel of sub-buffer (i, j) in the split texture.
    pub fn sub_buffer_origin(&self, i: u32, j: u32) -> (u32, u32) {
        (i * self.sub_width, j * self.sub_height)
    }

    /// Split-texture texel of pixel (x, y): texel (x div n, y div m) of sub-buffer
    /// (x mod n, y mod m).
    pub fn split_texel(&self, x: u32, y: u32) -> (u32, u32) {
        let Pattern { n, m } = self.pattern;
        (
            (x % n) * self.sub_width + x / n,
            (y % m) * self.sub_height + y / m,
        )
    }

    /// The pixel a split-texture texel holds, or `None` for a padding texel.
    pub fn source_pixel(&self, sx: u32, sy: u32) -> Option<(u32, u32)> {
        let Pattern { n, m } = self.pattern;
        let (i, u) = (sx / self.sub_width, sx % self.sub_width);
        let (j, v) = (sy / self.sub_height, sy % self.sub_height);
        let (x, y) = (u * n + i, v * m + j);
        (x < self.width && y < self.height).then_some((x, y))
    }

    /// Sub-buffer (i, j) that holds pixel (x, y).
    pub fn sub_buffer_of(&self, x: u32, y: u32) -> (u32, u32) {
        (x % self.pattern.n, y % self.pattern.m)
    }
}

/// The block of the two-pass split (§3.3), in pixels of the image: p columns, q rows. Each
/// block is split into the n×m sub-blocks of the pattern, so p must be a multiple of n and q
/// a multiple of m.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Block {
    /// Block width in pixels.
    pub p: u32,
    /// Block height in pixels.
    pub q: u32,
}

impl Block {
    /// The block of about `p × q` pixels that fits `pattern`: each side rounded up to a
    /// multiple of the pattern side.
    pub fn fitted(p: u32, q: u32, pattern: Pattern) -> Self {
        Self {
            p: p.max(1).div_ceil(pattern.n) * pattern.n,
            q: q.max(1).div_ceil(pattern.m) * pattern.m,
        }
    }

    /// Checks that the block fits the pattern.
    pub fn validate(self, pattern: Pattern) -> Result<(), InterleaveError> {
        let ok = |b: u32, s: u32| (1..=MAX_SIZE).contains(&b) && b.is_multiple_of(s);
        if ok(self.p, pattern.n) && ok(self.q, pattern.m) {
            Ok(())
        } else {
            Err(InterleaveError::Block {
                p: self.p,
                q: self.q,
                n: pattern.n,
                m: pattern.m,
            })
        }
    }
}

impl Default for Block {
    /// 32×32 pixels, the paper's best block for 2×2 on its GPU (§5.1).
    fn default() -> Self {
        Self { p: 32, q: 32 }
    }
}

/// How a G-buffer is split and gathered.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum SplitVariant {
    /// §3.2: one pass, each destination texel computes its source by index arithmetic.
    OnePass,
    /// §3.3: block splitting then block translation (gather: translation then gathering).
    TwoPass(Block),
    /// One pass: a tile read coalesced, transposed through workgroup memory, written coalesced.
    Tiled,
}

impl SplitVariant {
    /// Short name for tables and CLI.
    pub fn name(self) -> String {
        match self {
            Self::OnePass => "one-pass".into(),
            Self::TwoPass(b) => format!("two-pass {}x{}", b.p, b.q),
            Self::Tiled => "tiled".into(),
        }
    }

    /// Checks the variant against a pattern.
    pub fn validate(self, pattern: Pattern) -> Result<(), InterleaveError> {
        match self {
            Self::OnePass => Ok(()),
            Self::TwoPass(block) => block.validate(pattern),
            Self::Tiled => tile(pattern).map(|_| ()),
        }
    }
}

/// Sub-buffer texels per tile of the tiled variant: (a, b) with a·n·b·m ≤ [`TILE_TEXELS`],
/// aiming at a 32×16-pixel tile so rows of the image are read whole.
pub fn tile(pattern: Pattern) -> Result<(u32, u32), InterleaveError> {
    let Pattern { n, m } = pattern;
    if n * m > TILE_TEXELS {
        return Err(InterleaveError::TileTooSmall { n, m });
    }
    let a = (32 / n).max(1);
    let mut b = (16 / m).max(1);
    while a * n * b * m > TILE_TEXELS && b > 1 {
        b -= 1;
    }
    let a = if a * n * b * m > TILE_TEXELS {
        (TILE_TEXELS / (n * b * m)).max(1)
    } else {
        a
    };
    Ok((a, b))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pattern_parsing() {
        assert_eq!("8x6".parse::<Pattern>().ok(), Some(Pattern { n: 8, m: 6 }));
        assert_eq!("4×4".parse::<Pattern>().ok(), Some(Pattern { n: 4, m: 4 }));
        for bad in ["", "4", "0x4", "4x", "ax4", "4x-1", "300x1"] {
            assert!(bad.parse::<Pattern>().is_err(), "{bad:?} accepted");
        }
    }

    #[test]
    fn tiles_fit_workgroup_memory() {
        for n in 1..=40 {
            for m in 1..=40 {
                let p = Pattern::new(n, m).unwrap_or(Pattern { n: 1, m: 1 });
                match tile(p) {
                    Ok((a, b)) => assert!(a >= 1 && b >= 1 && a * n * b * m <= TILE_TEXELS),
                    Err(_) => assert!(n * m > TILE_TEXELS),
                }
            }
        }
    }

    #[test]
    fn layout_round_trip() -> Result<(), InterleaveError> {
        let l = SplitLayout::new(7, 5, Pattern::new(3, 2)?)?;
        assert_eq!((l.split_width(), l.split_height()), (9, 6));
        let mut seen = std::collections::HashSet::new();
        for y in 0..5 {
            for x in 0..7 {
                let (sx, sy) = l.split_texel(x, y);
                assert_eq!(l.source_pixel(sx, sy), Some((x, y)));
                assert!(seen.insert((sx, sy)));
            }
        }
        Ok(())
    }
}
