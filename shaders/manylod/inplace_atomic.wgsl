// The in-place variant with a workgroup atomic per split as its compaction (adapters without
// subgroups).
// #import manylod/inplace.wgsl

@compute @workgroup_size(64)
fn inplace(
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) t: u32,
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
        var slot = 0u;
        if p.split {
            slot = atomicAdd(&pushed, 2u);
        }
        push(p, slot, t);
    }
}
