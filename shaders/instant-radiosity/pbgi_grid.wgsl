// What point-based GI's per-frame kernels share (`pbgi_receivers.wgsl`, `pbgi_upsample.wgsl`):
// the frame, the receiver grid (`instant_radiosity::pbgi::ReceiverGrid`) and the G-buffer's
// view depth and normals.
// #import gbuffer/frame.wgsl
// #import gbuffer/normal_encoding.wgsl

struct Grid {
    stride: u32,
    columns: u32,
    rows: u32,
    tile: u32,
}

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<uniform> grid: Grid;
@group(0) @binding(2) var linear_depth: texture_2d<f32>;
@group(0) @binding(3) var normals: texture_2d<u32>;

fn normal_at(pixel: vec2<u32>) -> vec3<f32> {
    return decode_octahedral_snorm(unpack2x16snorm(textureLoad(normals, pixel, 0).x));
}

// The pixel of receiver cell `c` (`ReceiverGrid::pixel`) in a frame of `size`.
fn receiver_pixel(c: vec2<u32>, size: vec2<u32>) -> vec2<u32> {
    return min(c * grid.stride + grid.stride / 2u, size - 1u);
}
