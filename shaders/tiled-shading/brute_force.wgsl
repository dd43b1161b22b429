// #import gbuffer/frame.wgsl
// #import gbuffer/normal_encoding.wgsl
// #import tiled-shading/lighting.wgsl
// Brute force: light accumulation (Ishmukhametov 2013 §1.3 step 3) of every light at every
// pixel, diffuse and specular into two accumulation buffers — the baseline of the tiled
// methods. Twin of `tiled_shading::cpu::shade` with `Method::BruteForce`.

struct Params {
    light_count: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
};

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<uniform> params: Params;
@group(0) @binding(2) var<storage, read> lights: array<Light>;
@group(0) @binding(3) var linear_depth_texture: texture_2d<f32>;
@group(0) @binding(4) var normal_texture: texture_2d<u32>;
@group(0) @binding(5) var albedo_texture: texture_2d<f32>;
@group(0) @binding(6) var material_texture: texture_2d<u32>;
@group(0) @binding(7) var diffuse_out: texture_storage_2d<rgba32float, write>;
@group(0) @binding(8) var specular_out: texture_storage_2d<rgba32float, write>;

@compute @workgroup_size(8, 8)
fn brute_force(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = textureDimensions(linear_depth_texture);
    if id.x >= size.x || id.y >= size.y { return; }
    let pixel = id.xy;
    let depth = textureLoad(linear_depth_texture, pixel, 0).x;
    var diffuse = vec3<f32>(0.0);
    var specular = vec3<f32>(0.0);
    if depth > 0.0 {
        let p = position_from_view_ray(frame, pixel, depth);
        let n = decode_octahedral_snorm(unpack2x16snorm(textureLoad(normal_texture, pixel, 0).x));
        let v = normalize(frame.eye.xyz - p);
        let albedo = textureLoad(albedo_texture, pixel, 0).rgb;
        let word = textureLoad(material_texture, pixel, 0).x;
        let roughness = f32(word & 0xffu) / 255.0;
        let metallic = f32((word >> 8u) & 0xffu) / 255.0;
        for (var i = 0u; i < params.light_count; i++) {
            let c = shade_light(lights[i], p, n, v, albedo, roughness, metallic);
            diffuse += c.diffuse;
            specular += c.specular;
        }
    }
    textureStore(diffuse_out, pixel, vec4<f32>(diffuse, 0.0));
    textureStore(specular_out, pixel, vec4<f32>(specular, 0.0));
}
