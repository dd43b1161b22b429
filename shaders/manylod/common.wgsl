// ManyLoDs shared definitions (Holländer 2013 §3.5): node bounds, views, the cut criterion
// c(N, V) and the disc a node splats to. Mirrors `manylod::{Node, View::criterion, View::splat}`.

struct Node {
    center: vec3<f32>,
    radius: f32,
    axis: vec3<f32>,
    angle: f32,
}

// `manylod::view::GpuView`.
struct View {
    planes: array<vec4<f32>, 6>,
    transform: mat4x4<f32>,
    eye: vec3<f32>,
    kind: u32,
    size: vec2<f32>,
    pixels_per_radian: f32,
    // The largest angle from the axis the view sees (`View::rim`).
    rim: f32,
}

// The cut's threshold and sizes (`manylod::gpu`).
struct Problem {
    epsilon: f32,
    view_count: u32,
    // First leaf node (2^d − 1).
    leaf_start: u32,
    // Tree levels a cut pass descends (`GpuManyLod::set_levels_per_pass`, 1 to 4).
    levels: u32,
}

const PARABOLOID: u32 = 0u;
const CULLED: u32 = 0x80000000u;
// The eye is inside the sphere: always split (the CPU uses +∞).
const INSIDE: f32 = 3.0e38;
const HALF_PI: f32 = 1.5707963267948966;
const MIN_SPLAT_RADIUS: f32 = 0.70710677;
const MAX_SPLAT_RADIUS: f32 = 16.0;

// The paraboloid frame around unit `normal` (`manylod::view::paraboloid_frame`): columns t, b,
// normal, so `d * paraboloid_frame(normal)` is d in that frame.
fn paraboloid_frame(normal: vec3<f32>) -> mat3x3<f32> {
    let helper = select(vec3<f32>(1.0, 0.0, 0.0), vec3<f32>(0.0, 0.0, 1.0), abs(normal.z) < 0.9);
    let t = normalize(cross(helper, normal));
    return mat3x3<f32>(t, cross(normal, t), normal);
}

fn angle_between(a: vec3<f32>, b: vec3<f32>) -> f32 {
    return atan2(length(cross(a, b)), dot(a, b));
}

// The projection's scale where a sphere seen in direction `dir` under angular radius `beta`
// reaches furthest from the view's axis (`View::scale`): the paraboloid's 1 / (1 + cos γ)
// (its axis is planes[0]'s normal), a pinhole's radial stretch 1 / cos² γ (planes[4]'s).
fn scale_at(v: View, dir: vec3<f32>, beta: f32) -> f32 {
    if v.kind == PARABOLOID {
        return 1.0 / (1.0 + cos(min(angle_between(dir, v.planes[0].xyz) + beta, v.rim)));
    }
    let c = cos(min(angle_between(dir, v.planes[4].xyz) + beta, v.rim));
    return 1.0 / (c * c);
}

// c(N, V): projected diameter in pixels, 0 when culled (outside a plane or back-facing),
// measured at the scale where the sphere reaches furthest from the axis.
fn criterion(v: View, n: Node) -> f32 {
    let to = n.center - v.eye;
    let dist = length(to);
    if dist <= n.radius {
        return INSIDE;
    }
    let beta = asin(n.radius / dist);
    var visible = true;
    for (var k = 0u; k < 6u; k++) {
        let p = v.planes[k];
        visible = visible && dot(p.xyz, n.center) + p.w >= -n.radius;
    }
    let back_facing = angle_between(-to / dist, n.axis) - n.angle - beta > HALF_PI;
    if !visible || back_facing {
        return 0.0;
    }
    return 2.0 * beta * v.pixels_per_radian * scale_at(v, to / dist, beta);
}

struct Splat {
    center: vec2<f32>,
    radius: f32,
    depth: f32,
    ok: bool,
}

// Where node n lands in view v's tile (`View::splat`): centre and radius in pixels, depth in
// [0, 1] (paraboloid: distance / far, perspective: NDC depth).
fn splat_of(v: View, n: Node, far: f32) -> Splat {
    var s = Splat(vec2<f32>(0.0), 0.0, 0.0, false);
    var radius = 0.0;
    if v.kind == PARABOLOID {
        let local = (v.transform * vec4<f32>(n.center, 1.0)).xyz;
        let dist = length(local);
        if dist <= n.radius || local.z <= 0.0 {
            return s;
        }
        let d = local / dist;
        let uv = d.xy / (1.0 + d.z);
        s.center = (uv * 0.5 + 0.5) * v.size.x;
        radius = asin(n.radius / dist) * (v.size.x * 0.5) / (1.0 + d.z);
        s.depth = dist / far;
    } else {
        let clip = v.transform * vec4<f32>(n.center, 1.0);
        let dist = distance(n.center, v.eye);
        if clip.w <= 0.0 || dist <= n.radius {
            return s;
        }
        let ndc = clip.xyz / clip.w;
        s.center = vec2<f32>((ndc.x * 0.5 + 0.5) * v.size.x, (0.5 - ndc.y * 0.5) * v.size.y);
        let beta = asin(n.radius / dist);
        radius = beta * v.pixels_per_radian * scale_at(v, (n.center - v.eye) / dist, beta);
        s.depth = ndc.z;
    }
    s.radius = clamp(radius, MIN_SPLAT_RADIUS, MAX_SPLAT_RADIUS);
    s.depth = clamp(s.depth, 0.0, 1.0);
    s.ok = true;
    return s;
}

// FreePipe depth word with the thesis's correction (`manylod::splat::pack_depth`).
fn pack_depth(depth: f32, colour: u32) -> u32 {
    let m = min(0.5 + 0.5 * clamp(depth, 0.0, 1.0), bitcast<f32>(0x3F7FFFFFu));
    return ((bitcast<u32>(m) << 9u) & 0xFFFFF000u) | (colour & 0xFFFu);
}

fn unpack_depth(word: u32) -> f32 {
    return (bitcast<f32>(0x3F000000u | (word >> 9u)) - 0.5) * 2.0;
}
