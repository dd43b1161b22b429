// #import interleave/discontinuity.wgsl
// #import interleave/blur_params.wgsl
// The discontinuity buffer and both directions of the edge-aware blur of two images in one
// dispatch (Segovia 2006 §4.5): each workgroup finds the discontinuities of its TILE×TILE
// pixels and RADIUS around them into workgroup memory, blurs the rows its columns' vertical
// walks reach horizontally into workgroup memory (rounded to f16, as `blur.wgsl`'s scratch
// texture is), then vertically into the outputs, and writes its part of the discontinuity
// buffer. The walks and sums are `blur.wgsl`'s (and the CPU twin's); in the vertical direction
// the fast variant's tap pairs come from workgroup memory, so they are averaged exactly there,
// as the CPU twin averages them, rather than by the bilinear sampler.
//
// Bindings 0–3 are `discontinuity.wgsl`'s (depth, normals, the discontinuity buffer written,
// thresholds); `params` (its direction unused), two images, a bilinear sampler and two outputs
// follow.

// The blur's radius and variant (`interleave::gpu::DiscontinuityBlurPass` specialises both).
const RADIUS: i32 = 2;
const FAST: bool = true;

const TILE: i32 = 16;
// The discontinuities are needed RADIUS beyond the tile on each side.
const SPAN: i32 = TILE + 2 * RADIUS;

@group(0) @binding(4) var<uniform> params: BlurParams;
@group(0) @binding(5) var irradiance: texture_2d<f32>;
@group(0) @binding(6) var irradiance_b: texture_2d<f32>;
@group(0) @binding(7) var bilinear: sampler;
@group(0) @binding(8) var blurred: texture_storage_2d<rgba16float, write>;
@group(0) @binding(9) var blurred_b: texture_storage_2d<rgba16float, write>;

fn weight(k: i32) -> f32 {
    return params.weights[k / 4][k % 4];
}

// `discontinuity_flags` of the SPAN×SPAN pixels centred on the tile (0 outside the image).
var<workgroup> edges: array<u32, SPAN * SPAN>;
// Both images blurred horizontally and packed as f16 (image a in .xy, b in .zw), rows −RADIUS
// to TILE + RADIUS of the tile's columns.
var<workgroup> rows: array<vec4<u32>, SPAN * TILE>;

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

// Both images' fetch f on side s of p horizontally: one tap loaded, or a pair sampled
// bilinearly between their centres (as `blur.wgsl`'s fast kernel does).
fn horizontal_fetch(p: vec2<i32>, s: i32, f: Fetch) -> array<vec4<f32>, 2> {
    if f.a == f.b {
        let q = p + vec2(s * f.a, 0);
        return array(textureLoad(irradiance, q, 0), textureLoad(irradiance_b, q, 0));
    }
    let size = vec2<f32>(textureDimensions(irradiance));
    let uv = (vec2<f32>(p) + vec2(0.5 * f32(s * (f.a + f.b)), 0.0) + 0.5) / size;
    return array(
        textureSampleLevel(irradiance, bilinear, uv, 0.0),
        textureSampleLevel(irradiance_b, bilinear, uv, 0.0),
    );
}

// Both images at p blurred horizontally over the fetches `reach`.
fn horizontal(p: vec2<i32>, reach: vec2<i32>) -> array<vec4<f32>, 2> {
    let centre = array(textureLoad(irradiance, p, 0), textureLoad(irradiance_b, p, 0));
    var sum = array(vec4(0.0), vec4(0.0));
    var total = weight(0);
    for (var side = 0; side < 2; side++) {
        let s = select(1, -1, side == 1);
        for (var j = 0; j < reach[side]; j++) {
            let f = fetch(j);
            let v = horizontal_fetch(p, s, f);
            sum[0] += (v[0] - centre[0]) * f.weight;
            sum[1] += (v[1] - centre[1]) * f.weight;
            total += f.weight;
        }
    }
    return array(centre[0] + sum[0] / total, centre[1] + sum[1] / total);
}

// The horizontally blurred pair of row `r` (tile-relative row r − RADIUS) of column x, unpacked.
fn row(r: i32, x: i32) -> array<vec4<f32>, 2> {
    let v = rows[r * TILE + x];
    return array(
        vec4(unpack2x16float(v.x), unpack2x16float(v.y)),
        vec4(unpack2x16float(v.z), unpack2x16float(v.w)),
    );
}

@compute @workgroup_size(16, 16)
fn discontinuity_blur(
    @builtin(workgroup_id) tile: vec3<u32>,
    @builtin(local_invocation_id) local: vec3<u32>,
    @builtin(local_invocation_index) index: u32,
) {
    // 1. The discontinuities around the tile.
    for (var e = i32(index); e < SPAN * SPAN; e += TILE * TILE) {
        let p = pixel(tile.xy, vec2(e % SPAN, e / SPAN) - RADIUS);
        var flags = 0u;
        if inside(p) {
            flags = discontinuity_flags(vec2<u32>(p));
        }
        edges[e] = flags;
    }
    workgroupBarrier();
    // 2. The horizontal pass over the rows the vertical walks reach.
    for (var e = i32(index); e < SPAN * TILE; e += TILE * TILE) {
        let t = vec2(e % TILE, e / TILE - RADIUS);
        let p = pixel(tile.xy, t);
        var packed = vec4(0u);
        if inside(p) {
            let centre = (t.y + RADIUS) * SPAN + t.x + RADIUS;
            let h = horizontal(p, reach(p, vec2(1, 0), centre, 1));
            packed = vec4(pack2x16float(h[0].xy), pack2x16float(h[0].zw), pack2x16float(h[1].xy), pack2x16float(h[1].zw));
        }
        rows[e] = packed;
    }
    workgroupBarrier();
    // 3. The vertical pass of the tile's pixels.
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
