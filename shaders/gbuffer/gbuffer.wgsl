// #import gbuffer/frame.wgsl
// #import gbuffer/normal_encoding.wgsl
// #import gbuffer/material.wgsl
// G-buffer creation (Ishmukhametov 2013 §1.3 step 2): one render pass writing all targets
// at once (MRT). Mirrors `gbuffer::cpu::rasterize`; layout documented in `gbuffer::layout`.

@group(0) @binding(0) var<uniform> frame: Frame;
@group(1) @binding(0) var<uniform> material: Material;
@group(1) @binding(1) var base_color_texture: texture_2d<f32>;
@group(1) @binding(2) var base_color_sampler: sampler;

struct VertexOut {
    // Invariant: the z-prepass (`vs_depth`) must produce bit-identical depth.
    @builtin(position) @invariant clip: vec4<f32>,
    @location(0) normal: vec3<f32>,
    @location(1) uv: vec2<f32>,
    @location(2) view_depth: f32,
};

@vertex
fn vs_main(@location(0) position: vec3<f32>, @location(1) normal: vec3<f32>, @location(2) uv: vec2<f32>) -> VertexOut {
    var out: VertexOut;
    out.clip = frame.view_proj * vec4<f32>(position, 1.0);
    out.normal = normal;
    out.uv = uv;
    out.view_depth = out.clip.w;
    return out;
}

struct DepthOut {
    @builtin(position) @invariant clip: vec4<f32>,
};

// Z-prepass (Holländer 2013 §4.2): depth only, so the MRT pass shades each pixel once.
@vertex
fn vs_depth(@location(0) position: vec3<f32>) -> DepthOut {
    var out: DepthOut;
    out.clip = frame.view_proj * vec4<f32>(position, 1.0);
    return out;
}

struct GBufferOut {
    @location(0) linear_depth: f32,
    @location(1) normal: u32,
    @location(2) albedo: vec4<f32>,
    @location(3) material: u32,
};

// roughness (unorm8) | metallic (unorm8) << 8 | material id << 16.
fn pack_material(roughness: f32, metallic: f32, id: u32) -> u32 {
    let r = u32(round(clamp(roughness, 0.0, 1.0) * 255.0));
    let m = u32(round(clamp(metallic, 0.0, 1.0) * 255.0));
    return r | (m << 8u) | (id << 16u);
}

// The interpolated normal, unit, turned towards the camera on a back face: every surface is
// two-sided (nothing is culled), and its back is lit from the side it is seen from, as the
// path tracer's normals face the incoming ray.
fn facing_normal(normal: vec3<f32>, front: bool) -> vec3<f32> {
    let l2 = dot(normal, normal);
    let n = select(vec3<f32>(0.0, 0.0, 1.0), normal * inverseSqrt(l2), l2 > 1e-30);
    return select(-n, n, front);
}

@fragment
fn fs_main(in: VertexOut, @builtin(front_facing) front: bool) -> GBufferOut {
    var out: GBufferOut;
    out.linear_depth = in.view_depth;
    let n = facing_normal(in.normal, front);
    out.normal = pack2x16snorm(encode_octahedral_snorm(n));
    let texel = textureSampleLevel(base_color_texture, base_color_sampler, in.uv, 0.0);
    out.albedo = vec4<f32>(clamp(material.base_color.rgb * texel.rgb, vec3<f32>(0.0), vec3<f32>(1.0)), clamp(material.specular, 0.0, 1.0));
    out.material = pack_material(material.roughness, material.metallic, material.id);
    return out;
}
