//! The edge-aware separable Gaussian blur (§4.5): `blur.wgsl`.

use gbuffer::Image;

use crate::{Blur, BlurVariant, InterleaveError};

use super::{check_size, per_texel};

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
