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
//! let out = pipeline::cpu::render(&scene, &camera, &scene.lights, 320, 240, pipeline::DEFAULT_AMBIENT)?;
//! out.image.write_png(std::path::Path::new("cornell.png"))?;
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

pub mod bench;
pub mod cpu;
pub mod gpu;
pub mod indirect;

use gbuffer::Image;
use glam::Vec3;
use scene::Light;

/// Ambient term `A` of the composition (linear RGB).
pub const DEFAULT_AMBIENT: Vec3 = Vec3::splat(0.03);

pub use tiled_shading::{GpuLight, Method as ShadingMethod, ShadingConfig};

/// This crate's WGSL (`shaders/pipeline/`, carried into the package by the `shaders` link).
pub static SHADERS: ::gpu::shader::Library = ::gpu::shader_library!(
    "pipeline",
    imports: [gbuffer::SHADERS, tiled_shading::SHADERS, manylod::SHADERS],
    files: [
        "composition.wgsl",
        "vpl_shading.wgsl",
    ],
);

/// What this crate's kernels need of a device: what every stage it composes needs.
pub fn device_needs() -> ::gpu::DeviceNeeds {
    gbuffer::device_needs()
        .and(&interleave::device_needs())
        .and(&tiled_shading::device_needs())
        .and(&adaptive_ssaa::device_needs())
        .and(&subdiv_bft::device_needs())
        .and(&manylod::device_needs())
}

/// Time one pass of a frame took.
#[derive(Clone, Debug, PartialEq)]
pub struct PassTiming {
    /// Pass name (`z-prepass` (GPU only), `gbuffer`, `light accumulation`, `composition`).
    pub name: String,
    /// Milliseconds: GPU timestamps on the GPU path, wall clock on the CPU path.
    pub ms: f64,
}

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
    /// A bad interleaving pattern, blur, threshold or texture for the indirect stage.
    #[error(transparent)]
    Interleave(#[from] interleave::InterleaveError),
    /// VPL generation failed.
    #[error(transparent)]
    Vpl(#[from] indirect::vpl::VplError),
    /// The VPL shadow maps failed (ManyLoDs).
    #[error(transparent)]
    ManyLod(#[from] manylod::ManyLodError),
    /// The VPL set has another number of subsets than the pattern has sub-buffers.
    #[error("the VPLs come in {vpl_subsets} subsets but the pattern has {sub_buffers} sub-buffers")]
    Subsets {
        /// Subsets of the VPL set.
        vpl_subsets: u32,
        /// Sub-buffers n·m.
        sub_buffers: u32,
    },
    /// The VPL clamp distance is negative or not finite.
    #[error("the VPL clamp distance must be finite and >= 0, got {0}")]
    Clamp(f32),
    /// The light accumulation failed (tile size, light buffer, GPU).
    #[error(transparent)]
    Shading(tiled_shading::ShadingError),
    /// A light has non-finite or negative parameters.
    #[error("light {index} is invalid: {light:?}")]
    InvalidLight {
        /// Index in the light list.
        index: usize,
        /// The light.
        light: Light,
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
            tiled_shading::ShadingError::InvalidLight { index, light } => {
                RenderError::InvalidLight { index, light }
            }
            other => RenderError::Shading(other),
        }
    }
}

/// The scene a benchmark runs on: `path`, or else the shared fixtures' Dabrovic Sponza.
pub fn bench_scene_path(path: Option<&std::path::Path>) -> anyhow::Result<std::path::PathBuf> {
    use anyhow::Context;
    Ok(match path {
        Some(p) => p.to_path_buf(),
        None => scene::shared_fixtures()
            .context("../shared/fixtures not found; pass --scene")?
            .join("sponza/dabrovic/sponza.gltf"),
    })
}

/// The view `fixtures/views.json` gives for a scene file without a camera, by file name
/// (e.g. inside the Sponza atrium rather than the framing view from outside).
pub fn preset_view(path: &std::path::Path, scene: &scene::Scene) -> Option<scene::Camera> {
    #[derive(serde::Deserialize)]
    struct View {
        eye: [f32; 3],
        target: [f32; 3],
        fov_deg: f32,
    }
    let views: std::collections::HashMap<String, serde_json::Value> =
        serde_json::from_str(include_str!("../../../fixtures/views.json")).ok()?;
    let name = path.file_name()?.to_str()?;
    let view: View = serde_json::from_value(views.get(name)?.clone()).ok()?;
    let mut camera = scene::Camera::look_at(Vec3::from(view.eye), Vec3::from(view.target));
    camera.fov_y = view.fov_deg.to_radians();
    camera.fit_planes(scene.bounds());
    Some(camera)
}

/// Image error against a reference, on what a PNG shows (RGB clamped to \[0, 1\], sRGB).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Quality {
    /// Root-mean-square error.
    pub rmse: f64,
    /// Peak signal-to-noise ratio, dB ([`psnr`]).
    pub psnr: f64,
    /// Mean of the FLIP error map (LDR FLIP, 67 pixels per degree; 0 = identical, 1 = maximal).
    pub flip_mean: f64,
}

/// [`Quality`] of `test` against `reference` (same size).
pub fn quality(reference: &Image<[f32; 4]>, test: &Image<[f32; 4]>) -> Quality {
    let psnr = psnr(reference, test);
    let rmse = 10f64.powf(-psnr / 20.0);
    let srgb8 = |img: &Image<[f32; 4]>| -> Vec<u8> {
        img.pixels()
            .iter()
            .flat_map(|p| {
                [0, 1, 2]
                    .map(|c| (gbuffer::linear_to_srgb(p[c].clamp(0.0, 1.0)) * 255.0).round() as u8)
            })
            .collect()
    };
    let (w, h) = (reference.width(), reference.height());
    let map = nv_flip::flip(
        nv_flip::FlipImageRgb8::with_data(w, h, &srgb8(reference)),
        nv_flip::FlipImageRgb8::with_data(w, h, &srgb8(test)),
        nv_flip::DEFAULT_PIXELS_PER_DEGREE,
    );
    Quality {
        rmse,
        psnr,
        flip_mean: f64::from(nv_flip::FlipPool::from_image(&map).mean()),
    }
}

/// Peak signal-to-noise ratio in dB between two images' RGB, after clamping to \[0, 1\] and
/// the sRGB transfer function (what a PNG shows). Infinite for identical images.
pub fn psnr(a: &Image<[f32; 4]>, b: &Image<[f32; 4]>) -> f64 {
    let to = |c: f32| f64::from(gbuffer::linear_to_srgb(c));
    let mse = a
        .pixels()
        .iter()
        .zip(b.pixels())
        .map(|(p, q)| (0..3).map(|c| (to(p[c]) - to(q[c])).powi(2)).sum::<f64>())
        .sum::<f64>()
        / (a.pixels().len() * 3).max(1) as f64;
    if mse == 0.0 {
        f64::INFINITY
    } else {
        -10.0 * mse.log10()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn invalid_lights_are_rejected() {
        let bad = Light::Point {
            position: Vec3::NAN,
            color: Vec3::ONE,
            intensity: 1.0,
            radius: 1.0,
        };
        assert!(validate_lights(&[bad]).is_err());
        let bad = Light::Point {
            position: Vec3::ZERO,
            color: Vec3::ONE,
            intensity: 1.0,
            radius: 0.0,
        };
        assert!(validate_lights(&[bad]).is_err());
    }
}
