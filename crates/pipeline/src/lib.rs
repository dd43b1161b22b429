//! The deferred renderer: G-buffer → light accumulation → composition (Ishmukhametov 2013
//! §1.3), on the GPU ([`gpu::GpuRenderer`]) and on the CPU ([`cpu::render`]), and the
//! `deferred` command-line program.
//!
//! BRDF (`shaders/pipeline/lighting.wgsl`): Lambert diffuse plus GGX / height-correlated
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

pub mod cpu;
pub mod gpu;
pub mod indirect;

use gbuffer::Image;
use glam::Vec3;
use scene::Light;

/// Ambient term `A` of the composition (linear RGB).
pub const DEFAULT_AMBIENT: Vec3 = Vec3::splat(0.03);

/// A light as the shaders see it (WGSL `Light` in `pipeline/lighting.wgsl`).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuLight {
    /// Position (point, spot).
    pub position: [f32; 3],
    /// Influence radius (point, spot).
    pub radius: f32,
    /// Colour × intensity.
    pub color: [f32; 3],
    /// 0 point, 1 spot, 2 directional, 3 hemispherical.
    pub kind: u32,
    /// Direction the light travels (spot, directional); the emitter's normal (hemispherical).
    pub direction: [f32; 3],
    /// Cosine of the outer cone angle (spot).
    pub cos_outer: f32,
    /// Cosine of the inner cone angle (spot).
    pub cos_inner: f32,
    /// Padding to 64 bytes.
    pub _pad: [u32; 3],
}

impl From<&Light> for GpuLight {
    fn from(light: &Light) -> Self {
        let base = Self {
            position: [0.0; 3],
            radius: 1.0,
            color: [0.0; 3],
            kind: 0,
            direction: [0.0, -1.0, 0.0],
            cos_outer: 0.0,
            cos_inner: 1.0,
            _pad: [0; 3],
        };
        match *light {
            Light::Point {
                position,
                color,
                intensity,
                radius,
            } => Self {
                position: position.to_array(),
                radius,
                color: (color * intensity).to_array(),
                ..base
            },
            Light::Spot {
                position,
                direction,
                color,
                intensity,
                radius,
                inner_angle,
                outer_angle,
            } => Self {
                position: position.to_array(),
                radius,
                color: (color * intensity).to_array(),
                kind: 1,
                direction: direction.to_array(),
                cos_outer: outer_angle.cos(),
                cos_inner: inner_angle.cos().max(outer_angle.cos() + 1e-4),
                ..base
            },
            Light::Hemispherical {
                position,
                direction,
                color,
                intensity,
                radius,
            } => Self {
                position: position.to_array(),
                radius,
                color: (color * intensity).to_array(),
                kind: 3,
                direction: direction.to_array(),
                ..base
            },
            Light::Directional {
                direction,
                color,
                intensity,
            } => Self {
                color: (color * intensity).to_array(),
                kind: 2,
                direction: direction.to_array(),
                ..base
            },
        }
    }
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
    /// A light has non-finite or negative parameters.
    #[error("light {index} is invalid: {light:?}")]
    InvalidLight {
        /// Index in the light list.
        index: usize,
        /// The light.
        light: Light,
    },
}

/// Rejects lights with NaN/infinite values or non-positive radii.
pub fn validate_lights(lights: &[Light]) -> Result<(), RenderError> {
    for (index, light) in lights.iter().enumerate() {
        let g = GpuLight::from(light);
        let finite = g
            .position
            .iter()
            .chain(&g.color)
            .chain(&g.direction)
            .all(|v| v.is_finite())
            && g.radius.is_finite()
            && g.cos_inner.is_finite()
            && g.cos_outer.is_finite();
        if !finite || g.radius <= 0.0 || g.color.iter().any(|&c| c < 0.0) {
            return Err(RenderError::InvalidLight {
                index,
                light: *light,
            });
        }
    }
    Ok(())
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
    fn gpu_light_matches_wgsl_layout() {
        assert_eq!(size_of::<GpuLight>(), 64);
        assert_eq!(std::mem::offset_of!(GpuLight, color), 16);
        assert_eq!(std::mem::offset_of!(GpuLight, direction), 32);
        assert_eq!(std::mem::offset_of!(GpuLight, cos_inner), 48);
    }

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
