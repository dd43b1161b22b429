// #import adaptive-ssaa/common.wgsl
// The FXAA baseline on S (`adaptive_ssaa::cpu::fxaa`).

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
