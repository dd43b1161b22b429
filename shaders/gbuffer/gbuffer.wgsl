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
    // The eye relative to the vertex (small near the camera, for precise derivatives).
    @location(3) to_eye: vec3<f32>,
};

@vertex
fn vs_main(@location(0) position: vec3<f32>, @location(1) normal: vec3<f32>, @location(2) uv: vec2<f32>) -> VertexOut {
    var out: VertexOut;
    out.clip = frame.view_proj * vec4<f32>(position, 1.0);
    out.normal = normal;
    out.uv = uv;
    out.view_depth = out.clip.w;
    out.to_eye = frame.eye.xyz - position;
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

// The interpolated normal, unit, on the camera's side of the triangle's plane: every surface
// is two-sided (nothing is culled) and lit from the side it is seen from, and a vertex normal
// bent behind its triangle is turned as the path tracer turns it (`scene::reference`: the
// shading normal goes to the side of the geometric normal that faces the ray). The geometric
// normal comes from the screen derivatives of the position, which lie in the triangle's plane:
// with x right and y down, cross(∂p/∂y, ∂p/∂x) points towards the camera on every triangle.
// A normal within `BENT_NORMAL_COS` of the plane is replaced by the plane's normal
// (`scene::facing_shading_normal`, the path tracer's rule too).
const BENT_NORMAL_COS: f32 = 0.01;

fn facing_normal(normal: vec3<f32>, to_eye: vec3<f32>) -> vec3<f32> {
    let l2 = dot(normal, normal);
    let n = select(vec3<f32>(0.0, 0.0, 1.0), normal * inverseSqrt(l2), l2 > 1e-30);
    let geometric = cross(dpdyFine(to_eye), dpdxFine(to_eye));
    let g2 = dot(geometric, geometric);
    if g2 <= 1e-30 {
        return n;
    }
    let facing = geometric * inverseSqrt(g2);
    let c = dot(n, facing);
    if abs(c) < BENT_NORMAL_COS {
        return facing;
    }
    return select(n, -n, c < 0.0);
}

@fragment
fn fs_main(in: VertexOut) -> GBufferOut {
    var out: GBufferOut;
    out.linear_depth = in.view_depth;
    let n = facing_normal(in.normal, in.to_eye);
    out.normal = pack2x16snorm(encode_octahedral_snorm(n));
    let texel = textureSampleLevel(base_color_texture, base_color_sampler, in.uv, 0.0);
    out.albedo = vec4<f32>(clamp(material.base_color.rgb * texel.rgb, vec3<f32>(0.0), vec3<f32>(1.0)), clamp(material.specular, 0.0, 1.0));
    out.material = pack_material(material.roughness, material.metallic, material.id);
    return out;
}
