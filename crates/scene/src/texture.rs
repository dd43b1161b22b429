//! Textures as the CPU renderers sample them — the CPU G-buffer, the path tracer and the VPL
//! tracer share this one sampler, so their materials agree texel for texel — and the twin of
//! the GPU's texture units: mip chains built as the G-buffer's upload builds them, the glTF
//! sampler's wrap modes and filters, and anisotropic filtering as the Vulkan specification
//! describes it (§16.8, "Texel Anisotropic Filtering").

use glam::{Vec2, Vec4};

use crate::{Sampler, Texture, Wrap};

/// Largest anisotropy ratio a sampler may use (the GPU sampler's `anisotropy_clamp`).
pub const MAX_ANISOTROPY: u32 = 16;

/// sRGB → linear transfer function (IEC 61966-2-1).
pub fn srgb_to_linear(v: f32) -> f32 {
    if v <= 0.040_45 {
        v / 12.92
    } else {
        ((v + 0.055) / 1.055).powf(2.4)
    }
}

/// Linear → sRGB transfer function (IEC 61966-2-1), clamped to \[0, 1\].
pub fn linear_to_srgb(v: f32) -> f32 {
    let v = v.clamp(0.0, 1.0);
    if v <= 0.003_130_8 {
        v * 12.92
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    }
}

/// How a texture's colour channels are stored (glTF 2.0 §3.9: base colour and emissive
/// textures are sRGB; metallic-roughness, normal and occlusion textures linear). Alpha is
/// always linear.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ColorSpace {
    /// sRGB-encoded (an `Rgba8UnormSrgb` view decodes it).
    Srgb,
    /// Stored linear (`Rgba8Unorm`).
    Linear,
}

impl ColorSpace {
    /// The stored 8-bit value of linear `c` (colour channels; alpha is stored linear).
    fn encode(self, c: f32) -> u8 {
        let c = match self {
            Self::Srgb => linear_to_srgb(c),
            Self::Linear => c.clamp(0.0, 1.0),
        };
        (c * 255.0).round() as u8
    }
}

/// One mip level: RGBA8 texels as stored, row-major from the top-left.
#[derive(Clone, Debug)]
struct Level {
    width: u32,
    height: u32,
    rgba8: Vec<u8>,
}

/// A texture as the GPU's texture view reads it: stored texels decoded to linear floats on
/// read, sampled with the texture's [`Sampler`].
#[derive(Clone, Debug)]
pub struct LinearTexture {
    levels: Vec<Level>,
    sampler: Sampler,
    space: ColorSpace,
    /// Stored colour byte → linear value.
    lut: [f32; 256],
}

impl LinearTexture {
    /// Decodes a colour texture stored sRGB (base colour, emissive), level 0 only.
    pub fn new(t: &Texture) -> Self {
        Self::with_space(t, ColorSpace::Srgb)
    }

    /// A texture stored in `space`, level 0 only ([`LinearTexture::mipmapped`] adds the
    /// chain).
    pub fn with_space(t: &Texture, space: ColorSpace) -> Self {
        let lut = std::array::from_fn(|v| {
            let c = v as f32 / 255.0;
            match space {
                ColorSpace::Srgb => srgb_to_linear(c),
                ColorSpace::Linear => c,
            }
        });
        Self {
            levels: vec![Level {
                width: t.width,
                height: t.height,
                rgba8: t.rgba8.clone(),
            }],
            sampler: t.sampler,
            space,
            lut,
        }
    }

    /// Adds the full mip chain down to 1 × 1, as `gbuffer`'s upload builds it on the GPU:
    /// texel (x, y) of level l + 1 is the bilinear sample (clamped to the edge, in linear
    /// space) of level l at the texel's centre — the 2 × 2 box filter where level l's side is
    /// even — stored back in the texture's colour space, rounded to 8 bits.
    pub fn mipmapped(mut self) -> Self {
        self.levels.truncate(1);
        let clamp = Sampler {
            wrap_u: Wrap::ClampToEdge,
            wrap_v: Wrap::ClampToEdge,
            ..Sampler::default()
        };
        while let Some(prev) = self.levels.last().filter(|l| l.width.max(l.height) > 1) {
            let (w, h) = ((prev.width / 2).max(1), (prev.height / 2).max(1));
            let mut rgba8 = Vec::with_capacity((w * h * 4) as usize);
            for y in 0..h {
                for x in 0..w {
                    let uv = Vec2::new((x as f32 + 0.5) / w as f32, (y as f32 + 0.5) / h as f32);
                    let c = self.bilinear(prev, &clamp, uv);
                    let a = (c.w.clamp(0.0, 1.0) * 255.0).round() as u8;
                    rgba8.extend([
                        self.space.encode(c.x),
                        self.space.encode(c.y),
                        self.space.encode(c.z),
                        a,
                    ]);
                }
            }
            self.levels.push(Level {
                width: w,
                height: h,
                rgba8,
            });
        }
        self
    }

    /// Number of mip levels held.
    pub fn levels(&self) -> u32 {
        self.levels.len() as u32
    }

    /// Level `level`'s size and stored texels (RGBA8), or `None` past the last level.
    pub fn level(&self, level: u32) -> Option<(u32, u32, &[u8])> {
        self.levels
            .get(level as usize)
            .map(|l| (l.width, l.height, &l.rgba8[..]))
    }

    /// A sample of level 0 with the sampler's magnification filter and wrap modes
    /// (`textureSampleLevel(t, s, uv, 0.0)`); zero for non-finite coordinates.
    pub fn sample(&self, uv: Vec2) -> Vec4 {
        self.filter(&self.levels[0], uv, self.sampler.mag_linear)
    }

    /// `textureSampleGrad(t, s, uv, ddx, ddy)` with the texture's sampler and anisotropy up
    /// to `max_anisotropy` (used only where the sampler filters linearly between mip levels,
    /// as wgpu requires): the level of detail λ and the probes of
    /// [`anisotropic_footprint`]; λ ≤ 0 magnifies level 0, otherwise the minification filter
    /// reads level ⌊λ⌋ and ⌊λ⌋ + 1 blended (linear mipmaps), level ⌈λ + ½⌉ − 1 (nearest) or
    /// level 0 (none). Hardware filters are implementation-defined (fixed-point weights, the
    /// probe pattern), so the GPU result is close to, not equal to, this one.
    pub fn sample_grad(&self, uv: Vec2, ddx: Vec2, ddy: Vec2, max_anisotropy: u32) -> Vec4 {
        let s = &self.sampler;
        let anisotropy = if s.mag_linear && s.min_linear && s.mipmaps == Some(true) {
            max_anisotropy.clamp(1, MAX_ANISOTROPY)
        } else {
            1
        };
        let base = &self.levels[0];
        let size = Vec2::new(base.width as f32, base.height as f32);
        let (lod, probes, axis) = anisotropic_footprint(ddx * size, ddy * size, anisotropy);
        let axis = axis / size;
        let sum: Vec4 = (0..probes)
            .map(|i| {
                let t = (i as f32 + 0.5) / probes as f32 - 0.5;
                self.sample_lod(uv + axis * t, lod)
            })
            .sum();
        sum / probes as f32
    }

    /// One probe at level of detail `lod` (Vulkan §16.6.7, level selection).
    fn sample_lod(&self, uv: Vec2, lod: f32) -> Vec4 {
        let s = &self.sampler;
        if lod <= 0.0 {
            return self.filter(&self.levels[0], uv, s.mag_linear);
        }
        let last = (self.levels.len() - 1) as f32;
        match s.mipmaps {
            None => self.filter(&self.levels[0], uv, s.min_linear),
            Some(false) => {
                let level = ((lod + 0.5).ceil() - 1.0).clamp(0.0, last) as usize;
                self.filter(&self.levels[level], uv, s.min_linear)
            }
            Some(true) => {
                let lod = lod.min(last);
                let l0 = lod.floor() as usize;
                let a = self.filter(&self.levels[l0], uv, s.min_linear);
                match self.levels.get(l0 + 1) {
                    Some(next) => a.lerp(self.filter(next, uv, s.min_linear), lod - l0 as f32),
                    None => a,
                }
            }
        }
    }

    fn filter(&self, level: &Level, uv: Vec2, linear: bool) -> Vec4 {
        if linear {
            self.bilinear(level, &self.sampler, uv)
        } else {
            self.nearest(level, uv)
        }
    }

    /// The decoded texel (x, y) of `level`, addressed through `sampler`'s wrap modes.
    fn texel(&self, level: &Level, sampler: &Sampler, x: i64, y: i64) -> Vec4 {
        let x = wrap(sampler.wrap_u, x, level.width);
        let y = wrap(sampler.wrap_v, y, level.height);
        let i = 4 * (y * level.width as usize + x);
        let t = &level.rgba8[i..i + 4];
        Vec4::new(
            self.lut[t[0] as usize],
            self.lut[t[1] as usize],
            self.lut[t[2] as usize],
            f32::from(t[3]) / 255.0,
        )
    }

    fn nearest(&self, level: &Level, uv: Vec2) -> Vec4 {
        let p = (uv * Vec2::new(level.width as f32, level.height as f32)).floor();
        if !p.is_finite() {
            return Vec4::ZERO;
        }
        self.texel(level, &self.sampler, p.x as i64, p.y as i64)
    }

    fn bilinear(&self, level: &Level, sampler: &Sampler, uv: Vec2) -> Vec4 {
        let p = uv * Vec2::new(level.width as f32, level.height as f32) - 0.5;
        let f = p.floor();
        if !f.is_finite() {
            return Vec4::ZERO;
        }
        let t = p - f;
        let (x, y) = (f.x as i64, f.y as i64);
        let at = |dx, dy| self.texel(level, sampler, x + dx, y + dy);
        let top = at(0, 0).lerp(at(1, 0), t.x);
        let bottom = at(0, 1).lerp(at(1, 1), t.x);
        top.lerp(bottom, t.y)
    }
}

/// Texel index `i` of a row or column of `n` texels under `mode` (Vulkan §16.9.2).
fn wrap(mode: Wrap, i: i64, n: u32) -> usize {
    let n = i64::from(n);
    let i = match mode {
        Wrap::Repeat => i.rem_euclid(n),
        Wrap::ClampToEdge => i.clamp(0, n - 1),
        Wrap::MirroredRepeat => {
            let m = i.rem_euclid(2 * n);
            if m >= n { 2 * n - 1 - m } else { m }
        }
    };
    i as usize
}

/// The anisotropic footprint of a sample whose texel-space derivatives are `dx` and `dy`:
/// `(level of detail, probe count N, major axis)` with `P_max`, `P_min` the longer and shorter
/// derivative, `N = min(⌈P_max / P_min⌉, max_anisotropy)` and `λ = log₂(P_max / N)`. Zero or
/// non-finite derivatives give level 0 with one probe.
pub fn anisotropic_footprint(dx: Vec2, dy: Vec2, max_anisotropy: u32) -> (f32, u32, Vec2) {
    let (px, py) = (dx.length(), dy.length());
    let (major, p_max, p_min) = if px >= py { (dx, px, py) } else { (dy, py, px) };
    if !(p_max > 0.0 && p_max.is_finite()) {
        return (0.0, 1, Vec2::ZERO);
    }
    let ratio = if p_min > 0.0 {
        (p_max / p_min).ceil()
    } else {
        max_anisotropy as f32
    };
    let n = (ratio as u32).clamp(1, max_anisotropy.max(1));
    let axis = if n > 1 { major } else { Vec2::ZERO };
    ((p_max / n as f32).log2(), n, axis)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn texture(width: u32, height: u32, rgba8: Vec<u8>, sampler: Sampler) -> Texture {
        Texture {
            name: "t".into(),
            width,
            height,
            rgba8,
            sampler,
        }
    }

    /// A texel of 128 reads 0.2158 from an sRGB texture and 128/255 from a linear one; alpha
    /// is linear in both; a texel's centre reads it exactly and coordinates repeat.
    #[test]
    fn colour_spaces_decode_and_texel_centres_read_exactly() {
        let t = texture(
            2,
            1,
            vec![128, 0, 255, 128, 255, 255, 255, 255],
            Sampler::default(),
        );
        let centre = Vec2::new(0.25, 0.5);
        let srgb = LinearTexture::new(&t).sample(centre);
        let linear = LinearTexture::with_space(&t, ColorSpace::Linear).sample(centre);
        assert!((srgb.x - 0.215_861).abs() < 1e-5, "{srgb}");
        assert_eq!(linear.x, 128.0 / 255.0);
        assert_eq!((srgb.z, linear.z), (1.0, 1.0));
        assert_eq!((srgb.w, linear.w), (128.0 / 255.0, 128.0 / 255.0));
        assert_eq!(
            LinearTexture::with_space(&t, ColorSpace::Linear).sample(centre + Vec2::new(3.0, -2.0)),
            linear
        );
    }

    /// Wrap modes at texel indices −2..5 of a 3-texel row, as Vulkan's table gives them.
    #[test]
    fn wrap_modes_address_texels() {
        let row = |mode| (-2..5).map(|i| wrap(mode, i, 3)).collect::<Vec<_>>();
        assert_eq!(row(Wrap::Repeat), [1, 2, 0, 1, 2, 0, 1]);
        assert_eq!(row(Wrap::ClampToEdge), [0, 0, 0, 1, 2, 2, 2]);
        assert_eq!(row(Wrap::MirroredRepeat), [1, 0, 0, 1, 2, 2, 1]);
    }

    /// A 4 × 2 sRGB checker of 0 and 255: level 1 (2 × 1) holds the linear mean 0.5 stored
    /// as sRGB 188; the last level (1 × 1) the same; a nearest magnification reads texels
    /// whole; a stretched footprint takes 4 probes at level 1 and reads the mean.
    #[test]
    fn mips_average_in_linear_space_and_filters_select_levels() {
        let px = |v: u8| [v, v, v, 255];
        let rgba8: Vec<u8> = [0, 255, 0, 255, 255, 0, 255, 0]
            .iter()
            .flat_map(|&v| px(v))
            .collect();
        let t = LinearTexture::new(&texture(4, 2, rgba8.clone(), Sampler::default())).mipmapped();
        assert_eq!(t.levels(), 3);
        let (w, h, level1) = t.level(1).unwrap();
        assert_eq!((w, h), (2, 1));
        assert_eq!(&level1[..4], &[188, 188, 188, 255]);
        assert_eq!(t.level(2).unwrap().2, &[188, 188, 188, 255]);
        let mean = srgb_to_linear(188.0 / 255.0);
        // One texel per pixel along u, 8 along v, at most 4 probes: λ = log2(8 / 4) = 1.
        let (lod, n, _) = anisotropic_footprint(Vec2::new(1.0, 0.0), Vec2::new(0.0, 8.0), 4);
        assert_eq!((lod, n), (1.0, 4));
        let s = t.sample_grad(
            Vec2::new(0.375, 0.25),
            Vec2::new(0.25, 0.0),
            Vec2::new(0.0, 4.0),
            4,
        );
        assert!((s.x - mean).abs() < 1e-6, "{s} vs {mean}");
        let nearest = Sampler {
            mag_linear: false,
            ..Sampler::default()
        };
        let t = LinearTexture::new(&texture(4, 2, rgba8, nearest));
        assert_eq!(t.sample(Vec2::new(0.3, 0.3)).x, 1.0);
        assert_eq!(t.sample(Vec2::new(0.2, 0.3)).x, 0.0);
    }

    #[test]
    fn footprint_of_isotropic_and_stretched_derivatives() {
        let (lod, n, _) = anisotropic_footprint(Vec2::new(4.0, 0.0), Vec2::new(0.0, 4.0), 16);
        assert_eq!((lod, n), (2.0, 1));
        let (lod, n, axis) = anisotropic_footprint(Vec2::new(1.0, 0.0), Vec2::new(0.0, 8.0), 16);
        assert_eq!((lod, n, axis), (0.0, 8, Vec2::new(0.0, 8.0)));
        let (_, n, _) = anisotropic_footprint(Vec2::new(1.0, 0.0), Vec2::ZERO, 16);
        assert_eq!(n, 16);
        assert_eq!(
            anisotropic_footprint(Vec2::ZERO, Vec2::ZERO, 16),
            (0.0, 1, Vec2::ZERO)
        );
    }
}
