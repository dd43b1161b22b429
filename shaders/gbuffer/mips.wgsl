// Mip chain generation at load (the G-buffer's textures): level l + 1 is drawn from level l,
// each texel the bilinear sample (clamped to the edge) of level l at its centre — the 2 × 2
// box filter where level l's side is even. The view formats decode sRGB before filtering and
// encode it on write. Twin of `scene::LinearTexture::mipmapped`. `fs_resample` draws a texture
// into a target of another size (a layer of `MaterialTextures::array`): each texel the texture's
// own sampler at level 0 at the texel's centre, the twin of `scene::LinearTexture::sample`.

@group(0) @binding(0) var source: texture_2d<f32>;
@group(0) @binding(1) var edge: sampler;

// One triangle covering the viewport.
@vertex
fn vs_fullscreen(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let corner = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4<f32>(corner * 2.0 - 1.0, 0.0, 1.0);
}

@fragment
fn fs_downsample(@builtin(position) pixel: vec4<f32>) -> @location(0) vec4<f32> {
    let target_size = max(textureDimensions(source) / 2u, vec2<u32>(1u));
    return textureSampleLevel(source, edge, pixel.xy / vec2<f32>(target_size), 0.0);
}

struct Resample {
    @builtin(position) clip: vec4<f32>,
    @location(0) uv: vec2<f32>,
};

// The viewport's triangle with texture coordinates: (0, 0) at the top-left corner of the
// target, (1, 1) at the bottom-right, so a texel centre gets ((x + ½) / w, (y + ½) / h).
@vertex
fn vs_resample(@builtin(vertex_index) i: u32) -> Resample {
    let corner = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    return Resample(vec4<f32>(corner * 2.0 - 1.0, 0.0, 1.0), vec2<f32>(corner.x, 1.0 - corner.y));
}

@fragment
fn fs_resample(in: Resample) -> @location(0) vec4<f32> {
    return textureSampleLevel(source, edge, in.uv, 0.0);
}
