// #import manylod/common.wgsl
// Shadow lookup in an atlas of paraboloid views (`manylod::lookup`, Holländer 2013 §3.6),
// without bindings of its own: the importer finds the texel with `atlas_texel` in its atlas
// (`array<u32>`, packed depths) and compares with `atlas_test`.

struct AtlasParams {
    enabled: u32,
    tile: u32,
    columns: u32,
    width: u32,
    far: f32,
    lift: f32,
    bias: f32,
    // Receivers move this many atlas pixels (at their distance) along their normal.
    normal_offset: f32,
    // Depth tolerance in atlas pixels per unit of tan θ (θ: receiver normal to the view), tan θ
    // at most `MAX_SLOPE_TAN`.
    slope: f32,
};

const MAX_SLOPE_TAN: f32 = 6.0;

// Where a receiver falls in a view's tile: the atlas index (`NO_TEXEL` behind the view's base
// plane) and the receiver's depth with the bias taken off.
struct AtlasTexel {
    index: u32,
    depth: f32,
};

const NO_TEXEL: u32 = 0xffffffffu;

// The texel of `receiver` (unit normal `n`) in paraboloid view `k`, whose origin is `origin`
// with unit `normal`; the receiver first moves off its surface by the normal offset. Receivers
// in front of the view's surface but behind its lifted base plane are looked up on the rim.
fn atlas_texel(a: AtlasParams, k: u32, origin: vec3<f32>, normal: vec3<f32>, receiver: vec3<f32>, n: vec3<f32>) -> AtlasTexel {
    let to = receiver - origin;
    let distance = length(to);
    let dir = to / max(distance, 1e-30);
    let cos_view = max(dot(normal, dir), 0.0);
    let pixel = distance * 2.0 * (1.0 + cos_view) / f32(a.tile);
    let p = receiver + n * (pixel * a.normal_offset);
    let d = p - (origin + normal * a.lift);
    let dist = length(d);
    var l = d * paraboloid_frame(normal) / dist;
    if l.z <= 0.0 {
        if dot(normal, p - origin) <= 0.0 || all(l.xy == vec2<f32>(0.0)) {
            return AtlasTexel(NO_TEXEL, 0.0);
        }
        l = vec3<f32>(normalize(l.xy), 0.0);
    }
    let uv = l.xy / (1.0 + l.z);
    let px = min(vec2<u32>((uv * 0.5 + 0.5) * f32(a.tile)), vec2<u32>(a.tile - 1u));
    let corner = vec2<u32>(k % a.columns, k / a.columns) * a.tile;
    let c = clamp(dot(n, -dir), 1e-3, 1.0);
    let slope = a.slope * min(sqrt(1.0 - c * c) / c, MAX_SLOPE_TAN) * pixel / a.far;
    return AtlasTexel((corner.y + px.y) * a.width + corner.x + px.x, dist / a.far - a.bias - slope);
}

// 1 when the stored `word` is not nearer than the texel's receiver, else 0.
fn atlas_test(t: AtlasTexel, word: u32) -> f32 {
    return select(0.0, 1.0, t.depth <= unpack_depth(word));
}
