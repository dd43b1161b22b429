// The light accumulation's outputs at group 0, bindings 7 and 8 — the diffuse and specular
// sums per pixel — written by the compute passes (`tiled.wgsl`, `clustered.wgsl`).
// #import tiled-shading/lighting.wgsl

@group(0) @binding(7) var diffuse_out: texture_storage_2d<rgba32float, write>;
@group(0) @binding(8) var specular_out: texture_storage_2d<rgba32float, write>;

fn store_sums(pixel: vec2<u32>, sum: Accumulated) {
    textureStore(diffuse_out, pixel, vec4<f32>(sum.diffuse, 0.0));
    textureStore(specular_out, pixel, vec4<f32>(sum.specular, 0.0));
}
