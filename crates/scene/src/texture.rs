//! Textures as the CPU renderers sample them — the CPU G-buffer, the path tracer and the VPL
//! tracer share this one sampler, so their albedos agree texel for texel.

use glam::{Vec2, Vec4};

use crate::Texture;

/// sRGB → linear transfer function (IEC 61966-2-1).
pub fn srgb_to_linear(v: f32) -> f32 {
    if v <= 0.040_45 {
        v / 12.92
    } else {
        ((v + 0.055) / 1.055).powf(2.4)
    }
}

/// How a texture's colour channels are stored (glTF 2.0 §3.9: base colour and emissive
/// textures are sRGB; metallic-roughness, normal and occlusion textures linear). Alpha is
/// always linear.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ColorSpace {
    /// sRGB-encoded (an `Rgba8UnormSrgb` view decodes it).
    Srgb,
    /// Stored linear (`Rgba8Unorm`).
    Linear,
}

/// A texture decoded to linear floats, as the GPU's texture view reads it.
pub struct LinearTexture {
    width: u32,
    height: u32,
    texels: Vec<Vec4>,
}

impl LinearTexture {
    /// Decodes a colour texture stored sRGB (base colour, emissive).
    pub fn new(t: &Texture) -> Self {
        Self::with_space(t, ColorSpace::Srgb)
    }

    /// Decodes a texture stored in `space`.
    pub fn with_space(t: &Texture, space: ColorSpace) -> Self {
        let lut: Vec<f32> = (0..256)
            .map(|v| {
                let c = v as f32 / 255.0;
                match space {
                    ColorSpace::Srgb => srgb_to_linear(c),
                    ColorSpace::Linear => c,
                }
            })
            .collect();
        let texels = t
            .rgba8
            .chunks_exact(4)
            .map(|c| {
                Vec4::new(
                    lut[c[0] as usize],
                    lut[c[1] as usize],
                    lut[c[2] as usize],
                    f32::from(c[3]) / 255.0,
                )
            })
            .collect();
        Self {
            width: t.width,
            height: t.height,
            texels,
        }
    }

    /// Bilinear sample of mip 0 with repeat addressing (`textureSampleLevel(t, s, uv, 0.0)`
    /// with a linear, repeating sampler); zero for non-finite coordinates.
    pub fn sample(&self, uv: Vec2) -> Vec4 {
        let (w, h) = (self.width as i64, self.height as i64);
        let x = uv.x * self.width as f32 - 0.5;
        let y = uv.y * self.height as f32 - 0.5;
        let (fx, fy) = (x.floor(), y.floor());
        let (tx, ty) = (x - fx, y - fy);
        if !(fx.is_finite() && fy.is_finite()) {
            return Vec4::ZERO;
        }
        let (ix, iy) = (fx as i64, fy as i64);
        let texel = |dx: i64, dy: i64| {
            let (u, v) = ((ix + dx).rem_euclid(w), (iy + dy).rem_euclid(h));
            self.texels[(v * w + u) as usize]
        };
        let top = texel(0, 0).lerp(texel(1, 0), tx);
        let bottom = texel(0, 1).lerp(texel(1, 1), tx);
        top.lerp(bottom, ty)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A texel of 128 reads 0.2158 from an sRGB texture and 128/255 from a linear one; alpha
    /// is linear in both; a texel's centre reads it exactly and coordinates repeat.
    #[test]
    fn colour_spaces_decode_and_texel_centres_read_exactly() {
        let t = Texture {
            name: "t".into(),
            width: 2,
            height: 1,
            rgba8: vec![128, 0, 255, 128, 255, 255, 255, 255],
            sampler: Default::default(),
        };
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
}
