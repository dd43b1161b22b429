//! GPU G-buffer creation: a render pipeline writing all targets at once (MRT), the twin of
//! [`crate::cpu::rasterize`] ([`gbuffer`], shader `shaders/gbuffer/gbuffer.wgsl`); the targets
//! it writes ([`targets`]); the scene it draws ([`upload`]); test helpers ([`run()`]); the
//! visibility buffer of a compute rasteriser ([`visibility`]).

pub mod gbuffer;
pub mod run;
pub mod targets;
pub mod textures;
pub mod upload;
pub mod visibility;

pub use gbuffer::{FrameUniform, GBufferPass, begin_scene_pass, scene_pipeline, scene_pipelines};
pub use run::{run, run_visibility, run_with};
pub use targets::{GBufferTargets, GBufferTextures, UploadedGBuffer};
pub use textures::MaterialTextures;
pub use upload::{BlendedSurfaces, GpuScene};

use ::gpu::kernel::Binding;
use bytemuck::Zeroable;
use glam::Vec4;

/// The per-vertex attributes besides the position (vertex buffer slot 1; WGSL `vs_main`
/// locations 1–5). Positions have their own buffer (slot 0), so depth-only passes read 12
/// bytes per vertex.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuAttributes {
    /// Normal.
    pub normal: [f32; 3],
    /// Texture-coordinate set 0.
    pub uv0: [f32; 2],
    /// Texture-coordinate set 1 (zero where the mesh has none).
    pub uv1: [f32; 2],
    /// Tangent and bitangent sign (zero where the mesh has none).
    pub tangent: [f32; 4],
    /// Linear vertex colour (white where the mesh has none).
    pub color: [f32; 4],
}

/// One texture slot of a [`GpuMaterial`] (WGSL `TextureSlot`): the 2 × 2 part of the
/// `KHR_texture_transform` (column-major), the offset, the coordinate set and whether the
/// material has the texture.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuTextureSlot {
    /// Columns (m00, m10) and (m01, m11).
    pub linear: [f32; 4],
    /// Offset (xy), coordinate set (z), present (w: 1 or 0).
    pub offset: [f32; 4],
}

impl GpuTextureSlot {
    fn new(t: Option<::scene::TextureRef>) -> Self {
        let Some(t) = t else {
            return Self::zeroed();
        };
        let m = t.transform.matrix();
        Self {
            linear: [m.x_axis.x, m.x_axis.y, m.y_axis.x, m.y_axis.y],
            offset: [m.z_axis.x, m.z_axis.y, t.uv_set.min(1) as f32, 1.0],
        }
    }
}

/// A material as the shaders see it (WGSL `Material` in `gbuffer/material.wgsl`).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuMaterial {
    /// Linear base colour and alpha factor.
    pub base_color: Vec4,
    /// Emitted radiance factor.
    pub emissive: [f32; 3],
    /// Perceptual roughness factor.
    pub roughness: f32,
    /// Metalness factor.
    pub metallic: f32,
    /// Index in the scene's material list (the G-buffer's material id).
    pub id: u32,
    /// Specular factor (written to the G-buffer albedo's alpha).
    pub specular: f32,
    /// Scale of the normal map's x and y.
    pub normal_scale: f32,
    /// Strength of the occlusion texture.
    pub occlusion_strength: f32,
    /// 0 opaque, 1 mask, 2 blend (dithered).
    pub alpha_mode: u32,
    /// The mask's cutoff.
    pub alpha_cutoff: f32,
    /// [`scene::Material::transmission`]: the sampled albedo is scaled by 1 − it.
    pub transmission: f32,
    /// Base colour, metallic-roughness, normal, occlusion, emissive.
    pub slots: [GpuTextureSlot; 5],
}

impl GpuMaterial {
    /// The GPU form of material `id` of a scene.
    pub fn new(m: &::scene::Material, id: u32) -> Self {
        let (alpha_mode, alpha_cutoff) = match m.alpha_mode {
            ::scene::AlphaMode::Opaque => (0, 0.0),
            ::scene::AlphaMode::Mask { cutoff } => (1, cutoff),
            ::scene::AlphaMode::Blend => (2, 0.0),
        };
        Self {
            base_color: m.base_color,
            emissive: m.emissive.to_array(),
            roughness: m.roughness,
            metallic: m.metallic,
            id,
            specular: m.specular,
            normal_scale: m.normal_scale,
            occlusion_strength: m.occlusion_strength,
            alpha_mode,
            alpha_cutoff,
            transmission: m.transmission,
            slots: m.roles().map(|(_, t)| GpuTextureSlot::new(t)),
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
