// The nearest node of every atlas pixel, after the splat (point-based GI's lookup, §3.6.1): one
// thread per cut node-view, every pixel of its disc whose atlas depth is the disc's own takes
// the atomic minimum of the node's index. Mirrors `manylod::splat::nearest_nodes`.
// #import manylod/splat.wgsl

// Bindings 0–5 as `splat.wgsl` (6 is the in-place variant's problem).
@group(0) @binding(7) var<storage, read_write> ids: array<atomic<u32>>;

// `ids`' value of a pixel no node covers (`manylod::splat::NO_NODE`).
const NO_NODE: u32 = 0xFFFFFFFFu;

@compute @workgroup_size(256)
fn clear_ids(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = gid.x + gid.y * groups.x * 256u;
    if i < arrayLength(&ids) {
        atomicStore(&ids[i], NO_NODE);
    }
}

@compute @workgroup_size(256)
fn nearest(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let nv = cut_entry(gid.x + gid.y * groups.x * 256u);
    if (nv.x & CULLED) != 0u {
        return;
    }
    let d = disc_of(nv.y, nodes[nv.x]);
    if !d.ok {
        return;
    }
    for (var y = d.lo.y; y < d.hi.y; y++) {
        for (var x = d.lo.x; x < d.hi.x; x++) {
            let p = covered(d, x, y);
            if p >= 0 && atomicLoad(&atlas[p]) == d.word {
                atomicMin(&ids[p], nv.x);
            }
        }
    }
}
