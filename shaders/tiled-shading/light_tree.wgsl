// The light hierarchy built on the GPU (`tiled_shading::LightGroups` is its CPU twin; after
// Olsson et al. 2012, who sort the lights by Morton code every frame): five dispatches before
// the light search of `tiled.wgsl` and `clustered.wgsl`, in the first pass after the lights
// change (every frame when they move).
// 1. `tree_bounds` (per light): the bounds of the positional lights' centres, reduced in
//    workgroup memory, then into `bounds` by atomics on order-preserving float bits.
// 2. `tree_histogram` (per light): each light's bucket — 0 for directional lights, else 1 + the
//    top BUCKET_BITS of the 30-bit Morton code of its centre quantized to 10 bits per axis over
//    the bounds — counted in `bucket_counts`.
// 3. `tree_scan` (one workgroup): the buckets' first slots (exclusive prefix sums) into
//    `bucket_cursor`; it clears the counts and the bounds for the next frame.
// 4. `tree_scatter` (per light): each light takes the next slot of its bucket: the order is
//    sorted by bucket (within a bucket in no set order).
// 5. `tree_spheres` (per group of GROUP consecutive slots): the sphere about the centre of the
//    members' bounding box holding every member's sphere, grown for rounding; radius f32::MAX
//    when a member is directional.
// `light_tree` is laid out as `LightGroups::words`: the group spheres, then the order.
// #import tiled-shading/lighting.wgsl
// #import tiled-shading/params.wgsl

const GROUP: u32 = 32u;
const THREADS: u32 = 256u;
const BUCKET_BITS: u32 = 15u;
const BUCKETS: u32 = 32769u;
const F32_MAX: f32 = 3.40282347e38;
const F32_MIN_POSITIVE: f32 = 1.17549435e-38;

@group(0) @binding(1) var<uniform> params: Params;
@group(0) @binding(2) var<storage, read> lights: array<Light>;
@group(0) @binding(11) var<storage, read_write> light_tree: array<vec4<u32>>;
// Order-preserving bits of the least (0–2) and greatest (3–5) centre coordinates.
@group(0) @binding(16) var<storage, read_write> bounds: array<atomic<u32>, 6>;
@group(0) @binding(17) var<storage, read_write> bucket_counts: array<atomic<u32>, BUCKETS>;
@group(0) @binding(18) var<storage, read_write> bucket_cursor: array<atomic<u32>, BUCKETS>;

// Float bits whose unsigned order is the floats' order.
fn ordered(f: f32) -> u32 {
    let b = bitcast<u32>(f);
    return select(b | 0x80000000u, ~b, (b & 0x80000000u) != 0u);
}

fn unordered(u: u32) -> f32 {
    return bitcast<f32>(select(~u, u & 0x7fffffffu, (u & 0x80000000u) != 0u));
}

fn light_index(id: vec3<u32>, groups: vec3<u32>) -> u32 {
    return id.x + id.y * groups.x * THREADS;
}

var<workgroup> local_bounds: array<atomic<u32>, 6>;

@compute @workgroup_size(THREADS)
fn tree_bounds(
    @builtin(global_invocation_id) id: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) index: u32,
) {
    if index < 6u {
        atomicStore(&local_bounds[index], select(0u, 0xffffffffu, index < 3u));
    }
    workgroupBarrier();
    let i = light_index(id, groups);
    if i < params.light_count && lights[i].kind != LIGHT_DIRECTIONAL {
        let p = lights[i].position;
        for (var a = 0u; a < 3u; a++) {
            atomicMin(&local_bounds[a], ordered(p[a]));
            atomicMax(&local_bounds[a + 3u], ordered(p[a]));
        }
    }
    workgroupBarrier();
    if index < 3u {
        atomicMin(&bounds[index], atomicLoad(&local_bounds[index]));
    } else if index < 6u {
        atomicMax(&bounds[index], atomicLoad(&local_bounds[index]));
    }
}

// Spreads 10 bits to every third bit.
fn spread(v0: u32) -> u32 {
    var v = (v0 | (v0 << 16u)) & 0x030000ffu;
    v = (v | (v << 8u)) & 0x0300f00fu;
    v = (v | (v << 4u)) & 0x030c30c3u;
    return (v | (v << 2u)) & 0x09249249u;
}

fn bucket_of(light: Light) -> u32 {
    if light.kind == LIGHT_DIRECTIONAL {
        return 0u;
    }
    let lo = vec3<f32>(unordered(atomicLoad(&bounds[0])), unordered(atomicLoad(&bounds[1])), unordered(atomicLoad(&bounds[2])));
    let hi = vec3<f32>(unordered(atomicLoad(&bounds[3])), unordered(atomicLoad(&bounds[4])), unordered(atomicLoad(&bounds[5])));
    let scale = 1023.0 / max(hi - lo, vec3<f32>(F32_MIN_POSITIVE));
    let q = vec3<u32>(clamp((light.position - lo) * scale, vec3<f32>(0.0), vec3<f32>(1023.0)));
    let code = spread(q.x) | (spread(q.y) << 1u) | (spread(q.z) << 2u);
    return 1u + (code >> (30u - BUCKET_BITS));
}

@compute @workgroup_size(THREADS)
fn tree_histogram(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = light_index(id, groups);
    if i < params.light_count {
        atomicAdd(&bucket_counts[bucket_of(lights[i])], 1u);
    }
}

var<workgroup> partial: array<u32, THREADS>;

@compute @workgroup_size(THREADS)
fn tree_scan(@builtin(local_invocation_index) index: u32) {
    // Each invocation sums a run of PER buckets; the runs' sums are scanned in workgroup
    // memory (Hillis–Steele), then each run is written out from its first slot.
    let per = (BUCKETS + THREADS - 1u) / THREADS;
    let first = index * per;
    var sum = 0u;
    for (var b = first; b < min(first + per, BUCKETS); b++) {
        sum += atomicLoad(&bucket_counts[b]);
    }
    partial[index] = sum;
    workgroupBarrier();
    for (var stride = 1u; stride < THREADS; stride <<= 1u) {
        var add = 0u;
        if index >= stride {
            add = partial[index - stride];
        }
        workgroupBarrier();
        partial[index] += add;
        workgroupBarrier();
    }
    var slot = partial[index] - sum;
    for (var b = first; b < min(first + per, BUCKETS); b++) {
        let n = atomicLoad(&bucket_counts[b]);
        atomicStore(&bucket_cursor[b], slot);
        atomicStore(&bucket_counts[b], 0u);
        slot += n;
    }
}

@compute @workgroup_size(THREADS)
fn tree_scatter(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = light_index(id, groups);
    if i < params.light_count {
        let slot = atomicAdd(&bucket_cursor[bucket_of(lights[i])], 1u);
        light_tree[params.group_count + slot / 4u][slot % 4u] = i;
    }
}

@compute @workgroup_size(64)
fn tree_spheres(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let g = id.x + id.y * groups.x * 64u;
    if g == 0u {
        // The bounds start over for the next frame (every scatter has read them).
        for (var a = 0u; a < 3u; a++) {
            atomicStore(&bounds[a], 0xffffffffu);
            atomicStore(&bounds[a + 3u], 0u);
        }
    }
    if g >= params.group_count {
        return;
    }
    let first = g * GROUP;
    let last = min(first + GROUP, params.light_count);
    var lo = vec3<f32>(F32_MAX);
    var hi = vec3<f32>(-F32_MAX);
    var directional = false;
    for (var k = first; k < last; k++) {
        let light = lights[light_tree[params.group_count + k / 4u][k % 4u]];
        directional = directional || light.kind == LIGHT_DIRECTIONAL;
        lo = min(lo, light.position - vec3<f32>(light.radius));
        hi = max(hi, light.position + vec3<f32>(light.radius));
    }
    var sphere = vec4<f32>(0.0, 0.0, 0.0, F32_MAX);
    if !directional {
        let centre = (lo + hi) * 0.5;
        var radius = 0.0;
        for (var k = first; k < last; k++) {
            let light = lights[light_tree[params.group_count + k / 4u][k % 4u]];
            radius = max(radius, distance(centre, light.position) + light.radius);
        }
        let a = abs(centre);
        sphere = vec4<f32>(centre, radius * (1.0 + 1e-5) + max(a.x, max(a.y, a.z)) * 1e-6);
    }
    light_tree[g] = bitcast<vec4<u32>>(sphere);
}
