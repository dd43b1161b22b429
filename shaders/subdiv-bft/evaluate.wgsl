// Main GPU subdivision step (Holländer 2013 §2.2.3, Listing 2.1). The one-ring positions and
// normals of a patch go to workgroup memory; each thread evaluates grid vertices (i, j) that the
// patch owns as the weighted sum of the ring with the level-L table sampled at (i·step, j·step),
// the normal the same sum over M¹ normals, normalised (Subdivision Shading).
//
// `evaluate`: uniform tessellation with s segments per patch; mirrors
// `subdiv_bft::patch::{Patches::evaluate, output_vertex}`. A workgroup holds SLOTS patches
// (several small grids at low levels, one from level 4 on).
// `evaluate_adaptive` (built with SLOTS = 1): per-edge factors (§2.2.3 "Adaptive
// Refinement", Figs. 2.10/2.11), the patch at the finest of its edges, coarser edges snapped,
// linear geomorph, triangles appended to an indirect draw; mirrors `subdiv_bft::adaptive`. A
// workgroup takes one chunk of a patch (CHUNK_VERTICES grid vertices and CHUNK_TRIANGLES
// triangles), so a fine patch spreads over several workgroups and a coarse one over one.

const MAX_RING: u32 = 24u;
const REVERSED: u32 = 0x80000000u;
const WORKGROUP: u32 = 64u;
// Patches a workgroup of `evaluate` holds at once, WORKGROUP / SLOTS threads each: the host
// specialises it per level (`patch_slots`: 4 for grids of at most 16 vertices, else 1). Each
// thread loads at most two ring entries (SLOTS · MAX_RING ≤ 2 · WORKGROUP).
const SLOTS: u32 = 4u;
// Grid vertices and triangles of a patch one workgroup of `evaluate_adaptive` takes (the host
// specialises them: `ADAPTIVE_CHUNK`).
const CHUNK_VERTICES: u32 = 128u;
const CHUNK_TRIANGLES: u32 = 256u;

struct Params {
    // Segments per patch edge of this tessellation (adaptive: of the vertex layout, s_max).
    s: u32,
    // Segments of the tables' grid.
    table_segments: u32,
    vertex_count: u32,
    edge_count: u32,
    patch_count: u32,
    grid_count: u32,
    inner_count: u32,
};

struct Patch {
    ring_offset: u32,
    ring_size: u32,
    table_offset: u32,
    owned: u32,
    corners: vec4<u32>,
    edges: vec4<u32>,
};

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> patches: array<Patch>;
@group(0) @binding(2) var<storage, read> rings: array<u32>;
@group(0) @binding(3) var<storage, read> tables: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read> p1: array<vec4<f32>>;
@group(0) @binding(5) var<storage, read> n1: array<vec4<f32>>;
// Grid vertex g of the s-segment grid is (walk[g] & 0xffff, walk[g] >> 16); adaptive: the
// walks of s = 1, 2, 4, … s_max one after the other.
@group(0) @binding(6) var<storage, read> walk: array<u32>;
@group(0) @binding(7) var<storage, read_write> out_positions: array<vec4<f32>>;
@group(0) @binding(8) var<storage, read_write> out_normals: array<vec4<f32>>;

// Adaptive only: one factor per M¹ edge, the triangle list, DrawIndexedIndirect arguments
// (index count first, cleared before the dispatch).
@group(0) @binding(9) var<storage, read> factors: array<f32>;
@group(0) @binding(10) var<storage, read_write> out_indices: array<u32>;
@group(0) @binding(11) var<storage, read_write> draw: array<atomic<u32>>;
// Triangle q of the s-segment grid, in `Patches::triangulate` order, for s = 1, 2, 4, …
@group(0) @binding(12) var<storage, read> triangle_walk: array<u32>;

// The one-rings of the workgroup's patches (slot k at entry k · MAX_RING).
var<workgroup> ring_p: array<vec3<f32>, SLOTS * MAX_RING>;
var<workgroup> ring_n: array<vec3<f32>, SLOTS * MAX_RING>;

fn grid_index(i: u32, j: u32, s: u32) -> u32 {
    return j * (s + 1u) - (j * max(j, 1u) - j) / 2u + i;
}

// Output vertex of (i, j) and whether this patch evaluates it (bit 31 clear: owned).
fn output_vertex(pt: Patch, p: u32, i: u32, j: u32) -> vec2<u32> {
    let s = params.s;
    var k = 3u;
    var t = 0u;
    if j == 0u && i == 0u {
        return vec2<u32>(pt.corners.x, pt.owned & 1u);
    } else if j == 0u && i == s {
        return vec2<u32>(pt.corners.y, (pt.owned >> 1u) & 1u);
    } else if i == 0u && j == s {
        return vec2<u32>(pt.corners.z, (pt.owned >> 2u) & 1u);
    } else if j == 0u {
        k = 0u;
        t = i;
    } else if i + j == s {
        k = 1u;
        t = j;
    } else if i == 0u {
        k = 2u;
        t = s - j;
    }
    if k < 3u {
        let e = pt.edges[k];
        let along = select(t, s - t, (e & REVERSED) != 0u);
        return vec2<u32>(
            params.vertex_count + (e & ~REVERSED) * (s - 1u) + along - 1u,
            (pt.owned >> (3u + k)) & 1u,
        );
    }
    let row = (j - 1u) * (s - 1u) - (j - 1u) * j / 2u;
    let base = params.vertex_count + params.edge_count * (s - 1u) + p * params.inner_count;
    return vec2<u32>(base + row + i - 1u, 1u);
}

// Entry e of the rings of the patches from `first` on (slot e / MAX_RING, ring entry
// e % MAX_RING) into workgroup memory: the M¹ position and normal, zero past the ring.
fn load_ring_entry(first: u32, e: u32) {
    if e >= SLOTS * MAX_RING {
        return;
    }
    var q = vec3<f32>(0.0);
    var n = vec3<f32>(0.0);
    let p = first + e / MAX_RING;
    if p < params.patch_count {
        let pt = patches[p];
        let r = e % MAX_RING;
        if r < pt.ring_size {
            let v = rings[pt.ring_offset + r];
            q = p1[v].xyz;
            n = n1[v].xyz;
        }
    }
    ring_p[e] = q;
    ring_n[e] = n;
}

struct Vertex {
    p: vec3<f32>,
    n: vec3<f32>,
};

// Limit position and unit Subdivision Shading normal of grid vertex (i, j) of an s-segment grid,
// the patch's ring at entry `base` of the workgroup's rings.
fn eval_grid(pt: Patch, base: u32, i: u32, j: u32, s: u32) -> Vertex {
    let step = params.table_segments / s;
    let stride = (pt.ring_size + 3u) / 4u;
    let row = pt.table_offset + grid_index(i * step, j * step, params.table_segments) * stride;
    var pos = vec3<f32>(0.0);
    var nrm = vec3<f32>(0.0);
    for (var c = 0u; c < stride; c++) {
        let w = tables[row + c];
        let r = base + 4u * c;
        pos += w.x * ring_p[r];
        nrm += w.x * ring_n[r];
        pos += w.y * ring_p[r + 1u];
        nrm += w.y * ring_n[r + 1u];
        pos += w.z * ring_p[r + 2u];
        nrm += w.z * ring_n[r + 2u];
        pos += w.w * ring_p[r + 3u];
        nrm += w.w * ring_n[r + 3u];
    }
    return Vertex(pos, unit(nrm));
}

fn unit(n: vec3<f32>) -> vec3<f32> {
    let len = length(n);
    return select(vec3<f32>(0.0), n / len, len > 0.0);
}

// SLOTS patches per workgroup, WORKGROUP / SLOTS threads each.
@compute @workgroup_size(64)
fn evaluate(
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) lid: u32,
) {
    let first = (wid.x + wid.y * groups.x) * SLOTS;
    if first >= params.patch_count {
        return;
    }
    load_ring_entry(first, lid);
    load_ring_entry(first, lid + WORKGROUP);
    workgroupBarrier();
    let lanes = WORKGROUP / SLOTS;
    let slot = lid / lanes;
    let p = first + slot;
    if p >= params.patch_count {
        return;
    }
    let pt = patches[p];
    for (var g = lid % lanes; g < params.grid_count; g += lanes) {
        let ij = walk[g];
        let i = ij & 0xffffu;
        let j = ij >> 16u;
        let out = output_vertex(pt, p, i, j);
        if out.y == 0u {
            continue;
        }
        let v = eval_grid(pt, slot * MAX_RING, i, j, params.s);
        out_positions[out.x] = vec4<f32>(v.p, 1.0);
        out_normals[out.x] = vec4<f32>(v.n, 0.0);
    }
}

// ---- Adaptive tessellation (mirrors `subdiv_bft::adaptive`) ----

struct Levels {
    // Patch segments (the finest edge's) and its geomorph weight.
    s: u32,
    alpha: f32,
    // Segments and geomorph weight of edge k (corner k → k + 1).
    edge_s: vec3<u32>,
    edge_alpha: vec3<f32>,
};

// (2^ceil(f), f − (ceil(f) − 1)) with f clamped to [0, log2 s_max]; factor 0: (1, 1).
fn split_factor(f: f32) -> vec2<f32> {
    let fc = clamp(f, 0.0, f32(countTrailingZeros(params.s)));
    let c = ceil(fc);
    if c == 0.0 {
        return vec2<f32>(1.0, 1.0);
    }
    return vec2<f32>(f32(1u << u32(c)), fc - (c - 1.0));
}

fn patch_levels(pt: Patch) -> Levels {
    var l: Levels;
    var fmax = 0.0;
    for (var k = 0u; k < 3u; k++) {
        let f = factors[pt.edges[k] & ~REVERSED];
        let e = split_factor(f);
        l.edge_s[k] = u32(e.x);
        l.edge_alpha[k] = e.y;
        fmax = max(fmax, f);
    }
    let m = split_factor(fmax);
    l.s = u32(m.x);
    l.alpha = m.y;
    return l;
}

// Edge k and place t along it of grid vertex (i, j); k = 3 for inner vertices, 4 for corners.
fn on_edge(l: Levels, i: u32, j: u32) -> vec2<u32> {
    let s = l.s;
    if (i == 0u && j == 0u) || (j == 0u && i == s) || (i == 0u && j == s) {
        return vec2<u32>(4u, 0u);
    } else if j == 0u {
        return vec2<u32>(0u, i);
    } else if i + j == s {
        return vec2<u32>(1u, j);
    } else if i == 0u {
        return vec2<u32>(2u, s - j);
    }
    return vec2<u32>(3u, 0u);
}

fn edge_point(l: Levels, k: u32, t: u32) -> vec2<u32> {
    if k == 0u {
        return vec2<u32>(t, 0u);
    } else if k == 1u {
        return vec2<u32>(l.s - t, t);
    }
    return vec2<u32>(0u, l.s - t);
}

// Grid vertex snapped to the nearest vertex of a coarser edge (half up along the edge).
fn snap(l: Levels, ij: vec2<u32>) -> vec2<u32> {
    let e = on_edge(l, ij.x, ij.y);
    if e.x >= 3u {
        return ij;
    }
    let r = l.s / l.edge_s[e.x];
    return edge_point(l, e.x, (e.y + r / 2u) / r * r);
}

// Output vertex (s_max layout) of snapped grid vertex ij of the patch's s-segment grid.
fn adaptive_vertex(pt: Patch, p: u32, l: Levels, ij: vec2<u32>) -> u32 {
    let m = params.s / l.s;
    let v = snap(l, ij);
    return output_vertex(pt, p, v.x * m, v.y * m).x;
}

var<workgroup> triangle_base: u32;
// First entry of the s-segment grid's walk among those of s = 1, 2, 4, …
fn walk_offset(s: u32) -> u32 {
    var offset = 0u;
    for (var c = 1u; c < s; c *= 2u) {
        offset += (c + 1u) * (c + 2u) / 2u;
    }
    return offset;
}

// Chunks of a patch with s segments: enough for its grid vertices and for its s² triangles.
fn chunk_count(s: u32) -> u32 {
    let vertices = (s + 1u) * (s + 2u) / 2u;
    return max((vertices + CHUNK_VERTICES - 1u) / CHUNK_VERTICES,
               (s * s + CHUNK_TRIANGLES - 1u) / CHUNK_TRIANGLES);
}

// Workgroup `item` takes chunk item % chunk_count(s_max) of patch item / chunk_count(s_max);
// chunks past the patch's own count return at once.
@compute @workgroup_size(64)
fn evaluate_adaptive(
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) lid: u32,
) {
    let item = wid.x + wid.y * groups.x;
    let chunks = chunk_count(params.s);
    let p = item / chunks;
    let chunk = item % chunks;
    if p >= params.patch_count {
        return;
    }
    let pt = patches[p];
    let l = patch_levels(pt);
    let s = l.s;
    if chunk >= chunk_count(s) {
        return;
    }
    let m = params.s / s;
    let vertex_end = min((chunk + 1u) * CHUNK_VERTICES, (s + 1u) * (s + 2u) / 2u);
    let triangle_first = chunk * CHUNK_TRIANGLES;
    let triangle_end = min(triangle_first + CHUNK_TRIANGLES, s * s);
    if lid == 0u && triangle_first < triangle_end {
        triangle_base = atomicAdd(&draw[0], 3u * (triangle_end - triangle_first)) / 3u;
    }
    load_ring_entry(p, lid);
    workgroupBarrier();

    // The chunk's vertices this patch owns; one that is new at this level moves from its
    // parents' midpoint (geomorph; parents evaluated here too, which measured faster on the
    // H100 than sharing them through workgroup memory behind a barrier).
    let fine_walk = walk_offset(s);
    for (var g = chunk * CHUNK_VERTICES + lid; g < vertex_end; g += WORKGROUP) {
        let ij = walk[fine_walk + g];
        let i = ij & 0xffffu;
        let j = ij >> 16u;
        let e = on_edge(l, i, j);
        var r = 1u;
        if e.x < 3u {
            r = s / l.edge_s[e.x];
            if e.y % r != 0u {
                continue; // snapped away: not a vertex of this tessellation
            }
        }
        let out = output_vertex(pt, p, i * m, j * m);
        if out.y == 0u {
            continue;
        }
        var morph = false;
        var a = vec2<u32>(0u);
        var b = vec2<u32>(0u);
        var alpha = l.alpha;
        if e.x < 3u {
            if l.edge_s[e.x] > 1u && (e.y / r) % 2u == 1u {
                morph = true;
                a = edge_point(l, e.x, e.y - r);
                b = edge_point(l, e.x, e.y + r);
                alpha = l.edge_alpha[e.x];
            }
        } else if e.x == 3u && (i % 2u) + (j % 2u) > 0u {
            morph = true;
            if j % 2u == 0u {
                a = vec2<u32>(i - 1u, j);
                b = vec2<u32>(i + 1u, j);
            } else if i % 2u == 0u {
                a = vec2<u32>(i, j - 1u);
                b = vec2<u32>(i, j + 1u);
            } else {
                a = vec2<u32>(i + 1u, j - 1u);
                b = vec2<u32>(i - 1u, j + 1u);
            }
            a = snap(l, a);
            b = snap(l, b);
        }
        var v = eval_grid(pt, 0u, i, j, s);
        if morph && alpha < 1.0 {
            let va = eval_grid(pt, 0u, a.x, a.y, s);
            let vb = eval_grid(pt, 0u, b.x, b.y, s);
            let mp = 0.5 * (va.p + vb.p);
            let mn = 0.5 * (va.n + vb.n);
            v = Vertex(mp + alpha * (v.p - mp), unit(mn + alpha * (v.n - mn)));
        }
        out_positions[out.x] = vec4<f32>(v.p, 1.0);
        out_normals[out.x] = vec4<f32>(v.n, 0.0);
    }

    // Triangles: the s-grid's triangle walk (i | j << 8 | down << 16), also after the coarser
    // grids' (1 + 4 + 16 + … entries).
    var tri_offset = 0u;
    for (var c = 1u; c < s; c *= 2u) {
        tri_offset += c * c;
    }
    for (var q = triangle_first + lid; q < triangle_end; q += WORKGROUP) {
        let w = triangle_walk[tri_offset + q];
        let i = w & 0xffu;
        let j = (w >> 8u) & 0xffu;
        var t: array<vec2<u32>, 3>;
        if (w >> 16u) == 0u {
            t = array<vec2<u32>, 3>(vec2<u32>(i, j), vec2<u32>(i + 1u, j), vec2<u32>(i, j + 1u));
        } else {
            t = array<vec2<u32>, 3>(
                vec2<u32>(i + 1u, j),
                vec2<u32>(i + 1u, j + 1u),
                vec2<u32>(i, j + 1u),
            );
        }
        let o = 3u * (triangle_base + q - triangle_first);
        for (var c = 0u; c < 3u; c++) {
            out_indices[o + c] = adaptive_vertex(pt, p, l, t[c]);
        }
    }
}
