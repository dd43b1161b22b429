//! Screen-space ambient occlusion (Holländer 2013, annex 7.2: the separable approximation of
//! Huang et al. 2011, and its baselines), measured against ray-traced ambient occlusion.
//!
//! **The definition every estimator approximates** (eq. 7.1's integral): the accessibility of a
//! surface point p with normal n,
//!
//! A(p) = (1/π) ∫_Ω+ V_r(p, ω) cos(n, ω) dω,
//!
//! where V_r(p, ω) is 0 when the ray from p in direction ω meets geometry within the radius r
//! (world units) and 1 otherwise — a binary falloff. A is 1 in the open and 0 where every
//! direction is blocked within r. [`reference::ray_traced`] evaluates it with rays on the CPU:
//! the ground truth.
//!
//! [`cpu`] has the screen-space estimators of eq. 7.1 — the non-separable k × k kernel and the
//! separable approximation — over the G-buffer, and [`gpu`] their kernels. Status: the other
//! baselines (Crytek SSAO, volumetric obscurance, HBAO, GTAO), the feature-preserving smoothing
//! and the renderer stage are not built yet.

pub mod cpu;
pub mod gpu;
pub mod reference;

/// This crate's WGSL (`shaders/ssao/`, carried into the package by the `shaders` link).
pub static SHADERS: ::gpu::shader::Library = ::gpu::shader_library!(
    "ssao",
    imports: [gbuffer::SHADERS],
    files: ["common.wgsl", "kernel_2d.wgsl", "separable.wgsl"],
);

/// What this crate's kernels need of a device: nothing beyond `wgpu::Limits::default()`.
pub fn device_needs() -> ::gpu::DeviceNeeds {
    ::gpu::DeviceNeeds::default()
}

/// Errors of the ambient-occlusion passes.
#[derive(Debug, thiserror::Error)]
pub enum SsaoError {
    /// The radius is not a positive finite length.
    #[error("ambient-occlusion radius {0}: give a positive finite length in world units")]
    InvalidRadius(f32),
    /// A kernel side that is even or outside 3..=`cpu::MAX_KERNEL`.
    #[error("kernel of {0} pixels: give an odd size from 3 to {max}", max = cpu::MAX_KERNEL)]
    InvalidKernel(u32),
    /// Too few or too many rays per pixel.
    #[error("{0} rays per pixel: give 1 to {max}", max = reference::MAX_SAMPLES)]
    InvalidSamples(u32),
    /// A GPU resource could not be made, bound or read.
    #[error(transparent)]
    Gpu(#[from] ::gpu::GpuError),
    /// The G-buffer and the frame disagree on the image size.
    #[error("a {gbuffer:?} G-buffer for a {frame:?} frame")]
    SizeMismatch {
        /// The G-buffer's size.
        gbuffer: (u32, u32),
        /// The frame's viewport.
        frame: (u32, u32),
    },
}

/// What the occlusion is: the radius of V_r in world units.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AoConfig {
    /// Occluders count within this distance of the point (world units).
    pub radius: f32,
}

impl AoConfig {
    /// Checks the radius.
    pub fn validate(&self) -> Result<(), SsaoError> {
        if self.radius.is_finite() && self.radius > 0.0 {
            Ok(())
        } else {
            Err(SsaoError::InvalidRadius(self.radius))
        }
    }
}

/// The image of `f(x, y, pixel index)` over `gbuffer`'s pixels, in parallel.
pub(crate) fn per_pixel(
    gbuffer: &gbuffer::GBuffer,
    f: impl Fn(u32, u32, u32) -> f32 + Sync + Send,
) -> gbuffer::Image<f32> {
    use rayon::prelude::*;
    let (w, h) = (gbuffer.linear_depth.width(), gbuffer.linear_depth.height());
    let values: Vec<f32> = (0..w * h)
        .into_par_iter()
        .map(|i| f(i % w, i / w, i))
        .collect();
    let mut image = gbuffer::Image::filled(w, h, 1.0);
    image.pixels_mut().copy_from_slice(&values);
    image
}

/// Checks that `gbuffer` and `frame` describe one image size.
pub(crate) fn check_size(
    gbuffer: &gbuffer::GBuffer,
    frame: &gbuffer::Frame,
) -> Result<(), SsaoError> {
    let size = (gbuffer.linear_depth.width(), gbuffer.linear_depth.height());
    let viewport = (frame.viewport.x as u32, frame.viewport.y as u32);
    if size != viewport {
        return Err(SsaoError::SizeMismatch {
            gbuffer: size,
            frame: viewport,
        });
    }
    Ok(())
}
