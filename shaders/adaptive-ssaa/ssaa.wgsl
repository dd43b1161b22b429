// #import gbuffer/frame.wgsl
// #import gbuffer/normal_encoding.wgsl
// #import tiled-shading/lighting.wgsl
// Adaptive supersampling for deferred anti-aliasing (Holländer 2013 §4.3, Listing 4.1).
// Mirrors `adaptive_ssaa::cpu` function for function. The image is width × height pixels;
// pixel p's sampling window is the G-buffer samples p·m + (0..m)², visited in the order of an
// ordered-dither index matrix (`params.order`, §4.3.2).

struct Params {
    width: u32,
    height: u32,
    m: u32,
    n: u32,
    // 0 none, 1 MM, 2 NC, 3 DV, 4 NV, 5 ND
    metric: u32,
    shading_on: u32,
    min_samples: u32,
    stall: u32,
    c_mm: f32,
    c_nc: f32,
    c_dv: f32,
    c_nv: f32,
    c_shading: f32,
    min_threshold: f32,
    edge_threshold: f32,
    far: f32,
    ambient: vec3<f32>,
    light_count: u32,
    background: vec3<f32>,
    // Always 0: offsets the lights by r·zero in the stall loop so the repetitions cannot be
    // folded away.
    zero: f32,
    // Sample i of the window is cell (order[i] & 0xff, order[i] >> 8).
    order: array<vec4<u32>, 16>,
};

struct SsaaMaterial {
    base_color: vec4<f32>,
    emissive: vec3<f32>,
    layer: u32,
};

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<uniform> params: Params;
@group(0) @binding(2) var linear_depth_tex: texture_2d<f32>;
@group(0) @binding(3) var normal_tex: texture_2d<u32>;
@group(0) @binding(4) var uv_tex: texture_2d<f32>;
@group(0) @binding(5) var uv_grad_tex: texture_2d<f32>;
@group(0) @binding(6) var material_tex: texture_2d<u32>;
@group(0) @binding(7) var textures: texture_2d_array<f32>;
@group(0) @binding(8) var texture_sampler: sampler;
@group(0) @binding(9) var<storage, read> materials: array<SsaaMaterial>;
@group(0) @binding(10) var<storage, read> lights: array<Light>;
// S, the first sample per pixel.
@group(0) @binding(11) var<storage, read_write> first: array<vec4<f32>>;
@group(0) @binding(12) var<storage, read_write> counts: array<u32>;
@group(0) @binding(13) var<storage, read_write> out_image: array<vec4<f32>>;
// Counting sort by sample count: [0, 65) histogram, [65, 130) cursors, [130] total.
@group(0) @binding(14) var<storage, read_write> sort: array<atomic<u32>>;
@group(0) @binding(15) var<storage, read_write> list: array<u32>;
// Indirect dispatch arguments of `shade_sorted` (only `sort_scan` binds them).
@group(1) @binding(0) var<storage, read_write> dispatch_args: array<u32>;

const NO_MATERIAL: u32 = 0xffffffffu;
const HISTOGRAM: u32 = 0u;
const CURSORS: u32 = 65u;
const TOTAL: u32 = 130u;
const LUMINANCE: vec3<f32> = vec3<f32>(0.2126, 0.7152, 0.0722);

fn window_sample(p: vec2<u32>, i: u32) -> vec2<u32> {
    let c = params.order[i / 4u][i % 4u];
    return p * params.m + vec2<u32>(c & 0xffu, c >> 8u);
}

// The footprint of one of k samples averaged over a pixel, in sample steps: m / √k.
fn footprint_scale(k: u32) -> f32 {
    return f32(params.m) / sqrt(f32(k));
}

// Shades G-buffer sample q (§4.3.4): texture lookup with the stored derivatives × scale,
// every light (params.stall times), ambient and emission.
fn shade_sample(q: vec2<u32>, scale: f32) -> vec3<f32> {
    let depth = textureLoad(linear_depth_tex, q, 0).r;
    let word = textureLoad(material_tex, q, 0).r;
    if depth <= 0.0 || word == NO_MATERIAL {
        return params.background;
    }
    let id = word >> 16u;
    if id >= arrayLength(&materials) {
        return params.background;
    }
    let n = decode_octahedral_snorm(unpack2x16snorm(textureLoad(normal_tex, q, 0).r));
    let roughness = f32(word & 0xffu) / 255.0;
    let metallic = f32((word >> 8u) & 0xffu) / 255.0;
    let material = materials[id];
    let grad = textureLoad(uv_grad_tex, q, 0) * scale;
    let uv = textureLoad(uv_tex, q, 0).xy;
    let texel = textureSampleGrad(textures, texture_sampler, uv, material.layer, grad.xy, grad.zw);
    let albedo = clamp(material.base_color.rgb * texel.rgb, vec3<f32>(0.0), vec3<f32>(1.0));
    let p = position_from_view_ray(frame, q, depth);
    let v = normalize(frame.eye.xyz - p);
    var diffuse = vec3<f32>(0.0);
    var specular = vec3<f32>(0.0);
    for (var r = 0u; r < params.stall; r++) {
        diffuse = vec3<f32>(0.0);
        specular = vec3<f32>(0.0);
        let jitter = vec3<f32>(f32(r) * params.zero);
        for (var i = 0u; i < params.light_count; i++) {
            var light = lights[i];
            light.position += jitter;
            let a = shade_light(light, p, n, v, albedo, roughness, metallic);
            diffuse += a.diffuse;
            specular += a.specular;
        }
    }
    return albedo * (1.0 - metallic) * (params.ambient + diffuse) + specular + material.emissive;
}

fn pixel_index(p: vec2<u32>) -> u32 {
    return p.y * params.width + p.x;
}

fn in_image(p: vec2<u32>) -> bool {
    return p.x < params.width && p.y < params.height;
}

// Samples of pixel i from `evaluate`, clamped to 1..=n.
fn pixel_samples(i: u32) -> u32 {
    return clamp(counts[i], 1u, params.n);
}

// S: the first sample of every window, filtered over the whole pixel.
@compute @workgroup_size(8, 8)
fn shade_first(@builtin(global_invocation_id) id: vec3<u32>) {
    let p = id.xy;
    if !in_image(p) {
        return;
    }
    first[pixel_index(p)] = vec4<f32>(shade_sample(window_sample(p, 0u), footprint_scale(1u)), 1.0);
}

// Depth (view depth / far, 1 where no surface) of a window sample.
fn sample_depth(q: vec2<u32>) -> f32 {
    let d = textureLoad(linear_depth_tex, q, 0).r;
    return select(1.0, d / params.far, d > 0.0);
}

// Unit normal of a window sample; the camera's backward axis where no surface.
fn sample_normal(q: vec2<u32>) -> vec3<f32> {
    if textureLoad(linear_depth_tex, q, 0).r > 0.0 {
        return decode_octahedral_snorm(unpack2x16snorm(textureLoad(normal_tex, q, 0).r));
    }
    return frame.inv_view[2].xyz;
}

// The geometric metric k of pixel p's window (§4.3.1), constants applied.
fn geometric_metric(p: vec2<u32>) -> f32 {
    let n = params.n;
    var sum = vec3<f32>(0.0);
    var s = 0.0;
    var s2 = 0.0;
    var lo = 3.0e38;
    var hi = -3.0e38;
    for (var i = 0u; i < n; i++) {
        let q = window_sample(p, i);
        let d = sample_depth(q);
        sum += sample_normal(q);
        s += d;
        s2 += d * d;
        lo = min(lo, d);
        hi = max(hi, d);
    }
    if params.metric == 1u {
        return params.c_mm * (hi - lo);
    }
    let mean = s / f32(n);
    let depth_variance = params.c_dv * max(s2 / f32(n) - mean * mean, 0.0);
    if params.metric == 3u {
        return depth_variance;
    }
    var mean_normal = sample_normal(window_sample(p, 0u));
    if dot(sum, sum) > 0.0 {
        mean_normal = normalize(sum);
    }
    var min_cos = 1.0;
    var spread = 0.0;
    for (var i = 0u; i < n; i++) {
        let c = dot(mean_normal, sample_normal(window_sample(p, i)));
        min_cos = min(min_cos, abs(c));
        spread += (1.0 - c) * (1.0 - c);
    }
    if params.metric == 4u {
        return params.c_nv * spread;
    }
    let normal_cone = params.c_nc * sqrt(max(1.0 - min_cos, 0.0));
    if params.metric == 2u {
        return normal_cone;
    }
    return max(normal_cone, depth_variance);
}

fn first_luminance(p: vec2<i32>) -> f32 {
    let q = clamp(p, vec2<i32>(0), vec2<i32>(i32(params.width) - 1, i32(params.height) - 1));
    return dot(first[u32(q.y) * params.width + u32(q.x)].rgb, LUMINANCE);
}

// The shading metric on S (§4.3.1): luminance range over the pixel and its four neighbours.
fn shading_metric(p: vec2<u32>) -> f32 {
    let c = vec2<i32>(p);
    let l0 = first_luminance(c);
    let l1 = first_luminance(c + vec2<i32>(0, -1));
    let l2 = first_luminance(c + vec2<i32>(-1, 0));
    let l3 = first_luminance(c + vec2<i32>(1, 0));
    let l4 = first_luminance(c + vec2<i32>(0, 1));
    let lo = min(l0, min(min(l1, l2), min(l3, l4)));
    let hi = max(l0, max(max(l1, l2), max(l3, l4)));
    let r = hi - lo;
    if r < max(params.min_threshold, hi * params.edge_threshold) {
        return 0.0;
    }
    return params.c_shading * r;
}

// clamp(1 + ⌊k⌋, min_samples, n); NaN or huge k gives n.
fn sample_count(k: f32) -> u32 {
    var count = params.n;
    if k < f32(params.n) {
        count = 1u + u32(floor(max(k, 0.0)));
    }
    return clamp(count, params.min_samples, params.n);
}

// Listing 4.1's Evaluate: samples per pixel from the two metrics.
@compute @workgroup_size(8, 8)
fn evaluate(@builtin(global_invocation_id) id: vec3<u32>) {
    let p = id.xy;
    if !in_image(p) {
        return;
    }
    var k = 0.0;
    if params.metric != 0u {
        k = geometric_metric(p);
    }
    if params.shading_on != 0u {
        k = max(k, shading_metric(p));
    }
    counts[pixel_index(p)] = sample_count(k);
}

// Average of the first k samples of p's window in dither order.
fn average_samples(p: vec2<u32>, k: u32) -> vec4<f32> {
    let scale = footprint_scale(k);
    var sum = vec3<f32>(0.0);
    for (var i = 0u; i < k; i++) {
        sum += shade_sample(window_sample(p, i), scale);
    }
    return vec4<f32>(sum / f32(k), 1.0);
}

// Listing 4.1's ShadeRestAdaptively, one invocation per pixel looping over its samples.
@compute @workgroup_size(8, 8)
fn shade_adaptive(@builtin(global_invocation_id) id: vec3<u32>) {
    let p = id.xy;
    if !in_image(p) {
        return;
    }
    let i = pixel_index(p);
    let k = pixel_samples(i);
    if k == 1u {
        out_image[i] = first[i];
    } else {
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

// Grouping by sample count (§4.3.5), step 1: histogram of k > 1; one-sample pixels take S.
@compute @workgroup_size(8, 8)
fn sort_count(@builtin(global_invocation_id) id: vec3<u32>) {
    let p = id.xy;
    if !in_image(p) {
        return;
    }
    let i = pixel_index(p);
    let k = pixel_samples(i);
    if k == 1u {
        out_image[i] = first[i];
    } else {
        atomicAdd(&sort[HISTOGRAM + k], 1u);
    }
}

// Step 2: exclusive prefix sum of the histogram into cursors, and the indirect dispatch size.
@compute @workgroup_size(1)
fn sort_scan() {
    var total = 0u;
    for (var k = 2u; k <= params.n; k++) {
        atomicStore(&sort[CURSORS + k], total);
        total += atomicLoad(&sort[HISTOGRAM + k]);
    }
    atomicStore(&sort[TOTAL], total);
    dispatch_args[0] = (total + 63u) / 64u;
    dispatch_args[1] = 1u;
    dispatch_args[2] = 1u;
}

// Step 3: pixels with k > 1 scattered into the list, grouped by k.
@compute @workgroup_size(8, 8)
fn sort_scatter(@builtin(global_invocation_id) id: vec3<u32>) {
    let p = id.xy;
    if !in_image(p) {
        return;
    }
    let i = pixel_index(p);
    let k = pixel_samples(i);
    if k > 1u {
        list[atomicAdd(&sort[CURSORS + k], 1u)] = i;
    }
}

// Step 4: one invocation per listed pixel; neighbouring invocations share k.
@compute @workgroup_size(64)
fn shade_sorted(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= atomicLoad(&sort[TOTAL]) {
        return;
    }
    let i = list[id.x];
    let p = vec2<u32>(i % params.width, i / params.width);
    out_image[i] = average_samples(p, pixel_samples(i));
}

// Bilinear lookup of S at a continuous position (pixel centres at +0.5), clamped to the edges.
fn first_bilinear(pos: vec2<f32>) -> vec4<f32> {
    let q = pos - 0.5;
    let f = floor(q);
    let t = q - f;
    let hi = vec2<i32>(i32(params.width) - 1, i32(params.height) - 1);
    let b = vec2<i32>(f);
    let at = clamp(b, vec2<i32>(0), hi);
    let at1 = clamp(b + vec2<i32>(1), vec2<i32>(0), hi);
    let c00 = first[u32(at.y) * params.width + u32(at.x)];
    let c10 = first[u32(at.y) * params.width + u32(at1.x)];
    let c01 = first[u32(at1.y) * params.width + u32(at.x)];
    let c11 = first[u32(at1.y) * params.width + u32(at1.x)];
    return mix(mix(c00, c10, t.x), mix(c01, c11, t.x), t.y);
}

const FXAA_EDGE_THRESHOLD: f32 = 0.125;
const FXAA_EDGE_THRESHOLD_MIN: f32 = 0.0312;
const FXAA_REDUCE_MUL: f32 = 0.125;
const FXAA_REDUCE_MIN: f32 = 0.0078125;
const FXAA_SPAN_MAX: f32 = 8.0;

// The post-process baseline: FXAA's console variant (Lottes 2009) on S.
@compute @workgroup_size(8, 8)
fn fxaa(@builtin(global_invocation_id) id: vec3<u32>) {
    let p = id.xy;
    if !in_image(p) {
        return;
    }
    let pos = vec2<f32>(p) + 0.5;
    let m = first[pixel_index(p)];
    let nw = dot(first_bilinear(pos + vec2<f32>(-0.5, -0.5)).rgb, LUMINANCE);
    let ne = dot(first_bilinear(pos + vec2<f32>(0.5, -0.5)).rgb, LUMINANCE);
    let sw = dot(first_bilinear(pos + vec2<f32>(-0.5, 0.5)).rgb, LUMINANCE);
    let se = dot(first_bilinear(pos + vec2<f32>(0.5, 0.5)).rgb, LUMINANCE);
    let lm = dot(m.rgb, LUMINANCE);
    let lo = min(lm, min(min(nw, ne), min(sw, se)));
    let hi = max(lm, max(max(nw, ne), max(sw, se)));
    if hi - lo < max(FXAA_EDGE_THRESHOLD_MIN, hi * FXAA_EDGE_THRESHOLD) {
        out_image[pixel_index(p)] = m;
        return;
    }
    var dir = vec2<f32>(-((nw + ne) - (sw + se)), (nw + sw) - (ne + se));
    let reduce = max((nw + ne + sw + se) * (0.25 * FXAA_REDUCE_MUL), FXAA_REDUCE_MIN);
    let rcp_min = 1.0 / (min(abs(dir.x), abs(dir.y)) + reduce);
    dir = clamp(dir * rcp_min, vec2<f32>(-FXAA_SPAN_MAX), vec2<f32>(FXAA_SPAN_MAX));
    let a = (first_bilinear(pos + dir * (1.0 / 3.0 - 0.5)) + first_bilinear(pos + dir * (2.0 / 3.0 - 0.5))) * 0.5;
    let b = a * 0.5 + (first_bilinear(pos - dir * 0.5) + first_bilinear(pos + dir * 0.5)) * 0.25;
    let lb = dot(b.rgb, LUMINANCE);
    var c = b;
    if lb < lo || lb > hi {
        c = a;
    }
    out_image[pixel_index(p)] = vec4<f32>(c.rgb, 1.0);
}
