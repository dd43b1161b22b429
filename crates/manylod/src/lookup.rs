//! Shadow lookup in an atlas of paraboloid views (Holländer 2013 §3.6: the cut's splats are
//! shadow maps): is a receiver visible from a view's origin? `lookup.wgsl` mirrors it; the
//! VPL shading (`instant-radiosity`) and the direct lights' ManyLoD shadows (`tiled-shading`)
//! look up the same way, each in its own atlas binding.

use glam::{UVec2, Vec3};

use crate::{splat, view::paraboloid_frame};

/// Uniform block `AtlasParams` of `lookup.wgsl`: where view `k`'s tile lies and how a
/// receiver is compared with it.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct AtlasParams {
    /// 0: no visibility (every view sees everything).
    pub enabled: u32,
    /// Tile side in pixels.
    pub tile: u32,
    /// Tiles per atlas row.
    pub columns: u32,
    /// Atlas row length in pixels.
    pub width: u32,
    /// Distance mapped to depth 1.
    pub far: f32,
    /// How far each view sits off its origin, along its normal.
    pub lift: f32,
    /// Depth bias (fraction of `far`).
    pub bias: f32,
    /// Normal offset of receivers, in atlas pixels at their distance.
    pub normal_offset: f32,
}

/// Where `p` (unit normal `n`) falls in paraboloid view `k` of an atlas, whose origin is
/// `origin` with unit `normal` (`atlas_texel` of `lookup.wgsl`): the atlas index and the
/// receiver's depth with the bias taken off; `None` behind the view's base plane. The
/// receiver first moves off its surface by `normal_offset` atlas pixels at its distance (a
/// paraboloid pixel spans 2·(1 + cos θ)/tile radians), so the splats of its own surface in its
/// pixel do not shadow it.
pub fn texel(
    params: &AtlasParams,
    k: u32,
    (origin, normal): (Vec3, Vec3),
    p: Vec3,
    n: Vec3,
) -> Option<(usize, f32)> {
    let to = p - origin;
    let cos = normal.dot(to.normalize_or_zero()).max(0.0);
    let p = p + n * (to.length() * 2.0 * (1.0 + cos) / params.tile as f32 * params.normal_offset);
    let (t, b) = paraboloid_frame(normal);
    let d = p - (origin + normal * params.lift);
    let dist = d.length();
    let l = Vec3::new(t.dot(d), b.dot(d), normal.dot(d)) / dist;
    if l.z <= 0.0 {
        return None;
    }
    let uv = l.truncate() / (1.0 + l.z);
    let px = ((uv * 0.5 + 0.5) * params.tile as f32)
        .as_uvec2()
        .min(UVec2::splat(params.tile - 1));
    let corner = UVec2::new(k % params.columns, k / params.columns) * params.tile;
    let index = (corner.y + px.y) * params.width + corner.x + px.x;
    Some((index as usize, dist / params.far - params.bias))
}

/// Visibility of `p` (unit normal `n`) from paraboloid view `k` of `atlas` ([`texel`], then
/// [`test`]): 1 when the stored depth is not nearer than `p`, 0 behind
/// the view's base plane or occluded; always 1 when `params` are disabled.
pub fn visibility(
    atlas: &[u32],
    params: &AtlasParams,
    k: u32,
    view: (Vec3, Vec3),
    p: Vec3,
    n: Vec3,
) -> f32 {
    if params.enabled == 0 {
        return 1.0;
    }
    texel(params, k, view, p, n).map_or(0.0, |t| test(atlas, t))
}

/// 1 when the stored depth at a [`texel`] of `atlas` is not nearer than its receiver, else
/// 0 (`atlas_test` of `lookup.wgsl`).
pub fn test(atlas: &[u32], (index, depth): (usize, f32)) -> f32 {
    let word = atlas.get(index).copied().unwrap_or(u32::MAX);
    f32::from(u8::from(depth <= splat::unpack_depth(word)))
}
