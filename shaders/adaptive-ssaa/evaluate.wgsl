// #import adaptive-ssaa/common.wgsl
// The sample-count evaluation of §4.3.3: geometric and shading metrics (`adaptive_ssaa::cpu::evaluate`).

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
