// Per-frame camera data shared by every screen-space pass. Mirrors `gbuffer::Frame`.
struct Frame {
    view_proj: mat4x4<f32>,
    view: mat4x4<f32>,
    inv_view_proj: mat4x4<f32>,
    inv_view: mat4x4<f32>,
    // xyz: eye position in world space.
    eye: vec4<f32>,
    // width, height, 1 / width, 1 / height.
    viewport: vec4<f32>,
    // x: tan(fov_y / 2) * aspect, y: tan(fov_y / 2) (view ray at unit view depth).
    tan_half_fov: vec4<f32>,
    // xy: sample offset from the pixel centres in pixels (`Frame::with_jitter`; view_proj is
    // shifted by it, inv_view_proj is not); z: texture footprint in G-buffer pixels.
    sampling: vec4<f32>,
};

// Normalized device xy of a pixel's sample position, its centre moved by the jitter (x right,
// y up), thesis §3.6 step 1.
fn pixel_to_ndc(frame: Frame, pixel: vec2<u32>) -> vec2<f32> {
    let uv = (vec2<f32>(pixel) + 0.5 + frame.sampling.xy) * frame.viewport.zw;
    return vec2<f32>(uv.x * 2.0 - 1.0, (1.0 - uv.y) * 2.0 - 1.0);
}

// Thesis §3.6, inverse transformation: world position from hardware depth (z / w).
fn position_from_depth(frame: Frame, pixel: vec2<u32>, depth: f32) -> vec3<f32> {
    let p = frame.inv_view_proj * vec4<f32>(pixel_to_ndc(frame, pixel), depth, 1.0);
    return p.xyz / p.w;
}

// Thesis §3.6, ray and view frustum: world position as eye + view ray × linear view depth,
// with the view ray scaled to unit view depth.
fn position_from_view_ray(frame: Frame, pixel: vec2<u32>, linear_depth: f32) -> vec3<f32> {
    return frame.eye.xyz + view_ray(frame, pixel) * linear_depth;
}

// The view ray through a pixel in world space, scaled to unit view depth.
fn view_ray(frame: Frame, pixel: vec2<u32>) -> vec3<f32> {
    let ndc = pixel_to_ndc(frame, pixel);
    let ray_view = vec3<f32>(ndc * frame.tan_half_fov.xy, -1.0);
    return (frame.inv_view * vec4<f32>(ray_view, 0.0)).xyz;
}
