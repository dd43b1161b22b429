// The hybrid CPU/GPU basic cut's two GPU kernels (§3.7.3, Table 3.4): `events` classifies each
// node-view of the active list (CUT: valid, into the cut; SPLIT: its two children become
// active), `compact` writes the next active list and appends to the cut from the events. The
// CPU runs either half, or a share of the events, in between (`manylod::hybrid`). Starting
// from the roots, a basic cut never merges: every active node-view's parent is not valid.
// Compaction appends with atomics (the paper's CUDA code used a segmented prefix scan), so the
// lists' order is not the CPU's; the sets are.
// #import manylod/common.wgsl

struct Hybrid {
    // Node-views in `list`.
    count: u32,
    leaf_start: u32,
    epsilon: f32,
    pad: u32,
}

// `manylod::hybrid::{CUT, SPLIT}`.
const CUT: u32 = 0u;
const SPLIT: u32 = 1u;

@group(0) @binding(0) var<storage, read> nodes: array<Node>;
@group(0) @binding(1) var<storage, read> views: array<View>;
@group(0) @binding(2) var<uniform> hybrid: Hybrid;
@group(0) @binding(3) var<storage, read> list: array<vec2<u32>>;
@group(0) @binding(4) var<storage, read_write> events: array<u32>;
// [0]: next list length, [1]: cut length (both may exceed the lists: overflow).
@group(0) @binding(5) var<storage, read_write> counters: array<atomic<u32>, 2>;
@group(0) @binding(6) var<storage, read_write> next: array<vec2<u32>>;
@group(0) @binding(7) var<storage, read_write> cut: array<vec2<u32>>;

fn thread_index(gid: vec3<u32>, groups: vec3<u32>) -> u32 {
    return gid.x + gid.y * groups.x * 256u;
}

@compute @workgroup_size(256)
fn classify(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = thread_index(gid, groups);
    if i >= hybrid.count {
        return;
    }
    let nv = list[i];
    let valid = nv.x >= hybrid.leaf_start || criterion(views[nv.y], nodes[nv.x]) < hybrid.epsilon;
    events[i] = select(SPLIT, CUT, valid);
}

@compute @workgroup_size(256)
fn compact(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = thread_index(gid, groups);
    if i >= hybrid.count {
        return;
    }
    let nv = list[i];
    if events[i] == CUT {
        let k = atomicAdd(&counters[1], 1u);
        if k < arrayLength(&cut) {
            cut[k] = nv;
        }
    } else {
        let k = atomicAdd(&counters[0], 2u);
        if k + 1u < arrayLength(&next) {
            let child = 2u * nv.x + 1u;
            next[k] = vec2<u32>(child, nv.y);
            next[k + 1u] = vec2<u32>(child + 1u, nv.y);
        }
    }
}
