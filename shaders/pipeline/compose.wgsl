// The composition of one G-buffer sample (Ishmukhametov 2013 §1.3 step 4; Segovia 2006
// Figure 3g): albedo × (1 − metallic) × (direct diffuse + occlusion × (ambient + indirect
// diffuse)) + direct specular + occlusion × indirect specular + emission. The material's
// ambient occlusion (the emission target's alpha, glTF §3.9.4) scales the light that does not
// come straight from the lights. Where the material word is `NO_MATERIAL` (no surface): 0.
// Shared by `composition.wgsl` (one sample per pixel) and `supersampling.wgsl` (every sample
// of a supersampled G-buffer); twin of `pipeline::cpu::composition`.
fn compose(
    albedo: vec3<f32>,
    word: u32,
    emission: vec4<f32>,
    direct: array<vec3<f32>, 2>,
    indirect: array<vec3<f32>, 2>,
    ambient: vec3<f32>,
) -> vec4<f32> {
    if word == 0xffffffffu {
        return vec4<f32>(0.0);
    }
    let metallic = f32((word >> 8u) & 0xffu) / 255.0;
    let occlusion = emission.a;
    let diffuse = direct[0] + occlusion * (ambient + indirect[0]);
    let specular = direct[1] + occlusion * indirect[1];
    return vec4<f32>(albedo * (1.0 - metallic) * diffuse + specular + emission.rgb, 1.0);
}
