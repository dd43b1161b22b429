// Reflection maps through many-view cuts (Holländer 2013 §3.6.1, Fig. 3.19). `resolve`: after
// the probes' views were cut and splatted with nearest nodes (`manylod/nearest.wgsl`), every
// map texel takes its nearest node's exit radiance (zero where none). `reflect`: every pixel
// of a mirror or glass material mirrors its view ray about its normal and reads the
// dual-paraboloid map of the nearest probe of its material; Schlick's Fresnel F times that
// radiance is its reflection, and glass adds (1 − F) · transmission · tint times the map along
// the view ray refracted into it. Mirrors `instant_radiosity::reflections::{LitPoints::reflection_maps, reflect}`.
// #import gbuffer/frame.wgsl
// #import gbuffer/normal_encoding.wgsl
// #import manylod/common.wgsl

struct Maps {
    // Atlas row length in texels.
    width: u32,
    tile: u32,
    columns: u32,
    views: u32,
}

struct Reflect {
    tile: u32,
    // Entries of `probe_materials` (the scene's materials).
    materials: u32,
    pad0: u32,
    pad1: u32,
}

@group(0) @binding(0) var<uniform> maps_params: Maps;
@group(0) @binding(1) var<storage, read> ids: array<u32>;
@group(0) @binding(2) var<storage, read> radiance: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read_write> maps_out: array<vec4<f32>>;

@group(0) @binding(4) var<uniform> frame: Frame;
@group(0) @binding(5) var<uniform> params: Reflect;
@group(0) @binding(6) var linear_depth: texture_2d<f32>;
@group(0) @binding(7) var normals: texture_2d<u32>;
@group(0) @binding(8) var albedo_in: texture_2d<f32>;
@group(0) @binding(9) var material_in: texture_2d<u32>;
// `reflections::ProbeMaterial`: a material's probes and what glass transmits.
struct ProbeMaterial {
    first: u32,
    count: u32,
    transmission: f32,
    ior: f32,
    tint: vec4<f32>,
}

// Probe centres (xyz), material by material.
@group(0) @binding(10) var<storage, read> centers: array<vec4<f32>>;
@group(0) @binding(11) var<storage, read> probe_materials: array<ProbeMaterial>;
@group(0) @binding(12) var reflection_out: texture_storage_2d<rgba16float, write>;
@group(0) @binding(13) var<storage, read> maps: array<vec4<f32>>;

// `manylod::splat::NO_NODE`.
const NO_NODE: u32 = 0xFFFFFFFFu;
const NO_MATERIAL: u32 = 0xFFFFFFFFu;

@compute @workgroup_size(256)
fn resolve(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = gid.x + gid.y * groups.x * 256u;
    let tile = maps_params.tile;
    let per_view = tile * tile;
    if i >= maps_params.views * per_view {
        return;
    }
    let v = i / per_view;
    let t = i % per_view;
    let p = vec2<u32>(v % maps_params.columns, v / maps_params.columns) * tile + vec2<u32>(t % tile, t / tile);
    let node = ids[p.y * maps_params.width + p.x];
    var r = vec4<f32>(0.0);
    if node != NO_NODE {
        r = vec4<f32>(radiance[node].rgb, 0.0);
    }
    maps_out[i] = r;
}

// Probe `probe`'s radiance in unit direction `d` (`reflections::map_lookup`): the view around
// +Y or −Y that holds it, its paraboloid texel.
fn map_lookup(probe: u32, d: vec3<f32>) -> vec3<f32> {
    let tile = params.tile;
    let half = select(0u, 1u, d.y < 0.0);
    let normal = select(vec3<f32>(0.0, 1.0, 0.0), vec3<f32>(0.0, -1.0, 0.0), half == 1u);
    let tb = paraboloid_frame(normal);
    let z = max(dot(d, normal), 0.0);
    let uv = vec2<f32>(dot(d, tb[0]), dot(d, tb[1])) / (1.0 + z);
    let last = f32(tile) - 1.0;
    let texel = vec2<u32>(clamp(floor((uv * 0.5 + 0.5) * f32(tile)), vec2<f32>(0.0), vec2<f32>(last)));
    return maps[(2u * probe + half) * tile * tile + texel.y * tile + texel.x].rgb;
}

@compute @workgroup_size(8, 8)
fn reflect(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = vec2<u32>(frame.viewport.xy);
    if any(id.xy >= size) {
        return;
    }
    var out = vec3<f32>(0.0);
    let depth = textureLoad(linear_depth, id.xy, 0).x;
    let word = textureLoad(material_in, id.xy, 0).x;
    let material = word >> 16u;
    if depth > 0.0 && word != NO_MATERIAL && material < params.materials && probe_materials[material].count > 0u {
        let m = probe_materials[material];
        let p = position_from_view_ray(frame, id.xy, depth);
        var best = m.first;
        var best_d = 3.4e38;
        for (var k = m.first; k < m.first + m.count; k++) {
            let o = centers[k].xyz - p;
            let d = dot(o, o);
            if d < best_d {
                best_d = d;
                best = k;
            }
        }
        let n = decode_octahedral_snorm(unpack2x16snorm(textureLoad(normals, id.xy, 0).x));
        let v = normalize(frame.eye.xyz - p);
        let r = normalize(2.0 * dot(n, v) * n - v);
        let a = textureLoad(albedo_in, id.xy, 0);
        let metallic = f32((word >> 8u) & 0xffu) / 255.0;
        let q = (m.ior - 1.0) / (m.ior + 1.0);
        let dielectric = q * q * a.a;
        let f0 = mix(vec3<f32>(dielectric), a.rgb, metallic);
        let f = f0 + (1.0 - f0) * pow(1.0 - clamp(dot(n, v), 0.0, 1.0), 5.0);
        out = f * map_lookup(best, r);
        let t = refract(-v, n, 1.0 / m.ior);
        if m.transmission > 0.0 && any(t != vec3<f32>(0.0)) {
            out += (1.0 - f) * m.transmission * m.tint.rgb * map_lookup(best, t);
        }
    }
    textureStore(reflection_out, id.xy, vec4<f32>(out, 1.0));
}
