//! The output transform: linear radiance → display-linear RGB in \[0, 1\] (`output.wgsl`,
//! `OutputPass` on the GPU, [`OutputTransform::apply`] its CPU twin). Exposure is `2^EV`,
//! times `0.18 / L̄` with automatic exposure, where `L̄ = exp(mean log(δ + L))` is the
//! log-average luminance of the pixels with `L > 0` (Reinhard et al. 2002, "Photographic Tone
//! Reproduction", key 0.18, δ = 10⁻⁴); the tone mapper is the fitted ACES (Hill 2016: the RRT
//! and the sRGB ODT in one rational curve between two matrices) or a clamp. The sRGB encode
//! follows where the image is stored (PNG, or an sRGB surface); EXR files stay linear.
//!
//! ```
//! use pipeline::output::{OutputTransform, ToneMapper};
//! let t = OutputTransform { exposure_ev: 1.0, auto_exposure: false, tone_mapper: ToneMapper::AcesFitted };
//! let image = gbuffer::Image::from_vec(1, 1, vec![[0.18f32, 0.18, 0.18, 1.0]]).expect("1 pixel");
//! let display = t.apply(&image);
//! assert!(display.get(0, 0)[0] > 0.18 && display.get(0, 0)[0] < 0.36);
//! ```

use ::gpu::kernel::{self, Binding, Dispatch, Layout, Passes, Workgroups};
use ::gpu::{GpuError, PassTimer};
use gbuffer::Image;
use glam::{Mat3, Vec3};
use scene::luminance;

use crate::RenderError;

/// The key of automatic exposure: the log-average luminance maps to 0.18.
pub const KEY: f32 = 0.18;
/// δ of the log-average (keeps log finite for very dark pixels).
pub const LOG_DELTA: f32 = 1e-4;

/// The tone curve.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ToneMapper {
    /// Exposed radiance clamped to \[0, 1\] (no curve).
    Clamp,
    /// Hill's fit of ACES (RRT + sRGB ODT): a filmic shoulder, saturated highlights desaturate.
    #[default]
    AcesFitted,
}

impl std::str::FromStr for ToneMapper {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "clamp" | "none" => Ok(Self::Clamp),
            "aces" => Ok(Self::AcesFitted),
            other => Err(format!("unknown tone mapper {other:?} (aces, clamp)")),
        }
    }
}

/// Exposure and tone mapping of a frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OutputTransform {
    /// Exposure compensation in stops (the radiance is multiplied by `2^EV`).
    pub exposure_ev: f32,
    /// Also scale by `KEY / L̄`, the frame's log-average luminance.
    pub auto_exposure: bool,
    /// The tone curve.
    pub tone_mapper: ToneMapper,
}

impl Default for OutputTransform {
    fn default() -> Self {
        Self {
            exposure_ev: 0.0,
            auto_exposure: false,
            tone_mapper: ToneMapper::AcesFitted,
        }
    }
}

/// Hill's fitted ACES (`aces_fitted` in `output.wgsl`).
pub fn aces_fitted(c: Vec3) -> Vec3 {
    let input = Mat3::from_cols(
        Vec3::new(0.59719, 0.07600, 0.02840),
        Vec3::new(0.35458, 0.90834, 0.13383),
        Vec3::new(0.04823, 0.01566, 0.83777),
    );
    let output = Mat3::from_cols(
        Vec3::new(1.60475, -0.10208, -0.00327),
        Vec3::new(-0.53108, 1.10813, -0.07276),
        Vec3::new(-0.07367, -0.00605, 1.07602),
    );
    let v = input * c;
    let a = v * (v + 0.024_578_6) - 0.000_090_537;
    let b = v * (0.983_729 * v + 0.432_951) + 0.238_081;
    output * (a / b)
}

impl OutputTransform {
    /// Rejects a non-finite or out-of-range (beyond ±64 stops) exposure.
    pub fn validate(&self) -> Result<(), RenderError> {
        if !(self.exposure_ev.is_finite() && self.exposure_ev.abs() <= 64.0) {
            return Err(RenderError::InvalidOutput(format!(
                "exposure {} EV is not a finite number within ±64 stops",
                self.exposure_ev
            )));
        }
        Ok(())
    }

    /// The exposure multiplier for `image`: `2^EV`, times `KEY / L̄` when automatic.
    pub fn exposure(&self, image: &Image<[f32; 4]>) -> f32 {
        let mut scale = self.exposure_ev.exp2();
        if self.auto_exposure {
            let (sum, count) = image
                .pixels()
                .iter()
                .map(|p| luminance(Vec3::new(p[0], p[1], p[2])))
                .filter(|&l| l > 0.0)
                .fold((0.0f64, 0u64), |(s, n), l| {
                    (s + f64::from((LOG_DELTA + l).ln()), n + 1)
                });
            if count > 0 {
                scale *= KEY / (sum / count as f64).exp() as f32;
            }
        }
        scale
    }

    /// The display-linear image (alpha 1), `output_main`'s twin.
    pub fn apply(&self, image: &Image<[f32; 4]>) -> Image<[f32; 4]> {
        let exposure = self.exposure(image);
        image.map(|p| {
            let c = Vec3::new(p[0], p[1], p[2]) * exposure;
            let d = match self.tone_mapper {
                ToneMapper::Clamp => c,
                ToneMapper::AcesFitted => aces_fitted(c),
            }
            .clamp(Vec3::ZERO, Vec3::ONE);
            [d.x, d.y, d.z, 1.0]
        })
    }
}

/// `output.wgsl` on the GPU: new → bind → encode. Its three kernels share one layout.
pub struct OutputPass {
    layout: Layout,
    log_luminance: wgpu::ComputePipeline,
    exposure: wgpu::ComputePipeline,
    output: wgpu::ComputePipeline,
}

/// Format of the display texture [`OutputPass`] writes.
pub const DISPLAY_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;

const BINDINGS: [Binding; 4] = [
    Binding::Uniform,
    Binding::TextureUnfilterable,
    Binding::Storage,
    Binding::StorageTexture(DISPLAY_FORMAT),
];

/// [`OutputPass`] bound to a radiance texture and a display texture of its size.
pub struct BoundOutput {
    passes: Passes,
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct OutputParams {
    exposure: f32,
    auto_exposure: u32,
    tone_mapper: u32,
    partials: u32,
}

impl OutputPass {
    /// Builds the three kernels.
    pub fn new(device: &wgpu::Device) -> Result<Self, GpuError> {
        let module = crate::SHADERS.module(device, "output.wgsl")?;
        let layout = Layout::compute(device, "output transform", &BINDINGS);
        let pipeline = |entry| kernel::pipeline(device, &module, entry, &[&layout], &[]);
        Ok(Self {
            log_luminance: pipeline("log_luminance_main"),
            exposure: pipeline("exposure_main"),
            output: pipeline("output_main"),
            layout,
        })
    }

    /// Binds `radiance` (linear, `TEXTURE_BINDING`) and `display` (same size,
    /// [`DISPLAY_FORMAT`], `STORAGE_BINDING`) with `transform`.
    pub fn bind(
        &self,
        device: &wgpu::Device,
        radiance: &wgpu::Texture,
        display: &wgpu::Texture,
        transform: &OutputTransform,
    ) -> Result<BoundOutput, RenderError> {
        transform.validate()?;
        let (w, h) = (radiance.width(), radiance.height());
        ::gpu::kernel::check_texture(
            "the display texture",
            display,
            (w, h),
            DISPLAY_FORMAT,
            wgpu::TextureUsages::STORAGE_BINDING,
        )?;
        let tiles = w.div_ceil(16) * h.div_ceil(16);
        let params = OutputParams {
            exposure: transform.exposure_ev.exp2(),
            auto_exposure: u32::from(transform.auto_exposure),
            tone_mapper: match transform.tone_mapper {
                ToneMapper::Clamp => 0,
                ToneMapper::AcesFitted => 1,
            },
            partials: tiles,
        };
        let params = ::gpu::transfer::buffer_init(
            device,
            "output params",
            bytemuck::bytes_of(&params),
            wgpu::BufferUsages::UNIFORM,
        )?;
        let sums = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("log-luminance sums"),
            size: u64::from(tiles + 1) * 8,
            usage: wgpu::BufferUsages::STORAGE,
            mapped_at_creation: false,
        });
        let (radiance_view, display_view) = (
            radiance.create_view(&Default::default()),
            display.create_view(&Default::default()),
        );
        let group = self.layout.bind(
            device,
            &[
                params.as_entire_binding(),
                wgpu::BindingResource::TextureView(&radiance_view),
                sums.as_entire_binding(),
                wgpu::BindingResource::TextureView(&display_view),
            ],
        );
        let dispatch = |pipeline: &wgpu::ComputePipeline, workgroups| Dispatch {
            pipeline: pipeline.clone(),
            groups: vec![group.clone()],
            workgroups,
        };
        let passes = Passes::new().pass(
            "output transform",
            vec![
                dispatch(&self.log_luminance, Workgroups::covering(w, h, 16)),
                dispatch(&self.exposure, Workgroups::Direct([1, 1, 1])),
                dispatch(&self.output, Workgroups::covering(w, h, 8)),
            ],
        );
        Ok(BoundOutput { passes })
    }
}

impl BoundOutput {
    /// Records the transform, timed as "output transform".
    pub fn encode(&self, encoder: &mut wgpu::CommandEncoder, timer: Option<&PassTimer>) {
        self.passes.encode(encoder, timer);
    }
}
