//! The FXAA baseline on `S` (`shaders/adaptive-ssaa/fxaa.wgsl`).

use gbuffer::Image;
use glam::{Vec2, Vec4, Vec4Swizzles};

use super::{LUMINANCE, per_pixel};

/// FXAA constants (Lottes 2009, the "console" variant).
const FXAA_EDGE_THRESHOLD: f32 = 0.125;
const FXAA_EDGE_THRESHOLD_MIN: f32 = 0.0312;
const FXAA_REDUCE_MUL: f32 = 1.0 / 8.0;
const FXAA_REDUCE_MIN: f32 = 1.0 / 128.0;
const FXAA_SPAN_MAX: f32 = 8.0;

/// Bilinear lookup of an image at a continuous position (pixel centres at +0.5), clamped to
/// the edges (`bilinear`).
fn bilinear(img: &Image<[f32; 4]>, pos: Vec2) -> Vec4 {
    let (w, h) = (img.width() as i32, img.height() as i32);
    let p = pos - 0.5;
    let f = p.floor();
    let t = p - f;
    let at = |dx: i32, dy: i32| {
        let x = (f.x as i32 + dx).clamp(0, w - 1) as u32;
        let y = (f.y as i32 + dy).clamp(0, h - 1) as u32;
        Vec4::from(img.get(x, y))
    };
    at(0, 0)
        .lerp(at(1, 0), t.x)
        .lerp(at(0, 1).lerp(at(1, 1), t.x), t.y)
}

/// The post-process edge anti-aliasing baseline (`fxaa`): FXAA's console variant on `S`, the
/// one-sample image (§4.2's RGB-based filters).
pub fn fxaa(s: &Image<[f32; 4]>) -> Image<[f32; 4]> {
    let luma = |c: Vec4| c.xyz().dot(LUMINANCE);
    per_pixel(s.width(), s.height(), |x, y| {
        let pos = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
        let m = Vec4::from(s.get(x, y));
        let nw = luma(bilinear(s, pos + Vec2::new(-0.5, -0.5)));
        let ne = luma(bilinear(s, pos + Vec2::new(0.5, -0.5)));
        let sw = luma(bilinear(s, pos + Vec2::new(-0.5, 0.5)));
        let se = luma(bilinear(s, pos + Vec2::new(0.5, 0.5)));
        let lm = luma(m);
        let lo = lm.min(nw.min(ne).min(sw.min(se)));
        let hi = lm.max(nw.max(ne).max(sw.max(se)));
        if hi - lo < FXAA_EDGE_THRESHOLD_MIN.max(hi * FXAA_EDGE_THRESHOLD) {
            return m.to_array();
        }
        let dir = Vec2::new(-((nw + ne) - (sw + se)), (nw + sw) - (ne + se));
        let reduce = ((nw + ne + sw + se) * (0.25 * FXAA_REDUCE_MUL)).max(FXAA_REDUCE_MIN);
        let rcp_min = 1.0 / (dir.x.abs().min(dir.y.abs()) + reduce);
        let dir = (dir * rcp_min).clamp(Vec2::splat(-FXAA_SPAN_MAX), Vec2::splat(FXAA_SPAN_MAX));
        let a = (bilinear(s, pos + dir * (1.0 / 3.0 - 0.5))
            + bilinear(s, pos + dir * (2.0 / 3.0 - 0.5)))
            * 0.5;
        let b = a * 0.5 + (bilinear(s, pos - dir * 0.5) + bilinear(s, pos + dir * 0.5)) * 0.25;
        let lb = luma(b);
        let out = if lb < lo || lb > hi { a } else { b };
        out.xyz().extend(1.0).to_array()
    })
}
