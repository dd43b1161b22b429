//! Shading stages of §4.3.4 (`shaders/adaptive-ssaa/shade.wgsl`): `S`, the adaptive resolve of
//! Listing 4.1 and full supersampling.

use gbuffer::Image;
use glam::Vec3;

use super::{ShadingInputs, footprint_scale, per_pixel, shade_sample, window_sample};
use crate::{SsaaConfig, SsaaError, dither_order};

/// `S`: the first sample (dither index 0) of every window, filtered over the whole pixel
/// (`shade_first`).
pub fn shade_first(inp: &ShadingInputs, config: &SsaaConfig) -> Result<Image<[f32; 4]>, SsaaError> {
    let (w, h) = inp.check(config)?;
    let order = dither_order(config.m);
    let scale = footprint_scale(config.m, 1);
    Ok(per_pixel(w, h, |x, y| {
        let c = shade_sample(
            inp,
            config,
            window_sample([x, y], config.m, &order, 0),
            scale,
        );
        c.extend(1.0).to_array()
    }))
}

/// Average of samples `0..k` of pixel `p`'s window in dither order, each filtered over its
/// share of the pixel ([`footprint_scale`]); the same sum order as the shader.
fn average_samples(
    inp: &ShadingInputs,
    config: &SsaaConfig,
    order: &[[u32; 2]],
    p: [u32; 2],
    k: u32,
) -> Vec3 {
    let scale = footprint_scale(config.m, k);
    let mut sum = Vec3::ZERO;
    for i in 0..k as usize {
        sum += shade_sample(inp, config, window_sample(p, config.m, order, i), scale);
    }
    sum / k as f32
}

/// Adaptive shading (`shade_adaptive`, Listing 4.1's `ShadeRestAdaptively`): `S` where the
/// pixel needs one sample; otherwise the average of its `k` first samples in dither order.
/// `S` was filtered over the whole pixel, so a pixel with `k > 1` shades its first sample again
/// with the narrower footprint of one of `k` samples (one more shading than the paper's reuse
/// of `S`, counted in [`Output::shaded`]).
pub fn shade_adaptive(
    inp: &ShadingInputs,
    config: &SsaaConfig,
    s: &Image<[f32; 4]>,
    counts: &Image<u32>,
) -> Result<Image<[f32; 4]>, SsaaError> {
    let (w, h) = inp.check(config)?;
    if (counts.width(), counts.height()) != (w, h) || (s.width(), s.height()) != (w, h) {
        return Err(SsaaError::SizeMismatch("S or the sample counts".into()));
    }
    let order = dither_order(config.m);
    Ok(per_pixel(w, h, |x, y| {
        let k = counts.get(x, y).clamp(1, config.samples());
        if k == 1 {
            s.get(x, y)
        } else {
            average_samples(inp, config, &order, [x, y], k)
                .extend(1.0)
                .to_array()
        }
    }))
}

/// Full supersampling (`shade_full`): the average of all `m²` samples of every window, in
/// dither order.
pub fn shade_full(inp: &ShadingInputs, config: &SsaaConfig) -> Result<Image<[f32; 4]>, SsaaError> {
    let (w, h) = inp.check(config)?;
    let order = dither_order(config.m);
    let n = config.samples();
    Ok(per_pixel(w, h, |x, y| {
        average_samples(inp, config, &order, [x, y], n)
            .extend(1.0)
            .to_array()
    }))
}
