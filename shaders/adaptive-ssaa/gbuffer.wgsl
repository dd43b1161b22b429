// #import gbuffer/gbuffer.wgsl
// The supersampled G-buffer of adaptive supersampling (Holländer 2013 §4.3.3): the vertex
// stage of `gbuffer.wgsl`, but instead of albedo the fragment stage stores the texture
// coordinates and their derivatives per sample step, so the texture is looked up when a sample
// is shaded (`shade.wgsl`, §4.3.4). The material word carries the material id, whose texture
// layer the shading reads from the material table.

struct TexcoordOut {
    @location(0) linear_depth: f32,
    @location(1) normal: u32,
    @location(2) uv: vec2<f32>,
    @location(3) material: u32,
    // du/dx, dv/dx, du/dy, dv/dy (one sample step).
    @location(4) uv_grad: vec4<f32>,
};

@fragment
fn fs_texcoord(in: VertexOut) -> TexcoordOut {
    var out: TexcoordOut;
    out.linear_depth = in.view_depth;
    let n = facing_normal(in.normal, in.to_eye).normal;
    out.normal = pack2x16snorm(encode_octahedral_snorm(n));
    out.uv = in.uv.xy;
    out.uv_grad = vec4<f32>(dpdxFine(in.uv.xy), dpdyFine(in.uv.xy));
    out.material = pack_material(material.roughness, material.metallic, material.id);
    return out;
}
