// #import interleave/discontinuity.wgsl
// #import interleave/blur_params.wgsl
// The discontinuity buffer and both directions of the edge-aware blur of two images in one
// dispatch (Segovia 2006 §4.5): each workgroup loads the depths and normals of its TILE×TILE
// pixels and RADIUS around them (and, where they fit, both images) into workgroup memory,
// finds their discontinuities there, blurs the rows its columns' vertical walks reach
// horizontally into workgroup memory (rounded to f16, as `blur.wgsl`'s scratch texture is),
// then vertically into the outputs, and writes its part of the discontinuity buffer: each
// G-buffer texel and image pixel is read from its texture about once per workgroup.
// The walks and sums are `blur.wgsl`'s (and the CPU twin's); where the fast variant's tap pairs
// come from workgroup memory they are averaged exactly, as the CPU twin averages them, rather
// than by the bilinear sampler.
//
// Bindings 0–3 are `discontinuity.wgsl`'s (depth, normals, the discontinuity buffer written,
// thresholds); `params` (its direction unused), two images, a bilinear sampler and two outputs
// follow.

// The blur's radius and variant (`interleave::gpu::DiscontinuityBlurPass` specialises both).
const RADIUS: i32 = 2;
const FAST: bool = true;

const TILE: i32 = 16;
// The discontinuities are needed RADIUS beyond the tile on each side, the depths and normals
// one pixel further on the + sides.
const SPAN: i32 = TILE + 2 * RADIUS;
const GBUFFER_SPAN: i32 = SPAN + 1;
const ROWS: i32 = max(SPAN * TILE, (GBUFFER_SPAN * GBUFFER_SPAN + 1) / 2);
// Whether both images' SPAN × SPAN pixels around the tile fit in workgroup memory beside the
// rest (16 KiB in all, WebGPU's default limit): then the horizontal pass reads them there.
const STAGED: bool = SPAN * SPAN * 16 + ROWS * 16 + SPAN * SPAN * 4 <= 16384;
const STAGED_SPAN: i32 = select(1, SPAN, STAGED);

@group(0) @binding(4) var<uniform> params: BlurParams;
@group(0) @binding(5) var irradiance: texture_2d<f32>;
@group(0) @binding(6) var irradiance_b: texture_2d<f32>;
@group(0) @binding(7) var bilinear: sampler;
@group(0) @binding(8) var blurred: texture_storage_2d<rgba16float, write>;
@group(0) @binding(9) var blurred_b: texture_storage_2d<rgba16float, write>;

fn weight(k: i32) -> f32 {
    return params.weights[k / 4][k % 4];
}

// The discontinuity flags of the SPAN×SPAN pixels centred on the tile (0 outside the image).
var<workgroup> edges: array<u32, SPAN * SPAN>;
// First the GBUFFER_SPAN² depths and normals from the tile's corner − RADIUS (as bits, two
// pixels per element); then both images blurred horizontally and packed as f16 (image a in
// .xy, b in .zw), rows −RADIUS to TILE + RADIUS of the tile's columns.
var<workgroup> rows: array<vec4<u32>, ROWS>;
// Where STAGED: both images packed as f16 over the SPAN² pixels around the tile.
var<workgroup> images: array<vec4<u32>, STAGED_SPAN * STAGED_SPAN>;

fn inside(p: vec2<i32>) -> bool {
    return all(p >= vec2(0)) && all(p < vec2<i32>(textureDimensions(irradiance)));
}

// Fetch j on one side: the offsets (in taps, ≥ 1) of the two taps it averages — equal for a
// single tap — and their summed weight. Plain: tap j + 1; fast: taps 2j + 1 and
// min(2j + 2, RADIUS).
struct Fetch {
    a: i32,
    b: i32,
    weight: f32,
}

fn fetch(j: i32) -> Fetch {
    if FAST {
        let k = 2 * j + 1;
        let last = min(k + 1, RADIUS);
        return Fetch(k, last, weight(k) + select(0.0, weight(last), last > k));
    }
    return Fetch(j + 1, j + 1, weight(j + 1));
}

const FETCHES: i32 = select(RADIUS, (RADIUS + 1) / 2, FAST);

// The fetches reached on the + and − sides of p along `step` (`blur.wgsl`'s `reach_plain` /
// `reach_fast`); `edges[centre + k·stride]` is the pixel k taps away.
fn reach(p: vec2<i32>, step: vec2<i32>, centre: i32, stride: i32) -> vec2<i32> {
    var reach = vec2(0);
    for (var side = 0; side < 2; side++) {
        let s = select(1, -1, side == 1);
        if side == 0 && edges[centre] != 0u {
            continue;
        }
        for (var j = 0; j < FETCHES; j++) {
            let f = fetch(j);
            if !inside(p + step * (s * f.b)) {
                break;
            }
            let on = edges[centre + s * f.a * stride] != 0u || edges[centre + s * f.b * stride] != 0u;
            // Plain, + side: the neighbour on a discontinuity is blended, then the walk ends.
            if on && (FAST || side == 1) {
                break;
            }
            reach[side] = j + 1;
            if on {
                break;
            }
        }
    }
    return reach;
}

// Image pixel of the tile-relative position t of workgroup `tile`.
fn pixel(tile: vec2<u32>, t: vec2<i32>) -> vec2<i32> {
    return vec2<i32>(tile) * TILE + t;
}

// Two RGBA images as f16 (a in .xy, b in .zw), rounded as an `rgba16float` store rounds.
fn pack_pair(v: array<vec4<f32>, 2>) -> vec4<u32> {
    return vec4(pack2x16float(v[0].xy), pack2x16float(v[0].zw), pack2x16float(v[1].xy), pack2x16float(v[1].zw));
}

fn unpack_pair(v: vec4<u32>) -> array<vec4<f32>, 2> {
    return array(
        vec4(unpack2x16float(v.x), unpack2x16float(v.y)),
        vec4(unpack2x16float(v.z), unpack2x16float(v.w)),
    );
}

// Depth bits and normal word of pixel e of the GBUFFER_SPAN² around the tile (0 outside).
fn gbuffer_load(tile: vec2<u32>, e: i32) -> vec2<u32> {
    let p = pixel(tile, vec2(e % GBUFFER_SPAN, e / GBUFFER_SPAN) - RADIUS);
    if !inside(p) {
        return vec2(0u);
    }
    return vec2(bitcast<u32>(textureLoad(linear_depth, p, 0).r), textureLoad(normals, p, 0).r);
}

// Depth bits and normal word at `t` (from the tile's corner − RADIUS) of step 1's layout.
fn gbuffer_texel(t: vec2<i32>) -> vec2<u32> {
    let e = t.y * GBUFFER_SPAN + t.x;
    let v = rows[e / 2];
    return select(v.zw, v.xy, e % 2 == 0);
}

// Both images' pixels `t` (tile-relative) and `p` (in the image).
fn image_pair(t: vec2<i32>, p: vec2<i32>) -> array<vec4<f32>, 2> {
    if STAGED {
        return unpack_pair(images[(t.y + RADIUS) * SPAN + t.x + RADIUS]);
    }
    return array(textureLoad(irradiance, p, 0), textureLoad(irradiance_b, p, 0));
}

// Both images' fetch f on side s of pixel p (tile-relative t) horizontally: staged, the mean of
// its two taps (the CPU twin's); else one tap loaded, or a pair sampled bilinearly between
// their centres (as `blur.wgsl`'s fast kernel does).
fn horizontal_fetch(t: vec2<i32>, p: vec2<i32>, s: i32, f: Fetch) -> array<vec4<f32>, 2> {
    if STAGED || f.a == f.b {
        let a = image_pair(t + vec2(s * f.a, 0), p + vec2(s * f.a, 0));
        if f.a == f.b {
            return a;
        }
        let b = image_pair(t + vec2(s * f.b, 0), p + vec2(s * f.b, 0));
        return array(0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1]));
    }
    let size = vec2<f32>(textureDimensions(irradiance));
    let uv = (vec2<f32>(p) + vec2(0.5 * f32(s * (f.a + f.b)), 0.0) + 0.5) / size;
    return array(
        textureSampleLevel(irradiance, bilinear, uv, 0.0),
        textureSampleLevel(irradiance_b, bilinear, uv, 0.0),
    );
}

// Both images at p (tile-relative t) blurred horizontally over the fetches `reach`.
fn horizontal(t: vec2<i32>, p: vec2<i32>, reach: vec2<i32>) -> array<vec4<f32>, 2> {
    let centre = image_pair(t, p);
    var sum = array(vec4(0.0), vec4(0.0));
    var total = weight(0);
    for (var side = 0; side < 2; side++) {
        let s = select(1, -1, side == 1);
        for (var j = 0; j < reach[side]; j++) {
            let f = fetch(j);
            let v = horizontal_fetch(t, p, s, f);
            sum[0] += (v[0] - centre[0]) * f.weight;
            sum[1] += (v[1] - centre[1]) * f.weight;
            total += f.weight;
        }
    }
    return array(centre[0] + sum[0] / total, centre[1] + sum[1] / total);
}

// The horizontally blurred pair of row `r` (tile-relative row r − RADIUS) of column x.
fn row(r: i32, x: i32) -> array<vec4<f32>, 2> {
    return unpack_pair(rows[r * TILE + x]);
}

@compute @workgroup_size(16, 16)
fn discontinuity_blur(
    @builtin(workgroup_id) tile: vec3<u32>,
    @builtin(local_invocation_id) local: vec3<u32>,
    @builtin(local_invocation_index) index: u32,
) {
    // 1. The depths and normals around the tile (and the images, where staged).
    for (var i = i32(index); 2 * i < GBUFFER_SPAN * GBUFFER_SPAN; i += TILE * TILE) {
        rows[i] = vec4(gbuffer_load(tile.xy, 2 * i), gbuffer_load(tile.xy, 2 * i + 1));
    }
    if STAGED {
        for (var e = i32(index); e < SPAN * SPAN; e += TILE * TILE) {
            let p = pixel(tile.xy, vec2(e % SPAN, e / SPAN) - RADIUS);
            var packed = vec4(0u);
            if inside(p) {
                packed = pack_pair(array(textureLoad(irradiance, p, 0), textureLoad(irradiance_b, p, 0)));
            }
            images[e] = packed;
        }
    }
    workgroupBarrier();
    // 2. The discontinuities around the tile (`discontinuity_flags` from workgroup memory).
    for (var e = i32(index); e < SPAN * SPAN; e += TILE * TILE) {
        let t = vec2(e % SPAN, e / SPAN);
        let p = pixel(tile.xy, t - RADIUS);
        var flags = 0u;
        if inside(p) {
            let c = gbuffer_texel(t);
            for (var k = 0u; k < 3u; k++) {
                let step = vec2<i32>(neighbour(k));
                if inside(p + step) {
                    let q = gbuffer_texel(t + step);
                    flags |= edge_flags(bitcast<f32>(c.x), c.y, bitcast<f32>(q.x), q.y);
                }
            }
        }
        edges[e] = flags;
    }
    workgroupBarrier();
    // 3. The horizontal pass over the rows the vertical walks reach.
    for (var e = i32(index); e < SPAN * TILE; e += TILE * TILE) {
        let t = vec2(e % TILE, e / TILE - RADIUS);
        let p = pixel(tile.xy, t);
        var packed = vec4(0u);
        if inside(p) {
            let centre = (t.y + RADIUS) * SPAN + t.x + RADIUS;
            packed = pack_pair(horizontal(t, p, reach(p, vec2(1, 0), centre, 1)));
        }
        rows[e] = packed;
    }
    workgroupBarrier();
    // 4. The vertical pass of the tile's pixels.
    let t = vec2<i32>(local.xy);
    let p = pixel(tile.xy, t);
    if !inside(p) {
        return;
    }
    let centre = (t.y + RADIUS) * SPAN + t.x + RADIUS;
    let walk = reach(p, vec2(0, 1), centre, SPAN);
    let c = row(t.y + RADIUS, t.x);
    var sum = array(vec4(0.0), vec4(0.0));
    var total = weight(0);
    for (var side = 0; side < 2; side++) {
        let s = select(1, -1, side == 1);
        for (var j = 0; j < walk[side]; j++) {
            let f = fetch(j);
            let a = row(t.y + RADIUS + s * f.a, t.x);
            let b = row(t.y + RADIUS + s * f.b, t.x);
            sum[0] += (0.5 * (a[0] + b[0]) - c[0]) * f.weight;
            sum[1] += (0.5 * (a[1] + b[1]) - c[1]) * f.weight;
            total += f.weight;
        }
    }
    textureStore(blurred, p, c[0] + sum[0] / total);
    textureStore(blurred_b, p, c[1] + sum[1] / total);
    textureStore(discontinuities, p, discontinuity_texel(edges[centre]));
}
