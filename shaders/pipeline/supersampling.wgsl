// #import pipeline/compose.wgsl
// Supersampling inside the frame (`pipeline::supersampling`): the frame's stages on a
// supersampled G-buffer of m × m samples per pixel, adaptive after Holländer 2013 §4.3
// (Listing 4.1) or full. Pixel p's window holds the samples p·m + (0..m)², visited in the
// ordered-dither order `order` (`adaptive_ssaa::dither_order`). The frame's pixel-resolution
// G-buffer is jittered onto each window's first sample, so the frame without supersampling —
// light accumulation, indirect light, composition — computes S, the first sample's radiance
// (`store_first` keeps it for the evaluation and the resolve). The light accumulation
// (`tiled.wgsl`, any method, with shadows) then shades the remaining samples whose linear
// depth `mask_rest`/`mask_full` keep (the others read as no surface), so the direct light of a
// sample is culled and shadowed as in the frame without supersampling. Indirect light is the
// pixel's, shared by its samples: sample radiance = `compose` of the sample's G-buffer and
// direct light with the pixel's indirect light.

struct Params {
    width: u32,
    height: u32,
    m: u32,
    n: u32,
    // Sample i of the window is cell (order[i] & 0xff, order[i] >> 8).
    order: array<vec4<u32>, 16>,
    // Cell (x, y) of the window is sample rank[y·m + x] of the order.
    rank: array<vec4<u32>, 16>,
};

struct CompositionParams {
    // rgb: ambient radiance; w: 1 when `accessibility` holds screen-space ambient occlusion.
    ambient: vec4<f32>,
};

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<uniform> composition: CompositionParams;
@group(0) @binding(2) var linear_depth_in: texture_2d<f32>;
@group(0) @binding(3) var masked_depth_out: texture_storage_2d<r32float, write>;
@group(0) @binding(4) var emission_in: texture_2d<f32>;
@group(0) @binding(5) var albedo_in: texture_2d<f32>;
@group(0) @binding(6) var material_in: texture_2d<u32>;
@group(0) @binding(7) var diffuse_in: texture_2d<f32>;
@group(0) @binding(8) var specular_in: texture_2d<f32>;
@group(0) @binding(9) var indirect_diffuse_in: texture_2d<f32>;
@group(0) @binding(10) var indirect_specular_in: texture_2d<f32>;
@group(0) @binding(11) var near_field_in: texture_2d<f32>;
// Samples per pixel (`adaptive_ssaa::gpu::Ssaa::counts`, from its evaluation).
@group(0) @binding(12) var<storage, read> counts: array<u32>;
// S, the first sample's radiance per pixel (`Ssaa::first`, the shading metric's input).
@group(0) @binding(13) var<storage, read_write> first: array<vec4<f32>>;
@group(0) @binding(14) var radiance_out: texture_storage_2d<rgba32float, write>;
// The frame's radiance as `store_first` reads it (its own layout: 0, 13, 15).
@group(0) @binding(15) var radiance_in: texture_2d<f32>;
// Screen-space ambient occlusion per pixel (`ssao`), read where ambient.w is 1.
@group(0) @binding(16) var<storage, read> accessibility: array<f32>;

fn pixel_index(p: vec2<u32>) -> u32 {
    return p.y * params.width + p.x;
}

fn in_image(p: vec2<u32>) -> bool {
    return p.x < params.width && p.y < params.height;
}

fn window_sample(p: vec2<u32>, i: u32) -> vec2<u32> {
    let c = params.order[i / 4u][i % 4u];
    return p * params.m + vec2<u32>(c & 0xffu, c >> 8u);
}

// Samples of pixel p the resolve averages: counts clamped to 1..=n.
fn pixel_samples(p: vec2<u32>) -> u32 {
    return clamp(counts[pixel_index(p)], 1u, params.n);
}

// Writes sample q's linear depth where `keep`, else 0 (no surface).
fn mask_sample(q: vec2<u32>, keep: bool) {
    let depth = textureLoad(linear_depth_in, q, 0).r;
    textureStore(masked_depth_out, q, vec4<f32>(select(0.0, depth, keep), 0.0, 0.0, 0.0));
}

// Rank of sample q in its window's dither order.
fn sample_rank(q: vec2<u32>) -> u32 {
    let c = (q.y % params.m) * params.m + q.x % params.m;
    return params.rank[c / 4u][c % 4u];
}

fn in_samples(q: vec2<u32>) -> bool {
    return q.x < params.width * params.m && q.y < params.height * params.m;
}

// S: the frame's radiance, the first sample of every window.
@compute @workgroup_size(8, 8)
fn store_first(@builtin(global_invocation_id) id: vec3<u32>) {
    let p = id.xy;
    if in_image(p) {
        first[pixel_index(p)] = textureLoad(radiance_in, p, 0);
    }
}

// Keeps samples 1..k of every window whose pixel takes k > 1 (Listing 4.1's
// ShadeRestAdaptively).
@compute @workgroup_size(8, 8)
fn mask_rest(@builtin(global_invocation_id) id: vec3<u32>) {
    if in_samples(id.xy) {
        let k = pixel_samples(id.xy / params.m);
        let rank = sample_rank(id.xy);
        mask_sample(id.xy, rank > 0u && rank < k);
    }
}

// Keeps every sample but the first (full supersampling).
@compute @workgroup_size(8, 8)
fn mask_full(@builtin(global_invocation_id) id: vec3<u32>) {
    if in_samples(id.xy) {
        mask_sample(id.xy, sample_rank(id.xy) > 0u);
    }
}

// The radiance of sample q of pixel p: its G-buffer and direct light, p's indirect light.
fn sample_radiance(q: vec2<u32>, p: vec2<u32>) -> vec4<f32> {
    let direct = array<vec3<f32>, 2>(textureLoad(diffuse_in, q, 0).rgb, textureLoad(specular_in, q, 0).rgb);
    let indirect_diffuse = textureLoad(indirect_diffuse_in, p, 0).rgb + textureLoad(near_field_in, p, 0).rgb;
    let indirect = array<vec3<f32>, 2>(indirect_diffuse, textureLoad(indirect_specular_in, p, 0).rgb);
    // The sample's material occlusion times its pixel's screen-space occlusion.
    var emission = textureLoad(emission_in, q, 0);
    if composition.ambient.w > 0.5 {
        emission.a *= accessibility[pixel_index(p)];
    }
    return compose(
        textureLoad(albedo_in, q, 0).rgb,
        textureLoad(material_in, q, 0).x,
        emission,
        direct,
        indirect,
        composition.ambient.rgb,
    );
}

// The average radiance of the first k samples of p's window: S and samples 1..k.
fn average(p: vec2<u32>, k: u32) -> vec4<f32> {
    var sum = first[pixel_index(p)];
    for (var i = 1u; i < k; i++) {
        sum += sample_radiance(window_sample(p, i), p);
    }
    return sum / f32(k);
}

// The pixels of k > 1 samples: their average (the others keep S).
@compute @workgroup_size(8, 8)
fn resolve_adaptive(@builtin(global_invocation_id) id: vec3<u32>) {
    let p = id.xy;
    if in_image(p) {
        let k = pixel_samples(p);
        if k > 1u {
            textureStore(radiance_out, p, average(p, k));
        }
    }
}

// Full supersampling: every pixel averages its n samples.
@compute @workgroup_size(8, 8)
fn resolve_full(@builtin(global_invocation_id) id: vec3<u32>) {
    let p = id.xy;
    if in_image(p) {
        textureStore(radiance_out, p, average(p, params.n));
    }
}
