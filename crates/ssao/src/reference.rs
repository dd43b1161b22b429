//! Ray-traced ambient occlusion on the CPU: the ground truth of the crate's definition
//! ([`crate`]), evaluated at every pixel of a G-buffer with cosine-weighted rays through the
//! scene's BVH (`scene::Bvh`, obvhs).

use gbuffer::{Frame, GBuffer, Image};
use glam::{Vec2, Vec3};
use scene::{Bvh, reference::ray_lift};

use crate::{AoConfig, SsaoError};

/// The most rays a pixel takes.
pub const MAX_SAMPLES: u32 = 1 << 16;

/// The accessibility A of every pixel of `gbuffer` (seen through `frame`) with `samples` rays,
/// 1 where no surface is. The rays leave p lifted along n by `scene::reference::ray_lift` (as
/// the renderer's shadow rays do), are cosine-weighted over the hemisphere of the G-buffer's
/// normal — Hammersley points rotated per pixel, so a pixel's rays are stratified, its
/// neighbours' are decorrelated and the result is deterministic — and count as blocked when
/// they meet any triangle of `bvh` within `config.radius`. A is the unblocked fraction, which
/// estimates (1/π)∫V_r cos dω (independent rays would err by up to 0.5/√samples; the
/// stratified ones do better on smooth visibility).
pub fn ray_traced(
    bvh: &Bvh,
    gbuffer: &GBuffer,
    frame: &Frame,
    config: &AoConfig,
    samples: u32,
) -> Result<Image<f32>, SsaoError> {
    config.validate()?;
    if !(1..=MAX_SAMPLES).contains(&samples) {
        return Err(SsaoError::InvalidSamples(samples));
    }
    crate::check_size(gbuffer, frame)?;
    let size = (gbuffer.linear_depth.width(), gbuffer.linear_depth.height());
    Ok(crate::per_pixel(size, |x, y, i| {
        let depth = gbuffer.linear_depth.get(x, y);
        if depth <= 0.0 {
            return 1.0;
        }
        let p = gbuffer::position::from_view_ray(frame, x, y, depth);
        let n = gbuffer::normal::unpack_octahedral(gbuffer.normal.get(x, y));
        let origin = p + n * ray_lift(p);
        let (t, b) = tangent_frame(n);
        let rotation = pixel_rotation(i);
        let open = (0..samples)
            .filter(|&k| {
                let u = hammersley(k, samples) + rotation;
                let d = cosine_direction(Vec2::new(u.x.fract(), u.y.fract()));
                let direction = t * d.x + b * d.y + n * d.z;
                !bvh.any_hit(origin, direction, config.radius)
            })
            .count();
        open as f32 / samples as f32
    }))
}

/// Point k of the n-point Hammersley set in [0, 1)².
fn hammersley(k: u32, n: u32) -> Vec2 {
    Vec2::new(
        (k as f32 + 0.5) / n as f32,
        k.reverse_bits() as f32 * (1.0 / 4_294_967_296.0),
    )
}

/// A per-pixel toroidal shift of the point set (Cranley–Patterson rotation) from a hash of
/// the pixel index.
fn pixel_rotation(i: u32) -> Vec2 {
    let mut h = i.wrapping_mul(0x9e37_79b9) ^ 0x85eb_ca6b;
    h ^= h >> 16;
    h = h.wrapping_mul(0x7feb_352d);
    h ^= h >> 15;
    let g = h.wrapping_mul(0x846c_a68b);
    Vec2::new(
        h as f32 * (1.0 / 4_294_967_296.0),
        (g ^ (g >> 16)) as f32 * (1.0 / 4_294_967_296.0),
    )
}

/// The cosine-weighted direction of `u` ∈ [0, 1)² in the frame whose z is the normal.
fn cosine_direction(u: Vec2) -> Vec3 {
    let r = u.x.sqrt();
    let phi = std::f32::consts::TAU * u.y;
    Vec3::new(r * phi.cos(), r * phi.sin(), (1.0 - u.x).max(0.0).sqrt())
}

/// Two unit tangents completing `n` to an orthonormal frame (Duff et al. 2017).
fn tangent_frame(n: Vec3) -> (Vec3, Vec3) {
    let sign = 1f32.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    (
        Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
        Vec3::new(b, sign + n.y * n.y * a, -n.y),
    )
}
