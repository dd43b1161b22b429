//! Adaptive supersampling for deferred anti-aliasing (Holländer, Boubekeur & Eisemann 2013;
//! Holländer 2013 chapter 4).
//!
//! The scene is rendered into a G-buffer `m` times larger on each side, so every pixel of the
//! `w × h` image owns an `m × m` *sampling window* of `n = m²` samples (§4.3). The G-buffer
//! keeps texture coordinates and their screen derivatives instead of albedo (§4.3.3), so
//! textures are filtered anisotropically when a sample is shaded (§4.3.4). The method
//! (Listing 4.1):
//!
//! 1. **Shade the first sample** of every window into `S` (`w × h`).
//! 2. **Evaluate** the metrics (§4.3.1) per pixel: a geometric metric on the window's depths
//!    and normals ([`GeometricMetric`]: MM, NC, DV, NV or ND) and the shading metric on the
//!    luminance range of `S` around the pixel; their maximum `k` is the number of *additional*
//!    samples, so the pixel gets `min(1 + ⌊k⌋, n)` samples.
//! 3. **Shade the rest adaptively**: the samples are taken from the window in the order of an
//!    ordered-dither index matrix ([`dither_matrix`], Figure 4.7, §4.3.2) and averaged.
//!
//! The CPU reference is [`cpu`]; the GPU kernels ([`gpu`]) are one render pass (the
//! supersampled G-buffer) and compute passes, one WGSL file per stage under `shaders/adaptive-ssaa/` (`shade`, `evaluate`, `sort`, `fxaa` over `common.wgsl`).
//!
//! ```no_run
//! use adaptive_ssaa::{GeometricMetric, SsaaConfig};
//! # let gpu = gpu::Gpu::from_env()?;
//! let scene = scene::checkerboard();
//! let camera = scene.camera_or_framed();
//! let lights = tiled_shading::gpu_lights(&scene.lights)?;
//! let config = SsaaConfig { m: 4, metric: Some(GeometricMetric::NormalDepth), ..Default::default() };
//! let out = adaptive_ssaa::gpu::run(&gpu, &scene, &camera, &lights, 320, 240, &config)?;
//! println!("{:.1} % of the samples shaded", 100.0 * out.sample_fraction(config.m));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

pub mod cpu;
mod dither;
pub mod gpu;
mod texture;

use std::fmt;
use std::str::FromStr;

use glam::Vec3;

pub use dither::{bayer_matrix, dither_matrix, dither_order, prefix_spread};
pub use scene::{MAX_ANISOTROPY, anisotropic_footprint};
pub use texture::{ArrayLayers, TextureArray};

/// This crate's WGSL (`shaders/adaptive-ssaa/`, carried into the package by the `shaders` link).
pub static SHADERS: ::gpu::shader::Library = ::gpu::shader_library!(
    "adaptive-ssaa",
    imports: [gbuffer::SHADERS, tiled_shading::SHADERS],
    files: [
        "common.wgsl",
        "evaluate.wgsl",
        "fxaa.wgsl",
        "gbuffer.wgsl",
        "shade.wgsl",
        "sort.wgsl",
    ],
);

/// What this crate's kernels need of a device: wgpu's default limits suffice (the adaptive shading binds exactly the default 8 storage buffers).
pub fn device_needs() -> ::gpu::DeviceNeeds {
    ::gpu::DeviceNeeds::default()
}

/// Largest window side `m` (64 samples per pixel).
pub const MAX_M: u32 = 8;
/// Format of the supersampled texture-coordinate target.
pub const UV_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rg32Float;
/// Format of the texture-coordinate derivative target (∂u/∂x, ∂v/∂x, ∂u/∂y, ∂v/∂y per sample).
pub const UV_GRAD_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;
/// Format of the tint target: √(vertex colour) and occlusion as four unorm8 ([`unpack_tint`]).
/// One word keeps the supersampled G-buffer at 32 bytes a sample, wgpu's default
/// `max_color_attachment_bytes_per_sample`.
pub const TINT_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R32Uint;

/// The vertex colour (linear rgb) and occlusion of a tint word (WGSL
/// `unpack4x8unorm`, the colour squared: it is stored as its square root, so dark colours keep
/// more than 8 linear bits).
pub fn unpack_tint(word: u32) -> (Vec3, f32) {
    let [r, g, b, a] = word.to_le_bytes().map(|v| f32::from(v) / 255.0);
    (Vec3::new(r * r, g * g, b * b), a)
}

/// The geometric metrics of §4.3.1 on a sampling window of depths `d` (view depth over the far
/// plane distance) and unit normals `n`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum GeometricMetric {
    /// MinMax depth: `k = c·(d_max − d_min)`.
    MinMax,
    /// Normal cone: `k = c·√(1 − min |n̄·nᵢ|)` around the mean normal `n̄`.
    NormalCone,
    /// Depth variance: `k = c·(Σd²/n − (Σd/n)²)`.
    DepthVariance,
    /// Normal variance: `k = c·Σ(1 − nᵢ·n̄)²`.
    NormalVariance,
    /// Normal and depth: `max(k_NC, k_DV)`, the paper's choice.
    NormalDepth,
}

impl GeometricMetric {
    /// All metrics, in the order of Table 4.1.
    pub const ALL: [Self; 5] = [
        Self::NormalDepth,
        Self::MinMax,
        Self::NormalCone,
        Self::DepthVariance,
        Self::NormalVariance,
    ];

    /// The paper's abbreviation (MM, NC, DV, NV, ND).
    pub fn name(self) -> &'static str {
        match self {
            Self::MinMax => "MM",
            Self::NormalCone => "NC",
            Self::DepthVariance => "DV",
            Self::NormalVariance => "NV",
            Self::NormalDepth => "ND",
        }
    }

    /// The code the shader switches on (`Params::metric`; 0 means none).
    fn code(self) -> u32 {
        match self {
            Self::MinMax => 1,
            Self::NormalCone => 2,
            Self::DepthVariance => 3,
            Self::NormalVariance => 4,
            Self::NormalDepth => 5,
        }
    }
}

impl fmt::Display for GeometricMetric {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for GeometricMetric {
    type Err = SsaaError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Self::ALL
            .into_iter()
            .find(|m| m.name().eq_ignore_ascii_case(s))
            .ok_or_else(|| SsaaError::UnknownMetric(s.into()))
    }
}

/// The user constants `c` of the geometric metrics (§4.3.1: "adapted according to the scene").
/// Depths are view depths divided by the camera's far distance, so the constants do not depend
/// on the scene's units as long as the far plane fits the scene.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Constants {
    /// MM.
    pub mm: f32,
    /// NC (and ND).
    pub nc: f32,
    /// DV (and ND).
    pub dv: f32,
    /// NV.
    pub nv: f32,
}

impl Default for Constants {
    fn default() -> Self {
        Self {
            mm: 200.0,
            nc: 12.0,
            dv: 2.0e4,
            nv: 4.0,
        }
    }
}

/// The shading metric (§4.3.1): the luminance range `r = l_max − l_min` of `S` over the pixel
/// and its four direct neighbours; `k = 0` if `r < max(min_threshold, l_max·edge_threshold)`,
/// else `c·r` (as FXAA's edge test).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadingMetric {
    /// Samples per unit of luminance range.
    pub c: f32,
    /// Absolute threshold on the range.
    pub min_threshold: f32,
    /// Threshold relative to the largest luminance.
    pub edge_threshold: f32,
}

impl Default for ShadingMetric {
    fn default() -> Self {
        Self {
            c: 24.0,
            min_threshold: 0.0312,
            edge_threshold: 0.125,
        }
    }
}

/// How the pixels' remaining samples are shaded (§4.3.5).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Resolve {
    /// One invocation per pixel looping over its samples: the paper's choice.
    #[default]
    Loop,
    /// Pixels grouped by sample count (a counting sort on the GPU), then one invocation per
    /// pixel over the sorted list: the §4.3.5 alternatives that group or sort pixels by `k`.
    Sorted,
    /// The samples of each 8×8 tile's pixels listed one after the other and shaded by all of
    /// the tile's invocations alike, each pixel then summing its own (no invocation idles while
    /// another shades its pixel's sixteenth sample).
    Tiles,
}

impl Resolve {
    /// Every resolve.
    pub const ALL: [Self; 3] = [Self::Loop, Self::Sorted, Self::Tiles];

    /// Short name for reports and the command line.
    pub fn name(self) -> &'static str {
        match self {
            Self::Loop => "loop",
            Self::Sorted => "sorted",
            Self::Tiles => "tiles",
        }
    }
}

impl FromStr for Resolve {
    type Err = SsaaError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Self::ALL
            .into_iter()
            .find(|r| r.name() == s)
            .ok_or_else(|| SsaaError::UnknownResolve(s.into()))
    }
}

/// Configuration of adaptive supersampling.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SsaaConfig {
    /// Window side: `m × m` samples per pixel (2..=[`MAX_M`]).
    pub m: u32,
    /// Geometric metric; `None` uses the shading metric alone.
    pub metric: Option<GeometricMetric>,
    /// Constants of the geometric metrics.
    pub constants: Constants,
    /// Shading metric; `None` uses the geometric metric alone.
    pub shading: Option<ShadingMetric>,
    /// Least number of samples per pixel (1; `m²` forces full supersampling).
    pub min_samples: u32,
    /// How the remaining samples are shaded.
    pub resolve: Resolve,
    /// Times the light loop is evaluated per sample (1; more simulates an expensive shader,
    /// the paper's "stalled" column). The result does not change.
    pub stall: u32,
    /// Largest anisotropy of the texture filter (1: trilinear; 16 by default). Hardware
    /// anisotropic filtering is implementation-defined, so only with 1 does the CPU reference
    /// filter textures like the GPU.
    pub anisotropy: u32,
    /// Radiance added everywhere as `albedo·(1 − metallic)·ambient`.
    pub ambient: Vec3,
    /// Radiance where no surface is.
    pub background: Vec3,
}

impl Default for SsaaConfig {
    fn default() -> Self {
        Self {
            m: 4,
            metric: Some(GeometricMetric::NormalDepth),
            constants: Constants::default(),
            shading: Some(ShadingMetric::default()),
            min_samples: 1,
            resolve: Resolve::Loop,
            stall: 1,
            anisotropy: 16,
            ambient: Vec3::splat(0.03),
            background: Vec3::ZERO,
        }
    }
}

impl SsaaConfig {
    /// Samples per window, `m²`.
    pub fn samples(&self) -> u32 {
        self.m * self.m
    }

    /// Checks the window size, constants and thresholds.
    pub fn validate(&self) -> Result<(), SsaaError> {
        if !(2..=MAX_M).contains(&self.m) {
            return Err(SsaaError::WindowSize(self.m));
        }
        let c = self.constants;
        let s = self.shading.unwrap_or_default();
        let values = [
            ("c_MM", c.mm),
            ("c_NC", c.nc),
            ("c_DV", c.dv),
            ("c_NV", c.nv),
            ("c_shading", s.c),
            ("min threshold", s.min_threshold),
            ("edge threshold", s.edge_threshold),
        ];
        if let Some((name, value)) = values.iter().find(|(_, v)| !(v.is_finite() && *v >= 0.0)) {
            return Err(SsaaError::InvalidConstant {
                name,
                value: *value,
            });
        }
        if !(1..=self.samples()).contains(&self.min_samples) {
            return Err(SsaaError::MinSamples {
                min: self.min_samples,
                n: self.samples(),
            });
        }
        if !(1..=MAX_ANISOTROPY).contains(&self.anisotropy) {
            return Err(SsaaError::Anisotropy(self.anisotropy));
        }
        if !(self.ambient.is_finite() && self.background.is_finite()) || self.stall == 0 {
            return Err(SsaaError::InvalidShading);
        }
        Ok(())
    }
}

/// A material as `common.wgsl` sees it (`SsaaMaterial`): the factors and the array layers of
/// the two textures looked up when a sample is shaded (§4.3.3), base colour and emissive, both
/// read at the coordinates the supersampled G-buffer stores: the base colour texture's (else
/// the emissive texture's) through its `KHR_texture_transform`. An emissive texture with
/// another coordinate set or transform than the base colour's is read at the base colour's
/// coordinates. Roughness, metallic, the normal map and occlusion were evaluated into the
/// supersampled G-buffer from the scene's texture store.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct SsaaMaterial {
    /// Linear base colour factor; alpha: the material's specular factor
    /// ([`scene::Material::specular`]).
    pub base_color: [f32; 4],
    /// Emitted radiance factor.
    pub emissive: [f32; 3],
    /// Layer of the base colour texture in the [`TextureArray`] (0: white).
    pub base_layer: u32,
    /// Layer of the emissive texture (0: white).
    pub emissive_layer: u32,
    /// Padding to 16-byte alignment.
    pub _pad: [u32; 3],
}

impl SsaaMaterial {
    /// The materials of `scene`, indexed by material id, reading the array of `layers`.
    pub fn of_scene(scene: &scene::Scene, layers: &ArrayLayers) -> Vec<Self> {
        scene
            .materials
            .iter()
            .map(|m| Self {
                base_color: m.base_color.truncate().extend(m.specular).to_array(),
                emissive: m.emissive.to_array(),
                base_layer: layers.layer_of(m.base_color_texture),
                emissive_layer: layers.layer_of(m.emissive_texture),
                _pad: [0; 3],
            })
            .collect()
    }
}

/// The number of samples a pixel gets from its metric value `k` (additional samples, §4.3):
/// `clamp(1 + ⌊k⌋, min_samples, n)`; a NaN or huge `k` gives `n`.
pub fn sample_count(k: f32, min_samples: u32, n: u32) -> u32 {
    let count = if k < n as f32 {
        1 + k.max(0.0).floor() as u32
    } else {
        n
    };
    count.clamp(min_samples, n)
}

/// Errors of adaptive supersampling.
#[derive(Debug, thiserror::Error)]
pub enum SsaaError {
    /// Window side outside 2..=[`MAX_M`].
    #[error("the sampling window must be 2..={MAX_M} samples wide, got {0}")]
    WindowSize(u32),
    /// A metric constant or threshold is negative or not finite.
    #[error("{name} must be finite and >= 0, got {value}")]
    InvalidConstant {
        /// Which constant.
        name: &'static str,
        /// Its value.
        value: f32,
    },
    /// `min_samples` outside 1..=m².
    #[error("the least sample count must be 1..={n}, got {min}")]
    MinSamples {
        /// Given.
        min: u32,
        /// Samples per window.
        n: u32,
    },
    /// Non-finite ambient or background, or a stall count of 0.
    #[error("ambient and background must be finite and the stall count >= 1")]
    InvalidShading,
    /// Anisotropy outside 1..=16.
    #[error("the anisotropy must be 1..=16, got {0}")]
    Anisotropy(u32),
    /// A metric name that is not MM, NC, DV, NV or ND.
    #[error("unknown metric {0:?} (MM, NC, DV, NV or ND)")]
    UnknownMetric(String),
    /// A resolve name that is not loop or sorted.
    #[error("unknown resolve {0:?} (loop or sorted)")]
    UnknownResolve(String),
    /// The image is empty or its supersampled G-buffer is too large.
    #[error("invalid image size {width}×{height} at {m}×{m} samples per pixel")]
    InvalidSize {
        /// Width in pixels.
        width: u32,
        /// Height in pixels.
        height: u32,
        /// Window side.
        m: u32,
    },
    /// The inputs of a CPU function disagree in size.
    #[error("input sizes disagree: {0}")]
    SizeMismatch(String),
    /// G-buffer creation failed (invalid scene or camera).
    #[error(transparent)]
    GBuffer(#[from] gbuffer::GBufferError),
    /// A GPU resource could not be created or read.
    #[error(transparent)]
    Gpu(#[from] ::gpu::GpuError),
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sample_count_is_one_plus_additional_samples() {
        assert_eq!(sample_count(0.0, 1, 16), 1);
        assert_eq!(sample_count(0.999, 1, 16), 1);
        assert_eq!(sample_count(1.0, 1, 16), 2);
        assert_eq!(sample_count(14.5, 1, 16), 15);
        assert_eq!(sample_count(15.0, 1, 16), 16);
        assert_eq!(sample_count(1e30, 1, 16), 16);
        assert_eq!(sample_count(f32::NAN, 1, 16), 16);
        assert_eq!(sample_count(-3.0, 1, 16), 1);
        assert_eq!(sample_count(0.0, 16, 16), 16);
    }

    #[test]
    fn config_errors() {
        let bad = |f: fn(&mut SsaaConfig)| {
            let mut c = SsaaConfig::default();
            f(&mut c);
            c.validate().is_err()
        };
        assert!(SsaaConfig::default().validate().is_ok());
        assert!(bad(|c| c.m = 1));
        assert!(bad(|c| c.m = 9));
        assert!(bad(|c| c.constants.dv = f32::NAN));
        assert!(bad(|c| c.constants.nc = -1.0));
        assert!(bad(|c| c.min_samples = 0));
        assert!(bad(|c| c.min_samples = 17));
        assert!(bad(|c| c.stall = 0));
        assert!(bad(|c| c.anisotropy = 0));
        assert!(bad(|c| c.anisotropy = 17));
        assert!("nd".parse::<GeometricMetric>().is_ok());
        assert!("xx".parse::<GeometricMetric>().is_err());
        assert!("sorted".parse::<Resolve>().is_ok());
        assert_eq!("tiles".parse::<Resolve>().ok(), Some(Resolve::Tiles));
    }
}
