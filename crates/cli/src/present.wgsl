// The viewer's present kernel: the renderer's display-linear image (after the output
// transform) encoded as 8-bit sRGB, as render.png stores it (`gbuffer::Image::to_srgb8`), in a
// texture egui shows as it is.

@group(0) @binding(0) var display: texture_2d<f32>;
@group(0) @binding(1) var shown: texture_storage_2d<rgba8unorm, write>;

// IEC 61966-2-1, as `gbuffer::linear_to_srgb`.
fn linear_to_srgb(c: vec3<f32>) -> vec3<f32> {
    let x = clamp(c, vec3<f32>(0.0), vec3<f32>(1.0));
    return select(1.055 * pow(x, vec3<f32>(1.0 / 2.4)) - 0.055, 12.92 * x, x <= vec3<f32>(0.0031308));
}

@compute @workgroup_size(8, 8)
fn present_main(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = textureDimensions(shown);
    if any(id.xy >= size) {
        return;
    }
    let c = textureLoad(display, id.xy, 0).rgb;
    textureStore(shown, id.xy, vec4<f32>(linear_to_srgb(c), 1.0));
}
