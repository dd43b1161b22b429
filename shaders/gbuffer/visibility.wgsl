// A visibility buffer written by a compute rasteriser (Burns & Hunt 2013): per pixel the
// nearest triangle's depth and id packed in 64 bits, (depth bits << 32) | id, merged with
// `atomicMin` — a smaller depth wins and, at equal depths, the smaller id (the first
// submitted), which is the CPU rasteriser's depth test `Less` in submission order. The twin of
// `gbuffer::cpu::rasterize`'s coverage and depth: the same clip planes (near, far, a guard band
// of 4w), snapping to 1/256 pixel, integer edge functions with the top-left rule, depth
// interpolated from the unsnapped positions, back faces of one-sided meshes culled.
//
// The split rule: `raster_small` gives each triangle one invocation, which covers the pixels
// of its bounding box when the box has at most SMALL_PIXELS pixels and no vertex lies outside a
// clip plane; every other triangle is appended to `deferred`, and `raster_large` gives each
// deferred triangle a workgroup (an indirect dispatch sized by `prepare_large`), which clips it
// into a fan (one invocation) and covers each fan triangle's box with all its invocations.

struct Raster {
    view_proj: mat4x4<f32>,
    // The image's width and height.
    size: vec2<u32>,
    // Id of the mesh's first triangle, its triangle count, its first vertex and first index.
    first_id: u32,
    triangle_count: u32,
    base_vertex: u32,
    first_index: u32,
    // 1 where the mesh's material is one-sided: back faces are culled.
    cull_back: u32,
    _pad: u32,
}

@group(0) @binding(0) var<uniform> raster: Raster;
// The mesh's positions (x, y, z per vertex) and indices.
@group(0) @binding(1) var<storage, read> positions: array<f32>;
@group(0) @binding(2) var<storage, read> indices: array<u32>;
@group(0) @binding(3) var<storage, read_write> visibility: array<atomic<u64>>;
// [0]: how many triangles `raster_small` deferred; then their indices within the mesh.
@group(0) @binding(4) var<storage, read_write> deferred: array<atomic<u32>>;
// `raster_large`'s indirect dispatch size, written by `prepare_large`.
@group(0) @binding(5) var<storage, read_write> large_dispatch: array<u32, 3>;

const SUBPIXEL: i64 = 256li;
const GUARD_BAND: f32 = 4.0;
// The largest bounding box (pixels) one invocation covers.
const SMALL_PIXELS: i32 = 64;
const WORKGROUP: u32 = 64u;
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
struct Setup {
    // Snapped framebuffer positions in 1/SUBPIXEL pixels, y down.
    x: vec3<i64>,
    y: vec3<i64>,
    // 1 where the edge opposite vertex i is a top or left edge.
    top_left: vec3<i64>,
    // Unsnapped framebuffer positions (pixels) and NDC depths.
    screen: array<vec2<f32>, 3>,
    z: vec3<f32>,
    // Inclusive pixel bounds clamped to the image: x0, y0, x1, y1.
    bounds: vec4<i32>,
}

// Clip-space position of vertex k (0, 1, 2) of the mesh's triangle t.
fn clip_position(t: u32, k: u32) -> vec4<f32> {
    let v = 3u * (raster.base_vertex + indices[raster.first_index + 3u * t + k]);
    return raster.view_proj * vec4(positions[v], positions[v + 1u], positions[v + 2u], 1.0);
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
fn floor_div(a: i64, b: i64) -> i64 {
    let q = a / b;
    return select(q, q - 1li, a % b != 0li && a < 0li);
}

fn edge(ax: i64, ay: i64, bx: i64, by: i64, px: i64, py: i64) -> i64 {
    return (bx - ax) * (py - ay) - (by - ay) * (px - ax);
}

fn is_top_left(ax: i64, ay: i64, bx: i64, by: i64) -> i64 {
    let dx = bx - ax;
    let dy = by - ay;
    return select(0li, 1li, dy < 0li || (dy == 0li && dx > 0li));
}

fn snap(s: f32) -> i64 {
    // Rust's `f32::round`: halves away from zero (WGSL's `round` takes them to even).
    let v = s * 256.0;
    return i64(sign(v) * floor(abs(v) + 0.5));
}

// `gbuffer::cpu::setup` of clip-space vertices a, b, c: false where the triangle has no area,
// faces away from the camera on a one-sided mesh, or covers no pixel centre's box.
fn setup(a: vec4<f32>, b: vec4<f32>, c: vec4<f32>, out: ptr<function, Setup>) -> bool {
    let size = vec2<f32>(raster.size);
    var clip = array(a, b, c);
    var fx: vec3<i64>;
    var fy: vec3<i64>;
    var screen: array<vec2<f32>, 3>;
    for (var i = 0u; i < 3u; i++) {
        let ndc = clip[i].xyz / clip[i].w;
        screen[i] = vec2(ndc.x * (size.x * 0.5) + size.x * 0.5, -ndc.y * (size.y * 0.5) + size.y * 0.5);
        fx[i] = snap(screen[i].x);
        fy[i] = snap(screen[i].y);
    }
    let area = edge(fx[0], fy[0], fx[1], fy[1], fx[2], fy[2]);
    // Counter-clockwise on screen (y down: a negative area) is the winding's front.
    if area == 0li || (raster.cull_back != 0u && area > 0li) {
        return false;
    }
    var order = vec3(0u, 1u, 2u);
    if area < 0li {
        order = vec3(0u, 2u, 1u);
    }
    var s: Setup;
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
    let half = SUBPIXEL / 2li;
    let lo = vec2(min(s.x[0], min(s.x[1], s.x[2])), min(s.y[0], min(s.y[1], s.y[2])));
    let hi = vec2(max(s.x[0], max(s.x[1], s.x[2])), max(s.y[0], max(s.y[1], s.y[2])));
    let x0 = max(floor_div(lo.x - half + SUBPIXEL - 1li, SUBPIXEL), 0li);
    let y0 = max(floor_div(lo.y - half + SUBPIXEL - 1li, SUBPIXEL), 0li);
    let x1 = min(floor_div(hi.x - half, SUBPIXEL), i64(raster.size.x) - 1li);
    let y1 = min(floor_div(hi.y - half, SUBPIXEL), i64(raster.size.y) - 1li);
    if x0 > x1 || y0 > y1 {
        return false;
    }
    s.bounds = vec4(i32(x0), i32(y0), i32(x1), i32(y1));
    *out = s;
    return true;
}

fn edge_f(a: vec2<f32>, b: vec2<f32>, p: vec2<f32>) -> f32 {
    return (b.x - a.x) * (p.y - a.y) - (b.y - a.y) * (p.x - a.x);
}

// Pixel (px, py) against triangle `id`: covered (top-left rule) and in front of what the
// visibility buffer holds, it is merged in.
fn cover(s: Setup, id: u32, px: i32, py: i32) {
    let x = i64(px) * SUBPIXEL + SUBPIXEL / 2li;
    let y = i64(py) * SUBPIXEL + SUBPIXEL / 2li;
    let e0 = edge(s.x[1], s.y[1], s.x[2], s.y[2], x, y);
    let e1 = edge(s.x[2], s.y[2], s.x[0], s.y[0], x, y);
    let e2 = edge(s.x[0], s.y[0], s.x[1], s.y[1], x, y);
    if e0 + s.top_left[0] <= 0li || e1 + s.top_left[1] <= 0li || e2 + s.top_left[2] <= 0li {
        return;
    }
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
    let packed = (u64(bitcast<u32>(z)) << 32u) | u64(id);
    atomicMin(&visibility[u32(py) * raster.size.x + u32(px)], packed);
}

fn pixels(b: vec4<i32>) -> i32 {
    return (b.z - b.x + 1) * (b.w - b.y + 1);
}

fn defer(t: u32) {
    let at = atomicAdd(&deferred[0], 1u) + 1u;
    if at < arrayLength(&deferred) {
        atomicStore(&deferred[at], t);
    }
}

@compute @workgroup_size(64)
fn raster_small(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let t = gid.x + gid.y * groups.x * WORKGROUP;
    if t >= raster.triangle_count {
        return;
    }
    let a = clip_position(t, 0u);
    let b = clip_position(t, 1u);
    let c = clip_position(t, 2u);
    if !(inside_planes(a) && inside_planes(b) && inside_planes(c)) {
        defer(t);
        return;
    }
    var s: Setup;
    if !setup(a, b, c, &s) {
        return;
    }
    if pixels(s.bounds) > SMALL_PIXELS {
        defer(t);
        return;
    }
    let id = raster.first_id + t;
    for (var py = s.bounds.y; py <= s.bounds.w; py++) {
        for (var px = s.bounds.x; px <= s.bounds.z; px++) {
            cover(s, id, px, py);
        }
    }
}

// `raster_large`'s fan: the clipped polygon's setup triangles.
var<workgroup> fan: array<Setup, 7>;
var<workgroup> fan_count: u32;
// The deferred triangles' count and the id of the one being covered.
var<workgroup> deferred_count: u32;
var<workgroup> fan_id: u32;

// Sutherland–Hodgman clipping of a triangle against the six planes, as `gbuffer::cpu`
// (`clip_polygon`, `ClipVertex::lerp`), into `polygon`; returns its vertex count.
fn clip_triangle(a: vec4<f32>, b: vec4<f32>, c: vec4<f32>, polygon: ptr<function, array<vec4<f32>, 9>>) -> u32 {
    var poly = array<vec4<f32>, 9>(a, b, c, vec4(0.0), vec4(0.0), vec4(0.0), vec4(0.0), vec4(0.0), vec4(0.0));
    var n = 3u;
    if inside_planes(a) && inside_planes(b) && inside_planes(c) {
        *polygon = poly;
        return n;
    }
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

@compute @workgroup_size(64)
fn raster_large(@builtin(workgroup_id) group: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>, @builtin(local_invocation_index) lane: u32) {
    if lane == 0u {
        deferred_count = min(atomicLoad(&deferred[0]), arrayLength(&deferred) - 1u);
    }
    let count = workgroupUniformLoad(&deferred_count);
    for (var d = group.x; d < count; d += groups.x) {
        if lane == 0u {
            let t = atomicLoad(&deferred[d + 1u]);
            var polygon: array<vec4<f32>, 9>;
            let n = clip_triangle(
                clip_position(t, 0u),
                clip_position(t, 1u),
                clip_position(t, 2u),
                &polygon,
            );
            var m = 0u;
            for (var k = 1u; k + 1u < n; k++) {
                var s: Setup;
                if setup(polygon[0], polygon[k], polygon[k + 1u], &s) {
                    fan[m] = s;
                    m++;
                }
            }
            fan_count = m;
            fan_id = raster.first_id + t;
        }
        let m = workgroupUniformLoad(&fan_count);
        for (var f = 0u; f < m; f++) {
            let s = fan[f];
            let width = s.bounds.z - s.bounds.x + 1;
            for (var i = i32(lane); i < pixels(s.bounds); i += i32(WORKGROUP)) {
                cover(s, fan_id, s.bounds.x + i % width, s.bounds.y + i / width);
            }
        }
        workgroupBarrier();
    }
}

// Every pixel to "nothing": the largest depth and id.
@compute @workgroup_size(64)
fn clear(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = gid.x + gid.y * groups.x * WORKGROUP;
    if i < raster.size.x * raster.size.y {
        atomicStore(&visibility[i], 0xFFFFFFFFFFFFFFFFlu);
    }
}

// One workgroup per deferred triangle, up to MAX_LARGE_GROUPS (each loops over the rest).
const MAX_LARGE_GROUPS: u32 = 4096u;

@compute @workgroup_size(1)
fn prepare_large() {
    let count = min(atomicLoad(&deferred[0]), arrayLength(&deferred) - 1u);
    large_dispatch[0] = min(count, MAX_LARGE_GROUPS);
    large_dispatch[1] = 1u;
    large_dispatch[2] = 1u;
}

// No triangle deferred yet (before each mesh's `raster_small`).
@compute @workgroup_size(1)
fn reset() {
    atomicStore(&deferred[0], 0u);
}
