// Bottom-up refit of the bounding-sphere hierarchy after deformation (§3.5.3): `leaves`
// evaluates every surfel (s, t, triangle) on the deformed mesh into its leaf node (from node
// `first`: the tree's leaves, or the ISM baseline's points), `merge`
// recomputes one tree level from the level below. Mirrors `manylod::Bsh::refit`,
// `Node::{leaf, merge}` and `surfels::evaluate`.
// #import manylod/common.wgsl

struct Refit {
    // First node of the level `merge` writes (2^l − 1) and its node count (2^l).
    first: u32,
    count: u32,
    // Leaves (2^d); the leaves are nodes count_leaves − 1 ...
    leaves: u32,
    leaf_radius: f32,
}

struct Surfel {
    s: f32,
    t: f32,
    triangle: u32,
}

@group(0) @binding(0) var<storage, read_write> nodes: array<Node>;
@group(0) @binding(1) var<uniform> refit: Refit;
@group(0) @binding(2) var<storage, read> surfels: array<Surfel>;
@group(0) @binding(3) var<storage, read> order: array<u32>;
@group(0) @binding(4) var<storage, read> positions: array<vec4<f32>>;
@group(0) @binding(5) var<storage, read> indices: array<u32>;

const PI: f32 = 3.14159265358979;
const GROW: f32 = 1e-6;

fn index(gid: vec3<u32>, groups: vec3<u32>) -> u32 {
    return gid.x + gid.y * groups.x * 256u;
}

@compute @workgroup_size(256)
fn leaves(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let k = index(gid, groups);
    if k >= refit.leaves {
        return;
    }
    let p = surfels[order[k]];
    let a = positions[indices[3u * p.triangle]].xyz;
    let b = positions[indices[3u * p.triangle + 1u]].xyz;
    let c = positions[indices[3u * p.triangle + 2u]].xyz;
    let n = cross(b - a, c - a);
    let len = length(n);
    var node: Node;
    node.center = p.s * a + p.t * b + (1.0 - p.s - p.t) * c;
    node.radius = refit.leaf_radius;
    if len > 0.0 {
        node.axis = n / len;
        node.angle = 0.0;
    } else {
        node.axis = vec3<f32>(0.0, 0.0, 1.0);
        node.angle = PI;
    }
    nodes[refit.first + k] = node;
}

fn merge_nodes(x: Node, y: Node) -> Node {
    // Spheres.
    var center = x.center;
    var radius = x.radius;
    let d = distance(x.center, y.center);
    if d + y.radius <= x.radius {
        // x holds y.
    } else if d + x.radius <= y.radius {
        center = y.center;
        radius = y.radius;
    } else {
        radius = 0.5 * (d + x.radius + y.radius);
        center = x.center + (y.center - x.center) * ((radius - x.radius) / d);
    }
    // Cones.
    var axis = x.axis;
    var angle = x.angle;
    let phi = angle_between(x.axis, y.axis);
    if phi + y.angle <= x.angle {
        // x holds y.
    } else if phi + x.angle <= y.angle {
        axis = y.axis;
        angle = y.angle;
    } else {
        let t = 0.5 * (phi + x.angle + y.angle);
        if t >= PI || phi > PI - 1e-3 {
            angle = PI;
        } else {
            let f = (t - x.angle) / phi;
            let w = (x.axis * sin((1.0 - f) * phi) + y.axis * sin(f * phi)) / sin(phi);
            let l = length(w);
            if l > 0.0 {
                axis = w / l;
            }
            angle = t;
        }
    }
    let m = max(max(abs(center.x), abs(center.y)), max(abs(center.z), 1.0));
    return Node(center, radius * (1.0 + GROW) + GROW * m * 0.1, axis, min(angle + GROW, PI));
}

@compute @workgroup_size(256)
fn merge(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let k = index(gid, groups);
    if k >= refit.count {
        return;
    }
    let i = refit.first + k;
    nodes[i] = merge_nodes(nodes[2u * i + 1u], nodes[2u * i + 2u]);
}
