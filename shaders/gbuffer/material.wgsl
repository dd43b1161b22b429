// The glTF 2.0 metallic-roughness material (§3.9) as the G-buffer evaluates it: the material
// uniform, its five textures and their samplers (group 1), and `evaluate_material`, the twin of
// `scene::Material::evaluate`. Mirrors `gbuffer::gpu::GpuMaterial`.

// How a material reads one texture: the 2 × 2 part of its KHR_texture_transform (columns
// xy and zw) and the offset (xy), the texture-coordinate set (z: 0 or 1), and whether the
// material has the texture at all (w: 0 reads white).
struct TextureSlot {
    linear: vec4<f32>,
    offset: vec4<f32>,
};

const SLOT_BASE_COLOR: u32 = 0u;
const SLOT_METALLIC_ROUGHNESS: u32 = 1u;
const SLOT_NORMAL: u32 = 2u;
const SLOT_OCCLUSION: u32 = 3u;
const SLOT_EMISSIVE: u32 = 4u;

const ALPHA_OPAQUE: u32 = 0u;
const ALPHA_MASK: u32 = 1u;
const ALPHA_BLEND: u32 = 2u;

struct Material {
    base_color: vec4<f32>,
    emissive: vec3<f32>,
    roughness: f32,
    metallic: f32,
    id: u32,
    specular: f32,
    normal_scale: f32,
    occlusion_strength: f32,
    alpha_mode: u32,
    alpha_cutoff: f32,
    // The sample's albedo is scaled by 1 − transmission (`scene::MaterialSample::albedo`).
    transmission: f32,
    slots: array<TextureSlot, 5>,
};

@group(1) @binding(0) var<uniform> material: Material;
@group(1) @binding(1) var base_color_texture: texture_2d<f32>;
@group(1) @binding(2) var base_color_sampler: sampler;
@group(1) @binding(3) var metallic_roughness_texture: texture_2d<f32>;
@group(1) @binding(4) var metallic_roughness_sampler: sampler;
@group(1) @binding(5) var normal_texture: texture_2d<f32>;
@group(1) @binding(6) var normal_sampler: sampler;
@group(1) @binding(7) var occlusion_texture: texture_2d<f32>;
@group(1) @binding(8) var occlusion_sampler: sampler;
@group(1) @binding(9) var emissive_texture: texture_2d<f32>;
@group(1) @binding(10) var emissive_sampler: sampler;

// A surface point's interpolated attributes (`scene::SurfaceAttributes`): both coordinate sets
// in one vector (set 0 xy, set 1 zw) with their fine screen derivatives.
struct SurfaceAttributes {
    uv: vec4<f32>,
    uv_dx: vec4<f32>,
    uv_dy: vec4<f32>,
    normal: vec3<f32>,
    back_face: bool,
    tangent: vec4<f32>,
    color: vec4<f32>,
};

struct MaterialSample {
    albedo: vec3<f32>,
    alpha: f32,
    roughness: f32,
    metallic: f32,
    normal: vec3<f32>,
    occlusion: f32,
    emission: vec3<f32>,
};

// Where a texture slot reads at a surface point: its coordinates and their derivatives,
// through the slot's transform.
struct SlotCoordinates {
    uv: vec2<f32>,
    dx: vec2<f32>,
    dy: vec2<f32>,
};

fn slot_coordinates(slot: TextureSlot, at: SurfaceAttributes) -> SlotCoordinates {
    let set1 = slot.offset.z != 0.0;
    let uv = select(at.uv.xy, at.uv.zw, set1);
    let dx = select(at.uv_dx.xy, at.uv_dx.zw, set1);
    let dy = select(at.uv_dy.xy, at.uv_dy.zw, set1);
    let m = mat2x2<f32>(slot.linear.xy, slot.linear.zw);
    return SlotCoordinates(m * uv + slot.offset.xy, m * dx, m * dy);
}

// One texture of the material through its slot, filtered by the coordinates' derivatives.
fn read_slot(t: texture_2d<f32>, s: sampler, slot: TextureSlot, at: SurfaceAttributes) -> vec4<f32> {
    if slot.offset.w == 0.0 {
        return vec4<f32>(1.0);
    }
    let c = slot_coordinates(slot, at);
    return textureSampleGrad(t, s, c.uv, c.dx, c.dy);
}

// The normal map's tangent-space normal `c` in the surface's tangent frame (glTF §3.9.3,
// `scene::material::perturb_normal`).
fn perturb_normal(at: SurfaceAttributes, c: vec3<f32>) -> vec3<f32> {
    let turn = select(1.0, -1.0, at.back_face);
    let n0 = at.normal * turn;
    let t = at.tangent.xyz;
    let t0 = t - n0 * dot(n0, t);
    if dot(t0, t0) < 1e-12 || at.tangent.w == 0.0 {
        return at.normal;
    }
    let t1 = normalize(t0);
    let b0 = cross(n0, t1) * sign(at.tangent.w);
    let n = turn * (t1 * c.x + b0 * c.y) + at.normal * c.z;
    let l2 = dot(n, n);
    return select(at.normal, n * inverseSqrt(l2), l2 > 0.0);
}

fn base_color(at: SurfaceAttributes) -> vec4<f32> {
    return material.base_color
        * read_slot(base_color_texture, base_color_sampler, material.slots[SLOT_BASE_COLOR], at) * at.color;
}

// The alpha alone, for alpha-tested depth passes.
fn material_alpha(at: SurfaceAttributes) -> f32 {
    return base_color(at).a;
}

// The texels of a material's five textures at a surface point (white where it has none).
struct MaterialTexels {
    base_color: vec4<f32>,
    metallic_roughness: vec4<f32>,
    normal: vec4<f32>,
    occlusion: vec4<f32>,
    emissive: vec4<f32>,
};

// Material `m` at `at`, its textures read as `t`: `evaluate_material` of any material.
fn evaluate_material_of(m: Material, at: SurfaceAttributes, t: MaterialTexels) -> MaterialSample {
    var out: MaterialSample;
    let base = m.base_color * t.base_color * at.color;
    out.albedo = clamp(base.rgb, vec3<f32>(0.0), vec3<f32>(1.0)) * (1.0 - m.transmission);
    out.alpha = base.a;
    out.roughness = clamp(m.roughness * t.metallic_roughness.y, 0.0, 1.0);
    out.metallic = clamp(m.metallic * t.metallic_roughness.z, 0.0, 1.0);
    out.occlusion = 1.0 + m.occlusion_strength * (t.occlusion.x - 1.0);
    out.emission = m.emissive * t.emissive.rgb;
    out.normal = at.normal;
    if m.slots[SLOT_NORMAL].offset.w != 0.0 {
        let c = t.normal.rgb * 2.0 - 1.0;
        out.normal = perturb_normal(at, c * vec3<f32>(m.normal_scale, m.normal_scale, 1.0));
    }
    return out;
}

fn evaluate_material(at: SurfaceAttributes) -> MaterialSample {
    let t = MaterialTexels(
        read_slot(base_color_texture, base_color_sampler, material.slots[SLOT_BASE_COLOR], at),
        read_slot(metallic_roughness_texture, metallic_roughness_sampler, material.slots[SLOT_METALLIC_ROUGHNESS], at),
        read_slot(normal_texture, normal_sampler, material.slots[SLOT_NORMAL], at),
        read_slot(occlusion_texture, occlusion_sampler, material.slots[SLOT_OCCLUSION], at),
        read_slot(emissive_texture, emissive_sampler, material.slots[SLOT_EMISSIVE], at),
    );
    return evaluate_material_of(material, at, t);
}

// The 4 × 4 ordered dither of blended materials (`scene::dither_threshold`).
fn dither_threshold(pixel: vec2<u32>) -> f32 {
    let bayer = array<u32, 16>(0u, 8u, 2u, 10u, 12u, 4u, 14u, 6u, 3u, 11u, 1u, 9u, 15u, 7u, 13u, 5u);
    return (f32(bayer[(pixel.y % 4u) * 4u + pixel.x % 4u]) + 0.5) / 16.0;
}

// `scene::AlphaMode::keeps`.
fn alpha_keeps(alpha: f32, threshold: f32) -> bool {
    switch material.alpha_mode {
        case ALPHA_MASK: { return alpha >= material.alpha_cutoff; }
        case ALPHA_BLEND: { return alpha > threshold; }
        default: { return true; }
    }
}
