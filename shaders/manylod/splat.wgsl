// Splatting the drawn node-views of a cut into the atlas of per-view tiles (§3.7.2): one thread
// per cut node-view, every pixel whose centre lies in the node's disc takes an atomic-min of
// the FreePipe-packed depth. Mirrors `manylod::splat::splat`.
// #import manylod/common.wgsl

struct Atlas {
    // Atlas row length in pixels.
    width: u32,
    tile: u32,
    columns: u32,
    // Counter slot holding the cut's length.
    cut_slot: u32,
    far: f32,
    // Slot of view 0 (batches of views sharing one atlas).
    first_view: u32,
}

@group(0) @binding(0) var<storage, read> nodes: array<Node>;
@group(0) @binding(1) var<storage, read> views: array<View>;
@group(0) @binding(2) var<uniform> atlas_: Atlas;
@group(0) @binding(3) var<storage, read_write> counters: array<atomic<u32>, 16>;
@group(0) @binding(4) var<storage, read> cut: array<vec2<u32>>;
@group(0) @binding(5) var<storage, read_write> atlas: array<atomic<u32>>;


@compute @workgroup_size(256)
fn clear(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = gid.x + gid.y * groups.x * 256u;
    if i < arrayLength(&atlas) {
        atomicStore(&atlas[i], 0xFFFFFFFFu);
    }
}

// Node n's disc in view v's tile: its packed depth, the pixels of the view (its size, at most
// the tile's) that may lie in it, and where the tile starts in the atlas.
struct Disc {
    ok: bool,
    word: u32,
    center: vec2<f32>,
    radius: f32,
    lo: vec2<i32>,
    hi: vec2<i32>,
    origin: vec2<i32>,
}

fn disc_of(v: u32, n: Node) -> Disc {
    let view = views[v];
    let s = splat_of(view, n, atlas_.far);
    let tile = i32(atlas_.tile);
    let slot = atlas_.first_view + v;
    return Disc(
        s.ok,
        pack_depth(s.depth, 0u),
        s.center,
        s.radius,
        max(vec2<i32>(ceil(s.center - s.radius - 0.5)), vec2<i32>(0)),
        min(vec2<i32>(floor(s.center + s.radius - 0.5)) + 1, vec2<i32>(view.size)),
        vec2<i32>(i32(slot % atlas_.columns), i32(slot / atlas_.columns)) * tile,
    );
}

// The atlas index of tile pixel (x, y) when its centre lies in the disc, else -1.
fn covered(d: Disc, x: i32, y: i32) -> i32 {
    let o = vec2<f32>(f32(x), f32(y)) + 0.5 - d.center;
    if dot(o, o) > d.radius * d.radius {
        return -1;
    }
    let p = d.origin + vec2<i32>(x, y);
    return p.y * i32(atlas_.width) + p.x;
}

// Rasterises node n's disc into view v's tile (pixel centres inside the disc).
fn splat_disc(v: u32, n: Node) {
    let d = disc_of(v, n);
    if !d.ok {
        return;
    }
    for (var y = d.lo.y; y < d.hi.y; y++) {
        for (var x = d.lo.x; x < d.hi.x; x++) {
            let i = covered(d, x, y);
            if i >= 0 {
                atomicMin(&atlas[i], d.word);
            }
        }
    }
}

@compute @workgroup_size(256)
fn splat(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let nv = cut_entry(gid.x + gid.y * groups.x * 256u);
    if (nv.x & CULLED) != 0u {
        return;
    }
    splat_disc(nv.y, nodes[nv.x]);
}

// Node-view `i` of the cut (node, view), flagged CULLED past the cut's end.
fn cut_entry(i: u32) -> vec2<u32> {
    if i >= min(atomicLoad(&counters[atlas_.cut_slot]), arrayLength(&cut)) {
        return vec2<u32>(CULLED, 0u);
    }
    return cut[i];
}
