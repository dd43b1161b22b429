// Exact visibility by rays (`tiled_shading::rays`): a flattened BVH2 of the scene's
// triangles, traversed with a stack for any hit on a segment (`occluded`) or the first
// (`nearest`). Its two buffers sit where the
// light accumulation's shadow group has them (`shadows.wgsl`); another importer specialises
// `RAY_GROUP`, `RAY_NODES` and `RAY_TRIANGLES` to its own layout.

struct RayNode {
    min: vec3<f32>,
    // Triangles of a leaf; 0 for an inner node (children `first`, `first + 1`).
    count: u32,
    max: vec3<f32>,
    first: u32,
};

struct RayTriangle {
    v0: vec3<f32>,
    // The triangle's index in the mesh the BVH was built from.
    index: u32,
    e1: vec4<f32>,
    e2: vec4<f32>,
};

const RAY_STACK: u32 = 64u;

// How far a ray leaves a surface at p (`tiled_shading::rays::ray_lift`, the path tracer's rule).
fn ray_lift(p: vec3<f32>) -> f32 {
    let a = abs(p);
    return 1e-4 * (1.0 + max(max(a.x, a.y), a.z));
}

const RAY_GROUP: u32 = 1u;
const RAY_NODES: u32 = 6u;
const RAY_TRIANGLES: u32 = 7u;
@group(RAY_GROUP) @binding(RAY_NODES) var<storage, read> ray_nodes: array<RayNode>;
@group(RAY_GROUP) @binding(RAY_TRIANGLES) var<storage, read> ray_triangles: array<RayTriangle>;

// Whether the segment's parameter range [0, end] meets the node's box.
fn ray_slab(node: RayNode, origin: vec3<f32>, inv: vec3<f32>, end: f32) -> bool {
    let t0 = (node.min - origin) * inv;
    let t1 = (node.max - origin) * inv;
    let lo = min(t0, t1);
    let hi = max(t0, t1);
    let near = max(max(max(lo.x, lo.y), lo.z), 0.0);
    let far = min(min(min(hi.x, hi.y), hi.z), end);
    return near <= far;
}

// `ray_t` of a segment that misses.
const RAY_MISS: f32 = 2.0;

// Möller–Trumbore: the segment's parameter t where it meets the triangle, if 0 < t < 1; else
// RAY_MISS.
fn ray_t(tri: RayTriangle, origin: vec3<f32>, to: vec3<f32>) -> f32 {
    let p = cross(to, tri.e2.xyz);
    let det = dot(tri.e1.xyz, p);
    if abs(det) < 1e-30 {
        return RAY_MISS;
    }
    let inv_det = 1.0 / det;
    let s = origin - tri.v0.xyz;
    let u = dot(s, p) * inv_det;
    let q = cross(s, tri.e1.xyz);
    let v = dot(to, q) * inv_det;
    let t = dot(tri.e2.xyz, q) * inv_det;
    return select(RAY_MISS, t, u >= 0.0 && v >= 0.0 && u + v <= 1.0 && t > 0.0 && t < 1.0);
}

// The first triangle on a segment: its parameter t in (0, 1) and its slot in `ray_triangles`,
// or slot RAY_NONE.
struct RayHit {
    t: f32,
    slot: u32,
};

const RAY_NONE: u32 = 0xffffffffu;

// The first triangle the segment from `origin` to `origin + to` meets, or with `any` the first
// one found.
fn ray_traverse(origin: vec3<f32>, to: vec3<f32>, any: bool) -> RayHit {
    let inv = 1.0 / select(to, vec3<f32>(1e-30), to == vec3<f32>(0.0));
    var hit = RayHit(1.0, RAY_NONE);
    var stack: array<u32, RAY_STACK>;
    stack[0] = 0u;
    var top = 1u;
    while top > 0u {
        top -= 1u;
        let node = ray_nodes[stack[top]];
        if !ray_slab(node, origin, inv, hit.t) {
            continue;
        }
        if node.count == 0u {
            stack[top] = node.first;
            stack[top + 1u] = node.first + 1u;
            top += 2u;
            continue;
        }
        for (var i = node.first; i < node.first + node.count; i++) {
            let t = ray_t(ray_triangles[i], origin, to);
            if t < hit.t {
                hit = RayHit(t, i);
                if any {
                    return hit;
                }
            }
        }
    }
    return hit;
}

// Whether a triangle meets the open segment from `origin` to `origin + to`.
fn occluded(origin: vec3<f32>, to: vec3<f32>) -> bool {
    return ray_traverse(origin, to, true).slot != RAY_NONE;
}

// The first triangle the segment from `origin` to `origin + to` meets.
fn nearest(origin: vec3<f32>, to: vec3<f32>) -> RayHit {
    return ray_traverse(origin, to, false);
}
