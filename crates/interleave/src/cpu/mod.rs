//! CPU reference of every kernel. Each function mirrors the WGSL kernel of the same name
//! (in `shaders/interleave/`) loop for loop: the split and gather passes compute each
//! destination texel from its source by the same index arithmetic, the tiled variant stages a
//! tile the way the workgroup does. Rows (or tile rows) run in parallel with rayon.
//!
//! One module per kernel stage, named after its WGSL file: [`split`] (one-pass, two-pass block
//! and tiled split and gather), [`discontinuity`], [`blur`], [`shade`].

use gbuffer::Image;
use rayon::prelude::*;

use crate::InterleaveError;

pub mod blur;
pub mod discontinuity;
pub mod shade;
pub mod split;

pub use blur::{blur, blur_pass, to_f16};
pub use discontinuity::{depths_differ, discontinuity, normals_differ, octahedral_integer};
pub use shade::{SubsetLight, shade_subsets};
pub use split::*;

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
