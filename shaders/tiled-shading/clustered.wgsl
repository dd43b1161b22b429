// #import tiled-shading/shadows.wgsl
// #import tiled-shading/pixels.wgsl
// #import tiled-shading/sums.wgsl
// #import tiled-shading/slices.wgsl
// #import tiled-shading/light_search.wgsl
// Clustered deferred shading (Olsson et al. 2012, as the thesis summarises it in §2.5), four
// dispatches of one pass:
// 1. `cluster_keys` (a workgroup per TILE × TILE screen tile): each pixel's cluster key — its
//    tile and exponential depth slice — and, per slice, the least and greatest depth of the
//    tile's pixels in it (the cluster's explicit bounds); the occupied clusters are appended
//    to `clusters` (the unique clusters, compacted, in no set order) with their bounds.
// 2. `cluster_dispatch`: the indirect dispatch of step 3 (rows of ROW workgroups); it resets
//    the counters for the next steps and the next frame.
// 3. `assign_lights` (a workgroup per unique cluster): the cluster's lights — those meeting
//    the tile's side planes and the cluster's depths — found as `light_search.wgsl` says
//    (through the light hierarchy, or among all lights), gathered in workgroup memory, then appended to `entries` at an
//    offset taken from `state.entry_total`; `records[cell]` = (offset, count). A cluster with
//    more than CAPACITY lights, or whose entries do not fit, is recorded as OVERFLOW.
// 4. `shade_clusters` (per pixel): the sums over the pixel's cluster's entries; in an
//    OVERFLOW cluster over every light whose sphere holds the pixel (the same sums: a light
//    adds nothing beyond its radius) — so no light count is too large.
// Twin of `tiled_shading::cpu::shade` with `Method::Clustered` (the same lists).
// `tiled_shading::gpu::clustered` sets TILE, WG, THREADS, ROUND (= THREADS) and LIGHT_TREE.

const TILE: u32 = 16u;
// Invocations per tile side in `cluster_keys`, min(TILE, 16); each reads PER_SIDE² pixels.
const WG: u32 = 16u;
const PER_SIDE: u32 = TILE / WG;
const THREADS: u32 = 64u;
const CAPACITY: u32 = 1024u;
const OVERFLOW: u32 = 0xffffffffu;
const ROW: u32 = 32768u;
const EMPTY: u32 = 0xffffffffu;

struct ClusterState {
    // Appended by `cluster_keys`; moved to `clusters_found` and reset by `cluster_dispatch`.
    cluster_count: atomic<u32>,
    clusters_found: u32,
    entry_total: atomic<u32>,
};

// The unique clusters: (grid cell = tile × SLICES + slice, least depth, greatest depth as f32
// bits, 0), `state.clusters_found` of them.
@group(0) @binding(10) var<storage, read_write> clusters: array<vec4<u32>>;
// Per grid cell: (offset into `entries` or OVERFLOW, light count) — valid for this frame's
// occupied cells only.
@group(0) @binding(12) var<storage, read_write> records: array<vec2<u32>>;
@group(0) @binding(13) var<storage, read_write> entries: array<u32>;
@group(0) @binding(14) var<storage, read_write> state: ClusterState;
// `assign_lights`' indirect dispatch (x, y, z): its own buffer, which no bind group of that
// dispatch holds.
@group(0) @binding(15) var<storage, read_write> assign_groups: array<u32, 3>;

fn cell_of(pixel: vec2<u32>, depth: f32) -> u32 {
    let tile = (pixel.y / TILE) * params.tiles_x + pixel.x / TILE;
    return tile * SLICES + slice_of(depth);
}

// Per slice of `cluster_keys`' tile: the least and greatest depth (positive f32 bits order as
// u32), EMPTY and 0 when no pixel lies in it.
var<workgroup> slice_least: array<atomic<u32>, SLICES>;
var<workgroup> slice_greatest: array<atomic<u32>, SLICES>;

@compute @workgroup_size(WG, WG)
fn cluster_keys(
    @builtin(workgroup_id) group: vec3<u32>,
    @builtin(local_invocation_id) local: vec3<u32>,
    @builtin(local_invocation_index) index: u32,
) {
    if index < SLICES {
        atomicStore(&slice_least[index], EMPTY);
        atomicStore(&slice_greatest[index], 0u);
    }
    workgroupBarrier();
    let size = textureDimensions(linear_depth_texture);
    for (var i = 0u; i < PER_SIDE * PER_SIDE; i++) {
        let pixel = group.xy * TILE + local.xy + WG * vec2<u32>(i % PER_SIDE, i / PER_SIDE);
        if pixel.x < size.x && pixel.y < size.y {
            let depth = textureLoad(linear_depth_texture, pixel, 0).x;
            if depth > 0.0 {
                let k = slice_of(depth);
                atomicMin(&slice_least[k], bitcast<u32>(depth));
                atomicMax(&slice_greatest[k], bitcast<u32>(depth));
            }
        }
    }
    workgroupBarrier();
    if index < SLICES {
        let least = atomicLoad(&slice_least[index]);
        if least != EMPTY {
            let tile = group.y * params.tiles_x + group.x;
            let cluster = vec4<u32>(tile * SLICES + index, least, atomicLoad(&slice_greatest[index]), 0u);
            clusters[atomicAdd(&state.cluster_count, 1u)] = cluster;
        }
    }
}

@compute @workgroup_size(1)
fn cluster_dispatch() {
    let n = atomicLoad(&state.cluster_count);
    state.clusters_found = n;
    atomicStore(&state.cluster_count, 0u);
    atomicStore(&state.entry_total, 0u);
    assign_groups[0] = min(n, ROW);
    assign_groups[1] = (n + ROW - 1u) / ROW;
    assign_groups[2] = 1u;
}

// The cluster of `assign_lights`: its tile's side planes and its pixels' depths.
var<workgroup> cluster_cell: u32;
var<workgroup> cluster_planes: array<vec4<f32>, 4>;
var<workgroup> cluster_depths: vec2<f32>;
var<workgroup> cluster_total: u32;
var<workgroup> list_count: atomic<u32>;
var<workgroup> list_size: u32;
var<workgroup> list_light: array<u32, CAPACITY>;
var<workgroup> list_offset: u32;

fn sphere_meets_sides(c: vec3<f32>, r: f32) -> bool {
    var inside = true;
    for (var i = 0u; i < 4u; i++) {
        inside = inside && dot(cluster_planes[i].xyz, c) + cluster_planes[i].w >= -r;
    }
    return inside;
}

// Whether a sphere meets the cluster: its side planes and depths.
fn sphere_meets_cluster(c: vec3<f32>, r: f32) -> bool {
    let depth = view_depth(c);
    return sphere_meets_sides(c, r) && depth + r >= cluster_depths.x && depth - r <= cluster_depths.y;
}

// `cpu::cull_light` for `Method::Clustered`.
fn cluster_meets(light: Light) -> bool {
    return light.kind == LIGHT_DIRECTIONAL || sphere_meets_cluster(light.position, light.radius);
}

@compute @workgroup_size(THREADS)
fn assign_lights(
    @builtin(workgroup_id) group: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) index: u32,
) {
    let c = group.x + group.y * groups.x;
    if index == 0u {
        cluster_total = state.clusters_found;
        atomicStore(&list_count, 0u);
        if c < cluster_total {
            let cluster = clusters[c];
            let cell = cluster.x;
            let tile = cell / SLICES;
            let size = textureDimensions(linear_depth_texture);
            let origin = vec2<u32>(tile % params.tiles_x, tile / params.tiles_x) * TILE;
            let rect = vec4<u32>(origin.x, min(origin.x + TILE, size.x), origin.y, min(origin.y + TILE, size.y));
            let sides = side_planes(edge_slopes(rect));
            for (var i = 0u; i < 4u; i++) {
                cluster_planes[i] = sides[i];
            }
            cluster_cell = cell;
            cluster_depths = bitcast<vec2<f32>>(cluster.yz);
        }
    }
    if c >= workgroupUniformLoad(&cluster_total) {
        return;
    }
    for (var r = 0u; r < search_rounds(); r++) {
        var candidates = params.light_count;
        if LIGHT_TREE {
            let g = begin_round(r, index);
            // Directional lights' group has radius f32::MAX: it meets every cluster.
            if g != NO_LIGHT {
                let sphere = group_sphere(g);
                if sphere_meets_cluster(sphere.xyz, sphere.w) {
                    pass_group(g);
                }
            }
            candidates = end_round(index);
        }
        let batches = (candidates + THREADS - 1u) / THREADS;
        for (var b = 0u; b < batches; b++) {
            let i = candidate_light(b * THREADS + index);
            let valid = i != NO_LIGHT;
            if valid && cluster_meets(lights[i]) {
                let slot = atomicAdd(&list_count, 1u);
                if slot < CAPACITY {
                    list_light[slot] = i;
                }
            }
        }
    }
    workgroupBarrier();
    if index == 0u {
        let n = atomicLoad(&list_count);
        var offset = OVERFLOW;
        if n <= CAPACITY {
            let o = atomicAdd(&state.entry_total, n);
            if o + n <= arrayLength(&entries) {
                offset = o;
            }
        }
        records[cluster_cell] = vec2<u32>(offset, n);
        list_offset = offset;
        list_size = n;
    }
    let offset = workgroupUniformLoad(&list_offset);
    if offset != OVERFLOW {
        for (var j = index; j < list_size; j += THREADS) {
            entries[offset + j] = list_light[j];
        }
    }
}

@compute @workgroup_size(8, 8)
fn shade_clusters(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = textureDimensions(linear_depth_texture);
    if id.x >= size.x || id.y >= size.y {
        return;
    }
    let s = load_sample(id.xy, size);
    var sum = Accumulated(vec3<f32>(0.0), vec3<f32>(0.0));
    if s.present {
        let p = lit_pixel(s, id.xy);
        let record = records[cell_of(id.xy, s.depth)];
        if record.x != OVERFLOW {
            for (var j = 0u; j < record.y; j++) {
                sum = add_light(sum, lights[entries[record.x + j]], p);
            }
        } else {
            for (var i = 0u; i < params.light_count; i++) {
                let light = lights[i];
                if light.kind == LIGHT_DIRECTIONAL || distance(light.position, s.position) <= light.radius {
                    sum = add_light(sum, light, p);
                }
            }
        }
    }
    store_sums(id.xy, sum);
}
