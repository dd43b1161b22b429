// #import gbuffer/normal_encoding.wgsl
// Encodes and decodes every input normal with the five encodings (index = encoding id) and,
// as index 5, the per-pixel view-space one seen along PER_PIXEL_TO_EYE, without quantization:
// the GPU twin of `gbuffer::normal::NormalEncoding::{encode, decode}` and
// `{encode, decode}_per_pixel_view`.

// normalize(0.3, −0.2, 0.98), as the test.
const PER_PIXEL_TO_EYE: vec3<f32> = vec3<f32>(0.28729518, -0.19153012, 0.93849757);

@group(0) @binding(0) var<storage, read> normals: array<vec4<f32>>;
@group(0) @binding(1) var<storage, read_write> encoded: array<vec2<f32>>;
@group(0) @binding(2) var<storage, read_write> decoded: array<vec4<f32>>;

@compute @workgroup_size(64)
fn encode_normals(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    let count = arrayLength(&normals);
    if i >= count { return; }
    let n = normals[i].xyz;
    var e: array<vec2<f32>, 6>;
    e[0] = encode_xy(n);
    e[1] = encode_spherical(n);
    e[2] = encode_sphere_map(n);
    e[3] = encode_stereographic(n);
    e[4] = encode_octahedral(n);
    e[5] = encode_per_pixel_view(n, PER_PIXEL_TO_EYE);
    var d: array<vec3<f32>, 6>;
    d[0] = decode_xy(e[0]);
    d[1] = decode_spherical(e[1]);
    d[2] = decode_sphere_map(e[2]);
    d[3] = decode_stereographic(e[3]);
    d[4] = decode_octahedral(e[4]);
    d[5] = decode_per_pixel_view(e[5], PER_PIXEL_TO_EYE);
    for (var k = 0u; k < 6u; k++) {
        encoded[k * count + i] = e[k];
        decoded[k * count + i] = vec4<f32>(d[k], 0.0);
    }
}
