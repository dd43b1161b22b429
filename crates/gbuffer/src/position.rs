//! Position from depth, both ways of Ishmukhametov 2013 §3.6. WGSL twins in
//! `shaders/gbuffer/frame.wgsl` (`position_from_depth`, `position_from_view_ray`).

use glam::{Vec2, Vec3, Vec4};

use crate::Frame;

/// NDC xy of pixel (x, y)'s sample position — its centre, moved by the frame's jitter
/// ([`Frame::with_jitter`]): x right, y up (thesis §3.6 step 1).
pub fn pixel_to_ndc(frame: &Frame, x: u32, y: u32) -> Vec2 {
    let at = Vec2::new(x as f32, y as f32) + 0.5 + Vec2::new(frame.sampling.x, frame.sampling.y);
    let uv = at * Vec2::new(frame.viewport.z, frame.viewport.w);
    Vec2::new(uv.x * 2.0 - 1.0, (1.0 - uv.y) * 2.0 - 1.0)
}

/// Inverse transformation: world position from hardware depth z/w through the inverse
/// view-projection matrix, then the divide by w.
pub fn from_depth(frame: &Frame, x: u32, y: u32, depth: f32) -> Vec3 {
    let ndc = pixel_to_ndc(frame, x, y);
    let p = frame.inv_view_proj * Vec4::new(ndc.x, ndc.y, depth, 1.0);
    p.truncate() / p.w
}

/// Ray and view frustum: the eye plus the view ray through the pixel, scaled to unit view
/// depth, times the linear view depth. (The thesis normalizes the ray and stores the
/// distance; storing the view-axis depth instead needs no normalization and is what the
/// rasterizer interpolates exactly.)
pub fn from_view_ray(frame: &Frame, x: u32, y: u32, linear_depth: f32) -> Vec3 {
    frame.eye.truncate() + view_ray(frame, x, y) * linear_depth
}

/// The view ray through pixel (x, y) in world space, scaled to unit view depth.
pub fn view_ray(frame: &Frame, x: u32, y: u32) -> Vec3 {
    let ndc = pixel_to_ndc(frame, x, y);
    let ray_view = Vec3::new(
        ndc.x * frame.tan_half_fov.x,
        ndc.y * frame.tan_half_fov.y,
        -1.0,
    );
    frame.inv_view.transform_vector3(ray_view)
}
