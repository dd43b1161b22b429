// Compact normal storage, Ishmukhametov 2013 §3.6 (after Pranckevičius), plus octahedral.
// Every encoding maps a unit normal to two values in [0, 1]; mirrors `gbuffer::normal`.
const PI: f32 = 3.14159265358979;
const STEREO_SCALE: f32 = 1.7777;

fn safe_normalize2(v: vec2<f32>) -> vec2<f32> {
    let l2 = dot(v, v);
    return select(vec2<f32>(1.0, 0.0), v * inverseSqrt(l2), l2 > 1e-30);
}

// X & Y stored, Z reconstructed (Killzone 2): only for normals with z >= 0.
fn encode_xy(n: vec3<f32>) -> vec2<f32> { return n.xy * 0.5 + 0.5; }
fn decode_xy(e: vec2<f32>) -> vec3<f32> {
    let xy = e * 2.0 - 1.0;
    return vec3<f32>(xy, sqrt(max(0.0, 1.0 - dot(xy, xy))));
}

// Spherical coordinates (the thesis's `(normalOut + 1.0) + 0.5` read as `* 0.5`).
fn encode_spherical(n: vec3<f32>) -> vec2<f32> {
    return (vec2<f32>(atan2(n.y, n.x) / PI, n.z) + 1.0) * 0.5;
}
fn decode_spherical(e: vec2<f32>) -> vec3<f32> {
    let a = e * 2.0 - 1.0;
    let s = sin(a.x * PI);
    let c = cos(a.x * PI);
    let r = sqrt(max(0.0, 1.0 - a.y * a.y));
    return vec3<f32>(c * r, s * r, a.y);
}

// Sphere map transform (CryEngine 3), as written in the thesis.
fn encode_sphere_map(n: vec3<f32>) -> vec2<f32> {
    return safe_normalize2(n.xy) * sqrt(max(0.0, n.z * 0.5 + 0.5)) * 0.5 + 0.5;
}
fn decode_sphere_map(e: vec2<f32>) -> vec3<f32> {
    let v = e * 2.0 - 1.0;
    let z = dot(v, v) * 2.0 - 1.0;
    return vec3<f32>(safe_normalize2(v) * sqrt(max(0.0, 1.0 - z * z)), z);
}

// Stereographic projection scaled by 1.7777: for normals with z >= -0.5.
fn encode_stereographic(n: vec3<f32>) -> vec2<f32> {
    return n.xy / (n.z + 1.0) / STEREO_SCALE * 0.5 + 0.5;
}
fn decode_stereographic(e: vec2<f32>) -> vec3<f32> {
    let a = vec3<f32>(e * 2.0 * STEREO_SCALE - STEREO_SCALE, 1.0);
    let b = 2.0 / dot(a, a);
    return vec3<f32>(b * a.xy, b - 1.0);
}

// Octahedral mapping in [-1, 1]² (what the G-buffer stores, as two snorm16).
fn oct_wrap(v: vec2<f32>) -> vec2<f32> {
    return (1.0 - abs(v.yx)) * select(vec2<f32>(-1.0), vec2<f32>(1.0), v >= vec2<f32>(0.0));
}
fn encode_octahedral_snorm(n: vec3<f32>) -> vec2<f32> {
    let p = n.xy / (abs(n.x) + abs(n.y) + abs(n.z));
    return select(p, oct_wrap(p), n.z < 0.0);
}
fn decode_octahedral_snorm(e: vec2<f32>) -> vec3<f32> {
    var n = vec3<f32>(e, 1.0 - abs(e.x) - abs(e.y));
    let t = max(-n.z, 0.0);
    n.x += select(t, -t, n.x >= 0.0);
    n.y += select(t, -t, n.y >= 0.0);
    return normalize(n);
}
fn encode_octahedral(n: vec3<f32>) -> vec2<f32> { return encode_octahedral_snorm(n) * 0.5 + 0.5; }
fn decode_octahedral(e: vec2<f32>) -> vec3<f32> { return decode_octahedral_snorm(e * 2.0 - 1.0); }

// Per-pixel view space (thesis §3.6): x and y in the frame whose z points from the pixel to
// the eye (`gbuffer::normal::per_pixel_view_frame`); z ≥ 0 for every normal the eye sees.
fn per_pixel_view_frame(to_eye: vec3<f32>) -> mat3x3<f32> {
    let x = normalize(vec3<f32>(to_eye.z, 0.0, -to_eye.x));
    return mat3x3<f32>(x, cross(to_eye, x), to_eye);
}
fn encode_per_pixel_view(n: vec3<f32>, to_eye: vec3<f32>) -> vec2<f32> {
    let f = per_pixel_view_frame(to_eye);
    return vec2<f32>(dot(f[0], n), dot(f[1], n)) * 0.5 + 0.5;
}
fn decode_per_pixel_view(e: vec2<f32>, to_eye: vec3<f32>) -> vec3<f32> {
    let a = e * 2.0 - 1.0;
    return per_pixel_view_frame(to_eye) * vec3<f32>(a, sqrt(max(1.0 - dot(a, a), 0.0)));
}
