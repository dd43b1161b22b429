// #import tiled-shading/shadows.wgsl
// #import tiled-shading/pixels.wgsl
// #import tiled-shading/slices.wgsl
// Clustered deferred shading (Olsson et al. 2012, as the thesis summarises it in §2.5), four
// dispatches of one pass:
// 1. `cluster_keys` (per pixel): the pixel's cluster key — its TILE × TILE screen tile and its
//    exponential depth slice — flags the cluster in `occupied` (a grid of tiles × SLICES).
// 2. `compact_clusters` (per grid cell): each flagged cell is appended to `clusters` (the
//    unique clusters, in no set order) and its flag cleared for the next frame;
//    `cluster_dispatch` then writes the indirect dispatch of step 3 (rows of ROW workgroups).
// 3. `assign_lights` (a workgroup per unique cluster): the cluster's lights — those meeting
//    the tile's side planes and the slice's depths — found through the light hierarchy
//    (LIGHT_TREE: groups of GROUP lights under bounding spheres, `tiled_shading::LightGroups`)
//    or among all lights, gathered in workgroup memory, then appended to `entries` at an
//    offset taken from `state.entry_total`; `records[cell]` = (offset, count). A cluster with
//    more than CAPACITY lights, or whose entries do not fit, is recorded as OVERFLOW.
// 4. `shade_clusters` (per pixel): the sums over the pixel's cluster's entries; in an
//    OVERFLOW cluster over every light whose sphere holds the pixel (the same sums: a light
//    adds nothing beyond its radius) — so no light count is too large.
// Twin of `tiled_shading::cpu::shade` with `Method::Clustered` (the same lists).
// `tiled_shading::gpu::clustered` sets TILE and LIGHT_TREE.

const TILE: u32 = 16u;
const LIGHT_TREE: bool = true;
const GROUP: u32 = 32u;
const THREADS: u32 = 64u;
const CAPACITY: u32 = 1024u;
const OVERFLOW: u32 = 0xffffffffu;
const ROW: u32 = 32768u;

struct ClusterState {
    cluster_count: atomic<u32>,
    entry_total: atomic<u32>,
};

@group(0) @binding(7) var diffuse_out: texture_storage_2d<rgba32float, write>;
@group(0) @binding(8) var specular_out: texture_storage_2d<rgba32float, write>;
// Per grid cell (tile × SLICES + slice): 1 when a pixel of this frame lies in it.
@group(0) @binding(9) var<storage, read_write> occupied: array<atomic<u32>>;
// The occupied cells, `state.cluster_count` of them.
@group(0) @binding(10) var<storage, read_write> clusters: array<u32>;
// `LightGroups::words`: each group's bounding sphere, then the light indices in Morton order.
@group(0) @binding(11) var<storage, read> light_tree: array<vec4<u32>>;
// Per grid cell: (offset into `entries` or OVERFLOW, light count) — valid for this frame's
// occupied cells only.
@group(0) @binding(12) var<storage, read_write> records: array<vec2<u32>>;
@group(0) @binding(13) var<storage, read_write> entries: array<u32>;
@group(0) @binding(14) var<storage, read_write> state: ClusterState;
// `assign_lights`' indirect dispatch (x, y, z): its own buffer, which no bind group of that
// dispatch holds.
@group(0) @binding(15) var<storage, read_write> assign_groups: array<u32, 3>;

fn tiles_y(size: vec2<u32>) -> u32 {
    return (size.y + TILE - 1u) / TILE;
}

fn cell_of(pixel: vec2<u32>, depth: f32) -> u32 {
    let tile = (pixel.y / TILE) * params.tiles_x + pixel.x / TILE;
    return tile * SLICES + slice_of(depth);
}

@compute @workgroup_size(8, 8)
fn cluster_keys(@builtin(global_invocation_id) id: vec3<u32>) {
    if all(id.xy == vec2<u32>(0u)) {
        atomicStore(&state.cluster_count, 0u);
        atomicStore(&state.entry_total, 0u);
    }
    let size = textureDimensions(linear_depth_texture);
    if id.x >= size.x || id.y >= size.y {
        return;
    }
    let depth = textureLoad(linear_depth_texture, id.xy, 0).x;
    if depth <= 0.0 {
        return;
    }
    let cell = cell_of(id.xy, depth);
    // Most pixels find their cluster flagged already: a load spares the store.
    if atomicLoad(&occupied[cell]) == 0u {
        atomicStore(&occupied[cell], 1u);
    }
}

@compute @workgroup_size(THREADS)
fn compact_clusters(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let cell = id.x + id.y * groups.x * THREADS;
    let cells = params.tiles_x * tiles_y(textureDimensions(linear_depth_texture)) * SLICES;
    if cell >= cells || atomicLoad(&occupied[cell]) == 0u {
        return;
    }
    atomicStore(&occupied[cell], 0u);
    clusters[atomicAdd(&state.cluster_count, 1u)] = cell;
}

@compute @workgroup_size(1)
fn cluster_dispatch() {
    let n = atomicLoad(&state.cluster_count);
    assign_groups[0] = min(n, ROW);
    assign_groups[1] = (n + ROW - 1u) / ROW;
    assign_groups[2] = 1u;
}

// The cluster of `assign_lights`: its tile's side planes and its slice's depths.
var<workgroup> cluster_cell: u32;
var<workgroup> cluster_planes: array<vec4<f32>, 4>;
var<workgroup> cluster_slice: u32;
var<workgroup> cluster_total: u32;
var<workgroup> list_count: atomic<u32>;
var<workgroup> list_size: u32;
var<workgroup> list_light: array<u32, CAPACITY>;
var<workgroup> list_offset: u32;
var<workgroup> passed_count: atomic<u32>;
var<workgroup> passed_size: u32;
var<workgroup> passed_groups: array<u32, THREADS>;

fn sphere_meets_sides(c: vec3<f32>, r: f32) -> bool {
    var inside = true;
    for (var i = 0u; i < 4u; i++) {
        inside = inside && dot(cluster_planes[i].xyz, c) + cluster_planes[i].w >= -r;
    }
    return inside;
}

// `cpu::cull_light` for `Method::Clustered`.
fn cluster_meets(light: Light) -> bool {
    if light.kind == LIGHT_DIRECTIONAL {
        return true;
    }
    let depth = view_depth(light.position);
    return sphere_meets_sides(light.position, light.radius)
        && meets_slice(depth - light.radius, depth + light.radius, cluster_slice);
}

@compute @workgroup_size(THREADS)
fn assign_lights(
    @builtin(workgroup_id) group: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) index: u32,
) {
    let c = group.x + group.y * groups.x;
    if index == 0u {
        cluster_total = atomicLoad(&state.cluster_count);
        atomicStore(&list_count, 0u);
        if c < cluster_total {
            let cell = clusters[c];
            let tile = cell / SLICES;
            let size = textureDimensions(linear_depth_texture);
            let origin = vec2<u32>(tile % params.tiles_x, tile / params.tiles_x) * TILE;
            let rect = vec4<u32>(origin.x, min(origin.x + TILE, size.x), origin.y, min(origin.y + TILE, size.y));
            let sides = side_planes(edge_slopes(rect));
            for (var i = 0u; i < 4u; i++) {
                cluster_planes[i] = sides[i];
            }
            cluster_cell = cell;
            cluster_slice = cell % SLICES;
        }
    }
    if c >= workgroupUniformLoad(&cluster_total) {
        return;
    }
    var rounds = 1u;
    if LIGHT_TREE {
        rounds = (params.group_count + THREADS - 1u) / THREADS;
    }
    for (var r = 0u; r < rounds; r++) {
        var batches = (params.light_count + THREADS - 1u) / THREADS;
        if LIGHT_TREE {
            if index == 0u {
                atomicStore(&passed_count, 0u);
            }
            workgroupBarrier();
            let g = r * THREADS + index;
            if g < params.group_count {
                // Directional lights' group has radius f32::MAX: it meets every cluster.
                let sphere = bitcast<vec4<f32>>(light_tree[g]);
                let depth = view_depth(sphere.xyz);
                if sphere_meets_sides(sphere.xyz, sphere.w)
                    && meets_slice(depth - sphere.w, depth + sphere.w, cluster_slice) {
                    passed_groups[atomicAdd(&passed_count, 1u)] = g;
                }
            }
            workgroupBarrier();
            if index == 0u {
                passed_size = atomicLoad(&passed_count);
            }
            batches = (workgroupUniformLoad(&passed_size) * GROUP + THREADS - 1u) / THREADS;
        }
        for (var b = 0u; b < batches; b++) {
            var i = b * THREADS + index;
            var valid = i < params.light_count;
            if LIGHT_TREE {
                let k = passed_groups[min(i / GROUP, THREADS - 1u)] * GROUP + i % GROUP;
                valid = i / GROUP < passed_size && k < params.light_count;
                let o = min(k, params.light_count - 1u);
                i = light_tree[params.group_count + o / 4u][o % 4u];
            }
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
    var diffuse = vec3<f32>(0.0);
    var specular = vec3<f32>(0.0);
    if s.present {
        let v = normalize(frame.eye.xyz - s.position);
        let m = load_material(id.xy);
        let record = records[cell_of(id.xy, s.depth)];
        if record.x != OVERFLOW {
            for (var j = 0u; j < record.y; j++) {
                let c = shade_shadowed(lights[entries[record.x + j]], s.position, s.normal, v, m.albedo, m.roughness, m.metallic, m.specular);
                diffuse += c.diffuse;
                specular += c.specular;
            }
        } else {
            for (var i = 0u; i < params.light_count; i++) {
                let light = lights[i];
                if light.kind == LIGHT_DIRECTIONAL || distance(light.position, s.position) <= light.radius {
                    let c = shade_shadowed(light, s.position, s.normal, v, m.albedo, m.roughness, m.metallic, m.specular);
                    diffuse += c.diffuse;
                    specular += c.specular;
                }
            }
        }
    }
    textureStore(diffuse_out, id.xy, vec4<f32>(diffuse, 0.0));
    textureStore(specular_out, id.xy, vec4<f32>(specular, 0.0));
}
