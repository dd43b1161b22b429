// #import adaptive-ssaa/common.wgsl
// Shading stages of §4.3.4: S, the adaptive resolve (a loop per pixel, or compacted per tile) and full supersampling (`adaptive_ssaa::cpu::shade`).

// S: the first sample of every window, filtered over the whole pixel.
@compute @workgroup_size(8, 8)
fn shade_first(@builtin(global_invocation_id) id: vec3<u32>) {
    let p = id.xy;
    if !in_image(p) {
        return;
    }
    first[pixel_index(p)] = vec4<f32>(shade_sample(window_sample(p, 0u), footprint_scale(1u)), 1.0);
}

// Listing 4.1's ShadeRestAdaptively, one invocation per pixel looping over its samples.
@compute @workgroup_size(8, 8)
fn shade_adaptive(@builtin(global_invocation_id) id: vec3<u32>) {
    let p = id.xy;
    if !in_image(p) {
        return;
    }
    let i = pixel_index(p);
    let k = samples_or_first(i);
    if k > 1u {
        out_image[i] = average_samples(p, k);
    }
}

// The remaining samples of an 8×8 tile compacted: the tile's pixels of k > 1 list their k
// samples one after the other (a workgroup scan of k), the 64 invocations shade that list 64 at
// a time whatever pixel each sample belongs to, and every pixel sums its own from workgroup
// memory in window order — `shade_adaptive`'s image, without a warp waiting for its pixel with
// the most samples while its other lanes idle.
const TILE_SIDE: u32 = 8u;
const TILE: u32 = TILE_SIDE * TILE_SIDE;
// Inclusive prefix sums of the tile's k (0 for pixels of one sample), then the batch's colours.
var<workgroup> tile_prefix: array<u32, TILE>;
var<workgroup> tile_total: u32;
var<workgroup> tile_shaded: array<vec3<f32>, TILE>;

@compute @workgroup_size(8, 8)
fn shade_tiles(
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(local_invocation_index) lid: u32,
) {
    let origin = wid.xy * TILE_SIDE;
    let p = origin + vec2<u32>(lid % TILE_SIDE, lid / TILE_SIDE);
    var k = 0u;
    if in_image(p) {
        k = samples_or_first(pixel_index(p));
        if k == 1u {
            k = 0u;
        }
    }
    // Hillis–Steele scan of k over the tile.
    var prefix = k;
    for (var o = 1u; o < TILE; o *= 2u) {
        tile_prefix[lid] = prefix;
        workgroupBarrier();
        if lid >= o {
            prefix += tile_prefix[lid - o];
        }
        workgroupBarrier();
    }
    tile_prefix[lid] = prefix;
    if lid == TILE - 1u {
        tile_total = prefix;
    }
    let total = workgroupUniformLoad(&tile_total);
    let start = prefix - k;
    var sum = vec3<f32>(0.0);
    for (var base = 0u; base < total; base += TILE) {
        let item = base + lid;
        if item < total {
            // The pixel o whose samples hold the item: the first prefix above it.
            var lo = 0u;
            var hi = TILE - 1u;
            while lo < hi {
                let mid = (lo + hi) / 2u;
                if tile_prefix[mid] > item {
                    hi = mid;
                } else {
                    lo = mid + 1u;
                }
            }
            let end = tile_prefix[lo];
            let ko = end - select(0u, tile_prefix[lo - 1u], lo > 0u);
            let po = origin + vec2<u32>(lo % TILE_SIDE, lo / TILE_SIDE);
            let q = window_sample(po, item - (end - ko));
            tile_shaded[lid] = shade_sample(q, footprint_scale(ko));
        }
        workgroupBarrier();
        for (var t = max(start, base); t < min(start + k, base + TILE); t++) {
            sum += tile_shaded[t - base];
        }
        workgroupBarrier();
    }
    if k > 0u {
        out_image[pixel_index(p)] = vec4<f32>(sum / f32(k), 1.0);
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
