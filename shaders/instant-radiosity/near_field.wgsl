// #import gbuffer/frame.wgsl
// #import gbuffer/normal_encoding.wgsl
// #import tiled-shading/lighting.wgsl
// #import tiled-shading/rays.wgsl
// #import instant-radiosity/direct.wgsl
// #import instant-radiosity/vpl.wgsl
// The VPLs' near field (Kollig & Keller 2004's bias compensation; `instant_radiosity::near_field`
// is the CPU twin, function for function). The VPL estimator bounds 1/d² at the clamp distance
// c, which takes away, at a receiver x,
//   E_lost(x)/π = 1/π ∫ L(y(ω)) cos θ (1 − d²/c²)⁺ dω   (d = |x − y(ω)|),
// the light of surfaces within c — most of what a receiver h above a floor gets when h ≪ c.
// One cosine-distributed ray of length c per pixel and frame estimates it: at its first hit y,
// L(y) (1 − d²/c²), with L(y) = ρ_y/π · (the lights' irradiance at y by shadow rays + the clamped
// irradiance of `samples` VPLs from a random start, × vpls / samples, by rays): Lambert at both ends, y's albedo its
// triangle's (`near_field::triangle_albedos`); a hit within the ray's lift is x's own contact.
// The output is diffuse E/π, as the composition adds it to the indirect diffuse light.

struct NearFieldParams {
    clamp_squared: f32,
    samples: u32,
    vpls: u32,
    seed: u32,
    // Length of a directional light's shadow ray.
    reach: f32,
    lights: u32,
    _pad0: u32,
    _pad1: u32,
};

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<uniform> params: NearFieldParams;
@group(0) @binding(2) var<storage, read> vpls: array<Vpl>;
// 3: the lights (`direct.wgsl`).
@group(0) @binding(4) var<storage, read> albedos: array<u32>;
@group(0) @binding(5) var linear_depth: texture_2d<f32>;
@group(0) @binding(6) var normals: texture_2d<u32>;
@group(0) @binding(7) var near_out: texture_storage_2d<rgba16float, write>;
// `ray_nodes` and `ray_triangles` of `rays.wgsl` at bindings 8 and 9
// (`instant_radiosity::near_field::rays_at`).

// PCG hash (Jarzynski & Olano 2020).
fn pcg(x: u32) -> u32 {
    let state = x * 747796405u + 2891336453u;
    let word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

fn unit(x: u32) -> f32 {
    return f32(x >> 8u) * (1.0 / 16777216.0);
}

// A cosine-distributed direction around n, in `scene::orthonormal_basis`'s frame (Duff et al.
// 2017; the sign is n.z's sign bit, as Rust's copysign takes it).
fn cosine_direction(n: vec3<f32>, u1: f32, u2: f32) -> vec3<f32> {
    let s = select(1.0, -1.0, (bitcast<u32>(n.z) & 0x80000000u) != 0u);
    let a = -1.0 / (s + n.z);
    let b = n.x * n.y * a;
    let t = vec3<f32>(1.0 + s * n.x * n.x * a, s * b, -s * n.x);
    let bt = vec3<f32>(b, s + n.y * n.y * a, -n.y);
    let r = sqrt(u1);
    let phi = 6.283185307179586 * u2;
    return t * (r * cos(phi)) + bt * (r * sin(phi)) + n * sqrt(max(1.0 - u1, 0.0));
}

// Irradiance / π at y (normal n): the lights by shadow rays, `samples` VPLs from `first` by rays.
fn irradiance_at(y: vec3<f32>, n: vec3<f32>, first: u32) -> vec3<f32> {
    let origin = y + n * ray_lift(y);
    let e = direct_irradiance(y, n, params.lights, params.reach);
    var indirect = vec3<f32>(0.0);
    for (var i = 0u; i < params.samples; i++) {
        let vpl = vpls[(first + i) % params.vpls];
        var l: vec3<f32>;
        let intensity = vpl_intensity(vpl, y, params.clamp_squared, &l);
        let cos_y = dot(n, l);
        if cos_y <= 0.0 || all(intensity == vec3<f32>(0.0)) {
            continue;
        }
        let end = vpl.position + vpl.normal * ray_lift(vpl.position);
        if !occluded(origin, end - origin) {
            indirect += intensity * cos_y;
        }
    }
    return (e + indirect * (f32(params.vpls) / f32(params.samples))) * INV_PI;
}

// E_lost/π at p (normal n), pixel `pixel`'s sample of this frame.
fn near_field(p: vec3<f32>, n: vec3<f32>, pixel: vec2<u32>) -> vec3<f32> {
    if params.clamp_squared <= 0.0 {
        return vec3<f32>(0.0);
    }
    var h = pcg(pixel.x ^ pcg(pixel.y ^ pcg(params.seed)));
    let u1 = unit(h);
    h = pcg(h);
    let u2 = unit(h);
    h = pcg(h);
    let first = h % params.vpls;
    let dir = cosine_direction(n, u1, u2);
    let origin = p + n * ray_lift(p);
    let to = dir * sqrt(params.clamp_squared);
    let hit = nearest(origin, to);
    // A surface within the lift is the receiver's own contact, as for every ray that leaves
    // it: a pixel centre on an edge must not see the other face at distance 0.
    if hit.slot == RAY_NONE || hit.t * sqrt(params.clamp_squared) < ray_lift(p) {
        return vec3<f32>(0.0);
    }
    let tri = ray_triangles[hit.slot];
    var n_y = normalize(cross(tri.e1.xyz, tri.e2.xyz));
    if dot(n_y, dir) > 0.0 {
        n_y = -n_y;
    }
    let y = origin + to * hit.t;
    let albedo = unpack4x8unorm(albedos[tri.index]).rgb;
    return albedo * irradiance_at(y, n_y, first) * (1.0 - hit.t * hit.t);
}

@compute @workgroup_size(8, 8)
fn near_field_main(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = textureDimensions(linear_depth);
    if id.x >= size.x || id.y >= size.y {
        return;
    }
    let depth = textureLoad(linear_depth, id.xy, 0).r;
    var out = vec3<f32>(0.0);
    if depth > 0.0 {
        let p = position_from_view_ray(frame, id.xy, depth);
        let n = decode_octahedral_snorm(unpack2x16snorm(textureLoad(normals, id.xy, 0).x));
        out = near_field(p, n, id.xy);
    }
    textureStore(near_out, id.xy, vec4<f32>(out, 0.0));
}
