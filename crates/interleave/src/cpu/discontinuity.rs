//! The discontinuity buffer (§4.5): `discontinuity.wgsl`.

use gbuffer::Image;

use crate::{InterleaveError, Thresholds};

use super::{check_size, per_texel};

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
