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
    /// Slope-scaled depth tolerance: atlas pixels (at the receiver's distance) per unit of
    /// tan θ, θ between the receiver's normal and the direction to the view (at most
    /// [`MAX_SLOPE_TAN`]); a receiver's own plane moves that much depth across its pixel.
    pub slope: f32,
}

/// Largest tan θ of [`AtlasParams::slope`] (80.5°): past it a receiver is lit by a sliver.
pub const MAX_SLOPE_TAN: f32 = 6.0;

/// Where `p` (unit normal `n`) falls in paraboloid view `k` of an atlas, whose origin is
/// `origin` with unit `normal` (`atlas_texel` of `lookup.wgsl`): the atlas index and the
/// receiver's depth with the biases taken off; `None` behind the view's surface. The
/// receiver first moves off its surface by `normal_offset` atlas pixels at its distance (a
/// paraboloid pixel spans 2·(1 + cos θ)/tile radians), so the splats of its own surface in its
/// pixel do not shadow it. A receiver in front of the view's surface but behind its lifted
/// origin's base plane (a contact, within `lift` of the surface) is looked up on the rim,
/// along the surface: the view sees it there.
pub fn texel(
    params: &AtlasParams,
    k: u32,
    (origin, normal): (Vec3, Vec3),
    p: Vec3,
    n: Vec3,
) -> Option<(usize, f32)> {
    let to = p - origin;
    let distance = to.length();
    let dir = to / distance.max(1e-30);
    let cos = normal.dot(dir).max(0.0);
    let pixel = distance * 2.0 * (1.0 + cos) / params.tile as f32;
    let p = p + n * (pixel * params.normal_offset);
    let (t, b) = paraboloid_frame(normal);
    let d = p - (origin + normal * params.lift);
    let dist = d.length();
    let mut l = Vec3::new(t.dot(d), b.dot(d), normal.dot(d)) / dist;
    if l.z <= 0.0 {
        if normal.dot(p - origin) <= 0.0 || l.truncate() == glam::Vec2::ZERO {
            return None;
        }
        l = l.with_z(0.0).normalize();
    }
    let uv = l.truncate() / (1.0 + l.z);
    let px = ((uv * 0.5 + 0.5) * params.tile as f32)
        .as_uvec2()
        .min(UVec2::splat(params.tile - 1));
    let corner = UVec2::new(k % params.columns, k / params.columns) * params.tile;
    let index = (corner.y + px.y) * params.width + corner.x + px.x;
    let c = n.dot(-dir).clamp(1e-3, 1.0);
    let tan = ((1.0 - c * c).sqrt() / c).min(MAX_SLOPE_TAN);
    let slope = params.slope * tan * pixel / params.far;
    Some((index as usize, dist / params.far - params.bias - slope))
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

#[cfg(test)]
mod tests {
    use super::*;

    /// One 8×8 view at the origin looking up (+y), lifted 1 cm, over an empty atlas.
    fn params() -> AtlasParams {
        AtlasParams {
            enabled: 1,
            tile: 8,
            columns: 1,
            width: 8,
            far: 10.0,
            lift: 0.01,
            ..AtlasParams::default()
        }
    }

    #[test]
    fn contacts_within_the_lift_are_looked_up_on_the_rim() {
        let (params, atlas) = (params(), vec![splat::CLEAR; 64]);
        let view = (Vec3::ZERO, Vec3::Y);
        // A wall 0.5 m away, facing the view: a point 5 mm up lies below the lifted origin.
        let wall = Vec3::NEG_X;
        let (index, _) = texel(&params, 0, view, Vec3::new(0.5, 0.005, 0.0), wall)
            .expect("a receiver in front of the view's surface has a texel");
        // On the rim: the row through the tile's centre, the first column (the frame's t is −x).
        assert_eq!(paraboloid_frame(Vec3::Y).0, Vec3::NEG_X);
        assert_eq!(index, 4 * 8);
        assert_eq!(
            visibility(&atlas, &params, 0, view, Vec3::new(0.5, 0.005, 0.0), wall),
            1.0
        );
        // Behind the view's surface nothing is seen.
        assert_eq!(
            texel(&params, 0, view, Vec3::new(0.5, -0.005, 0.0), wall),
            None
        );
        assert_eq!(
            visibility(&atlas, &params, 0, view, Vec3::new(0.5, -0.005, 0.0), wall),
            0.0
        );
    }

    #[test]
    fn slope_tolerance_grows_with_the_receivers_tilt() {
        let params = AtlasParams {
            slope: 1.0,
            ..params()
        };
        let view = (Vec3::ZERO, Vec3::Y);
        let p = Vec3::new(0.0, 2.0, 0.0);
        let depth = |n: Vec3| texel(&params, 0, view, p, n).expect("texel").1;
        let (facing, tilted) = (
            depth(Vec3::NEG_Y),
            depth(Vec3::new(1.0, -1.0, 0.0).normalize()),
        );
        // A pixel at the centre spans 4/8 rad: at 2 m, 1 m; tan 45° = 1 → 1 m / far less depth.
        assert!((facing - (2.0 - 0.01) / 10.0).abs() < 1e-6, "{facing}");
        assert!((facing - tilted - 0.1).abs() < 1e-5, "{facing} vs {tilted}");
        // Grazing receivers stop at MAX_SLOPE_TAN.
        let grazing = depth(Vec3::new(1.0, -1e-4, 0.0).normalize());
        assert!(
            (facing - grazing - 0.1 * MAX_SLOPE_TAN).abs() < 1e-4,
            "{grazing}"
        );
    }
}
