// Main GPU subdivision step (Holländer 2013 §2.2.3, Listing 2.1): one workgroup per M¹ patch.
// The patch's one-ring positions and normals go to workgroup memory; each thread evaluates grid
// vertices (i, j) of the uniform tessellation with s segments that the patch owns, as the
// weighted sum of the ring with the level-L table sampled at (i·step, j·step), the normal the
// same sum over M¹ normals, normalised (Subdivision Shading). Mirrors
// `subdiv_bft::patch::{Patches::evaluate, output_vertex}`.

const MAX_RING: u32 = 24u;
const REVERSED: u32 = 0x80000000u;

struct Params {
    // Segments per patch edge of this tessellation.
    s: u32,
    // Table grid step: (table segments) / s.
    step: u32,
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
// Grid vertex g of the s-segment grid is (walk[g] & 0xffff, walk[g] >> 16).
@group(0) @binding(6) var<storage, read> walk: array<u32>;
@group(0) @binding(7) var<storage, read_write> out_positions: array<vec4<f32>>;
@group(0) @binding(8) var<storage, read_write> out_normals: array<vec4<f32>>;

var<workgroup> ring_p: array<vec3<f32>, MAX_RING>;
var<workgroup> ring_n: array<vec3<f32>, MAX_RING>;

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

@compute @workgroup_size(64)
fn evaluate(
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) lid: u32,
) {
    let p = wid.x + wid.y * groups.x;
    if p >= params.patch_count {
        return;
    }
    let pt = patches[p];
    if lid < MAX_RING {
        var q = vec3<f32>(0.0);
        var n = vec3<f32>(0.0);
        if lid < pt.ring_size {
            let v = rings[pt.ring_offset + lid];
            q = p1[v].xyz;
            n = n1[v].xyz;
        }
        ring_p[lid] = q;
        ring_n[lid] = n;
    }
    workgroupBarrier();
    let stride = (pt.ring_size + 3u) / 4u;
    for (var g = lid; g < params.grid_count; g += 64u) {
        let ij = walk[g];
        let i = ij & 0xffffu;
        let j = ij >> 16u;
        let out = output_vertex(pt, p, i, j);
        if out.y == 0u {
            continue;
        }
        let row = pt.table_offset
            + grid_index(i * params.step, j * params.step, params.table_segments) * stride;
        var pos = vec3<f32>(0.0);
        var nrm = vec3<f32>(0.0);
        for (var c = 0u; c < stride; c++) {
            let w = tables[row + c];
            let r = 4u * c;
            pos += w.x * ring_p[r];
            nrm += w.x * ring_n[r];
            pos += w.y * ring_p[r + 1u];
            nrm += w.y * ring_n[r + 1u];
            pos += w.z * ring_p[r + 2u];
            nrm += w.z * ring_n[r + 2u];
            pos += w.w * ring_p[r + 3u];
            nrm += w.w * ring_n[r + 3u];
        }
        let len = length(nrm);
        out_positions[out.x] = vec4<f32>(pos, 1.0);
        out_normals[out.x] = vec4<f32>(select(vec3<f32>(0.0), nrm / len, len > 0.0), 0.0);
    }
}
