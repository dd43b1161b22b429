// #import pipeline/compose.wgsl
// Composition of the frame, one sample per pixel (`compose`): albedo × (ambient + diffuse +
// indirect diffuse) + specular + indirect specular + emission. The albedo multiplies the
// indirect light only here, after its blur. The VPLs' near field (`instant_radiosity::near_field`,
// zero when not set) is indirect diffuse light too. Twin of `pipeline::cpu::composition` (whose
// indirect diffuse image holds the near field).

struct CompositionParams {
    // rgb: ambient radiance; w: 1 when `accessibility` holds screen-space ambient occlusion.
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
// Screen-space ambient occlusion per pixel (`ssao`), read where ambient.w is 1.
@group(0) @binding(10) var<storage, read> accessibility: array<f32>;

@compute @workgroup_size(8, 8)
fn composition_main(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = textureDimensions(albedo_in);
    if id.x >= size.x || id.y >= size.y { return; }
    let pixel = id.xy;
    let direct = array<vec3<f32>, 2>(textureLoad(diffuse_in, pixel, 0).rgb, textureLoad(specular_in, pixel, 0).rgb);
    let indirect_diffuse = textureLoad(indirect_diffuse_in, pixel, 0).rgb + textureLoad(near_field_in, pixel, 0).rgb;
    let indirect = array<vec3<f32>, 2>(indirect_diffuse, textureLoad(indirect_specular_in, pixel, 0).rgb);
    // The material's occlusion times the screen-space one: ambient and indirect light only.
    var emission = textureLoad(emission_in, pixel, 0);
    if composition.ambient.w > 0.5 {
        emission.a *= accessibility[pixel.y * size.x + pixel.x];
    }
    let out = compose(
        textureLoad(albedo_in, pixel, 0).rgb,
        textureLoad(material_in, pixel, 0).x,
        emission,
        direct,
        indirect,
        composition.ambient.rgb,
    );
    textureStore(radiance_out, pixel, out);
}
