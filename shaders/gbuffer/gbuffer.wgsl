// #import gbuffer/frame.wgsl
// #import gbuffer/normal_encoding.wgsl
// #import gbuffer/material.wgsl
// G-buffer creation (Ishmukhametov 2013 §1.3 step 2): one render pass writing all targets
// at once (MRT). Mirrors `gbuffer::cpu::rasterize`; layout documented in `gbuffer::layout`.

@group(0) @binding(0) var<uniform> frame: Frame;

struct VertexOut {
    // Invariant: the z-prepass (`vs_depth`) must produce bit-identical depth.
    @builtin(position) @invariant clip: vec4<f32>,
    @location(0) normal: vec3<f32>,
    // Texture-coordinate sets 0 (xy) and 1 (zw).
    @location(1) uv: vec4<f32>,
    @location(2) view_depth: f32,
    // The eye relative to the vertex (small near the camera, for precise derivatives).
    @location(3) to_eye: vec3<f32>,
    @location(4) tangent: vec4<f32>,
    @location(5) color: vec4<f32>,
};

@vertex
fn vs_main(
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) uv0: vec2<f32>,
    @location(3) uv1: vec2<f32>,
    @location(4) tangent: vec4<f32>,
    @location(5) color: vec4<f32>,
) -> VertexOut {
    var out: VertexOut;
    out.clip = frame.view_proj * vec4<f32>(position, 1.0);
    out.normal = normal;
    out.uv = vec4<f32>(uv0, uv1);
    out.view_depth = out.clip.w;
    out.to_eye = frame.eye.xyz - position;
    out.tangent = tangent;
    out.color = color;
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
    @location(4) emission: vec4<f32>,
};

// roughness (unorm8) | metallic (unorm8) << 8 | material id << 16.
fn pack_material(roughness: f32, metallic: f32, id: u32) -> u32 {
    let r = u32(round(clamp(roughness, 0.0, 1.0) * 255.0));
    let m = u32(round(clamp(metallic, 0.0, 1.0) * 255.0));
    return r | (m << 8u) | (id << 16u);
}

// The interpolated normal, unit, on the camera's side of the triangle's plane: a surface is
// lit from the side it is seen from (one-sided materials' back faces are culled by the
// pipeline), and a vertex normal
// bent behind its triangle is turned as the path tracer turns it (`scene::reference`: the
// shading normal goes to the side of the geometric normal that faces the ray). The geometric
// normal comes from the screen derivatives of the position, which lie in the triangle's plane:
// with x right and y down, cross(∂p/∂y, ∂p/∂x) points towards the camera on every triangle.
// A normal within `BENT_NORMAL_COS` of the plane is replaced by the plane's normal
// (`scene::facing_shading_normal`, the path tracer's rule too). `back_face` says whether the
// vertex normal points away from the camera (the tangent frame turns with it).
const BENT_NORMAL_COS: f32 = 0.01;

struct Facing {
    normal: vec3<f32>,
    back_face: bool,
};

fn facing_normal(normal: vec3<f32>, to_eye: vec3<f32>) -> Facing {
    return facing_geometric(normal, cross(dpdyFine(to_eye), dpdxFine(to_eye)));
}

// `facing_normal` with the triangle's geometric normal (not unit) on the camera's side given.
fn facing_geometric(normal: vec3<f32>, geometric: vec3<f32>) -> Facing {
    let l2 = dot(normal, normal);
    let n = select(vec3<f32>(0.0, 0.0, 1.0), normal * inverseSqrt(l2), l2 > 1e-30);
    let g2 = dot(geometric, geometric);
    if g2 <= 1e-30 {
        return Facing(n, false);
    }
    let facing = geometric * inverseSqrt(g2);
    let c = dot(n, facing);
    if abs(c) < BENT_NORMAL_COS {
        return Facing(facing, c < 0.0);
    }
    return Facing(select(n, -n, c < 0.0), c < 0.0);
}

// The largest finite half float: emission beyond it is clamped, not turned to infinity.
const HALF_MAX: f32 = 65504.0;

struct SurfaceFragment {
    at: SurfaceAttributes,
    m: MaterialSample,
};

// A fragment's attributes (coordinates with their fine derivatives, the facing normal) and
// its evaluated material, alpha included. Call in uniform control flow (the derivatives).
fn evaluate_fragment(in: VertexOut) -> SurfaceFragment {
    // The derivatives over the texture footprint (`Frame::with_texture_footprint`).
    let footprint = max(frame.sampling.z, 1.0);
    let uv_dx = dpdxFine(in.uv) * footprint;
    let uv_dy = dpdyFine(in.uv) * footprint;
    let facing = facing_normal(in.normal, in.to_eye);
    let at = SurfaceAttributes(in.uv, uv_dx, uv_dy, facing.normal, facing.back_face, in.tangent, in.color);
    return SurfaceFragment(at, evaluate_material(at));
}

// `evaluate_fragment`, and a fragment its material's alpha does not keep is discarded.
fn surface_fragment(in: VertexOut) -> SurfaceFragment {
    let f = evaluate_fragment(in);
    if !alpha_keeps(f.m.alpha, dither_threshold(vec2<u32>(in.clip.xy))) {
        discard;
    }
    return f;
}

// The G-buffer texels of material sample m at view depth `view_depth`.
fn gbuffer_texels(m: MaterialSample, view_depth: f32) -> GBufferOut {
    return gbuffer_texels_of(material, m, view_depth);
}

// `gbuffer_texels` of a sample m of material `sampled`.
fn gbuffer_texels_of(sampled: Material, m: MaterialSample, view_depth: f32) -> GBufferOut {
    var out: GBufferOut;
    out.linear_depth = view_depth;
    out.normal = pack2x16snorm(encode_octahedral_snorm(m.normal));
    out.albedo = vec4<f32>(m.albedo, clamp(sampled.specular, 0.0, 1.0));
    out.material = pack_material(m.roughness, m.metallic, sampled.id);
    out.emission = vec4<f32>(min(m.emission, vec3<f32>(HALF_MAX)), m.occlusion);
    return out;
}

@fragment
fn fs_main(in: VertexOut) -> GBufferOut {
    return gbuffer_texels(surface_fragment(in).m, in.view_depth);
}

// The depth-only pass of alpha-tested (masked or blended) materials: the same coverage as
// `fs_main`, without the G-buffer writes.
@fragment
fn fs_alpha_depth(in: VertexOut) {
    let at = SurfaceAttributes(in.uv, dpdxFine(in.uv), dpdyFine(in.uv), in.normal, false, in.tangent, in.color);
    if !alpha_keeps(material_alpha(at), dither_threshold(vec2<u32>(in.clip.xy))) {
        discard;
    }
}
