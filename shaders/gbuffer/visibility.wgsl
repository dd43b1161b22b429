// #import gbuffer/frame.wgsl
// #import gbuffer/meshes.wgsl
// #import gbuffer/visibility_word.wgsl
// A visibility buffer written by a compute rasteriser (Burns & Hunt 2013): per pixel the
// nearest triangle's depth and id packed in 64 bits, (depth bits << 32) | id, merged as one
// `atomicMin` (or two 32-bit passes, `visibility_word.wgsl`) — a smaller depth wins and, at
// equal depths, the smaller id (the first submitted), which is the CPU rasteriser's depth test
// `Less` in submission order. The twin of
// `gbuffer::cpu::rasterize`'s coverage and depth: the same clip planes (near, far, a guard band
// of 4w), snapping to 1/256 pixel, integer edge functions with the top-left rule, depth
// interpolated from the unsnapped positions, back faces of one-sided meshes culled.
//
// Every mesh of the scene in one set of dispatches (`meshes`, in id order). The split rule:
// `raster_small` gives each triangle one invocation, which covers the pixels of its bounding
// box when the box has at most SMALL_PIXELS pixels and no vertex lies outside a clip plane;
// every other triangle is appended to `deferred`. `setup_large` gives each deferred triangle
// an invocation, which clips it into a fan, stores each fan triangle's setup and appends one
// work item per TILE × TILE block of its box; `raster_tiles` gives each work item a workgroup,
// whose invocations cover the block together. `prepare` sizes the indirect dispatches.

struct Raster {
    // How many triangle ids the meshes span.
    triangle_count: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}

// The G-buffer pass's frame (its `view_proj` and `viewport`).
@group(0) @binding(0) var<uniform> frame: Frame;
// The scene's positions (x, y, z per vertex) and indices.
@group(0) @binding(2) var<storage, read> positions: array<f32>;
@group(0) @binding(3) var<storage, read> indices: array<u32>;
// Deferred triangles, fan setups and work items appended, and how many did not fit.
@group(0) @binding(5) var<storage, read_write> counts: array<atomic<u32>, 4>;
// The deferred triangles' ids.
@group(0) @binding(6) var<storage, read_write> deferred: array<u32>;
@group(0) @binding(7) var<storage, read_write> setups: array<LargeSetup>;
// (setup, block within its box) per work item.
@group(0) @binding(8) var<storage, read_write> work: array<vec2<u32>>;
@group(0) @binding(9) var<uniform> raster: Raster;
// `setup_large`'s and `raster_tiles`' indirect dispatch sizes (three words each), bound to
// `prepare` alone (a buffer read as dispatch sizes cannot be bound for writing there too).
@group(1) @binding(0) var<storage, read_write> dispatch: array<u32, 6>;

const DEFERRED: u32 = 0u;
const SETUPS: u32 = 1u;
const WORK: u32 = 2u;
const OVERFLOW: u32 = 3u;

const SUBPIXEL: i32 = 256;
// The snapped extent (1/SUBPIXEL pixels) up to which a triangle's edge functions fit in 32 bits:
// two products of at most 2^14 · 2^14 each. Larger triangles take the exact 64-bit sign.
const COMPACT_EXTENT: i32 = 16384;

fn image_size() -> vec2<u32> {
    return vec2<u32>(frame.viewport.xy);
}
const GUARD_BAND: f32 = 4.0;
// The largest bounding box (pixels) one invocation covers.
const SMALL_PIXELS: i32 = 64;
const WORKGROUP: u32 = 64u;
// The side of the blocks `raster_tiles` covers a workgroup each.
const TILE: i32 = 32;
const MAX_GROUPS_X: u32 = 32768u;
// A triangle clipped by six planes has at most nine vertices, so seven fan triangles.
const MAX_POLYGON: u32 = 9u;

// The clip planes, as `gbuffer::cpu` orders them: dot(plane, clip) ≥ 0 inside.
const PLANES = array(
    vec4(0.0, 0.0, 1.0, 0.0),
    vec4(0.0, 0.0, -1.0, 1.0),
    vec4(1.0, 0.0, 0.0, GUARD_BAND),
    vec4(-1.0, 0.0, 0.0, GUARD_BAND),
    vec4(0.0, 1.0, 0.0, GUARD_BAND),
    vec4(0.0, -1.0, 0.0, GUARD_BAND),
);

// A triangle ready for scan conversion (`gbuffer::cpu::SetupTriangle`, positively oriented).
// Snapped positions stay within 2^24 (the 4w guard band of an image of at most 16 384 pixels
// a side), so they and their differences fit 32 bits; their products need up to 51.
struct Setup {
    // Snapped framebuffer positions in 1/SUBPIXEL pixels, y down.
    x: vec3<i32>,
    y: vec3<i32>,
    // 1 where the edge opposite vertex i is a top or left edge.
    top_left: vec3<i32>,
    // Unsnapped framebuffer positions (pixels) and NDC depths.
    screen: array<vec2<f32>, 3>,
    z: vec3<f32>,
    // Inclusive pixel bounds clamped to the image: x0, y0, x1, y1.
    bounds: vec4<i32>,
    // 1 where the snapped extent is at most COMPACT_EXTENT both ways.
    compact: u32,
}

// Clip-space position of vertex k (0, 1, 2) of triangle t of `mesh`.
fn clip_position(mesh: Mesh, t: u32, k: u32) -> vec4<f32> {
    let v = 3u * (mesh.base_vertex + indices[mesh.first_index + 3u * t + k]);
    return frame.view_proj * vec4(positions[v], positions[v + 1u], positions[v + 2u], 1.0);
}

fn inside_planes(c: vec4<f32>) -> bool {
    for (var k = 0u; k < 6u; k++) {
        if dot(PLANES[k], c) < 0.0 {
            return false;
        }
    }
    return true;
}

// Floor division (`i64::div_euclid` for a positive divisor).
fn floor_div(a: i32, b: i32) -> i32 {
    let q = a / b;
    return select(q, q - 1, a % b != 0 && a < 0);
}

// The product of a and b as a 64-bit two's complement (low word, high word), from 16-bit
// halves: exact, with 32-bit integers only.
fn wide_product(a: i32, b: i32) -> vec2<u32> {
    let ua = u32(abs(a));
    let ub = u32(abs(b));
    let low = (ua & 0xFFFFu) * (ub & 0xFFFFu);
    let cross0 = (ua & 0xFFFFu) * (ub >> 16u);
    let cross1 = (ua >> 16u) * (ub & 0xFFFFu);
    let middle = (low >> 16u) + (cross0 & 0xFFFFu) + (cross1 & 0xFFFFu);
    let lo = (low & 0xFFFFu) | (middle << 16u);
    let hi = (ua >> 16u) * (ub >> 16u) + (cross0 >> 16u) + (cross1 >> 16u) + (middle >> 16u);
    if (a < 0) == (b < 0) {
        return vec2(lo, hi);
    }
    // −(hi, lo): the complement plus one, carried into the high word.
    let neg_lo = ~lo + 1u;
    return vec2(neg_lo, ~hi + select(0u, 1u, neg_lo == 0u));
}

// a · b − c · d as a 64-bit two's complement (low word, high word), exact for any 32-bit
// operands.
fn wide_difference(a: i32, b: i32, c: i32, d: i32) -> vec2<u32> {
    let p = wide_product(a, b);
    let q = wide_product(c, d);
    return vec2(p.x - q.x, p.y - q.y - select(0u, 1u, p.x < q.x));
}

// The sum of two 64-bit two's complements (low word, high word).
fn wide_add(p: vec2<u32>, q: vec2<u32>) -> vec2<u32> {
    let lo = p.x + q.x;
    return vec2(lo, p.y + q.y + select(0u, 1u, lo < p.x));
}

// The sign (−1, 0, 1) of a 64-bit two's complement (low word, high word).
fn wide_sign_of(v: vec2<u32>) -> i32 {
    if bitcast<i32>(v.y) < 0 {
        return -1;
    }
    return select(1, 0, v.y == 0u && v.x == 0u);
}

// The sign (−1, 0, 1) of a · b − c · d, exact for any 32-bit operands' products.
fn wide_sign(a: i32, b: i32, c: i32, d: i32) -> i32 {
    return wide_sign_of(wide_difference(a, b, c, d));
}

// The sign of the edge function of a→b at p, (b − a) × (p − a): in 32 bits for a compact
// triangle, else exactly in 64.
fn edge_sign(ax: i32, ay: i32, bx: i32, by: i32, px: i32, py: i32, compact: bool) -> i32 {
    if compact {
        return sign((bx - ax) * (py - ay) - (by - ay) * (px - ax));
    }
    return wide_sign(bx - ax, py - ay, by - ay, px - ax);
}

fn is_top_left(ax: i32, ay: i32, bx: i32, by: i32) -> i32 {
    let dx = bx - ax;
    let dy = by - ay;
    return select(0, 1, dy < 0 || (dy == 0 && dx > 0));
}

fn snap(s: f32) -> i32 {
    // Rust's `f32::round`: halves away from zero (WGSL's `round` takes them to even).
    let v = s * 256.0;
    return i32(sign(v) * floor(abs(v) + 0.5));
}

// `gbuffer::cpu::setup` of clip-space vertices a, b, c: false where the triangle has no area,
// faces away from the camera on a one-sided mesh, or covers no pixel centre's box.
fn setup(a: vec4<f32>, b: vec4<f32>, c: vec4<f32>, cull_back: bool, out: ptr<function, Setup>) -> bool {
    let size = vec2<f32>(image_size());
    var clip = array(a, b, c);
    var fx: vec3<i32>;
    var fy: vec3<i32>;
    var screen: array<vec2<f32>, 3>;
    for (var i = 0u; i < 3u; i++) {
        let ndc = clip[i].xyz / clip[i].w;
        screen[i] = vec2(ndc.x * (size.x * 0.5) + size.x * 0.5, -ndc.y * (size.y * 0.5) + size.y * 0.5);
        fx[i] = snap(screen[i].x);
        fy[i] = snap(screen[i].y);
    }
    let extent = max(max(fx[0], max(fx[1], fx[2])) - min(fx[0], min(fx[1], fx[2])), max(fy[0], max(fy[1], fy[2])) - min(fy[0], min(fy[1], fy[2])));
    let compact = extent <= COMPACT_EXTENT;
    let area = edge_sign(fx[0], fy[0], fx[1], fy[1], fx[2], fy[2], compact);
    // Counter-clockwise on screen (y down: a negative area) is the winding's front.
    if area == 0 || (cull_back && area > 0) {
        return false;
    }
    var order = vec3(0u, 1u, 2u);
    if area < 0 {
        order = vec3(0u, 2u, 1u);
    }
    var s: Setup;
    s.compact = select(0u, 1u, compact);
    for (var i = 0u; i < 3u; i++) {
        s.x[i] = fx[order[i]];
        s.y[i] = fy[order[i]];
        s.screen[i] = screen[order[i]];
        s.z[i] = clip[order[i]].z / clip[order[i]].w;
    }
    for (var i = 0u; i < 3u; i++) {
        let j = (i + 1u) % 3u;
        let k = (i + 2u) % 3u;
        s.top_left[i] = is_top_left(s.x[j], s.y[j], s.x[k], s.y[k]);
    }
    let half = SUBPIXEL / 2;
    let lo = vec2(min(s.x[0], min(s.x[1], s.x[2])), min(s.y[0], min(s.y[1], s.y[2])));
    let hi = vec2(max(s.x[0], max(s.x[1], s.x[2])), max(s.y[0], max(s.y[1], s.y[2])));
    let x0 = max(floor_div(lo.x - half + SUBPIXEL - 1, SUBPIXEL), 0);
    let y0 = max(floor_div(lo.y - half + SUBPIXEL - 1, SUBPIXEL), 0);
    let x1 = min(floor_div(hi.x - half, SUBPIXEL), i32(image_size().x) - 1);
    let y1 = min(floor_div(hi.y - half, SUBPIXEL), i32(image_size().y) - 1);
    if x0 > x1 || y0 > y1 {
        return false;
    }
    s.bounds = vec4(x0, y0, x1, y1);
    *out = s;
    return true;
}

fn edge_f(a: vec2<f32>, b: vec2<f32>, p: vec2<f32>) -> f32 {
    return (b.x - a.x) * (p.y - a.y) - (b.y - a.y) * (p.x - a.x);
}

// Pixel (px, py) against triangle `id`: covered (top-left rule) and in front of what the
// visibility buffer holds, it is merged in.
fn cover(s: Setup, id: u32, px: i32, py: i32) {
    let x = px * SUBPIXEL + SUBPIXEL / 2;
    let y = py * SUBPIXEL + SUBPIXEL / 2;
    let compact = s.compact != 0u;
    let e = vec3(
        edge_sign(s.x[1], s.y[1], s.x[2], s.y[2], x, y, compact),
        edge_sign(s.x[2], s.y[2], s.x[0], s.y[0], x, y, compact),
        edge_sign(s.x[0], s.y[0], s.x[1], s.y[1], x, y, compact),
    );
    if inside(s, e) {
        merge_covered(s, id, px, py);
    }
}

// Inside each edge, given the edge functions' signs `e`: positive, or zero on a top or left
// edge.
fn inside(s: Setup, e: vec3<i32>) -> bool {
    return all(e + s.top_left > vec3(0));
}

// Covered pixel (px, py) of triangle `id`: merged in where its depth lies in [0, 1).
fn merge_covered(s: Setup, id: u32, px: i32, py: i32) {
    // Depth from barycentrics of the unsnapped positions, as the CPU's plane equations.
    let c = vec2(f32(px) + 0.5, f32(py) + 0.5);
    let area = edge_f(s.screen[0], s.screen[1], s.screen[2]);
    let l = vec3(
        edge_f(s.screen[1], s.screen[2], c),
        edge_f(s.screen[2], s.screen[0], c),
        edge_f(s.screen[0], s.screen[1], c),
    ) / area;
    let z = l[0] * s.z[0] + l[1] * s.z[1] + l[2] * s.z[2];
    if !(z >= 0.0 && z < 1.0) {
        return;
    }
    merge(u32(py) * image_size().x + u32(px), z, id);
}

fn pixels(b: vec4<i32>) -> i32 {
    return (b.z - b.x + 1) * (b.w - b.y + 1);
}

// Appends to list `counter` of `capacity` entries: the slot, or none (counted as overflow).
fn append(counter: u32, capacity: u32) -> u32 {
    let at = atomicAdd(&counts[counter], 1u);
    if at >= capacity {
        atomicAdd(&counts[OVERFLOW], 1u);
    }
    return at;
}

@compute @workgroup_size(64)
fn raster_small(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let id = gid.x + gid.y * groups.x * WORKGROUP;
    if id >= raster.triangle_count {
        return;
    }
    let mesh = meshes[mesh_of(id)];
    let t = id - mesh.first_id;
    if t >= mesh.triangle_count {
        return;
    }
    let a = clip_position(mesh, t, 0u);
    let b = clip_position(mesh, t, 1u);
    let c = clip_position(mesh, t, 2u);
    if inside_planes(a) && inside_planes(b) && inside_planes(c) {
        var s: Setup;
        if !setup(a, b, c, mesh.cull_back != 0u, &s) {
            return;
        }
        if pixels(s.bounds) <= SMALL_PIXELS {
            for (var py = s.bounds.y; py <= s.bounds.w; py++) {
                for (var px = s.bounds.x; px <= s.bounds.z; px++) {
                    cover(s, id, px, py);
                }
            }
            return;
        }
    }
    // The narrow merge's id pass covers the deferred triangles from the depth pass's lists.
    if ID_PASS {
        return;
    }
    let at = append(DEFERRED, arrayLength(&deferred));
    if at < arrayLength(&deferred) {
        deferred[at] = id;
    }
}

// A fan triangle of a deferred triangle, set up, with the id it covers pixels for.
struct LargeSetup {
    s: Setup,
    id: u32,
}

// Sutherland–Hodgman clipping of a triangle against the six planes, as `gbuffer::cpu`
// (`clip_polygon`, `ClipVertex::lerp`), into `polygon`; returns its vertex count.
// A triangle inside every plane comes back as it is (what the loop would give, without it).
fn clip_triangle(a: vec4<f32>, b: vec4<f32>, c: vec4<f32>, polygon: ptr<function, array<vec4<f32>, 9>>) -> u32 {
    var poly = array<vec4<f32>, 9>(a, b, c, vec4(0.0), vec4(0.0), vec4(0.0), vec4(0.0), vec4(0.0), vec4(0.0));
    if inside_planes(a) && inside_planes(b) && inside_planes(c) {
        *polygon = poly;
        return 3u;
    }
    var n = 3u;
    for (var k = 0u; k < 6u && n >= 3u; k++) {
        var out: array<vec4<f32>, 9>;
        var m = 0u;
        for (var i = 0u; i < n; i++) {
            let p = poly[i];
            let q = poly[(i + 1u) % n];
            let dp = dot(PLANES[k], p);
            let dq = dot(PLANES[k], q);
            if dp >= 0.0 && m < MAX_POLYGON {
                out[m] = p;
                m++;
            }
            if (dp >= 0.0) != (dq >= 0.0) && m < MAX_POLYGON {
                let s = dp / (dp - dq);
                out[m] = p * (1.0 - s) + q * s;
                m++;
            }
        }
        poly = out;
        n = m;
    }
    *polygon = poly;
    return n;
}

// Blocks of TILE × TILE pixels in the box `b`: across and in all.
fn blocks(b: vec4<i32>) -> vec2<u32> {
    let across = u32((b.z - b.x) / TILE + 1);
    return vec2(across, across * u32((b.w - b.y) / TILE + 1));
}

@compute @workgroup_size(64)
fn setup_large(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let d = gid.x + gid.y * groups.x * WORKGROUP;
    if d >= min(atomicLoad(&counts[DEFERRED]), arrayLength(&deferred)) {
        return;
    }
    let id = deferred[d];
    let mesh = meshes[mesh_of(id)];
    let t = id - mesh.first_id;
    var polygon: array<vec4<f32>, 9>;
    let n = clip_triangle(clip_position(mesh, t, 0u), clip_position(mesh, t, 1u), clip_position(mesh, t, 2u), &polygon);
    for (var k = 1u; k + 1u < n; k++) {
        var s: Setup;
        if !setup(polygon[0], polygon[k], polygon[k + 1u], mesh.cull_back != 0u, &s) {
            continue;
        }
        let at = append(SETUPS, arrayLength(&setups));
        if at >= arrayLength(&setups) {
            return;
        }
        setups[at] = LargeSetup(s, id);
        let count = blocks(s.bounds).y;
        let first = atomicAdd(&counts[WORK], count);
        for (var i = 0u; i < count; i++) {
            if first + i < arrayLength(&work) {
                work[first + i] = vec2(at, i);
            } else {
                atomicAdd(&counts[OVERFLOW], 1u);
            }
        }
    }
}

// The edge functions at a block's corners that may be inside, per edge (`raster_tiles`).
var<workgroup> reaches: array<atomic<u32>, 3>;

// Edge i of a setup (opposite vertex i) at the snapped point (x, y), exactly in 64 bits.
fn wide_edge(s: Setup, i: u32, x: i32, y: i32) -> vec2<u32> {
    let j = (i + 1u) % 3u;
    let k = (i + 2u) % 3u;
    return wide_difference(s.x[k] - s.x[j], y - s.y[j], s.y[k] - s.y[j], x - s.x[j]);
}

// A block's pixels are covered by the workgroup's invocations, each walking one column two
// rows at a time with its edge functions stepped by exact 64-bit additions (the same values
// `cover` computes per pixel). Blocks some edge excludes at all four corners (the edge
// function is linear, so everywhere in between) are skipped, after twelve invocations test one
// corner of one edge each.
@compute @workgroup_size(64)
fn raster_tiles(@builtin(workgroup_id) group: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>, @builtin(local_invocation_index) lane: u32) {
    let item = group.x + group.y * groups.x;
    let valid = item < min(atomicLoad(&counts[WORK]), arrayLength(&work));
    if lane < 3u {
        atomicStore(&reaches[lane], 0u);
    }
    workgroupBarrier();
    var large: LargeSetup;
    var origin: vec2<i32>;
    var last: vec2<i32>;
    if valid {
        let w = work[item];
        large = setups[w.x];
        let b = large.s.bounds;
        let across = blocks(b).x;
        origin = vec2(b.x + i32(w.y % across) * TILE, b.y + i32(w.y / across) * TILE);
        last = min(origin + vec2(TILE - 1), b.zw);
        if lane < 12u {
            let corner = select(origin, last, vec2(lane % 2u == 1u, lane % 4u >= 2u));
            let at = corner * SUBPIXEL + SUBPIXEL / 2;
            if wide_sign_of(wide_edge(large.s, lane / 4u, at.x, at.y)) >= 0 {
                atomicOr(&reaches[lane / 4u], 1u);
            }
        }
    }
    workgroupBarrier();
    if !valid || atomicLoad(&reaches[0]) == 0u || atomicLoad(&reaches[1]) == 0u || atomicLoad(&reaches[2]) == 0u {
        return;
    }
    let rows = i32(WORKGROUP) / TILE;
    let px = origin.x + i32(lane) % TILE;
    let x = px * SUBPIXEL + SUBPIXEL / 2;
    let y = (origin.y + i32(lane) / TILE) * SUBPIXEL + SUBPIXEL / 2;
    var e = array(wide_edge(large.s, 0u, x, y), wide_edge(large.s, 1u, x, y), wide_edge(large.s, 2u, x, y));
    // Each edge's change over `rows` rows: (x_k − x_j) · rows · SUBPIXEL.
    var step: array<vec2<u32>, 3>;
    for (var i = 0u; i < 3u; i++) {
        step[i] = wide_product(large.s.x[(i + 2u) % 3u] - large.s.x[(i + 1u) % 3u], rows * SUBPIXEL);
    }
    if px > last.x {
        return;
    }
    for (var py = origin.y + i32(lane) / TILE; py <= last.y; py += rows) {
        let signs = vec3(wide_sign_of(e[0]), wide_sign_of(e[1]), wide_sign_of(e[2]));
        if inside(large.s, signs) {
            merge_covered(large.s, large.id, px, py);
        }
        for (var i = 0u; i < 3u; i++) {
            e[i] = wide_add(e[i], step[i]);
        }
    }
}

// Every pixel to "nothing" (the largest depth and id), and no list entries.
@compute @workgroup_size(64)
fn clear(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = gid.x + gid.y * groups.x * WORKGROUP;
    if i < arrayLength(&visibility) {
        clear_word(i);
    }
    if i < 4u {
        atomicStore(&counts[i], 0u);
    }
}

// The indirect dispatch sizes: `setup_large` over the deferred triangles (after
// `raster_small`), `raster_tiles` over the work items (after `setup_large`).
@compute @workgroup_size(1)
fn prepare() {
    let deferred_groups = (min(atomicLoad(&counts[DEFERRED]), arrayLength(&deferred)) + WORKGROUP - 1u) / WORKGROUP;
    set_dispatch(0u, deferred_groups);
    set_dispatch(3u, min(atomicLoad(&counts[WORK]), arrayLength(&work)));
}

// `groups` workgroups as the indirect dispatch size at `dispatch[at..at + 3]`, in rows of at
// most MAX_GROUPS_X.
fn set_dispatch(at: u32, groups: u32) {
    dispatch[at] = min(groups, MAX_GROUPS_X);
    dispatch[at + 1u] = (groups + MAX_GROUPS_X - 1u) / MAX_GROUPS_X;
    dispatch[at + 2u] = 1u;
}
