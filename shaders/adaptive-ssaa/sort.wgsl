// #import adaptive-ssaa/common.wgsl
// The sorted resolve of §4.3.5: pixels grouped by sample count, then shaded in groups
// (`adaptive_ssaa::cpu::sort`).

// Indirect dispatch arguments of `shade_sorted` (only `sort_scan` binds them).
@group(1) @binding(0) var<storage, read_write> dispatch_args: array<u32>;

// Grouping by sample count (§4.3.5), step 1: histogram of k > 1; one-sample pixels take S.
@compute @workgroup_size(8, 8)
fn sort_count(@builtin(global_invocation_id) id: vec3<u32>) {
    let p = id.xy;
    if !in_image(p) {
        return;
    }
    let k = samples_or_first(pixel_index(p));
    if k > 1u {
        atomicAdd(&sort[HISTOGRAM + k], 1u);
    }
}

// Step 2: exclusive prefix sum of the histogram into cursors, and the indirect dispatch size.
@compute @workgroup_size(1)
fn sort_scan() {
    var total = 0u;
    for (var k = 2u; k <= params.n; k++) {
        atomicStore(&sort[CURSORS + k], total);
        total += atomicLoad(&sort[HISTOGRAM + k]);
    }
    atomicStore(&sort[TOTAL], total);
    dispatch_args[0] = (total + 63u) / 64u;
    dispatch_args[1] = 1u;
    dispatch_args[2] = 1u;
}

// Step 3: pixels with k > 1 scattered into the list, grouped by k.
@compute @workgroup_size(8, 8)
fn sort_scatter(@builtin(global_invocation_id) id: vec3<u32>) {
    let p = id.xy;
    if !in_image(p) {
        return;
    }
    let i = pixel_index(p);
    let k = pixel_samples(i);
    if k > 1u {
        list[atomicAdd(&sort[CURSORS + k], 1u)] = i;
    }
}

// Step 4: one invocation per listed pixel; neighbouring invocations share k.
@compute @workgroup_size(64)
fn shade_sorted(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= atomicLoad(&sort[TOTAL]) {
        return;
    }
    let i = list[id.x];
    let p = vec2<u32>(i % params.width, i / params.width);
    out_image[i] = average_samples(p, pixel_samples(i));
}
