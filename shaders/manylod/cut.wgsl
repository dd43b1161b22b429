// Many-view cuts on the GPU (§3.5.2, §3.7, Listing 3.1): one thread per active node-view,
// ping-pong active lists with atomic appends, the cut appended to a third list. `prepare`
// (one thread) turns the next pass's input count into its indirect dispatch size, so the
// iterations run without reading counts back. Mirrors `manylod::cut::refine_levels`, including
// its merge that climbs to the highest valid ancestor at once and its passes that descend more
// than one tree level.
// #import manylod/common.wgsl

// What one pass does: read `in_slot`'s list (or the roots), append splits to `out_slot`'s,
// cut node-views to `cut_slot`'s.
struct Pass {
    in_slot: u32,
    out_slot: u32,
    cut_slot: u32,
    mode: u32,
}

const LIST: u32 = 0u;
const ROOTS: u32 = 1u;
// Lazy end of frame: every leftover active node-view joins the cut.
const FLUSH: u32 = 2u;
// Only a dispatch size for `in_slot`'s count (the splat).
const COUNT: u32 = 3u;
// Roots or the first pass of an incremental or lazy frame: the cut starts empty, and only
// this pass checks parents (later passes hold split children, whose parents are not valid).
const BEGIN: u32 = 0x100u;

// Counter slots after the lists' counts.
const OVERFLOW: u32 = 8u;
const PROCESSED: u32 = 9u;
const ITERATIONS: u32 = 10u;

const WORKGROUP: u32 = 256u;
const MAX_GROUPS_X: u32 = 32768u;

@group(0) @binding(0) var<storage, read> nodes: array<Node>;
@group(0) @binding(1) var<storage, read> views: array<View>;
@group(0) @binding(2) var<uniform> problem: Problem;
@group(0) @binding(3) var<uniform> pass_: Pass;
@group(0) @binding(4) var<storage, read_write> counters: array<atomic<u32>, 16>;
@group(0) @binding(5) var<storage, read> list_in: array<vec2<u32>>;
@group(0) @binding(6) var<storage, read_write> list_out: array<vec2<u32>>;
@group(0) @binding(7) var<storage, read_write> cut: array<vec2<u32>>;
@group(0) @binding(8) var<storage, read_write> dispatch: array<u32, 3>;

@compute @workgroup_size(1)
fn prepare() {
    let mode = pass_.mode & 0xFFu;
    var n = problem.view_count;
    if mode != ROOTS {
        n = atomicLoad(&counters[pass_.in_slot]);
    }
    if mode != COUNT {
        atomicStore(&counters[pass_.out_slot], 0u);
        if (pass_.mode & BEGIN) != 0u {
            atomicStore(&counters[pass_.cut_slot], 0u);
        }
        if mode != FLUSH {
            atomicAdd(&counters[PROCESSED], n);
            atomicAdd(&counters[ITERATIONS], select(0u, 1u, n > 0u));
        }
    }
    let groups = (n + WORKGROUP - 1u) / WORKGROUP;
    dispatch[0] = min(groups, MAX_GROUPS_X);
    dispatch[1] = (groups + MAX_GROUPS_X - 1u) / MAX_GROUPS_X;
    dispatch[2] = 1u;
}

fn c_of(node: u32, view: u32) -> f32 {
    return criterion(views[view], nodes[node]);
}

fn is_valid(node: u32, view: u32) -> bool {
    return node >= problem.leaf_start || c_of(node, view) < problem.epsilon;
}

fn parent_valid(node: u32, view: u32) -> bool {
    return node > 0u && is_valid((node - 1u) / 2u, view);
}

// Node-views below a split decided in the same pass (`problem.levels` > 1): bit r of a mask
// stands for the split node's descendant r, numbered in heap order relative to it (0 the node
// itself, 1 and 2 its children, 3 to 6 its grandchildren …), which is node s · 2^depth(r) + r.
fn descendant(s: u32, r: u32) -> u32 {
    return (s << firstLeadingBit(r + 1u)) + r;
}

// Appends are aggregated per workgroup: each thread takes its place with a workgroup atomic,
// one thread reserves the workgroup's total in the global list (one global atomic per list and
// workgroup instead of one per node-view).
var<workgroup> group_out: atomic<u32>;
var<workgroup> group_cut: atomic<u32>;
var<workgroup> group_processed: atomic<u32>;
var<workgroup> base_out: u32;
var<workgroup> base_cut: u32;

const NONE: u32 = 0xFFFFFFFFu;

@compute @workgroup_size(256)
fn step(
    @builtin(global_invocation_id) gid: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) t: u32,
) {
    if t == 0u {
        atomicStore(&group_out, 0u);
        atomicStore(&group_cut, 0u);
        atomicStore(&group_processed, 0u);
    }
    workgroupBarrier();
    let i = gid.x + gid.y * groups.x * WORKGROUP;
    let mode = pass_.mode & 0xFFu;
    var nv = vec2<u32>(NONE, i);
    if mode == ROOTS {
        if i < problem.view_count {
            nv.x = 0u;
        }
    } else if i < atomicLoad(&counters[pass_.in_slot]) {
        nv = list_in[i];
        nv.x &= ~CULLED;
    }
    // What this node-view yields: a cut node-view (`drawn`, its criterion `c` when known) or a
    // split (children of `split`). Only a frame's first pass can hold node-views whose parent
    // is valid (last frame's cut under moved views); later passes hold split children.
    var drawn = NONE;
    var c = -1.0;
    var split = NONE;
    if nv.x != NONE {
        if mode == FLUSH {
            drawn = nv.x;
        } else if (pass_.mode & BEGIN) == 0u || !parent_valid(nv.x, nv.y) {
            c = c_of(nv.x, nv.y);
            if nv.x >= problem.leaf_start || c < problem.epsilon {
                drawn = nv.x;
            } else {
                split = nv.x;
            }
        } else {
            // Merge: climb to the highest valid ancestor; the node-view on its leftmost path
            // brings it.
            var node = nv.x;
            var leftmost = true;
            while parent_valid(node, nv.y) {
                leftmost = leftmost && (node & 1u) == 1u;
                node = (node - 1u) / 2u;
            }
            if leftmost {
                drawn = node;
            }
        }
    }
    // A split's descendants down to `problem.levels − 1` levels below it: each whose parent
    // splits is decided here (Listing 3.1's steps 1 and 2, as the next passes would); the
    // children of those that split on the last of these levels go to the next pass.
    var splits = 0u;
    var cut_bits = 0u;
    var culled_bits = 0u;
    // Descendants 2^(levels − 1) − 1 up to `end` − 1 lie on the last level decided here.
    let end = (1u << problem.levels) - 1u;
    let deepest = ((1u << end) - 1u) & ~((1u << ((1u << (problem.levels - 1u)) - 1u)) - 1u);
    if split != NONE {
        splits = 1u;
        for (var r = 1u; r < end; r++) {
            if (splits & (1u << ((r - 1u) / 2u))) != 0u {
                let node = descendant(split, r);
                let cr = c_of(node, nv.y);
                if node >= problem.leaf_start || cr < problem.epsilon {
                    cut_bits |= 1u << r;
                    culled_bits |= select(0u, 1u << r, cr == 0.0);
                } else {
                    splits |= 1u << r;
                }
            }
        }
    }
    let out_count = 2u * countOneBits(splits & deepest);
    let cut_count = countOneBits(cut_bits) + select(0u, 1u, drawn != NONE);
    let descendants = countOneBits(cut_bits | (splits & ~1u));
    var out_at = 0u;
    var cut_at = 0u;
    if out_count > 0u {
        out_at = atomicAdd(&group_out, out_count);
    }
    if cut_count > 0u {
        cut_at = atomicAdd(&group_cut, cut_count);
    }
    if descendants > 0u {
        atomicAdd(&group_processed, descendants);
    }
    workgroupBarrier();
    if t == 0u {
        base_out = atomicAdd(&counters[pass_.out_slot], atomicLoad(&group_out));
        base_cut = atomicAdd(&counters[pass_.cut_slot], atomicLoad(&group_cut));
        let processed = atomicLoad(&group_processed);
        if processed > 0u {
            atomicAdd(&counters[PROCESSED], processed);
        }
    }
    workgroupBarrier();
    var o = base_out + out_at;
    var outs = splits & deepest;
    while outs != 0u {
        let node = descendant(split, firstTrailingBit(outs));
        outs &= outs - 1u;
        if o + 1u < arrayLength(&list_out) {
            list_out[o] = vec2<u32>(2u * node + 1u, nv.y);
            list_out[o + 1u] = vec2<u32>(2u * node + 2u, nv.y);
        } else {
            atomicAdd(&counters[OVERFLOW], 2u);
        }
        o += 2u;
    }
    o = base_cut + cut_at;
    if drawn != NONE {
        if o < arrayLength(&cut) {
            if c < 0.0 {
                c = c_of(drawn, nv.y);
            }
            cut[o] = vec2<u32>(select(drawn, drawn | CULLED, c == 0.0), nv.y);
        } else {
            atomicAdd(&counters[OVERFLOW], 1u);
        }
        o += 1u;
    }
    var cuts = cut_bits;
    while cuts != 0u {
        let r = firstTrailingBit(cuts);
        cuts &= cuts - 1u;
        let node = descendant(split, r);
        if o < arrayLength(&cut) {
            let culled = (culled_bits & (1u << r)) != 0u;
            cut[o] = vec2<u32>(select(node, node | CULLED, culled), nv.y);
        } else {
            atomicAdd(&counters[OVERFLOW], 1u);
        }
        o += 1u;
    }
}
