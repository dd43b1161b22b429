// The in-place variant with Listing 3.4's ballot compaction (adapters with subgroups): a
// splitting cutfinder's slot is twice the number of splitting lanes below it in its subgroup's
// ballot, and the subgroup's lane 0 reserves all of the subgroup's pushes with one workgroup
// atomic. Compiled only where the device has `wgpu::Features::SUBGROUP`.
// #import manylod/inplace.wgsl

// Slot of this lane's children among the round's pushes.
fn ballot_slot(split: bool, lane: u32) -> u32 {
    let mask = subgroupBallot(split);
    var below = 0u;
    var total = 0u;
    for (var k = 0u; k < 4u; k++) {
        let first = 32u * k;
        let bits = mask[k];
        total += countOneBits(bits);
        if lane >= first + 32u {
            below += countOneBits(bits);
        } else if lane > first {
            below += countOneBits(bits & ((1u << (lane - first)) - 1u));
        }
    }
    var start = 0u;
    if lane == 0u && total > 0u {
        start = atomicAdd(&pushed, 2u * total);
    }
    return subgroupBroadcast(start, 0u) + 2u * below;
}

@compute @workgroup_size(64)
fn inplace(
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) t: u32,
    @builtin(subgroup_invocation_id) lane: u32,
) {
    let v = walked_view(wid, groups);
    if v >= problem.view_count {
        return;
    }
    start_walk(t);
    loop {
        let n = workgroupUniformLoad(&size);
        if n == 0u {
            break;
        }
        let p = pop(v, t, n);
        push(p, ballot_slot(p.split, lane), t);
    }
}
