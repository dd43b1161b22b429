//! The deferred renderer: G-buffer → light accumulation → composition (Ishmukhametov 2013
//! §1.3), on the GPU ([`gpu::GpuRenderer`]) and on the CPU ([`cpu::render`]), and the
//! `deferred` command-line program.
//!
//! BRDF (`shaders/tiled-shading/lighting.wgsl`, light accumulation by `tiled_shading`): Lambert diffuse plus GGX / height-correlated
//! Smith / Schlick specular, metallic-roughness parameterization. Light accumulation keeps
//! diffuse and specular apart, as the thesis's light accumulation buffer does, so the
//! composition multiplies the albedo once:
//! `colour = albedo · (1 − metallic) · (ambient + Σ E/π) + Σ E·D·V·F + emissive`,
//! with `E = Att · (N·L) · colour · intensity` and a point/spot attenuation that reaches
//! exactly zero at the light's radius.
//!
//! ```no_run
//! let scene = scene::cornell_box();
//! let camera = scene.camera_or_framed();
//! let inputs = pipeline::cpu::FrameInputs::new(&scene, &camera, &scene.lights, (320, 240), pipeline::DEFAULT_AMBIENT);
//! let out = pipeline::cpu::render(&inputs)?;
//! out.image.write_png(std::path::Path::new("cornell.png"))?;
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

pub mod cpu;
pub mod gpu;
pub mod output;
pub mod progressive;
pub mod sequence;
pub mod skinning;
pub mod subdivision;
mod supersampling;

use gbuffer::Image;
use glam::Vec3;
use scene::Light;

/// Ambient term `A` of the composition (linear RGB).
pub const DEFAULT_AMBIENT: Vec3 = Vec3::splat(0.03);

pub use tiled_shading::{GpuLight, LightSearch, Method as ShadingMethod, ShadingConfig};

/// This crate's WGSL (`shaders/pipeline/`, carried into the package by the `shaders` link).
pub static SHADERS: ::gpu::shader::Library = ::gpu::shader_library!(
    "pipeline",
    imports: [gbuffer::SHADERS],
    files: [
        "compose.wgsl",
        "composition.wgsl",
        "supersampling.wgsl",
        "accumulate.wgsl",
        "output.wgsl",
        "skinning.wgsl",
        "subdivision.wgsl",
    ],
);

/// What this crate's kernels need of a device: what every stage it composes needs.
pub fn device_needs() -> ::gpu::DeviceNeeds {
    gbuffer::device_needs()
        .and(&instant_radiosity::device_needs())
        .and(&tiled_shading::device_needs())
        .and(&adaptive_ssaa::device_needs())
        .and(&subdiv_bft::device_needs())
        .and(&manylod::device_needs())
        .and(&ssao::device_needs())
}

/// Time one pass of a frame took (`z-prepass` (GPU only), `gbuffer`, `light accumulation`,
/// `composition`, the indirect stages): GPU timestamps on the GPU path, wall clock on the CPU.
pub use ::gpu::PassTiming;

/// A rendered frame: linear radiance (alpha 1 where a surface is, 0 elsewhere) and timings.
pub struct Rendered {
    /// Linear RGBA radiance.
    pub image: Image<[f32; 4]>,
    /// Per-pass times (empty on a GPU without timestamp queries).
    pub timings: Vec<PassTiming>,
}

/// Errors of the renderer.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    /// G-buffer creation failed (bad size, camera or scene).
    #[error(transparent)]
    GBuffer(#[from] gbuffer::GBufferError),
    /// A GPU resource could not be created or read.
    #[error(transparent)]
    Gpu(#[from] ::gpu::GpuError),
    /// The indirect-light stage failed (configuration, VPLs, visibility).
    #[error(transparent)]
    Indirect(#[from] instant_radiosity::IndirectError),
    /// The light accumulation failed (tile size, light buffer, GPU).
    #[error(transparent)]
    Shading(tiled_shading::ShadingError),
    /// Screen-space ambient occlusion cannot be set up (kernel size, radius).
    #[error(transparent)]
    Ssao(#[from] ssao::SsaoError),
    /// Supersampling cannot be set up (window size, constants, size).
    #[error(transparent)]
    Ssaa(#[from] adaptive_ssaa::SsaaError),
    /// Subdivision cannot be set up (a mesh the subdivider refuses, a plan that does not fit
    /// the uploaded scene).
    #[error("subdivision: {0}")]
    Subdivision(String),
    /// The animation cannot be bound (a rig that does not fit the uploaded scene).
    #[error("animation: {0}")]
    Animation(String),
    /// The G-buffer cannot be drawn through the visibility buffer (what the scene or the
    /// other stages need that it does not do yet).
    #[error("visibility buffer: {0}")]
    Visibility(String),
    /// VPLs were given to a renderer without an indirect stage.
    #[error("the renderer has no indirect light: set one (set_indirect) before its VPLs")]
    NoIndirect,
    /// The output transform's options are out of range.
    #[error("invalid output transform: {0}")]
    InvalidOutput(String),
    /// A light has non-finite or negative parameters.
    #[error("light {index}: {problem}")]
    InvalidLight {
        /// Index in the light list.
        index: usize,
        /// What is wrong, with the values.
        problem: String,
    },
}

/// Rejects lights with NaN/infinite values or non-positive radii
/// ([`tiled_shading::gpu_lights`]) and returns their shader form.
pub fn validate_lights(lights: &[Light]) -> Result<Vec<GpuLight>, RenderError> {
    Ok(tiled_shading::gpu_lights(lights)?)
}

impl From<tiled_shading::ShadingError> for RenderError {
    fn from(e: tiled_shading::ShadingError) -> Self {
        match e {
            tiled_shading::ShadingError::InvalidLight { index, problem } => {
                RenderError::InvalidLight { index, problem }
            }
            other => RenderError::Shading(other),
        }
    }
}

pub use gbuffer::psnr;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn invalid_lights_are_rejected() {
        let point = |position: Vec3, radius: f32| Light::Point {
            position,
            color: Vec3::ONE,
            intensity: 1.0,
            radius,
        };
        assert!(validate_lights(&[point(Vec3::ZERO, 1.0)]).is_ok());
        assert!(validate_lights(&[point(Vec3::NAN, 1.0)]).is_err());
        assert!(validate_lights(&[point(Vec3::ZERO, 0.0)]).is_err());
    }
}
