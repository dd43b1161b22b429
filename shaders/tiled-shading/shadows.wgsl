// Shadow-map lookup of the direct lights; mirrors `tiled_shading::shadows` (same names).
// A light owns `shadow_count` views from `shadow_first` (one depth-array layer each). The
// receiver moves `normal_offset` texels of its footprint along its normal, is projected into
// the view that holds it (the cube face of the largest axis; the first cascade containing it),
// and a 3×3 tent (bilinear taps at −1, 0, +1 texel: weights (1−f, 1, 1, f)/3 per axis over
// 4×4 texels, four gathers) counts the texels whose linear depth + `bias` texels + the
// receiver's slope tolerance (`slope_texels`) is not in front of the receiver.
// A light whose `shadow_count` carries `PARABOLOID_SHADOW` instead owns (count & 0xff)
// paraboloid views of the ManyLoD atlas from tile `shadow_first` (Holländer 2013 §3.6 for many
// lights): one around a spot's or hemispherical light's direction, two (±y) for a point light;
// the receiver is looked up in the one facing it, or at the seam of a pair in the other
// (`manylod/lookup.wgsl`, one texel).
// A light whose `shadow_count` is `RAY_SHADOW` casts a ray per receiver through the scene's
// BVH (`rays.wgsl`; `tiled_shading::rays::RayShadows`): to its position, or towards a
// directional light for `ray_params.reach`, from the receiver lifted along its normal by
// `ray_lift` (× `ray_params.offset`, 1).
// #import tiled-shading/lighting.wgsl
// #import tiled-shading/rays.wgsl
// #import tiled-shading/shadow_view.wgsl
// #import manylod/lookup.wgsl

struct ShadowParams {
    bias: f32,
    normal_offset: f32,
    _pad0: f32,
    _pad1: f32,
};

// Group SHADOW_GROUP (1; the Forward+ pass sets 3, and RAY_GROUP with it): the shadow maps
// (`tiled_shading::gpu::shadows`); a 1×1 stand-in when no light has shadows.
const SHADOW_GROUP: u32 = 1u;
@group(SHADOW_GROUP) @binding(0) var<storage, read> shadow_views: array<ShadowView>;
@group(SHADOW_GROUP) @binding(1) var<uniform> shadow_params: ShadowParams;
@group(SHADOW_GROUP) @binding(2) var shadow_maps: texture_depth_2d_array;
@group(SHADOW_GROUP) @binding(3) var shadow_sampler: sampler;
// The ManyLoD atlas of the lights with paraboloid shadows (a stand-in without them).
@group(SHADOW_GROUP) @binding(4) var<storage, read> atlas: array<u32>;
@group(SHADOW_GROUP) @binding(5) var<uniform> atlas_params: AtlasParams;
// The scene's BVH for the lights with ray shadows (stand-ins without them): nodes and
// triangles at bindings 6 and 7 (`rays.wgsl`), and:
@group(SHADOW_GROUP) @binding(8) var<uniform> ray_params: RayParams;

struct RayParams {
    offset: f32,
    reach: f32,
    _pad0: f32,
    _pad1: f32,
};

const PARABOLOID_SHADOW: u32 = 0x80000000u;
const RAY_SHADOW: u32 = 0x40000000u;

// Whether p (normal n) sees `light` along a ray through the BVH: 1 or 0.
fn ray_shadow(light: Light, p: vec3<f32>, n: vec3<f32>) -> f32 {
    let origin = p + n * (ray_params.offset * ray_lift(p));
    var to = light.position - origin;
    if light.kind == LIGHT_DIRECTIONAL {
        to = -light.direction * ray_params.reach;
    }
    return select(1.0, 0.0, occluded(origin, to));
}

// The axis of paraboloid view `k` (0 or 1) of `light` (`tiled_shading::shadows::paraboloid_views`).
fn paraboloid_axis(light: Light, k: u32) -> vec3<f32> {
    if light.kind == LIGHT_POINT {
        return select(vec3<f32>(0.0, 1.0, 0.0), vec3<f32>(0.0, -1.0, 0.0), k == 1u);
    }
    return select(light.direction, -light.direction, k == 1u);
}

// Visibility of p (normal n) from `light` through its paraboloid views.
fn paraboloid_visibility(light: Light, p: vec3<f32>, n: vec3<f32>) -> f32 {
    let count = light.shadow_count & 0xffu;
    var k = 0u;
    if count == 2u && dot(p - light.position, paraboloid_axis(light, 0u)) < 0.0 {
        k = 1u;
    }
    var t = atlas_texel(atlas_params, light.shadow_first + k, light.position, paraboloid_axis(light, k), p, n);
    // At a pair's seam the normal offset may carry the receiver over to the other view.
    if t.index == NO_TEXEL && count == 2u {
        k = 1u - k;
        t = atlas_texel(atlas_params, light.shadow_first + k, light.position, paraboloid_axis(light, k), p, n);
    }
    if t.index == NO_TEXEL {
        return 0.0;
    }
    return atlas_test(t, atlas[t.index]);
}

// Texels kept around every cube face and cascade (`MARGIN_TEXELS`).
const MARGIN_TEXELS: f32 = 2.0;

// Index among the light's views of the one that holds `p`.
fn pick_shadow_view(light: Light, p: vec3<f32>, resolution: f32) -> u32 {
    if light.kind == LIGHT_DIRECTIONAL {
        let inner = 1.0 - 2.0 * MARGIN_TEXELS / resolution;
        for (var k = 0u; k < light.shadow_count; k++) {
            let c = shadow_views[light.shadow_first + k].view_proj * vec4<f32>(p, 1.0);
            if abs(c.x) <= inner && abs(c.y) <= inner {
                return k;
            }
        }
        return light.shadow_count - 1u;
    }
    let w = p - light.position;
    var best = 0u;
    var best_dot = dot(w, shadow_views[light.shadow_first].axis);
    for (var k = 1u; k < light.shadow_count; k++) {
        let d = dot(w, shadow_views[light.shadow_first + k].axis);
        if d > best_dot {
            best = k;
            best_dot = d;
        }
    }
    return best;
}

// The tolerance a tilted receiver needs (`tiled_shading::shadows::slope_texels`): its plane
// moves tan θ texels of depth per texel across the map (θ between n and the light), and the
// tent reaches 2 texels from the receiver; at most `MAX_SLOPE_TEXELS`.
const MAX_SLOPE_TEXELS: f32 = 6.0;

fn slope_texels(light: Light, p: vec3<f32>, n: vec3<f32>) -> f32 {
    let c = clamp(dot(n, light_incidence(light, p).xyz), 1e-3, 1.0);
    return min(2.0 * sqrt(1.0 - c * c) / c, MAX_SLOPE_TEXELS);
}

fn shadow_visibility(light: Light, p: vec3<f32>, n: vec3<f32>) -> f32 {
    if light.shadow_count == 0u {
        return 1.0;
    }
    if light.shadow_count == RAY_SHADOW {
        return ray_shadow(light, p, n);
    }
    if (light.shadow_count & PARABOLOID_SHADOW) != 0u {
        return paraboloid_visibility(light, p, n);
    }
    let res = textureDimensions(shadow_maps).x;
    let resolution = f32(res);
    let layer = light.shadow_first + pick_shadow_view(light, p, resolution);
    let v = shadow_views[layer];
    var distance = 1.0;
    if v.orthographic == 0u {
        distance = max(dot(p - light.position, v.axis), 0.0);
    }
    let footprint = v.texel * distance;
    let q = p + n * (shadow_params.normal_offset * footprint);
    let clip = v.view_proj * vec4<f32>(q, 1.0);
    if clip.w <= 0.0 {
        return 1.0;
    }
    let ndc = clip.xyz / clip.w;
    let receiver = linear_shadow_depth(v, clamp(ndc.z, 0.0, 1.0)) - (shadow_params.bias + slope_texels(light, p, n)) * footprint;
    let xy = vec2<f32>(ndc.x * 0.5 + 0.5, 0.5 - ndc.y * 0.5) * resolution - 0.5;
    let b = floor(xy);
    let f = xy - b;
    let wx = array<f32, 4>(1.0 - f.x, 1.0, 1.0, f.x);
    let wy = array<f32, 4>(1.0 - f.y, 1.0, 1.0, f.y);
    var lit = 0.0;
    // Texel blocks (b−1, b) and (b+1, b+2) per axis; a gather at the corner between texels
    // i and i+1 reads (x: (i, j+1), y: (i+1, j+1), z: (i+1, j), w: (i, j)), clamped to the edge.
    for (var bj = 0; bj < 2; bj++) {
        for (var bi = 0; bi < 2; bi++) {
            let corner = (b + vec2<f32>(f32(2 * bi), f32(2 * bj))) / resolution;
            let d = textureGather(shadow_maps, shadow_sampler, corner, layer);
            let i = 2 * bi;
            let j = 2 * bj;
            let z = vec4<f32>(
                linear_shadow_depth(v, d.x),
                linear_shadow_depth(v, d.y),
                linear_shadow_depth(v, d.z),
                linear_shadow_depth(v, d.w),
            );
            let inside = vec4<f32>(vec4<bool>(receiver <= z.x, receiver <= z.y, receiver <= z.z, receiver <= z.w));
            lit += inside.w * wx[i] * wy[j] + inside.z * wx[i + 1] * wy[j]
                + inside.x * wx[i] * wy[j + 1] + inside.y * wx[i + 1] * wy[j + 1];
        }
    }
    return min(lit / 9.0, 1.0);
}

// `shade_light` with the light's shadow (`tiled_shading::shadows::shade_shadowed`): the
// lookup runs only where the light reaches the surface's front.
fn shade_shadowed(light: Light, p: vec3<f32>, n: vec3<f32>, v: vec3<f32>, albedo: vec3<f32>, roughness: f32, metallic: f32, specular: f32) -> Accumulated {
    var none: Accumulated;
    none.diffuse = vec3<f32>(0.0);
    none.specular = vec3<f32>(0.0);
    let inc = light_incidence(light, p);
    if inc.w <= 0.0 || dot(n, inc.xyz) <= 0.0 {
        return none;
    }
    let visible = shadow_visibility(light, p, n);
    if visible <= 0.0 {
        return none;
    }
    return reflect_light(light.color * (inc.w * visible), inc.xyz, n, v, albedo, roughness, metallic, specular);
}
