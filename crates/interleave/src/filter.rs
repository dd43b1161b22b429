//! Parameters of the discontinuity buffer and the edge-aware blur (Segovia 2006 §4.5).

use crate::InterleaveError;

/// Discontinuity thresholds (§4.5): a pixel is on a discontinuity when its normal or its
/// depth differs too much from one of its three positive neighbours (x+1, y), (x, y+1),
/// (x+1, y+1).
///
/// - normals: the angle between the two normals exceeds `normal_deg`;
/// - positions: the larger view depth exceeds the smaller by more than the fraction
///   `depth_ratio` of the smaller one (a relative test along the view ray, so one threshold
///   works near and far). A pixel with no surface (linear depth 0) differs from every
///   surface pixel and from no other empty pixel.
///
/// Both tests are computed with operations that round the same on every IEEE machine (see
/// `cpu::discontinuity`), so the CPU and GPU buffers are equal bit for bit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Thresholds {
    /// Largest angle in degrees between continuous normals, in (0, 180).
    pub normal_deg: f32,
    /// Largest relative depth difference between continuous pixels, ≥ 0.
    pub depth_ratio: f32,
}

impl Default for Thresholds {
    /// 30° and 5 %.
    fn default() -> Self {
        Self {
            normal_deg: 30.0,
            depth_ratio: 0.05,
        }
    }
}

impl Thresholds {
    /// Checks the ranges.
    pub fn validate(&self) -> Result<(), InterleaveError> {
        if !(self.normal_deg > 0.0 && self.normal_deg < 180.0) {
            return Err(InterleaveError::Threshold {
                what: "normal_deg",
                value: self.normal_deg,
                why: "must be an angle in degrees strictly between 0 and 180",
            });
        }
        if !(self.depth_ratio >= 0.0 && self.depth_ratio.is_finite()) {
            return Err(InterleaveError::Threshold {
                what: "depth_ratio",
                value: self.depth_ratio,
                why: "must be a finite fraction ≥ 0",
            });
        }
        Ok(())
    }

    /// cos² of the normal threshold and its sign (cos < 0 above 90°), as the kernels use them.
    pub(crate) fn cos_squared(&self) -> (f32, bool) {
        let c = self.normal_deg.to_radians().cos();
        (c * c, c >= 0.0)
    }

    /// 1 + depth_ratio, the factor of the depth test.
    pub(crate) fn depth_factor(&self) -> f32 {
        1.0 + self.depth_ratio
    }
}

/// The two blurs of §4.5 / Table 2.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum BlurVariant {
    /// One texel fetch per kernel tap, at texel centres.
    Plain,
    /// "Fast Gaussian blur": taps fetched in pairs between two texel centres (0.5 texel bias)
    /// with hardware bilinear filtering; the discontinuity buffer is sampled the same way and a
    /// pair is ignored, with everything beyond it, as soon as the filtered value is > 0.
    Fast,
}

/// An edge-aware separable Gaussian blur of `kernel × kernel` taps (odd, 5 to 17).
///
/// The Gaussian has σ = radius / 2 (radius = (kernel − 1) / 2), so the outermost taps weigh
/// e⁻² ≈ 0.14 of the centre. Weights are renormalised by the sum of the taps actually
/// blended, so a constant image stays constant next to discontinuities.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Blur {
    /// Taps per direction, odd, 5..=17.
    pub kernel: u32,
    /// Plain or fast.
    pub variant: BlurVariant,
}

impl Blur {
    /// A validated blur.
    pub fn new(kernel: u32, variant: BlurVariant) -> Result<Self, InterleaveError> {
        let blur = Self { kernel, variant };
        blur.validate()?;
        Ok(blur)
    }

    /// Checks the kernel size.
    pub fn validate(&self) -> Result<(), InterleaveError> {
        if (5..=17).contains(&self.kernel) && self.kernel % 2 == 1 {
            Ok(())
        } else {
            Err(InterleaveError::Kernel(self.kernel))
        }
    }

    /// Taps on each side of the centre.
    pub fn radius(&self) -> u32 {
        (self.kernel - 1) / 2
    }

    /// Gaussian weights of taps 0..=radius (centre first), not normalised.
    pub fn weights(&self) -> Vec<f32> {
        let sigma = self.radius() as f32 / 2.0;
        (0..=self.radius())
            .map(|k| (-((k * k) as f32) / (2.0 * sigma * sigma)).exp())
            .collect()
    }
}
