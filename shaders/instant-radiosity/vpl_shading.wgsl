// #import gbuffer/frame.wgsl
// #import gbuffer/normal_encoding.wgsl
// #import tiled-shading/lighting.wgsl
// #import manylod/lookup.wgsl
// #import interleave/pattern.wgsl
// #import tiled-shading/rays.wgsl
// #import instant-radiosity/vpl.wgsl
// SNSM — shading with no shadow map (Segovia 2006 §4.3, §6.2): each pixel sums the diffuse and
// glossy light reflected from the hemispherical VPLs of its subset, visibility ignored. Twin of
// `instant_radiosity::cpu::shade_vpls`.
//
// A VPL of flux Φ at q with normal n_q lights p with intensity Φ/π · max(n_q·(p − q)/d, 0)
// / max(d², clamp²): the clamp bounds the 1/d² singularity of VPLs close to the receiver.
// The domain is the split layout: invocation (x, y) is texel (x mod sub_width, y mod sub_height)
// of sub-buffer (i, j) = (x div sub_width, y div sub_height), the image pixel
// ((x mod sub_width)·n + i, (y mod sub_height)·m + j), and shades subset j·n + i, scaled by
// `scale` (the subset count: one subset estimates the whole set). n = m = 1 is the reference.
//   shade_split: reads the split G-buffer at (x, y), writes split irradiance at (x, y) (BS/BG around it);
//   shade_fused: reads the G-buffer and writes the irradiance at the image pixel (no BS/BG).
//
// With VPL shadow maps (`atlas_params.enabled`, Holländer 2013 §3.6 SSM mode), VPL k's light is
// multiplied by its visibility: p is looked up in micro-view k of the ManyLoDs / ISM atlas
// (paraboloid around the VPL normal, `manylod::View::splat`'s projection). With rays
// (`ray_offset` > 0) it is instead 0 when a triangle of `ray_nodes`/`ray_triangles` lies between
// p and the VPL, each lifted off its surface by `ray_offset` × `ray_lift` (`tiled_shading::rays`).

struct ShadingParams {
    per_subset: u32,
    scale: f32,
    clamp_squared: f32,
    ray_offset: f32,
};

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<uniform> params: ShadingParams;
@group(0) @binding(2) var<storage, read> vpls: array<Vpl>;
@group(0) @binding(3) var linear_depth: texture_2d<f32>;
@group(0) @binding(4) var normals: texture_2d<u32>;
@group(0) @binding(5) var albedos: texture_2d<f32>;
@group(0) @binding(6) var materials: texture_2d<u32>;
@group(0) @binding(7) var diffuse_out: texture_storage_2d<rgba16float, write>;
@group(0) @binding(8) var specular_out: texture_storage_2d<rgba16float, write>;

// The VPL shadow maps (`manylod/lookup.wgsl`'s atlas; `manylod::lookup::AtlasParams`).
@group(0) @binding(9) var<storage, read> atlas: array<u32>;
@group(0) @binding(10) var<uniform> atlas_params: AtlasParams;
// The scene's BVH for visibility by rays (`tiled_shading::rays::RayBvh`): `ray_nodes` and
// `ray_triangles` of `rays.wgsl` at bindings 11 and 12 (`instant_radiosity::gpu::shading_rays`).

// Visibility of p (normal n) from VPL k: by a ray (`instant_radiosity::rays::visibility`) or
// in its atlas tile (`instant_radiosity::shadows::vpl_visibility`).
fn vpl_visibility(k: u32, vpl: Vpl, p: vec3<f32>, n: vec3<f32>) -> f32 {
    if params.ray_offset > 0.0 {
        let start = p + n * (params.ray_offset * ray_lift(p));
        let end = vpl.position + vpl.normal * (params.ray_offset * ray_lift(vpl.position));
        return select(1.0, 0.0, occluded(start, end - start));
    }
    if atlas_params.enabled == 0u {
        return 1.0;
    }
    let t = atlas_texel(atlas_params, k, vpl.position, vpl.normal, p, n);
    if t.index == NO_TEXEL {
        return 0.0;
    }
    return atlas_test(t, atlas[t.index]);
}

// Sums the subset's VPLs at G-buffer texel `texel`, which holds image pixel `pixel`, scaled.
fn shade(texel: vec2<u32>, pixel: vec2<u32>, subset: u32) -> Accumulated {
    var sum: Accumulated;
    sum.diffuse = vec3<f32>(0.0);
    sum.specular = vec3<f32>(0.0);
    let depth = textureLoad(linear_depth, texel, 0).r;
    if depth > 0.0 {
        let p = position_from_view_ray(frame, pixel, depth);
        let nrm = decode_octahedral_snorm(unpack2x16snorm(textureLoad(normals, texel, 0).x));
        let v = normalize(frame.eye.xyz - p);
        let albedo_specular = textureLoad(albedos, texel, 0);
        let albedo = albedo_specular.rgb;
        let word = textureLoad(materials, texel, 0).x;
        let roughness = f32(word & 0xffu) / 255.0;
        let metallic = f32((word >> 8u) & 0xffu) / 255.0;
        let first = subset * params.per_subset;
        for (var k = first; k < first + params.per_subset; k++) {
            var l: vec3<f32>;
            let vpl = vpls[k];
            let unoccluded = vpl_intensity(vpl, p, params.clamp_squared, &l);
            // Behind the VPL or facing away from it: nothing to add, no visibility to find.
            if all(unoccluded == vec3(0.0)) || dot(nrm, l) <= 0.0 {
                continue;
            }
            let intensity = unoccluded * vpl_visibility(k, vpl, p, nrm);
            let c = reflect_light(intensity, l, nrm, v, albedo, roughness, metallic, albedo_specular.a);
            sum.diffuse += c.diffuse;
            sum.specular += c.specular;
        }
    }
    sum.diffuse *= params.scale;
    sum.specular *= params.scale;
    return sum;
}

fn store(texel: vec2<u32>, sum: Accumulated) {
    textureStore(diffuse_out, texel, vec4<f32>(sum.diffuse, 0.0));
    textureStore(specular_out, texel, vec4<f32>(sum.specular, 0.0));
}

@compute @workgroup_size(8, 8)
fn shade_split(@builtin(global_invocation_id) id: vec3<u32>) {
    if !in_split_layout(id.xy) {
        return;
    }
    // Padding texels (pixel outside the image) hold depth 0 and get zero.
    store(id.xy, shade(id.xy, split_pixel(id.xy), split_subset(id.xy)));
}

@compute @workgroup_size(8, 8)
fn shade_fused(@builtin(global_invocation_id) id: vec3<u32>) {
    let pixel = split_pixel(id.xy);
    if !in_split_layout(id.xy) || pixel.x >= width || pixel.y >= height {
        return;
    }
    store(pixel, shade(pixel, pixel, split_subset(id.xy)));
}
