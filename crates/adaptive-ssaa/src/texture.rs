//! The scene's textures as one array with mip maps (§4.3.3: "we store all textures of the
//! scene in a 3D-array"), and the CPU twin of `textureSampleGrad` with anisotropic filtering.

use gbuffer::{linear_to_srgb, srgb_to_linear};
use glam::{Vec2, Vec4};
use rayon::prelude::*;
use scene::Scene;
use scene::{LinearTexture, anisotropic_footprint};

/// Every scene texture resampled to one power-of-two size, with a full mip chain, as sRGB8
/// texels: the CPU copy of the GPU's `Rgba8UnormSrgb` 2D array. Layer 0 is white (materials
/// without a texture); scene texture `t` is layer `t + 1`.
#[derive(Clone, Debug, PartialEq)]
pub struct TextureArray {
    /// Side of every layer at mip 0.
    pub size: u32,
    /// Number of layers.
    pub layers: u32,
    /// `mips[level][layer]`: `(size >> level)²` RGBA8 texels, row-major.
    pub mips: Vec<Vec<Vec<u8>>>,
    lut: Vec<f32>,
}

impl TextureArray {
    /// Builds the array for `scene`; layers are as large as the largest texture (rounded up to
    /// a power of two) but at most `max_size`. Each texture is resampled bilinearly in linear
    /// space (repeat addressing); mips are 2 × 2 box filters in linear space.
    pub fn new(scene: &Scene, max_size: u32) -> Self {
        let largest = scene
            .textures
            .iter()
            .map(|t| t.width.max(t.height))
            .max()
            .unwrap_or(1);
        let size = largest
            .next_power_of_two()
            .min(max_size.max(1).next_power_of_two());
        let levels = size.ilog2() + 1;
        let white = vec![Vec4::ONE; (size * size) as usize];
        let resampled: Vec<Vec<Vec4>> = scene
            .textures
            .par_iter()
            .map(|t| {
                let linear = LinearTexture::new(t);
                (0..size * size)
                    .map(|i| {
                        let texel = Vec2::new((i % size) as f32 + 0.5, (i / size) as f32 + 0.5);
                        linear.sample(texel / size as f32)
                    })
                    .collect()
            })
            .collect();
        let base: Vec<Vec<Vec4>> = std::iter::once(white).chain(resampled).collect();
        let mut linear_mips = vec![base];
        for level in 1..levels {
            let side = size >> level;
            let prev = &linear_mips[level as usize - 1];
            let next = prev
                .iter()
                .map(|texels| {
                    (0..side * side)
                        .map(|i| {
                            let (x, y) = (2 * (i % side), 2 * (i / side));
                            let at =
                                |dx: u32, dy: u32| texels[((y + dy) * 2 * side + x + dx) as usize];
                            (at(0, 0) + at(1, 0) + at(0, 1) + at(1, 1)) * 0.25
                        })
                        .collect()
                })
                .collect();
            linear_mips.push(next);
        }
        let encode = |c: f32| (linear_to_srgb(c.clamp(0.0, 1.0)) * 255.0).round() as u8;
        let mips = linear_mips
            .iter()
            .map(|layers| {
                layers
                    .iter()
                    .map(|texels| {
                        texels
                            .iter()
                            .flat_map(|t| {
                                [
                                    encode(t.x),
                                    encode(t.y),
                                    encode(t.z),
                                    (t.w.clamp(0.0, 1.0) * 255.0).round() as u8,
                                ]
                            })
                            .collect()
                    })
                    .collect()
            })
            .collect();
        Self {
            size,
            layers: scene.textures.len() as u32 + 1,
            mips,
            lut: (0..256).map(|v| srgb_to_linear(v as f32 / 255.0)).collect(),
        }
    }

    /// The layer of a material's base colour texture.
    pub fn layer_of(texture: Option<u32>) -> u32 {
        texture.map_or(0, |t| t + 1)
    }

    /// Number of mip levels.
    pub fn levels(&self) -> u32 {
        self.mips.len() as u32
    }

    fn texel(&self, level: usize, layer: usize, x: i64, y: i64) -> Vec4 {
        let side = i64::from(self.size >> level);
        let i = 4 * (y.rem_euclid(side) * side + x.rem_euclid(side)) as usize;
        let t = &self.mips[level][layer][i..i + 4];
        Vec4::new(
            self.lut[t[0] as usize],
            self.lut[t[1] as usize],
            self.lut[t[2] as usize],
            f32::from(t[3]) / 255.0,
        )
    }

    fn bilinear(&self, level: usize, layer: usize, uv: Vec2) -> Vec4 {
        let side = (self.size >> level) as f32;
        let p = uv * side - 0.5;
        let f = p.floor();
        if !f.is_finite() {
            return Vec4::ZERO;
        }
        let t = p - f;
        let (x, y) = (f.x as i64, f.y as i64);
        let top = self
            .texel(level, layer, x, y)
            .lerp(self.texel(level, layer, x + 1, y), t.x);
        let bottom = self
            .texel(level, layer, x, y + 1)
            .lerp(self.texel(level, layer, x + 1, y + 1), t.x);
        top.lerp(bottom, t.y)
    }

    fn trilinear(&self, layer: usize, uv: Vec2, lod: f32) -> Vec4 {
        let lod = lod.clamp(0.0, (self.levels() - 1) as f32);
        let l0 = lod.floor() as usize;
        let a = self.bilinear(l0, layer, uv);
        if l0 + 1 >= self.mips.len() {
            return a;
        }
        a.lerp(self.bilinear(l0 + 1, layer, uv), lod - l0 as f32)
    }

    /// `textureSampleGrad(textures, sampler, uv, layer, ddx, ddy)` with a trilinear,
    /// repeating sampler and anisotropy up to `max_anisotropy`, filtered as the Vulkan
    /// specification describes anisotropic filtering: `N` trilinear probes spread along the
    /// major axis of the footprint at the level of detail `log₂(P_max / N)`
    /// ([`anisotropic_footprint`]). Hardware filters are implementation-defined, so the GPU
    /// result is close to, not equal to, this one.
    pub fn sample_grad(
        &self,
        layer: u32,
        uv: Vec2,
        ddx: Vec2,
        ddy: Vec2,
        max_anisotropy: u32,
    ) -> Vec4 {
        let layer = (layer.min(self.layers - 1)) as usize;
        let size = self.size as f32;
        let (lod, probes, axis) = anisotropic_footprint(ddx * size, ddy * size, max_anisotropy);
        if probes == 1 {
            return self.trilinear(layer, uv, lod);
        }
        let axis = axis / size;
        let sum: Vec4 = (0..probes)
            .map(|i| {
                let t = (i as f32 + 0.5) / probes as f32 - 0.5;
                self.trilinear(layer, uv + axis * t, lod)
            })
            .sum();
        sum / probes as f32
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn white_layer_and_mip_averages() {
        let scene = scene::checkerboard();
        let t = TextureArray::new(&scene, 1024);
        assert_eq!((t.size, t.layers, t.levels()), (256, 2, 9));
        assert!(t.mips[0][0].iter().all(|&b| b == 255));
        // The checker's last mip is the linear average of its two tones.
        let mean = 0.5 * (srgb_to_linear(230.0 / 255.0) + srgb_to_linear(26.0 / 255.0));
        let top = t.sample_grad(
            1,
            Vec2::splat(0.3),
            Vec2::new(1.0, 0.0),
            Vec2::new(0.0, 1.0),
            16,
        );
        assert!((top.x - mean).abs() < 0.01, "{top} vs {mean}");
    }
}
