// The in-place variant (§3.7.2, Listings 3.3/3.4): one workgroup per view walks the tree
// depth-first from the root with a stack in workgroup memory. Each round the cutfinders pop up
// to one node each; valid nodes are rasterised at once, split nodes push their two children into
// slots handed out by a compaction; no cut list is written. Basic cuts only, as in the paper.
// The entry points (`inplace_atomic.wgsl`, `inplace_ballot.wgsl`) differ only in the compaction.
// #import manylod/splat.wgsl

@group(0) @binding(6) var<uniform> problem: Problem;

// Counter slot of the stack overflow (as `cut.wgsl`'s OVERFLOW).
const OVERFLOW: u32 = 8u;
const CUTFINDERS: u32 = 64u;
// x(1 + (n − 1)d) node-views for x cutfinders, arity n = 2, depth d ≤ 26.
const STACK: u32 = 64u * 27u;

var<workgroup> stack: array<u32, STACK>;
var<workgroup> size: u32;
// Children pushed this round (2 per split).
var<workgroup> pushed: atomic<u32>;

// What one cutfinder popped in a round: the node, whether it splits, the stack's new base.
struct Pop {
    node: u32,
    split: bool,
    base: u32,
}

// View index of workgroup `wid`.
fn walked_view(wid: vec3<u32>, groups: vec3<u32>) -> u32 {
    return wid.x + wid.y * groups.x;
}

// Puts the root on the stack.
fn start_walk(t: u32) {
    if t == 0u {
        stack[0] = 0u;
        size = 1u;
    }
}

// Pops up to CUTFINDERS of the `n` stacked nodes; valid ones are rasterised into view v's tile.
fn pop(v: u32, t: u32, n: u32) -> Pop {
    let take = min(n, CUTFINDERS);
    var p = Pop(0u, false, n - take);
    if t < take {
        p.node = stack[p.base + t];
    }
    if t == 0u {
        atomicStore(&pushed, 0u);
    }
    workgroupBarrier();
    if t < take {
        let node = nodes[p.node];
        let c = criterion(views[v], node);
        if p.node >= problem.leaf_start || c < problem.epsilon {
            if c > 0.0 {
                splat_disc(v, node);
            }
        } else {
            p.split = true;
        }
    }
    return p;
}

// Pushes a splitting cutfinder's children at `slot` above the base, then sets the stack size.
fn push(p: Pop, slot: u32, t: u32) {
    if p.split {
        let o = p.base + slot;
        if o + 1u < STACK {
            stack[o] = 2u * p.node + 1u;
            stack[o + 1u] = 2u * p.node + 2u;
        } else {
            atomicAdd(&counters[OVERFLOW], 2u);
        }
    }
    workgroupBarrier();
    if t == 0u {
        size = min(p.base + atomicLoad(&pushed), STACK);
    }
}
