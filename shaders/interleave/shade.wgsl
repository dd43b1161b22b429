// #import gbuffer/normal_encoding.wgsl
// #import interleave/pattern.wgsl
// Shading of interleaved samples (Segovia 2006 §4.3), the crate's probe shader: the pixels of
// sub-buffer (i, j) receive only the directional lights of subset s = j·n + i.
//   shade_split: reads the split G-buffer, writes split irradiance (to be gathered);
//   shade_fused: the §3.1 indirection baseline — threads in sub-buffer order read the
//                interleaved G-buffer and write the interleaved irradiance by strided address.

struct SubsetLight {
    direction: vec4<f32>,
    color: vec4<f32>,
}

@group(0) @binding(0) var linear_depth: texture_2d<f32>;
@group(0) @binding(1) var normals: texture_2d<u32>;
@group(0) @binding(2) var<storage, read> lights: array<SubsetLight>;
@group(0) @binding(3) var irradiance: texture_storage_2d<rgba16float, write>;

override per_subset: u32 = 1u;

fn shade(texel: vec2<u32>, subset: u32) -> vec4<f32> {
    if textureLoad(linear_depth, texel, 0).r == 0.0 {
        return vec4(0.0);
    }
    let w = textureLoad(normals, texel, 0).r;
    let nrm = decode_octahedral_snorm(unpack2x16snorm(w));
    var e = vec3(0.0);
    for (var l = subset * per_subset; l < (subset + 1u) * per_subset; l++) {
        e += max(dot(nrm, lights[l].direction.xyz), 0.0) * lights[l].color.xyz;
    }
    return vec4(e, 1.0);
}

@compute @workgroup_size(16, 16)
fn shade_split(@builtin(global_invocation_id) id: vec3<u32>) {
    if !in_split_layout(id.xy) {
        return;
    }
    textureStore(irradiance, id.xy, shade(id.xy, split_subset(id.xy)));
}

@compute @workgroup_size(16, 16)
fn shade_fused(@builtin(global_invocation_id) id: vec3<u32>) {
    let p = split_pixel(id.xy);
    if !in_split_layout(id.xy) || p.x >= width || p.y >= height {
        return;
    }
    textureStore(irradiance, p, shade(p, split_subset(id.xy)));
}
