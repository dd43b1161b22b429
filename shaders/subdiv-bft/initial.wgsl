// Initial GPU subdivision step (Holländer 2013 §2.2.2): one thread per M¹ vertex.
// `refine_m1` applies its computational entry (weights and indices over M⁰);
// `normals_m1` its normal entry (one-ring, counter-clockwise, boundary flag in bit 31 of the
// row start) with Loop's tangent masks. Mirrors `subdiv_bft::cpu::{Stencils::apply, limit_normal}`.

const PI: f32 = 3.14159265358979;
const BOUNDARY: u32 = 0x80000000u;

struct Counts {
    vertices: u32,
};

@group(0) @binding(0) var<uniform> counts: Counts;
@group(0) @binding(1) var<storage, read> p0: array<vec4<f32>>;
// Row starts, one more than M¹ vertices.
@group(0) @binding(2) var<storage, read> entry_offsets: array<u32>;
// (M⁰ vertex, weight bits).
@group(0) @binding(3) var<storage, read> entries: array<vec2<u32>>;
@group(0) @binding(4) var<storage, read_write> p1_out: array<vec4<f32>>;

@compute @workgroup_size(64)
fn refine_m1(
    @builtin(global_invocation_id) id: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
) {
    let v = id.x + id.y * groups.x * 64u;
    if v >= counts.vertices {
        return;
    }
    var p = vec3<f32>(0.0);
    for (var k = entry_offsets[v]; k < entry_offsets[v + 1u]; k++) {
        let e = entries[k];
        p += bitcast<f32>(e.y) * p0[e.x].xyz;
    }
    p1_out[v] = vec4<f32>(p, 1.0);
}

@group(1) @binding(0) var<storage, read> p1: array<vec4<f32>>;
@group(1) @binding(1) var<storage, read> ring_offsets: array<u32>;
@group(1) @binding(2) var<storage, read> ring: array<u32>;
@group(1) @binding(3) var<storage, read_write> n1_out: array<vec4<f32>>;

@compute @workgroup_size(64)
fn normals_m1(
    @builtin(global_invocation_id) id: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
) {
    let v = id.x + id.y * groups.x * 64u;
    if v >= counts.vertices {
        return;
    }
    let start = ring_offsets[v] & ~BOUNDARY;
    let boundary = (ring_offsets[v] & BOUNDARY) != 0u;
    let n = (ring_offsets[v + 1u] & ~BOUNDARY) - start;
    var normal = vec3<f32>(0.0);
    if n > 0u && boundary {
        let k = n - 1u;
        let first = p1[ring[start]].xyz;
        let last = p1[ring[start + k]].xyz;
        let along = first - last;
        var across: vec3<f32>;
        if k == 1u {
            across = first + last - 2.0 * p1[v].xyz;
        } else {
            let t = PI / f32(k);
            let lambda = 0.375 + 0.25 * cos(t);
            var inner = vec3<f32>(0.0);
            var sum = 0.0;
            for (var i = 1u; i < k; i++) {
                let w = sin(f32(i) * t);
                inner += w * p1[ring[start + i]].xyz;
                sum += w;
            }
            let a = (0.375 * sum + (lambda - 0.75) * sin(t))
                / (8.0 * (lambda - 0.75) * (lambda - 0.5) - 1.0);
            let b = 8.0 * (lambda - 0.5) * a - sin(t);
            across = inner + a * (first + last) + b * p1[v].xyz;
        }
        normal = cross(along, across);
    } else if n > 0u {
        var t1 = vec3<f32>(0.0);
        var t2 = vec3<f32>(0.0);
        for (var i = 0u; i < n; i++) {
            let a = 2.0 * PI * f32(i) / f32(n);
            let p = p1[ring[start + i]].xyz;
            t1 += cos(a) * p;
            t2 += sin(a) * p;
        }
        normal = cross(t1, t2);
    }
    let len = length(normal);
    n1_out[v] = vec4<f32>(select(vec3<f32>(0.0), normal / len, len > 0.0), 0.0);
}
