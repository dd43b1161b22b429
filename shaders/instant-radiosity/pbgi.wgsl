// Point-based GI's convolution with the BRDF (Holländer 2013 §3.6.1): one workgroup per
// receiver's paraboloid view sums, over its tile's texels, the exit radiance of the nearest
// node (`manylod/nearest.wgsl`) times cos θ · dω — the receiver's irradiance. Mirrors
// `instant_radiosity::pbgi::LitPoints::gather`.

struct Gather {
    // Atlas row length in texels.
    width: u32,
    tile: u32,
    columns: u32,
    views: u32,
}

@group(0) @binding(0) var<uniform> gather: Gather;
@group(0) @binding(1) var<storage, read> ids: array<u32>;
@group(0) @binding(2) var<storage, read> radiance: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read_write> irradiance: array<vec4<f32>>;

// `manylod::splat::NO_NODE`.
const NO_NODE: u32 = 0xFFFFFFFFu;
const GROUP: u32 = 256u;

var<workgroup> partial: array<vec3<f32>, GROUP>;

// `cos θ · dω` of texel (x, y) of a paraboloid tile (`pbgi::texel_weight`).
fn texel_weight(x: u32, y: u32, tile: u32) -> f32 {
    let side = 2.0 / f32(tile);
    let uv = (vec2<f32>(f32(x), f32(y)) + 0.5) * side - 1.0;
    let r2 = dot(uv, uv);
    if r2 >= 1.0 {
        return 0.0;
    }
    let k = 1.0 + r2;
    return (1.0 - r2) / k * 4.0 / (k * k) * side * side;
}

@compute @workgroup_size(256)
fn convolve(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) t: u32,
) {
    // The same for the whole workgroup: the barriers below stay in uniform control flow.
    let v = wg.x + wg.y * groups.x;
    if v >= gather.views {
        return;
    }
    let tile = gather.tile;
    let origin = vec2<u32>(v % gather.columns, v / gather.columns) * tile;
    var sum = vec3<f32>(0.0);
    for (var i = t; i < tile * tile; i += GROUP) {
        let x = i % tile;
        let y = i / tile;
        let id = ids[(origin.y + y) * gather.width + origin.x + x];
        if id != NO_NODE {
            sum += radiance[id].rgb * texel_weight(x, y, tile);
        }
    }
    partial[t] = sum;
    workgroupBarrier();
    for (var s = GROUP / 2u; s > 0u; s >>= 1u) {
        if t < s {
            partial[t] += partial[t + s];
        }
        workgroupBarrier();
    }
    if t == 0u {
        irradiance[v] = vec4<f32>(partial[0], 0.0);
    }
}
