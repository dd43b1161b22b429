// Discontinuity buffer (Segovia 2006 §4.5): each pixel against its three positive neighbours
// (x+1, y), (x, y+1), (x+1, y+1). Red = normal test failed, green = depth test failed.
// Integer normals and single correctly rounded f32 products, so it equals the CPU exactly.

struct Thresholds {
    // cos² of the largest continuous angle between normals.
    cos_squared: f32,
    // 1 when that angle is at most 90° (cos ≥ 0), else 0.
    cos_positive: u32,
    // 1 + the largest continuous relative depth difference.
    depth_factor: f32,
    _pad: u32,
}

@group(0) @binding(0) var linear_depth: texture_2d<f32>;
@group(0) @binding(1) var normals: texture_2d<u32>;
@group(0) @binding(2) var discontinuities: texture_storage_2d<rgba8unorm, write>;
@group(0) @binding(3) var<uniform> thresholds: Thresholds;

// Octahedral snorm16×2 word → unnormalised integer vector with 11-bit components.
fn octahedral_integer(word: u32) -> vec3<i32> {
    let one = 32767;
    let x = max(bitcast<i32>(word << 16u) >> 16u, -one);
    let y = max(bitcast<i32>(word) >> 16u, -one);
    let z = one - abs(x) - abs(y);
    var v = vec3(x, y, z);
    if z < 0 {
        v.x = (one - abs(y)) * select(-1, 1, x >= 0);
        v.y = (one - abs(x)) * select(-1, 1, y >= 0);
    }
    return v >> vec3(4u);
}

fn normals_differ(a: u32, b: u32) -> bool {
    let v0 = octahedral_integer(a);
    let v1 = octahedral_integer(b);
    let d = dot(v0, v1);
    let dot2 = f32(d) * f32(d);
    let bound = thresholds.cos_squared * f32(dot(v0, v0)) * f32(dot(v1, v1));
    if thresholds.cos_positive != 0u {
        return d <= 0 || dot2 < bound;
    }
    return d < 0 && dot2 > bound;
}

fn depths_differ(a: f32, b: f32) -> bool {
    return max(a, b) > min(a, b) * thresholds.depth_factor;
}

// The flags one neighbour (depth qz, normal word qn) raises against a pixel (z, nrm): bit 0
// when the normal test fails, bit 1 when the depth test does.
fn edge_flags(z: f32, nrm: u32, qz: f32, qn: u32) -> u32 {
    return select(0u, 1u, normals_differ(nrm, qn)) | select(0u, 2u, depths_differ(z, qz));
}

// Offset k (0, 1, 2) of the three positive neighbours: (1, 0), (0, 1), (1, 1).
fn neighbour(k: u32) -> vec2<u32> {
    return vec2(select(0u, 1u, k != 1u), select(0u, 1u, k != 0u));
}

// The discontinuity flags of texel p: `edge_flags` of its neighbours inside the image.
fn discontinuity_flags(p: vec2<u32>) -> u32 {
    let size = textureDimensions(linear_depth);
    let z = textureLoad(linear_depth, p, 0).r;
    let nrm = textureLoad(normals, p, 0).r;
    var flags = 0u;
    for (var k = 0u; k < 3u; k++) {
        let q = p + neighbour(k);
        if all(q < size) {
            flags |= edge_flags(z, nrm, textureLoad(linear_depth, q, 0).r, textureLoad(normals, q, 0).r);
        }
    }
    return flags;
}

// The discontinuity buffer's texel of `discontinuity_flags`.
fn discontinuity_texel(flags: u32) -> vec4<f32> {
    return vec4(f32(flags & 1u), f32(flags >> 1u), 0.0, 1.0);
}

@compute @workgroup_size(16, 16)
fn discontinuity(@builtin(global_invocation_id) id: vec3<u32>) {
    if any(id.xy >= textureDimensions(linear_depth)) {
        return;
    }
    textureStore(discontinuities, id.xy, discontinuity_texel(discontinuity_flags(id.xy)));
}
