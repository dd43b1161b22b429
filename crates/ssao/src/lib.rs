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
//! [`cpu`] has the screen-space estimators ([`Method`]) — eq. 7.1's local filter, Crytek SSAO,
//! volumetric obscurance, HBAO and GTAO — each non-separable or separable ([`Estimator`]),
//! and [`gpu`] their kernels.

pub mod cpu;
pub mod gpu;
pub mod reference;

/// This crate's WGSL (`shaders/ssao/`, carried into the package by the `shaders` link).
pub static SHADERS: ::gpu::shader::Library = ::gpu::shader_library!(
    "ssao",
    imports: [gbuffer::SHADERS],
    files: ["common.wgsl", "estimators.wgsl"],
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
    /// An estimator name that is not `METHOD` or `METHOD-separable`.
    #[error(
        "unknown ambient-occlusion estimator {0:?}: give filter, crytek, vo, hbao or gtao, optionally followed by -separable (or -separable-unsmoothed), then optionally by -half"
    )]
    UnknownEstimator(String),
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

/// A screen-space estimator of A (the [`cpu`] module says how each one samples).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Method {
    /// Eq. 7.1 (Holländer 2013 §7.2.1, Huang et al. 2011): the cosine of the direction to each
    /// neighbour pixel's point that lies above the tangent plane within the radius.
    Filter,
    /// Crytek SSAO (Mittring 2007): points of the sphere of radius r around p, tested against
    /// the depth buffer; normal-free.
    Crytek,
    /// Volumetric obscurance (Loos & Sloan 2010): the fraction of line segments through the
    /// sphere that lies behind the depth buffer.
    VolumetricObscurance,
    /// Horizon-based AO (Bavoil et al. 2008): sin h − sin t per screen direction.
    Hbao,
    /// Ground-truth-based AO (Jimenez et al. 2016): the cosine-weighted visible arc between
    /// the two horizons of each slice, with the projected normal.
    Gtao,
}

impl Method {
    /// Every method, in the paper's order, then GTAO.
    pub const ALL: [Method; 5] = [
        Method::Filter,
        Method::Crytek,
        Method::VolumetricObscurance,
        Method::Hbao,
        Method::Gtao,
    ];

    /// The method's name on the command line and in reports.
    pub fn name(self) -> &'static str {
        match self {
            Method::Filter => "filter",
            Method::Crytek => "crytek",
            Method::VolumetricObscurance => "vo",
            Method::Hbao => "hbao",
            Method::Gtao => "gtao",
        }
    }

    /// Whether the method walks lines (horizon-based): its k × k form is k lines through p
    /// instead of the k × k window.
    pub fn is_horizon_based(self) -> bool {
        matches!(self, Method::Hbao | Method::Gtao)
    }
}

/// A method and how it is evaluated: over the whole kernel, or separably (§7.2.2: one line
/// along the pixel's interleaved direction, then the same-surface average along the
/// perpendicular, then — unless left out — the feature-preserving smoothing); at full or half
/// resolution.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Estimator {
    /// What is estimated.
    pub method: Method,
    /// Two 1D passes (2k − 1 samples a pixel) instead of the k × k kernel.
    pub separable: bool,
    /// Separable only: the feature-preserving smoothing after pass 2 (a k × k cross-bilateral
    /// box that evens out the interleaving pattern; on by default). It doubles the separable
    /// passes' cost and blurs occlusion near edges: measured on the H200 it removes the
    /// pattern's blotches but raises the error against ray-traced AO a little.
    pub smoothing: bool,
    /// Estimate at the pixels (2x, 2y) only — the kernel's k pixels are then steps of two, so
    /// it reaches twice as far — and upsample to every pixel from the four nearest estimates on
    /// its surface (the [`cpu`] module says how): a quarter of the samples.
    pub half_resolution: bool,
}

impl Estimator {
    /// `method`, separable (with the smoothing) or not, at full resolution.
    pub fn new(method: Method, separable: bool) -> Self {
        Self {
            method,
            separable,
            smoothing: separable,
            half_resolution: false,
        }
    }

    /// This estimator without the smoothing after pass 2.
    pub fn without_smoothing(self) -> Self {
        Self {
            smoothing: false,
            ..self
        }
    }

    /// This estimator at half resolution.
    pub fn at_half_resolution(self) -> Self {
        Self {
            half_resolution: true,
            ..self
        }
    }
}

impl std::fmt::Display for Estimator {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let separable = match (self.separable, self.smoothing) {
            (true, true) => "-separable",
            (true, false) => "-separable-unsmoothed",
            (false, _) => "",
        };
        let half = if self.half_resolution { "-half" } else { "" };
        write!(f, "{}{separable}{half}", self.method.name())
    }
}

impl std::str::FromStr for Estimator {
    type Err = SsaoError;

    /// `METHOD[-separable[-unsmoothed]][-half]`, METHOD one of filter, crytek, vo, hbao, gtao.
    fn from_str(s: &str) -> Result<Self, SsaoError> {
        let (rest, half_resolution) = match s.strip_suffix("-half") {
            Some(rest) => (rest, true),
            None => (s, false),
        };
        let (rest, unsmoothed) = match rest.strip_suffix("-unsmoothed") {
            Some(rest) => (rest, true),
            None => (rest, false),
        };
        let (name, separable) = match rest.strip_suffix("-separable") {
            Some(name) => (name, true),
            None => (rest, false),
        };
        Method::ALL
            .into_iter()
            .find(|m| m.name() == name)
            .filter(|_| separable || !unsmoothed)
            .map(|method| Estimator {
                method,
                separable,
                smoothing: separable && !unsmoothed,
                half_resolution,
            })
            .ok_or_else(|| SsaoError::UnknownEstimator(s.to_owned()))
    }
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

/// The `(w, h)` image of `f(x, y, pixel index)`, in parallel.
pub(crate) fn per_pixel<T: Copy + Default + Send>(
    (w, h): (u32, u32),
    f: impl Fn(u32, u32, u32) -> T + Sync + Send,
) -> gbuffer::Image<T> {
    use rayon::prelude::*;
    let values: Vec<T> = (0..w * h)
        .into_par_iter()
        .map(|i| f(i % w, i / w, i))
        .collect();
    let mut image = gbuffer::Image::filled(w, h, T::default());
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
