// Composition (Ishmukhametov 2013 §1.3 step 4; Segovia 2006 Figure 3g): albedo × (ambient +
// diffuse + indirect diffuse) + specular + indirect specular, plus the emitted radiance of the
// G-buffer's emission target. The albedo multiplies the indirect light only here, after its
// blur. The VPLs' near field (`instant_radiosity::near_field`, zero when not set) is indirect
// diffuse light too. The material's ambient occlusion (the emission target's alpha, glTF
// §3.9.4) scales the light that does not come straight from the lights: ambient, indirect
// diffuse and specular. Twin of `pipeline::cpu::composition` (whose indirect diffuse image
// holds the near field).

struct CompositionParams {
    ambient: vec4<f32>,
};

@group(0) @binding(0) var<uniform> composition: CompositionParams;
@group(0) @binding(1) var emission_in: texture_2d<f32>;
@group(0) @binding(2) var albedo_in: texture_2d<f32>;
@group(0) @binding(3) var material_in: texture_2d<u32>;
@group(0) @binding(4) var diffuse_in: texture_2d<f32>;
@group(0) @binding(5) var specular_in: texture_2d<f32>;
@group(0) @binding(6) var radiance_out: texture_storage_2d<rgba32float, write>;
@group(0) @binding(7) var indirect_diffuse_in: texture_2d<f32>;
@group(0) @binding(8) var indirect_specular_in: texture_2d<f32>;
@group(0) @binding(9) var near_field_in: texture_2d<f32>;

@compute @workgroup_size(8, 8)
fn composition_main(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = textureDimensions(albedo_in);
    if id.x >= size.x || id.y >= size.y { return; }
    let pixel = id.xy;
    let word = textureLoad(material_in, pixel, 0).x;
    var out = vec4<f32>(0.0);
    if word != 0xffffffffu {
        let albedo = textureLoad(albedo_in, pixel, 0).rgb;
        let metallic = f32((word >> 8u) & 0xffu) / 255.0;
        let emission = textureLoad(emission_in, pixel, 0);
        let occlusion = emission.a;
        let indirect_diffuse = textureLoad(indirect_diffuse_in, pixel, 0).rgb + textureLoad(near_field_in, pixel, 0).rgb;
        let diffuse = textureLoad(diffuse_in, pixel, 0).rgb + occlusion * (composition.ambient.rgb + indirect_diffuse);
        let specular = textureLoad(specular_in, pixel, 0).rgb + occlusion * textureLoad(indirect_specular_in, pixel, 0).rgb;
        out = vec4<f32>(albedo * (1.0 - metallic) * diffuse + specular + emission.rgb, 1.0);
    }
    textureStore(radiance_out, pixel, out);
}
