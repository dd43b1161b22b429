// #import gbuffer/frame.wgsl
// #import gbuffer/normal_encoding.wgsl
// #import tiled-shading/lighting.wgsl
// Adaptive supersampling for deferred anti-aliasing (Holländer 2013 §4.3, Listing 4.1): what
// every stage shares — parameters, bindings, the window order and the shading of one sample.
// Mirrors `adaptive_ssaa::cpu` function for function. The image is width × height pixels;
// pixel p's sampling window is the G-buffer samples p·m + (0..m)², visited in the order of an
// ordered-dither index matrix (`params.order`, §4.3.2).

struct Params {
    width: u32,
    height: u32,
    m: u32,
    n: u32,
    // 0 none, 1 MM, 2 NC, 3 DV, 4 NV, 5 ND
    metric: u32,
    shading_on: u32,
    min_samples: u32,
    stall: u32,
    c_mm: f32,
    c_nc: f32,
    c_dv: f32,
    c_nv: f32,
    c_shading: f32,
    min_threshold: f32,
    edge_threshold: f32,
    far: f32,
    ambient: vec3<f32>,
    light_count: u32,
    background: vec3<f32>,
    // Always 0: offsets the lights by r·zero in the stall loop so the repetitions cannot be
    // folded away.
    zero: f32,
    // Sample i of the window is cell (order[i] & 0xff, order[i] >> 8).
    order: array<vec4<u32>, 16>,
};

// A material as the shading reads it (`adaptive_ssaa::SsaaMaterial`): the factors and the
// array layers (0: white) of the two textures looked up per sample, both at the stored
// coordinates.
struct SsaaMaterial {
    // Linear base colour factor; alpha: the specular factor.
    base_color: vec4<f32>,
    emissive: vec3<f32>,
    base_layer: u32,
    emissive_layer: u32,
};

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<uniform> params: Params;
@group(0) @binding(2) var linear_depth_tex: texture_2d<f32>;
@group(0) @binding(3) var normal_tex: texture_2d<u32>;
@group(0) @binding(4) var uv_tex: texture_2d<f32>;
@group(0) @binding(5) var uv_grad_tex: texture_2d<f32>;
@group(0) @binding(6) var material_tex: texture_2d<u32>;
@group(0) @binding(7) var textures: texture_2d_array<f32>;
@group(0) @binding(8) var texture_sampler: sampler;
@group(0) @binding(9) var<storage, read> materials: array<SsaaMaterial>;
@group(0) @binding(10) var<storage, read> lights: array<Light>;
// S, the first sample per pixel.
@group(0) @binding(11) var<storage, read_write> first: array<vec4<f32>>;
@group(0) @binding(12) var<storage, read_write> counts: array<u32>;
@group(0) @binding(13) var<storage, read_write> out_image: array<vec4<f32>>;
// Counting sort by sample count: [0, 65) histogram, [65, 130) cursors, [130] total.
@group(0) @binding(14) var<storage, read_write> sort: array<atomic<u32>>;
@group(0) @binding(15) var<storage, read_write> list: array<u32>;
@group(0) @binding(16) var tint_tex: texture_2d<u32>;

const NO_MATERIAL: u32 = 0xffffffffu;
const HISTOGRAM: u32 = 0u;
const CURSORS: u32 = 65u;
const TOTAL: u32 = 130u;
const LUMINANCE: vec3<f32> = vec3<f32>(0.2126, 0.7152, 0.0722);

fn window_sample(p: vec2<u32>, i: u32) -> vec2<u32> {
    let c = params.order[i / 4u][i % 4u];
    return p * params.m + vec2<u32>(c & 0xffu, c >> 8u);
}

// The footprint of one of k samples averaged over a pixel, in sample steps: m / √k.
fn footprint_scale(k: u32) -> f32 {
    return f32(params.m) / sqrt(f32(k));
}

// Layer `layer` of the array at the sample's coordinates, filtered over the derivatives
// `grad` (du/dx, dv/dx, du/dy, dv/dy); layer 0 is white and not sampled (a mesh without
// texture coordinates has zero derivatives, which llvmpipe's anisotropic filter never
// finishes).
fn read_array(layer: u32, uv: vec2<f32>, grad: vec4<f32>) -> vec4<f32> {
    if layer == 0u {
        return vec4<f32>(1.0);
    }
    return textureSampleGrad(textures, texture_sampler, uv, layer, grad.xy, grad.zw);
}

// Shades G-buffer sample q (§4.3.4): base colour and emission looked up in the array with the
// stored derivatives × scale, every light (params.stall times), ambient × occlusion and
// emission.
fn shade_sample(q: vec2<u32>, scale: f32) -> vec3<f32> {
    let depth = textureLoad(linear_depth_tex, q, 0).r;
    let word = textureLoad(material_tex, q, 0).r;
    if depth <= 0.0 || word == NO_MATERIAL {
        return params.background;
    }
    let id = word >> 16u;
    if id >= arrayLength(&materials) {
        return params.background;
    }
    let n = decode_octahedral_snorm(unpack2x16snorm(textureLoad(normal_tex, q, 0).r));
    let roughness = f32(word & 0xffu) / 255.0;
    let metallic = f32((word >> 8u) & 0xffu) / 255.0;
    let material = materials[id];
    let grad = textureLoad(uv_grad_tex, q, 0) * scale;
    let uv = textureLoad(uv_tex, q, 0).xy;
    let tint = unpack4x8unorm(textureLoad(tint_tex, q, 0).r);
    // The vertex colour, stored as its square root (`unpack_tint`).
    let color = tint.rgb * tint.rgb;
    let texel = read_array(material.base_layer, uv, grad);
    let albedo = clamp(material.base_color.rgb * color * texel.rgb, vec3<f32>(0.0), vec3<f32>(1.0));
    let emission = material.emissive * read_array(material.emissive_layer, uv, grad).rgb;
    let p = position_from_view_ray(frame, q, depth);
    let v = normalize(frame.eye.xyz - p);
    var diffuse = vec3<f32>(0.0);
    var specular = vec3<f32>(0.0);
    for (var r = 0u; r < params.stall; r++) {
        diffuse = vec3<f32>(0.0);
        specular = vec3<f32>(0.0);
        let jitter = vec3<f32>(f32(r) * params.zero);
        for (var i = 0u; i < params.light_count; i++) {
            var light = lights[i];
            light.position += jitter;
            let a = shade_light(light, p, n, v, albedo, roughness, metallic, material.base_color.a);
            diffuse += a.diffuse;
            specular += a.specular;
        }
    }
    return albedo * (1.0 - metallic) * (params.ambient * tint.a + diffuse) + specular + emission;
}

fn pixel_index(p: vec2<u32>) -> u32 {
    return p.y * params.width + p.x;
}

fn in_image(p: vec2<u32>) -> bool {
    return p.x < params.width && p.y < params.height;
}

// Samples of pixel i from `evaluate`, clamped to 1..=n.
fn pixel_samples(i: u32) -> u32 {
    return clamp(counts[i], 1u, params.n);
}

// Samples of pixel i; a pixel of one sample takes S as its output here (Listing 4.1: those
// pixels are done after the first sample).
fn samples_or_first(i: u32) -> u32 {
    let k = pixel_samples(i);
    if k == 1u {
        out_image[i] = first[i];
    }
    return k;
}


// Average of the first k samples of p's window in dither order.
fn average_samples(p: vec2<u32>, k: u32) -> vec4<f32> {
    let scale = footprint_scale(k);
    var sum = vec3<f32>(0.0);
    for (var i = 0u; i < k; i++) {
        sum += shade_sample(window_sample(p, i), scale);
    }
    return vec4<f32>(sum / f32(k), 1.0);
}
