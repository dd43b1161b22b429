//! One-bounce indirect light by instant radiosity with interleaved deferred shading — the
//! pipeline of Segovia 2006 §4 applied as in §6.2: G-buffer creation (BC), split (BS),
//! shading with no shadow map of one VPL subset per sub-buffer (SNSM), gather (BG),
//! discontinuity buffer (DB), edge-aware blur (B), then composition with the albedo and the
//! direct light. [`Interleaving::Reference`] is the non-interleaved frame where every pixel
//! shades every VPL. VPLs come from light paths traced on the CPU ([`vpl`]); their visibility
//! on the GPU comes from ManyLoD cuts or imperfect shadow maps ([`shadows`], Holländer 2013
//! §3.6). The CPU twin is [`cpu::indirect`], the GPU stage [`gpu::IndirectStage`]
//! (`new` → `bind` of the caller's G-buffer views → `encode`).
//!
//! ```
//! use instant_radiosity::{IndirectConfig, vpl};
//! let scene = scene::cornell_box();
//! let camera = scene.camera_or_framed();
//! let gb = gbuffer::cpu::rasterize(&scene, &camera, 64, 48)?.gbuffer;
//! let frame = gbuffer::Frame::new(&camera, 64, 48);
//! let config = IndirectConfig::new(scene.bounds());
//! let set = vpl::generate(&scene, &scene::Bvh::build(&scene), &scene.lights, &vpl::VplConfig {
//!     count: 256,
//!     subsets: config.subsets(),
//!     seed: 1,
//!     emissive: false,
//!     bounces: 1,
//! })?;
//! let stages = instant_radiosity::cpu::indirect(&gb, &frame, &set, &config)?;
//! let (diffuse, _specular) = stages.result();
//! assert_eq!(diffuse.width(), 64);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

pub mod cpu;
pub mod gpu;
pub mod near_field;
pub mod pbgi;
pub mod rays;
pub mod reflections;
pub mod shadows;
pub mod ssm;
pub mod vpl;

use gbuffer::Image;
use interleave::{Blur, BlurVariant, Pattern, SplitVariant, Thresholds};
use scene::Aabb;

/// This crate's WGSL (`shaders/instant-radiosity/`, carried into the package by the `shaders`
/// link).
pub static SHADERS: ::gpu::shader::Library = ::gpu::shader_library!(
    "instant-radiosity",
    imports: [gbuffer::SHADERS, tiled_shading::SHADERS, manylod::SHADERS, interleave::SHADERS],
    files: [
        "vpl.wgsl",
        "vpl_shading.wgsl",
        "direct.wgsl",
        "near_field.wgsl",
        "ssm.wgsl",
        "pbgi.wgsl",
        "pbgi_grid.wgsl",
        "pbgi_lighting.wgsl",
        "pbgi_receivers.wgsl",
        "pbgi_upsample.wgsl",
        "reflections.wgsl",
    ],
);

/// What this crate's kernels need of a device: the interleaving passes' and the VPL
/// visibility's (ManyLoDs) needs.
pub fn device_needs() -> ::gpu::DeviceNeeds {
    gbuffer::device_needs()
        .and(&interleave::device_needs())
        .and(&tiled_shading::device_needs())
        .and(&manylod::device_needs())
}

/// Errors of the indirect-light stage.
#[derive(Debug, thiserror::Error)]
pub enum IndirectError {
    /// The G-buffer could not be made or uploaded.
    #[error(transparent)]
    GBuffer(#[from] gbuffer::GBufferError),
    /// A GPU resource could not be created, bound or read.
    #[error(transparent)]
    Gpu(#[from] ::gpu::GpuError),
    /// A bad interleaving pattern, blur, threshold or texture.
    #[error(transparent)]
    Interleave(#[from] interleave::InterleaveError),
    /// VPL generation failed, or a VPL set does not fit the stage.
    #[error(transparent)]
    Vpl(#[from] vpl::VplError),
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
    /// The direct lights' shadow-map pass failed (the rasterised VPL shadow maps use it).
    #[error(transparent)]
    Shadows(#[from] tiled_shading::ShadingError),
    /// VPL visibility by rays that the scene cannot give (no triangles, too deep a tree).
    #[error("VPL visibility by rays: {0}")]
    Rays(String),
    /// A VPL set that does not fit the near field it replaces.
    #[error("the VPLs' near field: {0}")]
    NearField(String),
    /// Point-based GI settings that cannot be used.
    #[error("{0}")]
    Config(String),
    /// Rasterised VPL shadow maps that the device or the views cannot hold.
    #[error("rasterised VPL shadow maps: {0}")]
    Ssm(String),
    /// A VPL shadow-map bias, normal offset or slope tolerance is negative or not finite.
    #[error("the VPL shadow maps' {what} must be finite and >= 0, got {value}")]
    ShadowLookup {
        /// Which setting.
        what: &'static str,
        /// Its value.
        value: f32,
    },
    /// The VPL clamp distance is negative or not finite.
    #[error("the VPL clamp distance must be finite and >= 0, got {0}")]
    Clamp(f32),
}

/// How the shading is interleaved.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Interleaving {
    /// The paper's pipeline: split the G-buffer (BS), shade the sub-buffers (SNSM), gather
    /// (BG), with the given split variant.
    Split(SplitVariant),
    /// Shading in sub-buffer order straight from the G-buffer, writing each pixel in place
    /// (§3.1's indirection): no BS and no BG pass, the same image.
    Fused,
    /// No interleaving: every pixel shades every VPL (the reference).
    Reference,
}

/// Configuration of the indirect-light stage.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IndirectConfig {
    /// Interleaved sampling pattern n × m (one VPL subset per sub-buffer).
    pub pattern: Pattern,
    /// Split/fused interleaving or the reference.
    pub interleaving: Interleaving,
    /// Edge-aware blur of the gathered irradiance (`None`: unfiltered). Not applied to the
    /// reference.
    pub blur: Option<Blur>,
    /// Discontinuity thresholds for the blur.
    pub thresholds: Thresholds,
    /// Distance below which a VPL's `1/d²` is clamped (world units).
    pub clamp_distance: f32,
}

impl IndirectConfig {
    /// The defaults for a scene of `bounds`: 4×4 pattern, fused interleaving, 5×5 fast blur,
    /// 30°/5 % thresholds, clamp at [`default_clamp`].
    pub fn new(bounds: Aabb) -> Self {
        Self {
            pattern: Pattern { n: 4, m: 4 },
            interleaving: Interleaving::Fused,
            blur: Some(Blur {
                kernel: 5,
                variant: BlurVariant::Fast,
            }),
            thresholds: Thresholds::default(),
            clamp_distance: default_clamp(bounds),
        }
    }

    /// Number of VPL subsets this configuration shades: n·m, or 1 for the reference.
    pub fn subsets(&self) -> u32 {
        match self.interleaving {
            Interleaving::Reference => 1,
            _ => self.pattern.count(),
        }
    }

    /// The pattern the shading runs with (1×1 for the reference).
    pub fn shading_pattern(&self) -> Pattern {
        match self.interleaving {
            Interleaving::Reference => Pattern { n: 1, m: 1 },
            _ => self.pattern,
        }
    }

    /// The blur that is applied: none for the reference, nor for a 1×1 pattern (every pixel
    /// shades every VPL: no interleaving noise to remove, the reference's image).
    pub fn applied_blur(&self) -> Option<Blur> {
        match self.interleaving {
            Interleaving::Reference => None,
            _ if self.pattern.count() == 1 => None,
            _ => self.blur,
        }
    }

    /// Checks the configuration against a VPL set: valid pattern, blur, thresholds and clamp,
    /// and as many VPL subsets as sub-buffers (any subset count for the reference, which
    /// shades them all).
    pub fn validate(&self, set: &vpl::VplSet) -> Result<(), IndirectError> {
        self.validate_alone()?;
        if self.interleaving != Interleaving::Reference && set.subsets != self.pattern.count() {
            return Err(IndirectError::Subsets {
                vpl_subsets: set.subsets,
                sub_buffers: self.pattern.count(),
            });
        }
        Ok(())
    }

    /// Checks the configuration on its own: valid pattern, blur, thresholds and clamp.
    pub fn validate_alone(&self) -> Result<(), IndirectError> {
        Pattern::new(self.pattern.n, self.pattern.m)?;
        if let Some(blur) = &self.blur {
            blur.validate()?;
        }
        self.thresholds.validate()?;
        if let Interleaving::Split(variant) = self.interleaving {
            variant.validate(self.pattern)?;
        }
        if !(self.clamp_distance.is_finite() && self.clamp_distance >= 0.0) {
            return Err(IndirectError::Clamp(self.clamp_distance));
        }
        Ok(())
    }

    /// The subset scale of the shading: one subset of a set of `set.subsets` estimates the
    /// whole set when multiplied by `set.subsets`; the reference shades all of them once.
    pub fn scale(&self, set: &vpl::VplSet) -> f32 {
        match self.interleaving {
            Interleaving::Reference => 1.0,
            _ => set.subsets as f32,
        }
    }

    /// VPLs each shading invocation sums.
    pub fn per_invocation(&self, set: &vpl::VplSet) -> u32 {
        match self.interleaving {
            Interleaving::Reference => set.vpls.len() as u32,
            _ => set.per_subset,
        }
    }
}

/// The default VPL clamp distance: 2 % of the scene's bounding-box diagonal.
pub fn default_clamp(bounds: Aabb) -> f32 {
    0.02 * bounds.diagonal()
}

/// The images of every stage of the indirect pipeline (for dumps, tests and pictures).
/// Irradiance images are RGB in `[f32; 4]` with values rounded to f16, as the GPU stores them.
pub struct IndirectStages {
    /// The split G-buffer normals (BS; `None` when fused or the reference).
    pub split_normal: Option<Image<u32>>,
    /// Diffuse light of the shading pass in its layout (split for [`Interleaving::Split`]).
    pub shaded_diffuse: Image<[f32; 4]>,
    /// Diffuse light `Σ E/π` per pixel after the gather, before the blur.
    pub diffuse: Image<[f32; 4]>,
    /// Specular light `Σ E·D·V·F` per pixel after the gather, before the blur.
    pub specular: Image<[f32; 4]>,
    /// The discontinuity buffer (DB; `None` without blur).
    pub discontinuities: Option<Image<[u8; 4]>>,
    /// Diffuse and specular after the blur (B; `None` without blur).
    pub blurred: Option<[Image<[f32; 4]>; 2]>,
    /// Wall-clock time of each stage on the CPU path (empty when read back from the GPU,
    /// whose renderer times the passes with timestamps).
    pub timings: Vec<::gpu::PassTiming>,
}

impl IndirectStages {
    /// The diffuse and specular indirect light that the composition uses.
    pub fn result(&self) -> (&Image<[f32; 4]>, &Image<[f32; 4]>) {
        match &self.blurred {
            Some([d, s]) => (d, s),
            None => (&self.diffuse, &self.specular),
        }
    }
}
