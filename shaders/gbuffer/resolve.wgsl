// #import gbuffer/gbuffer.wgsl
// #import gbuffer/meshes.wgsl
// The visibility buffer resolved into the G-buffer layout (Burns & Hunt 2013): per pixel, the
// triangle its id names is fetched again, its attributes are interpolated at the pixel centre
// with perspective-correct barycentrics and their derivatives taken analytically at the
// neighbour of the 2 × 2 quad (as `dpdxFine`/`dpdyFine` and `gbuffer::cpu` take them), and
// the material is evaluated as `fs_main` evaluates it.
//
// Pixels are classified once per frame, by 8 × 8 tile: `classify_count` counts the tiles each
// material slot (a material some mesh draws, `Mesh::slot`) appears in and writes the cleared
// texels where no triangle is, `classify_scan` places each slot's tile list and sizes its
// indirect dispatch, `classify_write` fills the lists. Then one dispatch per material (its
// bind group is group 1, as in the G-buffer pass) covers the tiles of its list alone.

struct Resolve {
    // The material slot this dispatch resolves.
    slot: u32,
    // How many slots there are.
    slots: u32,
    // Tiles across the image.
    tiles_x: u32,
    _pad: u32,
}

// (depth bits << 32) | id per pixel, as two words: id, depth bits.
@group(0) @binding(2) var<storage, read> visibility: array<vec2<u32>>;
@group(0) @binding(3) var<uniform> resolve: Resolve;
@group(0) @binding(4) var<storage, read> positions: array<f32>;
// `gbuffer::gpu::GpuAttributes`: normal (3), uv0 (2), uv1 (2), tangent (4), colour (4).
@group(0) @binding(5) var<storage, read> attributes: array<f32>;
@group(0) @binding(6) var<storage, read> indices: array<u32>;
@group(0) @binding(7) var linear_depth_out: texture_storage_2d<r32float, write>;
@group(0) @binding(8) var normal_out: texture_storage_2d<r32uint, write>;
@group(0) @binding(9) var albedo_out: texture_storage_2d<rgba8unorm, write>;
@group(0) @binding(10) var material_out: texture_storage_2d<r32uint, write>;
@group(0) @binding(11) var emission_out: texture_storage_2d<rgba16float, write>;
// Per slot three words: the tiles it appears in (counted), the tiles listed so far (after
// `classify_write`: its list's length), the first entry of its list in `tiles`.
@group(0) @binding(12) var<storage, read_write> classes: array<atomic<u32>>;
// The tiles (x + y · tiles_x) of each slot's list.
@group(0) @binding(13) var<storage, read_write> tiles: array<u32>;
// Each slot's dispatch size (three words), bound to `classify_scan` alone (a buffer read as
// dispatch sizes cannot be bound for writing there too; group 1 is the material's elsewhere,
// whose bindings end at 10).
@group(1) @binding(11) var<storage, read_write> dispatch: array<u32>;

const NO_TRIANGLE: u32 = 0xFFFFFFFFu;
const NO_SLOT: u32 = 0xFFFFFFFFu;
const TILE: u32 = 8u;
// Workgroups across a slot's dispatch (tile k of its list is workgroup (k % MAX_X, k / MAX_X)).
const MAX_X: u32 = 32768u;
const ATTRIBUTE_FLOATS: u32 = 15u;

fn world_position(v: u32) -> vec3<f32> {
    return vec3(positions[3u * v], positions[3u * v + 1u], positions[3u * v + 2u]);
}

fn vertex_attribute(v: u32, k: u32) -> f32 {
    return attributes[ATTRIBUTE_FLOATS * v + k];
}

// Perspective-correct barycentrics of the triangle with clip positions `clip` at the image
// point c (pixels, y down): the homogeneous 2D edge functions, valid whatever the signs of w.
fn barycentrics(clip: array<vec4<f32>, 3>, c: vec2<f32>) -> vec3<f32> {
    let size = frame.viewport.xy;
    let p = vec3(c.x / size.x * 2.0 - 1.0, 1.0 - c.y / size.y * 2.0, 1.0);
    let r0 = clip[0].xyw;
    let r1 = clip[1].xyw;
    let r2 = clip[2].xyw;
    let e = vec3(dot(cross(r1, r2), p), dot(cross(r2, r0), p), dot(cross(r0, r1), p));
    return e / (e.x + e.y + e.z);
}

// Attributes `first` to `first + 3` at barycentrics l.
fn interpolate(v: vec3<u32>, l: vec3<f32>, first: u32) -> vec4<f32> {
    var a = vec4(0.0);
    for (var k = 0u; k < 4u; k++) {
        a[k] = l.x * vertex_attribute(v.x, first + k) + l.y * vertex_attribute(v.y, first + k) + l.z * vertex_attribute(v.z, first + k);
    }
    return a;
}

fn store(p: vec2<u32>, out: GBufferOut) {
    textureStore(linear_depth_out, p, vec4(out.linear_depth, 0.0, 0.0, 0.0));
    textureStore(normal_out, p, vec4(out.normal, 0u, 0u, 0u));
    textureStore(albedo_out, p, out.albedo);
    textureStore(material_out, p, vec4(out.material, 0u, 0u, 0u));
    textureStore(emission_out, p, out.emission);
}

// The texels of a pixel no triangle covers.
fn store_cleared(p: vec2<u32>) {
    var out: GBufferOut;
    out.linear_depth = 0.0;
    out.normal = 0u;
    out.albedo = vec4(0.0);
    out.material = NO_MATERIAL_WORD;
    out.emission = vec4(0.0);
    store(p, out);
}

// The material slot of the pixel at p (NO_SLOT outside the image or where no triangle is).
fn pixel_slot(p: vec2<u32>) -> u32 {
    let size = vec2<u32>(frame.viewport.xy);
    if any(p >= size) {
        return NO_SLOT;
    }
    let id = visibility[p.y * size.x + p.x].x;
    if id == NO_TRIANGLE {
        return NO_SLOT;
    }
    return meshes[mesh_of(id)].slot;
}

var<workgroup> tile_slots: array<u32, 64>;

// Whether `slot` (of invocation `lane` of the tile's workgroup) is a slot and no invocation
// before `lane` has it: each slot of the tile is counted once. Every invocation calls it.
fn first_in_tile(lane: u32, slot: u32) -> bool {
    tile_slots[lane] = slot;
    workgroupBarrier();
    if slot == NO_SLOT {
        return false;
    }
    for (var j = 0u; j < lane; j++) {
        if tile_slots[j] == slot {
            return false;
        }
    }
    return true;
}

@compute @workgroup_size(8, 8)
fn classify_count(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(local_invocation_index) lane: u32) {
    let slot = pixel_slot(gid.xy);
    let size = vec2<u32>(frame.viewport.xy);
    if slot == NO_SLOT && all(gid.xy < size) {
        store_cleared(gid.xy);
    }
    if first_in_tile(lane, slot) {
        atomicAdd(&classes[3u * slot], 1u);
    }
}

// Places the slots' lists one after the other and sizes their dispatches; leaves the counts
// at zero for the next frame.
@compute @workgroup_size(1)
fn classify_scan() {
    var first = 0u;
    for (var s = 0u; s < resolve.slots; s++) {
        let n = atomicExchange(&classes[3u * s], 0u);
        atomicStore(&classes[3u * s + 1u], 0u);
        atomicStore(&classes[3u * s + 2u], first);
        dispatch[3u * s] = min(n, MAX_X);
        dispatch[3u * s + 1u] = (n + MAX_X - 1u) / MAX_X;
        dispatch[3u * s + 2u] = 1u;
        first += n;
    }
}

@compute @workgroup_size(8, 8)
fn classify_write(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(workgroup_id) group: vec3<u32>, @builtin(local_invocation_index) lane: u32) {
    let slot = pixel_slot(gid.xy);
    if first_in_tile(lane, slot) {
        let k = atomicAdd(&classes[3u * slot + 1u], 1u);
        tiles[atomicLoad(&classes[3u * slot + 2u]) + k] = group.x + group.y * resolve.tiles_x;
    }
}

// A pixel's surface: its attributes at the pixel centre and its view depth.
struct ResolvedSurface {
    at: SurfaceAttributes,
    view_depth: f32,
};

// The surface triangle `id` (of `mesh`) shows at `pixel`.
fn resolve_surface(mesh: Mesh, id: u32, pixel: vec2<u32>) -> ResolvedSurface {
    let t = id - mesh.first_id;
    var v: vec3<u32>;
    var clip: array<vec4<f32>, 3>;
    var world: array<vec3<f32>, 3>;
    for (var k = 0u; k < 3u; k++) {
        v[k] = mesh.base_vertex + indices[mesh.first_index + 3u * t + k];
        world[k] = world_position(v[k]);
        clip[k] = frame.view_proj * vec4(world[k], 1.0);
    }
    let c = vec2<f32>(pixel) + 0.5;
    let l = barycentrics(clip, c);
    let view_depth = l.x * clip[0].w + l.y * clip[1].w + l.z * clip[2].w;
    // The derivatives over the texture footprint, towards the quad's other pixel.
    let footprint = max(frame.sampling.z, 1.0);
    let step = vec2(select(-1.0, 1.0, pixel.x % 2u == 0u), select(-1.0, 1.0, pixel.y % 2u == 0u));
    let uv = interpolate(v, l, 3u);
    let uv_dx = (interpolate(v, barycentrics(clip, c + vec2(step.x, 0.0)), 3u) - uv) * step.x * footprint;
    let uv_dy = (interpolate(v, barycentrics(clip, c + vec2(0.0, step.y)), 3u) - uv) * step.y * footprint;
    // Shaded from the side of the triangle's plane the camera sees.
    var geometric = cross(world[1] - world[0], world[2] - world[0]);
    if dot(geometric, frame.eye.xyz - world[0]) < 0.0 {
        geometric = -geometric;
    }
    let normal = vec3(
        l.x * vertex_attribute(v.x, 0u) + l.y * vertex_attribute(v.y, 0u) + l.z * vertex_attribute(v.z, 0u),
        l.x * vertex_attribute(v.x, 1u) + l.y * vertex_attribute(v.y, 1u) + l.z * vertex_attribute(v.z, 1u),
        l.x * vertex_attribute(v.x, 2u) + l.y * vertex_attribute(v.y, 2u) + l.z * vertex_attribute(v.z, 2u),
    );
    let facing = facing_geometric(normal, geometric);
    return ResolvedSurface(SurfaceAttributes(uv, uv_dx, uv_dy, facing.normal, facing.back_face, interpolate(v, l, 7u), interpolate(v, l, 11u)), view_depth);
}

@compute @workgroup_size(8, 8)
fn resolve_material(@builtin(workgroup_id) group: vec3<u32>, @builtin(local_invocation_id) local: vec3<u32>) {
    let entry = group.x + group.y * MAX_X;
    if entry >= atomicLoad(&classes[3u * resolve.slot + 1u]) {
        return;
    }
    let tile = tiles[atomicLoad(&classes[3u * resolve.slot + 2u]) + entry];
    let pixel = vec2(tile % resolve.tiles_x, tile / resolve.tiles_x) * TILE + local.xy;
    let size = vec2<u32>(frame.viewport.xy);
    if any(pixel >= size) {
        return;
    }
    let id = visibility[pixel.y * size.x + pixel.x].x;
    if id == NO_TRIANGLE {
        return;
    }
    let mesh = meshes[mesh_of(id)];
    if mesh.slot != resolve.slot {
        return;
    }
    let surface = resolve_surface(mesh, id, pixel);
    store(pixel, gbuffer_texels(evaluate_material(surface.at), surface.view_depth));
}

const NO_MATERIAL_WORD: u32 = 0xFFFFFFFFu;

// The hardware depth target from the visibility buffer: a viewport-covering triangle whose
// fragments write the z/w of the visibility buffer's upper word (depth compare `Always`), and
// are discarded where no triangle is (the target stays cleared to 1).
@vertex
fn vs_depth_fullscreen(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let corner = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4<f32>(corner * 2.0 - 1.0, 0.0, 1.0);
}

@fragment
fn fs_depth(@builtin(position) pixel: vec4<f32>) -> @builtin(frag_depth) f32 {
    let v = visibility[u32(pixel.y) * u32(frame.viewport.x) + u32(pixel.x)];
    if v.x == NO_TRIANGLE {
        discard;
    }
    return bitcast<f32>(v.y);
}
