// #import adaptive-ssaa/common.wgsl
// Shading stages of §4.3.4: S, the adaptive resolve and full supersampling (`adaptive_ssaa::cpu::shade`).

// S: the first sample of every window, filtered over the whole pixel.
@compute @workgroup_size(8, 8)
fn shade_first(@builtin(global_invocation_id) id: vec3<u32>) {
    let p = id.xy;
    if !in_image(p) {
        return;
    }
    first[pixel_index(p)] = vec4<f32>(shade_sample(window_sample(p, 0u), footprint_scale(1u)), 1.0);
}

// Listing 4.1's ShadeRestAdaptively, one invocation per pixel looping over its samples.
@compute @workgroup_size(8, 8)
fn shade_adaptive(@builtin(global_invocation_id) id: vec3<u32>) {
    let p = id.xy;
    if !in_image(p) {
        return;
    }
    let i = pixel_index(p);
    let k = samples_or_first(i);
    if k > 1u {
        out_image[i] = average_samples(p, k);
    }
}

// Full supersampling: every sample of every window.
@compute @workgroup_size(8, 8)
fn shade_full(@builtin(global_invocation_id) id: vec3<u32>) {
    let p = id.xy;
    if !in_image(p) {
        return;
    }
    out_image[pixel_index(p)] = average_samples(p, params.n);
}
