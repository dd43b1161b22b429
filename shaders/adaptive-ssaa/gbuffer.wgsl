// #import gbuffer/gbuffer.wgsl
// The supersampled G-buffer of adaptive supersampling (Holländer 2013 §4.3.3): the vertex
// stage of `gbuffer.wgsl` and its material (`evaluate_material` over the scene's one texture
// store: normal map, metallic-roughness, occlusion, alpha test at the sample rate), but
// instead of albedo and emission the fragment stage stores texture coordinates and their
// derivatives per sample step, so those textures are looked up when a sample is shaded, in
// the texture array (`shade.wgsl`, §4.3.4). The material word carries the material id, whose
// array layers and texture transforms the shading reads from the material table.

struct TexcoordOut {
    @location(0) linear_depth: f32,
    @location(1) normal: u32,
    // The base colour's (else the emissive texture's) coordinates, through its transform.
    @location(2) uv: vec2<f32>,
    @location(3) material: u32,
    // du/dx, dv/dx, du/dy, dv/dy (one sample step).
    @location(4) uv_grad: vec4<f32>,
    // √(vertex colour) rgb (unorm8 each) and occlusion (unorm8): `unpack_tint`.
    @location(5) tint: u32,
};

@fragment
fn fs_texcoord(in: VertexOut) -> TexcoordOut {
    let fragment = surface_fragment(in);
    let m = fragment.m;
    let uv_dx = fragment.at.uv_dx;
    let uv_dy = fragment.at.uv_dy;
    // The coordinates of the base colour texture, else of the emissive one, through its
    // transform (`adaptive_ssaa::SsaaMaterial` reads both textures at them).
    let base = material.slots[SLOT_BASE_COLOR];
    let emissive = material.slots[SLOT_EMISSIVE];
    let has_base = base.offset.w != 0.0;
    let linear = select(emissive.linear, base.linear, has_base);
    let offset = select(emissive.offset, base.offset, has_base);
    let set1 = offset.z != 0.0;
    // A material without either texture keeps its coordinates (its slots are zero, and zero
    // derivatives hang llvmpipe's anisotropic filter).
    let textured = has_base || emissive.offset.w != 0.0;
    let columns = select(vec4<f32>(1.0, 0.0, 0.0, 1.0), linear, textured);
    let transform = mat2x2<f32>(columns.xy, columns.zw);
    var out: TexcoordOut;
    out.linear_depth = in.view_depth;
    out.normal = pack2x16snorm(encode_octahedral_snorm(m.normal));
    out.uv = transform * select(in.uv.xy, in.uv.zw, set1) + offset.xy;
    // Finite in half precision (an infinite derivative at a grazing edge would become NaN
    // through a transform).
    let grad = select(vec4<f32>(uv_dx.xy, uv_dy.xy), vec4<f32>(uv_dx.zw, uv_dy.zw), set1);
    out.uv_grad = clamp(vec4<f32>(transform * grad.xy, transform * grad.zw), vec4<f32>(-HALF_MAX), vec4<f32>(HALF_MAX));
    out.material = pack_material(m.roughness, m.metallic, material.id);
    out.tint = pack4x8unorm(vec4<f32>(sqrt(clamp(in.color.rgb, vec3<f32>(0.0), vec3<f32>(1.0))), m.occlusion));
    return out;
}
