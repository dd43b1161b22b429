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

// Rasterises node n's disc into view v's tile (pixel centres inside the disc).
fn splat_disc(v: u32, n: Node) {
    let view = views[v];
    let s = splat_of(view, n, atlas_.far);
    if !s.ok {
        return;
    }
    let word = pack_depth(s.depth, 0u);
    let tile = i32(atlas_.tile);
    let lo = max(vec2<i32>(ceil(s.center - s.radius - 0.5)), vec2<i32>(0));
    let hi = min(vec2<i32>(floor(s.center + s.radius - 0.5)) + 1, vec2<i32>(tile));
    let slot = atlas_.first_view + v;
    let origin = vec2<i32>(i32(slot % atlas_.columns), i32(slot / atlas_.columns)) * tile;
    for (var y = lo.y; y < hi.y; y++) {
        for (var x = lo.x; x < hi.x; x++) {
            let d = vec2<f32>(f32(x), f32(y)) + 0.5 - s.center;
            if dot(d, d) <= s.radius * s.radius {
                let p = origin + vec2<i32>(x, y);
                atomicMin(&atlas[u32(p.y) * atlas_.width + u32(p.x)], word);
            }
        }
    }
}

@compute @workgroup_size(256)
fn splat(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = gid.x + gid.y * groups.x * 256u;
    if i >= min(atomicLoad(&counters[atlas_.cut_slot]), arrayLength(&cut)) {
        return;
    }
    let nv = cut[i];
    if (nv.x & CULLED) != 0u {
        return;
    }
    splat_disc(nv.y, nodes[nv.x]);
}
