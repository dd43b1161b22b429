//! CPU reference of adaptive supersampling: the specification the WGSL stages are tested
//! against. One module per stage with the stem of its WGSL file and GPU module
//! ([`shade`], [`evaluate`], [`fxaa`]; the sorted resolve of `sort.wgsl` computes the image of
//! [`shade::shade_adaptive`]); what every stage shares (`common.wgsl`) is here. Every function
//! mirrors the shader function or entry point of the same name.
//!
//! Input is a supersampled G-buffer ([`SsGBuffer`], e.g. read back from
//! [`crate::gpu::SsGBufferTargets`]); the image is `w × h` with `m × m` samples per pixel, and
//! pixel `(x, y)`'s sample `i` is G-buffer sample `(m·x, m·y) + dither_order(m)[i]`.

use gbuffer::normal::unpack_octahedral;
use gbuffer::{Frame, Image, unpack_material};
use glam::{Vec2, Vec3, Vec4, Vec4Swizzles};
use rayon::prelude::*;
use tiled_shading::GpuLight;
use tiled_shading::lighting::{Surface, shade_light};

pub mod evaluate;
pub mod fxaa;
pub mod shade;

pub use evaluate::{
    evaluate, geometric_metric, luminance, luminance_range, pixel_metric, shading_metric, window,
};
pub use fxaa::fxaa;
pub use shade::{shade_adaptive, shade_first, shade_full};

use crate::{SsaaConfig, SsaaError, SsaaMaterial, TextureArray, unpack_tint};

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
    /// Vertex colour and occlusion ([`crate::unpack_tint`]).
    pub tint: Image<u32>,
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
            && same(g.material.width(), g.material.height())
            && same(g.tint.width(), g.tint.height()))
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

/// Shades G-buffer sample `q` (`shade_sample`): base colour and emission looked up in the
/// array with the derivatives scaled by `scale` (`read_array`), every light, ambient ×
/// occlusion and emission; the background colour where no surface is.
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
    let uv = Vec2::from(g.uv.get(q[0], q[1]));
    let (color, occlusion) = unpack_tint(g.tint.get(q[0], q[1]));
    let read_array = |layer| {
        if layer == 0 {
            return Vec4::ONE;
        }
        inp.textures
            .sample_grad(layer, uv, grad.xy(), grad.zw(), config.anisotropy)
    };
    let texel = read_array(material.base_layer);
    let albedo =
        (Vec4::from(material.base_color).xyz() * color * texel.xyz()).clamp(Vec3::ZERO, Vec3::ONE);
    let emission = Vec3::from(material.emissive) * read_array(material.emissive_layer).xyz();
    let p = gbuffer::position::from_view_ray(inp.frame, q[0], q[1], depth);
    let v = (inp.frame.eye.xyz() - p).normalize();
    let surface = Surface {
        p,
        n,
        v,
        albedo,
        roughness,
        metallic,
        specular: material.base_color[3],
    };
    let (mut diffuse, mut specular) = (Vec3::ZERO, Vec3::ZERO);
    for light in inp.lights {
        let (d, s) = shade_light(light, &surface);
        diffuse += d;
        specular += s;
    }
    albedo * (1.0 - metallic) * (config.ambient * occlusion + diffuse) + specular + emission
}

fn per_pixel<T: Copy + Send>(w: u32, h: u32, f: impl Fn(u32, u32) -> T + Sync) -> Image<T> {
    let data: Vec<T> = (0..w * h)
        .into_par_iter()
        .map(|i| f(i % w, i / w))
        .collect();
    Image::from_vec(w, h, data).expect("per_pixel builds w × h values")
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
