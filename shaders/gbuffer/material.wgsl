// A material as the shaders see it. Mirrors `gbuffer::gpu::GpuMaterial`.
struct Material {
    base_color: vec4<f32>,
    emissive: vec3<f32>,
    roughness: f32,
    metallic: f32,
    id: u32,
    specular: f32,
    _pad1: u32,
};
