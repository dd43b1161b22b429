//! CPU reference of adaptive supersampling: the specification `ssaa.wgsl` is tested against.
//! Every function mirrors the shader function or entry point of the same name.
//!
//! Input is a supersampled G-buffer ([`SsGBuffer`], e.g. read back from
//! [`crate::gpu::SsGBufferTargets`]); the image is `w × h` with `m × m` samples per pixel, and
//! pixel `(x, y)`'s sample `i` is G-buffer sample `(m·x, m·y) + dither_order(m)[i]`.

use gbuffer::normal::unpack_octahedral;
use gbuffer::{Frame, Image, unpack_material};
use glam::{Vec2, Vec3, Vec4, Vec4Swizzles};
use rayon::prelude::*;
use tiled_shading::GpuLight;
use tiled_shading::lighting::shade_light;

use crate::{
    GeometricMetric, SsaaConfig, SsaaError, SsaaMaterial, TextureArray, dither_order, sample_count,
};

/// Rec. 709 luminance weights of the shading metric and FXAA.
pub const LUMINANCE: Vec3 = Vec3::new(0.2126, 0.7152, 0.0722);

/// A supersampled G-buffer on the CPU, sample for sample what the GPU targets hold.
#[derive(Clone, Debug, PartialEq)]
pub struct SsGBuffer {
    /// View depth, 0 where no surface.
    pub linear_depth: Image<f32>,
    /// Octahedral normal words.
    pub normal: Image<u32>,
    /// Texture coordinates.
    pub uv: Image<[f32; 2]>,
    /// Texture-coordinate derivatives per sample step: ∂u/∂x, ∂v/∂x, ∂u/∂y, ∂v/∂y.
    pub uv_grad: Image<[f32; 4]>,
    /// Material words (`gbuffer::pack_material`), `gbuffer::NO_MATERIAL` where no surface.
    pub material: Image<u32>,
}

/// Everything shading a sample needs besides the configuration.
#[derive(Clone, Copy)]
pub struct ShadingInputs<'a> {
    /// The supersampled G-buffer.
    pub gbuffer: &'a SsGBuffer,
    /// Camera data at the G-buffer's (sample) resolution.
    pub frame: &'a Frame,
    /// Distance of the far plane: depths enter the metrics as view depth / far.
    pub far: f32,
    /// The texture array.
    pub textures: &'a TextureArray,
    /// Materials by id.
    pub materials: &'a [SsaaMaterial],
    /// Lights.
    pub lights: &'a [GpuLight],
}

impl ShadingInputs<'_> {
    fn image_size(&self, m: u32) -> (u32, u32) {
        (
            self.gbuffer.linear_depth.width() / m,
            self.gbuffer.linear_depth.height() / m,
        )
    }

    fn check(&self, config: &SsaaConfig) -> Result<(u32, u32), SsaaError> {
        config.validate()?;
        let g = self.gbuffer;
        let (w, h) = (g.linear_depth.width(), g.linear_depth.height());
        let same = |iw: u32, ih: u32| iw == w && ih == h;
        if !(same(g.normal.width(), g.normal.height())
            && same(g.uv.width(), g.uv.height())
            && same(g.uv_grad.width(), g.uv_grad.height())
            && same(g.material.width(), g.material.height()))
        {
            return Err(SsaaError::SizeMismatch(
                "the G-buffer images differ in size".into(),
            ));
        }
        if w == 0 || h == 0 || w % config.m != 0 || h % config.m != 0 {
            return Err(SsaaError::InvalidSize {
                width: w,
                height: h,
                m: config.m,
            });
        }
        Ok(self.image_size(config.m))
    }
}

/// The footprint of one of `k` samples averaged over a pixel, in sample steps: `m / √k`. The
/// stored derivatives (per sample step) are scaled by it before the texture lookup, so the
/// anisotropic filter covers the part of the pixel the sample stands for (§4.3.4).
pub fn footprint_scale(m: u32, k: u32) -> f32 {
    m as f32 / (k as f32).sqrt()
}

/// G-buffer sample of pixel `p`'s window that is the `i`-th in dither order.
fn window_sample(p: [u32; 2], m: u32, order: &[[u32; 2]], i: usize) -> [u32; 2] {
    [p[0] * m + order[i][0], p[1] * m + order[i][1]]
}

/// Shades G-buffer sample `q` (`shade_sample`): material and texture lookup with the
/// derivatives scaled by `scale`, every light, ambient and emission; the background colour
/// where no surface is.
pub fn shade_sample(inp: &ShadingInputs, config: &SsaaConfig, q: [u32; 2], scale: f32) -> Vec3 {
    let g = inp.gbuffer;
    let depth = g.linear_depth.get(q[0], q[1]);
    let word = g.material.get(q[0], q[1]);
    if depth <= 0.0 || word == gbuffer::NO_MATERIAL {
        return config.background;
    }
    let n = unpack_octahedral(g.normal.get(q[0], q[1]));
    let (roughness, metallic, id) = unpack_material(word);
    let Some(material) = inp.materials.get(id as usize) else {
        return config.background;
    };
    let grad = Vec4::from(g.uv_grad.get(q[0], q[1])) * scale;
    let texel = inp.textures.sample_grad(
        material.layer,
        Vec2::from(g.uv.get(q[0], q[1])),
        grad.xy(),
        grad.zw(),
        config.anisotropy,
    );
    let albedo = (Vec4::from(material.base_color).xyz() * texel.xyz()).clamp(Vec3::ZERO, Vec3::ONE);
    let p = gbuffer::position::from_view_ray(inp.frame, q[0], q[1], depth);
    let v = (inp.frame.eye.xyz() - p).normalize();
    let (mut diffuse, mut specular) = (Vec3::ZERO, Vec3::ZERO);
    for light in inp.lights {
        let (d, s) = shade_light(light, p, n, v, albedo, roughness, metallic);
        diffuse += d;
        specular += s;
    }
    albedo * (1.0 - metallic) * (config.ambient + diffuse)
        + specular
        + Vec3::from(material.emissive)
}

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

fn per_pixel<T: Copy + Send>(w: u32, h: u32, f: impl Fn(u32, u32) -> T + Sync) -> Image<T> {
    let data: Vec<T> = (0..w * h)
        .into_par_iter()
        .map(|i| f(i % w, i / w))
        .collect();
    Image::from_vec(w, h, data).expect("per_pixel builds w × h values")
}

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

/// The result of [`render`].
pub struct Output {
    /// The anti-aliased image.
    pub image: Image<[f32; 4]>,
    /// `S`, the first sample per pixel (the one-sample-per-pixel image).
    pub first: Image<[f32; 4]>,
    /// Samples per pixel.
    pub counts: Image<u32>,
}

impl Output {
    /// Samples averaged over all pixels as a fraction of `m²` per pixel (the paper's
    /// "Samples %").
    pub fn sample_fraction(&self, m: u32) -> f64 {
        let total: u64 = self.counts.pixels().iter().map(|&k| u64::from(k)).sum();
        total as f64 / (self.counts.pixels().len() as f64 * f64::from(m * m))
    }

    /// Shading evaluations as a fraction of full supersampling's: `S` for every pixel plus `k`
    /// for every pixel with `k > 1`.
    pub fn shaded(&self, m: u32) -> f64 {
        let total: u64 = self
            .counts
            .pixels()
            .iter()
            .map(|&k| 1 + if k > 1 { u64::from(k) } else { 0 })
            .sum();
        total as f64 / (self.counts.pixels().len() as f64 * f64::from(m * m))
    }
}

/// Samples per pixel as heat colours: 1 black … `n` white (`tiled_shading::heat_color`).
pub fn sample_heatmap(counts: &Image<u32>, n: u32) -> Image<[f32; 4]> {
    counts.map(|k| tiled_shading::heat_color(k.saturating_sub(1) as f32 / (n - 1).max(1) as f32))
}

/// Listing 4.1 on the CPU: shade the first sample, evaluate the metrics, shade the rest.
pub fn render(inp: &ShadingInputs, config: &SsaaConfig) -> Result<Output, SsaaError> {
    let first = shade_first(inp, config)?;
    let counts = evaluate(inp, config, &first)?;
    let image = shade_adaptive(inp, config, &first, &counts)?;
    Ok(Output {
        image,
        first,
        counts,
    })
}

/// FXAA constants (Lottes 2009, the "console" variant).
const FXAA_EDGE_THRESHOLD: f32 = 0.125;
const FXAA_EDGE_THRESHOLD_MIN: f32 = 0.0312;
const FXAA_REDUCE_MUL: f32 = 1.0 / 8.0;
const FXAA_REDUCE_MIN: f32 = 1.0 / 128.0;
const FXAA_SPAN_MAX: f32 = 8.0;

/// Bilinear lookup of an image at a continuous position (pixel centres at +0.5), clamped to
/// the edges (`bilinear`).
fn bilinear(img: &Image<[f32; 4]>, pos: Vec2) -> Vec4 {
    let (w, h) = (img.width() as i32, img.height() as i32);
    let p = pos - 0.5;
    let f = p.floor();
    let t = p - f;
    let at = |dx: i32, dy: i32| {
        let x = (f.x as i32 + dx).clamp(0, w - 1) as u32;
        let y = (f.y as i32 + dy).clamp(0, h - 1) as u32;
        Vec4::from(img.get(x, y))
    };
    at(0, 0)
        .lerp(at(1, 0), t.x)
        .lerp(at(0, 1).lerp(at(1, 1), t.x), t.y)
}

/// The post-process edge anti-aliasing baseline (`fxaa`): FXAA's console variant on `S`, the
/// one-sample image (§4.2's RGB-based filters).
pub fn fxaa(s: &Image<[f32; 4]>) -> Image<[f32; 4]> {
    let luma = |c: Vec4| c.xyz().dot(LUMINANCE);
    per_pixel(s.width(), s.height(), |x, y| {
        let pos = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
        let m = Vec4::from(s.get(x, y));
        let nw = luma(bilinear(s, pos + Vec2::new(-0.5, -0.5)));
        let ne = luma(bilinear(s, pos + Vec2::new(0.5, -0.5)));
        let sw = luma(bilinear(s, pos + Vec2::new(-0.5, 0.5)));
        let se = luma(bilinear(s, pos + Vec2::new(0.5, 0.5)));
        let lm = luma(m);
        let lo = lm.min(nw.min(ne).min(sw.min(se)));
        let hi = lm.max(nw.max(ne).max(sw.max(se)));
        if hi - lo < FXAA_EDGE_THRESHOLD_MIN.max(hi * FXAA_EDGE_THRESHOLD) {
            return m.to_array();
        }
        let dir = Vec2::new(-((nw + ne) - (sw + se)), (nw + sw) - (ne + se));
        let reduce = ((nw + ne + sw + se) * (0.25 * FXAA_REDUCE_MUL)).max(FXAA_REDUCE_MIN);
        let rcp_min = 1.0 / (dir.x.abs().min(dir.y.abs()) + reduce);
        let dir = (dir * rcp_min).clamp(Vec2::splat(-FXAA_SPAN_MAX), Vec2::splat(FXAA_SPAN_MAX));
        let a = (bilinear(s, pos + dir * (1.0 / 3.0 - 0.5))
            + bilinear(s, pos + dir * (2.0 / 3.0 - 0.5)))
            * 0.5;
        let b = a * 0.5 + (bilinear(s, pos - dir * 0.5) + bilinear(s, pos + dir * 0.5)) * 0.25;
        let lb = luma(b);
        let out = if lb < lo || lb > hi { a } else { b };
        out.xyz().extend(1.0).to_array()
    })
}
