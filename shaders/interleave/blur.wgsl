// Edge-aware separable Gaussian blur (Segovia 2006 §4.5, Figure 4), one direction per dispatch.
// The result is the centre plus the weighted mean of the differences to it, so a constant
// image stays exactly constant however the sums round.

struct BlurParams {
    // (1, 0) for the horizontal pass, (0, 1) for the vertical one.
    direction: vec2<i32>,
    radius: i32,
    _pad: i32,
    // Gaussian weights of taps 0..=radius (radius ≤ 8), four per vector.
    weights: array<vec4<f32>, 3>,
}

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
// discontinuity walks only in the − direction.
@compute @workgroup_size(16, 16)
fn blur_plain(@builtin(global_invocation_id) id: vec3<u32>) {
    let p = vec2<i32>(id.xy);
    if !inside(p) {
        return;
    }
    let centre = textureLoad(irradiance, p, 0);
    var sum = vec4(0.0);
    var total = weight(0);
    if !on_discontinuity(p) {
        for (var k = 1; k <= params.radius; k++) {
            let q = p + params.direction * k;
            if !inside(q) {
                break;
            }
            sum += (textureLoad(irradiance, q, 0) - centre) * weight(k);
            total += weight(k);
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
        sum += (textureLoad(irradiance, q, 0) - centre) * weight(k);
        total += weight(k);
    }
    textureStore(blurred, p, centre + sum / total);
}

// Fast: taps k and k+1 fetched together at the point between their centres (0.5 texel bias)
// with bilinear filtering; the discontinuity buffer is sampled at the same point and the walk
// stops as soon as the filtered value is > 0. An odd last tap is fetched at its centre.
@compute @workgroup_size(16, 16)
fn blur_fast(@builtin(global_invocation_id) id: vec3<u32>) {
    let p = vec2<i32>(id.xy);
    if !inside(p) {
        return;
    }
    let centre = textureLoad(irradiance, p, 0);
    var sum = vec4(0.0);
    var total = weight(0);
    for (var side = 0; side < 2; side++) {
        let step = params.direction * select(1, -1, side == 1);
        if side == 0 && on_discontinuity(p) {
            continue;
        }
        let size = vec2<f32>(textureDimensions(irradiance));
        for (var k = 1; k <= params.radius; k += 2) {
            let last = min(k + 1, params.radius);
            let qa = p + step * k;
            let qb = p + step * last;
            if !inside(qb) {
                break;
            }
            let uv = (0.5 * vec2<f32>(qa + qb) + 0.5) / size;
            let e = textureSampleLevel(discontinuities, bilinear, uv, 0.0);
            if e.r > 0.0 || e.g > 0.0 {
                break;
            }
            var w = weight(k);
            if last > k {
                w += weight(last);
            }
            sum += (textureSampleLevel(irradiance, bilinear, uv, 0.0) - centre) * w;
            total += w;
        }
    }
    textureStore(blurred, p, centre + sum / total);
}
