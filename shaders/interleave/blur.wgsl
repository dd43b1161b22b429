// #import interleave/blur_params.wgsl
// Edge-aware separable Gaussian blur (Segovia 2006 §4.5, Figure 4), one direction per dispatch.
// The result is the centre plus the weighted mean of the differences to it, so a constant
// image stays exactly constant however the sums round. `discontinuity_blur.wgsl` runs the same
// walks and sums for two images, both directions and the discontinuity buffer in one dispatch.

@group(0) @binding(0) var irradiance: texture_2d<f32>;
@group(0) @binding(1) var discontinuities: texture_2d<f32>;
@group(0) @binding(2) var blurred: texture_storage_2d<rgba16float, write>;
@group(0) @binding(3) var<uniform> params: BlurParams;
@group(0) @binding(4) var bilinear: sampler;

fn weight(k: i32) -> f32 {
    return params.weights[k / 4][k % 4];
}

fn inside(p: vec2<i32>) -> bool {
    return all(p >= vec2(0)) && all(p < vec2<i32>(textureDimensions(irradiance)));
}

fn on_discontinuity(p: vec2<i32>) -> bool {
    let e = textureLoad(discontinuities, p, 0);
    return e.r > 0.0 || e.g > 0.0;
}

// Plain: one fetch per tap at texel centres. In the + direction a neighbour on a discontinuity
// is blended and ends the walk; in the − direction it ends the walk unblended; a pixel on a
// discontinuity walks only in the − direction. The taps reached on the + and − sides.
fn reach_plain(p: vec2<i32>) -> vec2<i32> {
    var reach = vec2(0);
    if !on_discontinuity(p) {
        for (var k = 1; k <= params.radius; k++) {
            let q = p + params.direction * k;
            if !inside(q) {
                break;
            }
            reach.x = k;
            if on_discontinuity(q) {
                break;
            }
        }
    }
    for (var k = 1; k <= params.radius; k++) {
        let q = p - params.direction * k;
        if !inside(q) || on_discontinuity(q) {
            break;
        }
        reach.y = k;
    }
    return reach;
}

// `image` at p blurred over the taps `reach` of [`reach_plain`].
fn blurred_plain(image: texture_2d<f32>, p: vec2<i32>, reach: vec2<i32>) -> vec4<f32> {
    let centre = textureLoad(image, p, 0);
    var sum = vec4(0.0);
    var total = weight(0);
    for (var side = 0; side < 2; side++) {
        let step = params.direction * select(1, -1, side == 1);
        for (var k = 1; k <= reach[side]; k++) {
            sum += (textureLoad(image, p + step * k, 0) - centre) * weight(k);
            total += weight(k);
        }
    }
    return centre + sum / total;
}

@compute @workgroup_size(16, 16)
fn blur_plain(@builtin(global_invocation_id) id: vec3<u32>) {
    let p = vec2<i32>(id.xy);
    if inside(p) {
        textureStore(blurred, p, blurred_plain(irradiance, p, reach_plain(p)));
    }
}

// Fast: taps k and k+1 fetched together at the point between their centres (0.5 texel bias)
// with bilinear filtering; the discontinuity buffer is sampled at the same point and the walk
// stops as soon as the filtered value is > 0. An odd last tap is fetched at its centre.
// Fetch i of a side covers taps 2i + 1 and min(2i + 2, radius): its point (texture
// coordinates) and summed weight.
fn fast_fetch(p: vec2<i32>, step: vec2<i32>, i: i32) -> vec3<f32> {
    let k = 2 * i + 1;
    let last = min(k + 1, params.radius);
    let size = vec2<f32>(textureDimensions(irradiance));
    let uv = (0.5 * vec2<f32>(2 * p + step * (k + last)) + 0.5) / size;
    return vec3(uv, weight(k) + select(0.0, weight(last), last > k));
}

// The fetches reached on the + and − sides.
fn reach_fast(p: vec2<i32>) -> vec2<i32> {
    var reach = vec2(0);
    for (var side = 0; side < 2; side++) {
        let step = params.direction * select(1, -1, side == 1);
        if side == 0 && on_discontinuity(p) {
            continue;
        }
        for (var i = 0; 2 * i + 1 <= params.radius; i++) {
            if !inside(p + step * min(2 * i + 2, params.radius)) {
                break;
            }
            let e = textureSampleLevel(discontinuities, bilinear, fast_fetch(p, step, i).xy, 0.0);
            if e.r > 0.0 || e.g > 0.0 {
                break;
            }
            reach[side] = i + 1;
        }
    }
    return reach;
}

// `image` at p blurred over the fetches `reach` of [`reach_fast`].
fn blurred_fast(image: texture_2d<f32>, p: vec2<i32>, reach: vec2<i32>) -> vec4<f32> {
    let centre = textureLoad(image, p, 0);
    var sum = vec4(0.0);
    var total = weight(0);
    for (var side = 0; side < 2; side++) {
        let step = params.direction * select(1, -1, side == 1);
        for (var i = 0; i < reach[side]; i++) {
            let f = fast_fetch(p, step, i);
            sum += (textureSampleLevel(image, bilinear, f.xy, 0.0) - centre) * f.z;
            total += f.z;
        }
    }
    return centre + sum / total;
}

@compute @workgroup_size(16, 16)
fn blur_fast(@builtin(global_invocation_id) id: vec3<u32>) {
    let p = vec2<i32>(id.xy);
    if inside(p) {
        textureStore(blurred, p, blurred_fast(irradiance, p, reach_fast(p)));
    }
}
