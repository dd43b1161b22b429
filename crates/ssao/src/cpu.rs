//! The screen-space estimators on the CPU (the GPU kernels' twins to be): the non-separable
//! k×k kernel of eq. 7.1 and its separable approximation (Holländer 2013 §7.2.2, Huang et al.
//! 2011), both over the G-buffer's positions and normals.
//!
//! **Neighbour samples.** A neighbour pixel q's surface point Q stands for the direction
//! ω = (Q − p)/|Q − p| from p: it blocks ω when it lies above p's tangent plane within the
//! radius, and then contributes o(p, q) = cos(n, ω) (0 otherwise). With directions taken as
//! if spread uniformly over the hemisphere, (1/π)∫(1 − V_r) cos dω ≈ 2·mean(o), so
//! A ≈ 1 − 2·mean(o), clamped to [0, 1]: 1 on an open plane (every neighbour lies in the
//! tangent plane). Pixels without a surface are neither occluded nor occluders (A = 1).
//!
//! **The separable approximation.** Pass 1 evaluates the 1D kernel along one screen direction
//! u(p) — the k − 1 neighbours p + t·u, t = −k/2..k/2, t ≠ 0 — into O₁(p) = mean(o). Pass 2
//! averages O₁ over the k pixels p + t·v along the perpendicular v(p), keeping only those on
//! p's surface (depth within 5 % and normals within 25°: the feature-preserving smoothing), and
//! A = 1 − 2·mean. The frame (u, v) turns per pixel by interleaved sampling with the pattern
//! size equal to the kernel size (§7.2.2): the pixel at (x mod k, y mod k) of each k × k tile
//! takes angle π·(x mod k + k·(y mod k) + ½)/k², so the 1D evaluations of neighbouring pixels
//! cover all directions of the half circle and pass 2 combines them. Cost: 2k − 1 samples a
//! pixel instead of k² − 1.

use gbuffer::{Frame, GBuffer, Image};
use glam::{Vec2, Vec3};

use crate::{AoConfig, SsaoError};

/// The kernel: `size` pixels on a side (odd, 3..=[`MAX_KERNEL`]) and the occlusion radius.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KernelConfig {
    /// Kernel side in pixels (the paper's k: 5, 11, 21).
    pub size: u32,
    /// The occlusion definition.
    pub ao: AoConfig,
}

/// The widest kernel.
pub const MAX_KERNEL: u32 = 63;

impl KernelConfig {
    /// Checks the kernel size and the radius.
    pub fn validate(&self) -> Result<(), SsaoError> {
        self.ao.validate()?;
        if self.size.is_multiple_of(2) || !(3..=MAX_KERNEL).contains(&self.size) {
            return Err(SsaoError::InvalidKernel(self.size));
        }
        Ok(())
    }
}

/// A G-buffer pixel's surface: position and normal (`None` where nothing was drawn).
struct Surfaces<'a> {
    gbuffer: &'a GBuffer,
    frame: &'a Frame,
}

impl Surfaces<'_> {
    fn size(&self) -> (i32, i32) {
        (
            self.gbuffer.linear_depth.width() as i32,
            self.gbuffer.linear_depth.height() as i32,
        )
    }

    fn at(&self, x: i32, y: i32) -> Option<(Vec3, Vec3, f32)> {
        let (w, h) = self.size();
        if x < 0 || y < 0 || x >= w || y >= h {
            return None;
        }
        let (x, y) = (x as u32, y as u32);
        let depth = self.gbuffer.linear_depth.get(x, y);
        (depth > 0.0).then(|| {
            let p = gbuffer::position::from_view_ray(self.frame, x, y, depth);
            let n = gbuffer::normal::unpack_octahedral(self.gbuffer.normal.get(x, y));
            (p, n, depth)
        })
    }
}

fn check(gbuffer: &GBuffer, frame: &Frame, config: &KernelConfig) -> Result<(), SsaoError> {
    config.validate()?;
    crate::check_size(gbuffer, frame)
}

/// o(p, q): the cosine of the direction to `q` when it blocks it within `radius`, else 0.
fn occlusion(p: Vec3, n: Vec3, q: Vec3, radius: f32) -> f32 {
    let v = q - p;
    let d = v.length();
    if d <= 0.0 || d >= radius {
        return 0.0;
    }
    (n.dot(v) / d).max(0.0)
}

/// A = 1 − 2·mean(o), clamped.
fn accessibility(mean_occlusion: f32) -> f32 {
    (1.0 - 2.0 * mean_occlusion).clamp(0.0, 1.0)
}

/// Eq. 7.1: every neighbour of the k × k window (k² − 1 samples a pixel).
pub fn kernel_2d(
    gbuffer: &GBuffer,
    frame: &Frame,
    config: &KernelConfig,
) -> Result<Image<f32>, SsaoError> {
    check(gbuffer, frame, config)?;
    let s = Surfaces { gbuffer, frame };
    let half = (config.size / 2) as i32;
    let samples = (config.size * config.size - 1) as f32;
    Ok(crate::per_pixel(gbuffer, |x, y, _| {
        let (x, y) = (x as i32, y as i32);
        let Some((p, n, _)) = s.at(x, y) else {
            return 1.0;
        };
        let mut sum = 0.0;
        for dy in -half..=half {
            for dx in -half..=half {
                if let Some((q, _, _)) = s.at(x + dx, y + dy).filter(|_| (dx, dy) != (0, 0)) {
                    sum += occlusion(p, n, q, config.ao.radius);
                }
            }
        }
        accessibility(sum / samples)
    }))
}

/// The frame directions u of a k × k interleaving tile: entry x + k·y at angle
/// π·(x + k·y + ½)/k² (the GPU kernels read the same table).
pub fn frame_directions(k: u32) -> Vec<Vec2> {
    let n = k * k;
    (0..n)
        .map(|i| {
            let a = std::f32::consts::PI * (i as f32 + 0.5) / n as f32;
            Vec2::new(a.cos(), a.sin())
        })
        .collect()
}

/// Pixel (x, y)'s frame direction u in `directions` ([`frame_directions`] of k).
fn frame_direction(directions: &[Vec2], x: i32, y: i32, k: u32) -> Vec2 {
    let k = k as i32;
    directions[(x.rem_euclid(k) + k * y.rem_euclid(k)) as usize]
}

/// The pixel `t` steps along `direction` from (x, y), rounded half up.
fn step(x: i32, y: i32, direction: Vec2, t: i32) -> (i32, i32) {
    let o = (direction * t as f32 + 0.5).floor();
    (x + o.x as i32, y + o.y as i32)
}

/// Pass 1: mean occlusion O₁ along `direction(x, y)` (k − 1 samples).
pub fn pass_1d(
    gbuffer: &GBuffer,
    frame: &Frame,
    config: &KernelConfig,
    direction: impl Fn(i32, i32) -> Vec2 + Sync + Send,
) -> Result<Image<f32>, SsaoError> {
    check(gbuffer, frame, config)?;
    let s = Surfaces { gbuffer, frame };
    let half = (config.size / 2) as i32;
    let samples = (config.size - 1) as f32;
    Ok(crate::per_pixel(gbuffer, |x, y, _| {
        let (x, y) = (x as i32, y as i32);
        let Some((p, n, _)) = s.at(x, y) else {
            return 0.0;
        };
        let u = direction(x, y);
        let mut sum = 0.0;
        for t in (-half..=half).filter(|&t| t != 0) {
            let (qx, qy) = step(x, y, u, t);
            if let Some((q, _, _)) = s.at(qx, qy) {
                sum += occlusion(p, n, q, config.ao.radius);
            }
        }
        sum / samples
    }))
}

/// Whether pixel q lies on p's surface (the feature-preserving weight of pass 2).
fn same_surface(p: (Vec3, Vec3, f32), q: (Vec3, Vec3, f32)) -> bool {
    (q.2 - p.2).abs() <= 0.05 * p.2 && p.1.dot(q.1) >= 0.9
}

/// The separable approximation (§7.2.2): pass 1 along each pixel's interleaved frame's u,
/// pass 2 over its v (see the module).
pub fn separable(
    gbuffer: &GBuffer,
    frame: &Frame,
    config: &KernelConfig,
) -> Result<Image<f32>, SsaoError> {
    let k = config.size;
    let directions = frame_directions(k);
    let u = |x: i32, y: i32| frame_direction(&directions, x, y, k);
    let first = pass_1d(gbuffer, frame, config, u)?;
    let s = Surfaces { gbuffer, frame };
    let half = (k / 2) as i32;
    Ok(crate::per_pixel(gbuffer, |x, y, _| {
        let (x, y) = (x as i32, y as i32);
        let Some(here) = s.at(x, y) else {
            return 1.0;
        };
        let d = u(x, y);
        let v = Vec2::new(-d.y, d.x);
        let (mut sum, mut count) = (0.0, 0.0);
        for t in -half..=half {
            let (qx, qy) = step(x, y, v, t);
            if s.at(qx, qy).is_some_and(|q| same_surface(here, q)) {
                sum += first.get(qx as u32, qy as u32);
                count += 1.0;
            }
        }
        accessibility(sum / count)
    }))
}
