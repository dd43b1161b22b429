//! Exact VPL visibility by rays (beyond Segovia 2006, whose SSM maps are exact only up to their
//! resolution): the scene's BVH of [`tiled_shading::rays`] traversed per (receiver, VPL) pair
//! by `vpl_shading.wgsl`.

use glam::Vec3;
pub use tiled_shading::rays::{RayBvh, RayNode, RayTriangle, STACK, ray_lift};

/// Visibility of receiver `p` (unit normal `n`) from a VPL at `q` (unit normal `n_q`): 0 when
/// a triangle lies between the two, each lifted off its surface by `offset` × [`ray_lift`]
/// (`vpl_visibility` of `vpl_shading.wgsl`).
pub fn visibility(bvh: &RayBvh, (p, n): (Vec3, Vec3), (q, n_q): (Vec3, Vec3), offset: f32) -> f32 {
    let from = p + n * (offset * ray_lift(p));
    let to = q + n_q * (offset * ray_lift(q));
    f32::from(u8::from(!bvh.occluded(from, to - from)))
}
