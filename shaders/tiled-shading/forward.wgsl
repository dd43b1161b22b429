// #import gbuffer/gbuffer.wgsl
// #import tiled-shading/params.wgsl
// #import tiled-shading/shadows.wgsl
// Forward+ (Ishmukhametov 2013 §2.4.2 after Harada et al. 2012): the scene's geometry drawn
// again after the depth pre-pass, each fragment lit from its tile's list that the culling pass
// (`tiled.wgsl`, METHOD_FORWARD) kept in memory. The vertex stage and the material are the
// G-buffer pass's (`gbuffer.wgsl`, groups 0 and 1); group 2 holds the lists; group 3 the
// shadow lookup (SHADOW_GROUP and RAY_GROUP set to 3 by `tiled_shading::gpu::forward`).
// `fs_forward` writes an opaque surface's direct diffuse and specular into the light
// accumulation (what the deferred methods compute from the G-buffer, from the same lights);
// `fs_blended` composes an alpha-blended surface (`compose.wgsl`'s rule with the ambient
// light, without the frame's indirect light and ambient occlusion) and returns it with its
// alpha for blending over the composed frame.

const TILE: u32 = 16u;
// `tiled.wgsl`'s list entry bits.
const FORWARD_OPAQUE: u32 = 1u;
const FORWARD_BLENDED: u32 = 2u;

@group(2) @binding(0) var<uniform> params: Params;
@group(2) @binding(1) var<storage, read> lights: array<Light>;
@group(2) @binding(2) var<storage, read> counts: array<u32>;
@group(2) @binding(3) var<storage, read> lists: array<vec2<u32>>;
// The composition's ambient radiance (xyz).
@group(2) @binding(4) var<uniform> ambient: vec4<f32>;

// The direct light at the fragment from the entries of its tile's list that carry `bit`.
fn tile_light(in: VertexOut, m: MaterialSample, bit: u32) -> Accumulated {
    let tile = vec2<u32>(in.clip.xy) / TILE;
    let t = tile.y * params.tiles_x + tile.x;
    let first = t * params.list_stride;
    let n = min(counts[t], params.list_stride);
    let p = frame.eye.xyz - in.to_eye;
    let v = normalize(in.to_eye);
    let specular = clamp(material.specular, 0.0, 1.0);
    var sum: Accumulated;
    sum.diffuse = vec3<f32>(0.0);
    sum.specular = vec3<f32>(0.0);
    for (var j = 0u; j < n; j++) {
        let entry = lists[first + j];
        if (entry.y & bit) != 0u {
            let c = shade_shadowed(lights[entry.x], p, m.normal, v, m.albedo, m.roughness, m.metallic, specular);
            sum.diffuse += c.diffuse;
            sum.specular += c.specular;
        }
    }
    return sum;
}

struct ForwardOut {
    @location(0) diffuse: vec4<f32>,
    @location(1) specular: vec4<f32>,
};

@fragment
fn fs_forward(in: VertexOut) -> ForwardOut {
    let f = surface_fragment(in);
    let c = tile_light(in, f.m, FORWARD_OPAQUE);
    return ForwardOut(vec4<f32>(c.diffuse, 0.0), vec4<f32>(c.specular, 0.0));
}

@fragment
fn fs_blended(in: VertexOut) -> @location(0) vec4<f32> {
    let f = evaluate_fragment(in);
    let m = f.m;
    let c = tile_light(in, m, FORWARD_BLENDED);
    let diffuse = c.diffuse + m.occlusion * ambient.xyz;
    let radiance = m.albedo * (1.0 - m.metallic) * diffuse + c.specular + min(m.emission, vec3<f32>(HALF_MAX));
    return vec4<f32>(radiance, clamp(m.alpha, 0.0, 1.0));
}
