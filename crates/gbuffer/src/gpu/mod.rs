//! GPU G-buffer creation: a render pipeline writing all targets at once (MRT), the twin of
//! [`crate::cpu::rasterize`] ([`gbuffer`], shader `shaders/gbuffer/gbuffer.wgsl`); the targets
//! it writes ([`targets`]); the scene it draws ([`upload`]); test helpers ([`run`]).

pub mod gbuffer;
pub mod run;
pub mod targets;
pub mod upload;

pub use gbuffer::{GBufferPass, begin_scene_pass, scene_pipeline};
pub use run::{run, run_with};
pub use targets::{GBufferTargets, GBufferTextures, UploadedGBuffer};
pub use upload::GpuScene;

use ::gpu::kernel::Binding;
use glam::Vec4;

/// Vertex layout of the uploaded scene (WGSL `vs_main` inputs).
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuVertex {
    /// World position.
    pub position: [f32; 3],
    /// Normal.
    pub normal: [f32; 3],
    /// Texture coordinate.
    pub uv: [f32; 2],
}

/// A material as the shaders see it (WGSL `Material`).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuMaterial {
    /// Linear base colour factor.
    pub base_color: Vec4,
    /// Emitted radiance.
    pub emissive: [f32; 3],
    /// Perceptual roughness.
    pub roughness: f32,
    /// Metalness.
    pub metallic: f32,
    /// Index in the scene's material list (the G-buffer's material id).
    pub id: u32,
    /// Specular factor (written to the G-buffer albedo's alpha).
    pub specular: f32,
    /// Padding to 16-byte alignment.
    pub _pad: u32,
}

impl GpuMaterial {
    /// The GPU form of material `id` of a scene.
    pub fn new(m: &::scene::Material, id: u32) -> Self {
        Self {
            base_color: m.base_color,
            emissive: m.emissive.to_array(),
            roughness: m.roughness,
            metallic: m.metallic,
            id,
            specular: m.specular,
            _pad: 0,
        }
    }
}

/// How a compute kernel binds [`GBufferTextures`] (read with `textureLoad`): linear depth,
/// normal, albedo, material — the order of their bindings in every shading kernel.
pub const GBUFFER_BINDINGS: [Binding; 4] = [
    Binding::TextureUnfilterable,
    Binding::TextureUint,
    Binding::TextureUnfilterable,
    Binding::TextureUint,
];
