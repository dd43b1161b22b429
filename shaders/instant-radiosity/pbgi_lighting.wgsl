// Point-based GI's lit surfels on the GPU (`instant_radiosity::pbgi::LitPoints::new`'s
// lighting): every leaf of the hierarchy (a surfel: centre and normal) leaves the Lambertian
// radiance ρ/π · E of its direct light by shadow rays (`light_leaves`), then every node the mean
// of its two children, one level per dispatch from the leaves up (`average`).
// #import instant-radiosity/direct.wgsl
// #import manylod/common.wgsl

struct Lighting {
    // The first node of the range and how many there are (the leaves, or one level).
    first: u32,
    count: u32,
    lights: u32,
    reach: f32,
}

@group(0) @binding(0) var<uniform> lighting: Lighting;
@group(0) @binding(1) var<storage, read> nodes: array<Node>;
// Packed linear albedo (`pack4x8unorm`) of every leaf slot's surfel.
@group(0) @binding(2) var<storage, read> leaf_albedos: array<u32>;
// 3: the lights (`direct.wgsl`); 5, 6: the scene's BVH (`rays.wgsl`, specialised).
@group(0) @binding(4) var<storage, read_write> radiance: array<vec4<f32>>;

fn index(gid: vec3<u32>, groups: vec3<u32>) -> u32 {
    return gid.x + gid.y * groups.x * 64u;
}

@compute @workgroup_size(64)
fn light_leaves(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = index(gid, groups);
    if i >= lighting.count {
        return;
    }
    let k = lighting.first + i;
    let node = nodes[k];
    let e = direct_irradiance(node.center, node.axis, lighting.lights, lighting.reach);
    radiance[k] = vec4<f32>(unpack4x8unorm(leaf_albedos[i]).rgb * e * INV_PI, 0.0);
}

@compute @workgroup_size(64)
fn average(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = index(gid, groups);
    if i >= lighting.count {
        return;
    }
    let k = lighting.first + i;
    radiance[k] = (radiance[2u * k + 1u] + radiance[2u * k + 2u]) * 0.5;
}
