//! The sample-count evaluation of §4.3.3 (`shaders/adaptive-ssaa/evaluate.wgsl`): the geometric
//! metrics of the window and the shading metric on `S`.

use gbuffer::{Image, normal::unpack_octahedral};
use glam::{Vec3, Vec4Swizzles};

use super::{LUMINANCE, ShadingInputs, per_pixel, window_sample};
use crate::{GeometricMetric, SsaaConfig, SsaaError, dither_order, sample_count};

/// The window's depths (view depth / far, 1 where no surface) and unit normals (the camera's
/// backward axis where no surface: the background is treated as a surface on the far plane
/// facing the viewer), in the order `order` ([`dither_order`]).
pub fn window(
    inp: &ShadingInputs,
    m: u32,
    order: &[[u32; 2]],
    p: [u32; 2],
) -> (Vec<f32>, Vec<Vec3>) {
    let back = inp.frame.inv_view.z_axis.xyz();
    (0..order.len())
        .map(|i| {
            let q = window_sample(p, m, order, i);
            let depth = inp.gbuffer.linear_depth.get(q[0], q[1]);
            if depth > 0.0 {
                (
                    depth / inp.far,
                    unpack_octahedral(inp.gbuffer.normal.get(q[0], q[1])),
                )
            } else {
                (1.0, back)
            }
        })
        .unzip()
}

/// The geometric metric `k` of one window (§4.3.1), constants applied (`geometric_metric`).
pub fn geometric_metric(
    config: &SsaaConfig,
    metric: GeometricMetric,
    d: &[f32],
    n: &[Vec3],
) -> f32 {
    let c = config.constants;
    let count = d.len() as f32;
    let sum: Vec3 = n.iter().copied().sum();
    let mean_normal = if sum.length_squared() > 0.0 {
        sum.normalize()
    } else {
        n[0]
    };
    let normal_cone = || {
        let min_cos = n
            .iter()
            .map(|ni| mean_normal.dot(*ni).abs())
            .fold(1.0f32, f32::min);
        c.nc * (1.0 - min_cos).max(0.0).sqrt()
    };
    let depth_variance = || {
        let (s, s2) = d
            .iter()
            .fold((0.0f32, 0.0f32), |(s, s2), &di| (s + di, s2 + di * di));
        let mean = s / count;
        c.dv * (s2 / count - mean * mean).max(0.0)
    };
    match metric {
        GeometricMetric::MinMax => {
            let (lo, hi) = d
                .iter()
                .fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), &di| {
                    (lo.min(di), hi.max(di))
                });
            c.mm * (hi - lo)
        }
        GeometricMetric::NormalCone => normal_cone(),
        GeometricMetric::DepthVariance => depth_variance(),
        GeometricMetric::NormalVariance => {
            c.nv * n
                .iter()
                .map(|ni| (1.0 - ni.dot(mean_normal)).powi(2))
                .sum::<f32>()
        }
        GeometricMetric::NormalDepth => normal_cone().max(depth_variance()),
    }
}

/// Luminance of a colour of `S`.
pub fn luminance(c: [f32; 4]) -> f32 {
    Vec3::new(c[0], c[1], c[2]).dot(LUMINANCE)
}

/// The luminance range `r` of `S` over pixel `(x, y)` and its four direct neighbours (clamped
/// at the image border) and the threshold it is compared with,
/// `max(min_threshold, l_max·edge_threshold)`.
pub fn luminance_range(config: &SsaaConfig, s: &Image<[f32; 4]>, x: u32, y: u32) -> (f32, f32) {
    let sm = config.shading.unwrap_or_default();
    let (w, h) = (s.width(), s.height());
    let l = |dx: i32, dy: i32| {
        let qx = (x as i32 + dx).clamp(0, w as i32 - 1) as u32;
        let qy = (y as i32 + dy).clamp(0, h as i32 - 1) as u32;
        luminance(s.get(qx, qy))
    };
    let ls = [l(0, 0), l(0, -1), l(-1, 0), l(1, 0), l(0, 1)];
    let lo = ls.iter().copied().fold(f32::INFINITY, f32::min);
    let hi = ls.iter().copied().fold(f32::NEG_INFINITY, f32::max);
    (hi - lo, sm.min_threshold.max(hi * sm.edge_threshold))
}

/// The shading metric of pixel `(x, y)` on `S` (`shading_metric`): `0` if the
/// [`luminance_range`] is below its threshold, else `c·r`.
pub fn shading_metric(config: &SsaaConfig, s: &Image<[f32; 4]>, x: u32, y: u32) -> f32 {
    let Some(sm) = config.shading else {
        return 0.0;
    };
    let (r, threshold) = luminance_range(config, s, x, y);
    if r < threshold { 0.0 } else { sm.c * r }
}

/// The metric value `k` of pixel `(x, y)`: the maximum of the geometric and the shading
/// metric (additional samples before rounding).
pub fn pixel_metric(
    inp: &ShadingInputs,
    config: &SsaaConfig,
    s: &Image<[f32; 4]>,
    x: u32,
    y: u32,
) -> f32 {
    metric_in_order(inp, config, &dither_order(config.m), s, x, y)
}

/// [`pixel_metric`] with the window's sample order computed once by the caller.
fn metric_in_order(
    inp: &ShadingInputs,
    config: &SsaaConfig,
    order: &[[u32; 2]],
    s: &Image<[f32; 4]>,
    x: u32,
    y: u32,
) -> f32 {
    let geometric = config.metric.map_or(0.0, |metric| {
        let (d, n) = window(inp, config.m, order, [x, y]);
        geometric_metric(config, metric, &d, &n)
    });
    geometric.max(shading_metric(config, s, x, y))
}

/// The number of samples per pixel (`evaluate`, Listing 4.1's `Evaluate`): the maximum of the
/// geometric and the shading metric, as [`sample_count`].
pub fn evaluate(
    inp: &ShadingInputs,
    config: &SsaaConfig,
    s: &Image<[f32; 4]>,
) -> Result<Image<u32>, SsaaError> {
    let (w, h) = inp.check(config)?;
    if (s.width(), s.height()) != (w, h) {
        return Err(SsaaError::SizeMismatch(format!(
            "S is {}×{} but the image is {w}×{h}",
            s.width(),
            s.height()
        )));
    }
    let order = dither_order(config.m);
    Ok(per_pixel(w, h, |x, y| {
        let k = metric_in_order(inp, config, &order, s, x, y);
        sample_count(k, config.min_samples, config.samples())
    }))
}
