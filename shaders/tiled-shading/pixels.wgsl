// The light accumulation's inputs shared by its compute passes (`tiled.wgsl`) and its light
// volumes (`volumes.wgsl`): the frame, the parameters, the lights and the G-buffer at group 0,
// bindings 0–6, and the per-pixel reads of the G-buffer.
// #import gbuffer/frame.wgsl
// #import gbuffer/normal_encoding.wgsl
// #import tiled-shading/lighting.wgsl
// #import tiled-shading/params.wgsl
// #import tiled-shading/shadows.wgsl

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<uniform> params: Params;
@group(0) @binding(2) var<storage, read> lights: array<Light>;
@group(0) @binding(3) var linear_depth_texture: texture_2d<f32>;
@group(0) @binding(4) var normal_texture: texture_2d<u32>;
@group(0) @binding(5) var albedo_texture: texture_2d<f32>;
@group(0) @binding(6) var material_texture: texture_2d<u32>;

// A pixel of the G-buffer: its world position and view depth, its normal (absent: background).
struct Sample {
    position: vec3<f32>,
    depth: f32,
    normal: vec3<f32>,
    present: bool,
};

fn load_sample(pixel: vec2<u32>, size: vec2<u32>) -> Sample {
    var s: Sample;
    s.present = false;
    if pixel.x >= size.x || pixel.y >= size.y {
        return s;
    }
    let depth = textureLoad(linear_depth_texture, pixel, 0).x;
    if depth <= 0.0 {
        return s;
    }
    s.present = true;
    s.position = position_from_view_ray(frame, pixel, depth);
    s.depth = depth;
    s.normal = decode_octahedral_snorm(unpack2x16snorm(textureLoad(normal_texture, pixel, 0).x));
    return s;
}

// Albedo, roughness and metallic of a pixel (`gbuffer::pack_material`'s word), and the
// specular factor (the albedo's alpha).
struct SurfaceMaterial {
    albedo: vec3<f32>,
    roughness: f32,
    metallic: f32,
    specular: f32,
};

fn load_material(pixel: vec2<u32>) -> SurfaceMaterial {
    let word = textureLoad(material_texture, pixel, 0).x;
    let albedo = textureLoad(albedo_texture, pixel, 0);
    return SurfaceMaterial(
        albedo.rgb,
        f32(word & 0xffu) / 255.0,
        f32((word >> 8u) & 0xffu) / 255.0,
        albedo.a,
    );
}

// A surface pixel ready for its light loop: its sample, direction to the eye and material.
struct LitPixel {
    s: Sample,
    v: vec3<f32>,
    m: SurfaceMaterial,
};

fn lit_pixel(s: Sample, pixel: vec2<u32>) -> LitPixel {
    return LitPixel(s, normalize(frame.eye.xyz - s.position), load_material(pixel));
}

// `sum` plus `light`'s shadowed contribution at `p` (`shade_shadowed`).
fn add_light(sum: Accumulated, light: Light, p: LitPixel) -> Accumulated {
    let c = shade_shadowed(light, p.s.position, p.s.normal, p.v, p.m.albedo, p.m.roughness, p.m.metallic, p.m.specular);
    return Accumulated(sum.diffuse + c.diffuse, sum.specular + c.specular);
}
