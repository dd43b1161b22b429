enable wgpu_binding_array;
// #import gbuffer/resolve.wgsl
// The resolve in one dispatch over every pixel, for devices with binding arrays of textures
// indexed by non-uniform values: each pixel reads its mesh's material from `materials` and
// that material's textures through `textures`/`samplers`, so no pixel waits for a
// classification by material and no dispatch per material is needed (the visibility-buffer
// shading of Burns & Hunt 2013 §3 with every material in reach of one kernel). The same
// texels as `resolve_material` (`evaluate_material_of` of the same material and textures).

// A material of the scene (`gbuffer::gpu::GpuMaterial`) and its five textures' entries in
// `textures` and `samplers` (base colour, metallic-roughness, normal, occlusion, emissive;
// white where it has none): `gbuffer::gpu::upload::MaterialEntry`.
struct MaterialEntry {
    material: Material,
    textures: array<u32, 5>,
    _pad: array<u32, 3>,
};

// The scene's textures (`gbuffer::gpu::MaterialTextures::all`), set per scene: sized arrays
// (an unsized binding array becomes a runtime array of descriptors in SPIR-V, which needs a
// capability naga does not declare).
const MATERIAL_TEXTURES: u32 = 1u;

// By material index.
@group(1) @binding(12) var<storage, read> materials: array<MaterialEntry>;
@group(1) @binding(14) var textures: binding_array<texture_2d<f32>, MATERIAL_TEXTURES>;
@group(1) @binding(15) var samplers: binding_array<sampler, MATERIAL_TEXTURES>;

// Texture `role` (`SLOT_*`) of material `k` at `at` (`read_slot` through the arrays).
fn read_role(k: u32, role: u32, at: SurfaceAttributes) -> vec4<f32> {
    let slot = materials[k].material.slots[role];
    if slot.offset.w == 0.0 {
        return vec4<f32>(1.0);
    }
    let i = materials[k].textures[role];
    let c = slot_coordinates(slot, at);
    return textureSampleGrad(textures[i], samplers[i], c.uv, c.dx, c.dy);
}

@compute @workgroup_size(8, 8)
fn resolve_bindless(@builtin(global_invocation_id) gid: vec3<u32>) {
    let pixel = gid.xy;
    let size = vec2<u32>(frame.viewport.xy);
    if any(pixel >= size) {
        return;
    }
    let id = visibility[pixel.y * size.x + pixel.x].x;
    if id == NO_TRIANGLE {
        store_cleared(pixel);
        return;
    }
    let mesh = meshes[mesh_of(id)];
    let surface = resolve_surface(mesh, id, pixel);
    let k = mesh.material;
    let m = materials[k].material;
    let t = MaterialTexels(
        read_role(k, SLOT_BASE_COLOR, surface.at),
        read_role(k, SLOT_METALLIC_ROUGHNESS, surface.at),
        read_role(k, SLOT_NORMAL, surface.at),
        read_role(k, SLOT_OCCLUSION, surface.at),
        read_role(k, SLOT_EMISSIVE, surface.at),
    );
    store(pixel, gbuffer_texels_of(m, evaluate_material_of(m, surface.at, t), surface.view_depth));
}
