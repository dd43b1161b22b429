// #import gbuffer/gbuffer.wgsl
// #import tiled-shading/lighting.wgsl
// The light pre-pass's second geometry pass (Ishmukhametov 2013 §2.1 after Engel 2008): the
// scene drawn again after the depth pre-pass (depth `Equal`), each fragment applying its
// material to the light buffer the lighting pass wrote (`tiled.wgsl`, METHOD_PREPASS): the
// diffuse light as it is, and the monochrome specular light times the Fresnel factor at N·V
// (the lighting pass had no material: F at each light's V·H is not known) tinted by the
// chromaticity of the diffuse light (Engel 2009) — exact for white lights on materials whose F
// does not vary (no specular, or white metals), an approximation elsewhere. It writes what
// the deferred methods write, the direct diffuse and specular accumulation.

@group(2) @binding(0) var light_buffer: texture_2d<f32>;

struct PrePassOut {
    @location(0) diffuse: vec4<f32>,
    @location(1) specular: vec4<f32>,
};

@fragment
fn fs_light_prepass(in: VertexOut) -> PrePassOut {
    let m = surface_fragment(in).m;
    let light = textureLoad(light_buffer, vec2<u32>(in.clip.xy), 0);
    let n_dot_v = clamp(dot(m.normal, normalize(in.to_eye)), 0.0, 1.0);
    let fw = pow(1.0 - n_dot_v, 5.0);
    let specular = clamp(material.specular, 0.0, 1.0);
    let f = mix(vec3<f32>(specular * (0.04 + 0.96 * fw)), m.albedo + (vec3<f32>(1.0) - m.albedo) * fw, m.metallic);
    let lum = luminance(light.rgb);
    let chroma = select(vec3<f32>(1.0), light.rgb / lum, lum > 0.0);
    return PrePassOut(vec4<f32>(light.rgb, 0.0), vec4<f32>(f * light.a * chroma, 0.0));
}
