//! The scene's textures as one array with mip maps (§4.3.3: "we store all textures of the
//! scene in a 3D-array"), and the CPU twin of `textureSampleGrad` with anisotropic filtering.
//! The GPU array is drawn from the scene's one texture store
//! ([`gbuffer::gpu::MaterialTextures::array`]); this is its CPU twin.

use gbuffer::{linear_to_srgb, srgb_to_linear};
use glam::{Vec2, Vec4};
use rayon::prelude::*;
use scene::{ColorSpace, LinearTexture, Scene, TextureRef, anisotropic_footprint};

/// Which scene textures the array holds: layer 0 is white (a material without the texture),
/// then every texture a material reads in sRGB (base colour or emissive, the textures looked up
/// when a sample is shaded), in scene order.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ArrayLayers {
    /// The scene texture of each layer (`None`: white).
    pub sources: Vec<Option<u32>>,
    /// The layer of each scene texture (0 where the array does not hold it).
    of_texture: Vec<u32>,
}

impl ArrayLayers {
    /// The layers of `scene`'s array.
    pub fn new(scene: &Scene) -> Self {
        let used = scene::texture_spaces(scene);
        let mut sources = vec![None];
        let of_texture = used
            .iter()
            .enumerate()
            .map(|(t, u)| {
                if u[0] {
                    sources.push(Some(t as u32));
                    sources.len() as u32 - 1
                } else {
                    0
                }
            })
            .collect();
        Self {
            sources,
            of_texture,
        }
    }

    /// The layer a material's texture is read from (0, white, without one).
    pub fn layer_of(&self, texture: Option<TextureRef>) -> u32 {
        texture.map_or(0, |t| {
            self.of_texture
                .get(t.texture as usize)
                .copied()
                .unwrap_or(0)
        })
    }

    /// The side of every layer: the largest held texture's side rounded up to a power of two,
    /// but at most `max_size` (rounded up to a power of two); 1 when the array holds none.
    pub fn side(&self, scene: &Scene, max_size: u32) -> u32 {
        let largest = self
            .sources
            .iter()
            .flatten()
            .filter_map(|&t| scene.textures.get(t as usize))
            .map(|t| t.width.max(t.height))
            .max()
            .unwrap_or(1);
        largest
            .next_power_of_two()
            .min(max_size.max(1).next_power_of_two())
    }
}

/// The scene's sRGB textures ([`ArrayLayers`]) resampled to one power-of-two size, with a full
/// mip chain, as sRGB8 texels: the CPU copy of the GPU's `Rgba8UnormSrgb` 2D array.
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
    /// Builds `scene`'s array of `layers`, `size` texels on a side: each texture resampled at
    /// level 0 with its own sampler at the texel centres ([`LinearTexture::sample`], as the
    /// GPU's `fs_resample`); each level above is the 2 × 2 box filter, in linear space, of the
    /// stored sRGB8 level below (as `fs_downsample` reads it).
    pub fn new(scene: &Scene, layers: &ArrayLayers, size: u32) -> Self {
        let size = size.max(1).next_power_of_two();
        let levels = size.ilog2() + 1;
        let lut: Vec<f32> = (0..256).map(|v| srgb_to_linear(v as f32 / 255.0)).collect();
        let encode = |t: Vec4| {
            let c = |c: f32| (linear_to_srgb(c.clamp(0.0, 1.0)) * 255.0).round() as u8;
            [
                c(t.x),
                c(t.y),
                c(t.z),
                (t.w.clamp(0.0, 1.0) * 255.0).round() as u8,
            ]
        };
        let decode = |t: &[u8]| {
            Vec4::new(
                lut[t[0] as usize],
                lut[t[1] as usize],
                lut[t[2] as usize],
                f32::from(t[3]) / 255.0,
            )
        };
        let base: Vec<Vec<u8>> = layers
            .sources
            .par_iter()
            .map(|t| {
                let Some(t) = t.and_then(|t| scene.textures.get(t as usize)) else {
                    return vec![255; (size * size * 4) as usize];
                };
                let linear = LinearTexture::with_space(t, ColorSpace::Srgb);
                (0..size * size)
                    .flat_map(|i| {
                        let texel = Vec2::new((i % size) as f32 + 0.5, (i / size) as f32 + 0.5);
                        encode(linear.sample(texel / size as f32))
                    })
                    .collect()
            })
            .collect();
        let mut mips = vec![base];
        for level in 1..levels {
            let side = size >> level;
            let next = mips[level as usize - 1]
                .par_iter()
                .map(|texels| {
                    let at = |x: u32, y: u32| decode(&texels[((y * 2 * side + x) * 4) as usize..]);
                    (0..side * side)
                        .flat_map(|i| {
                            let (x, y) = (2 * (i % side), 2 * (i / side));
                            let sum = at(x, y) + at(x + 1, y) + at(x, y + 1) + at(x + 1, y + 1);
                            encode(sum * 0.25)
                        })
                        .collect()
                })
                .collect();
            mips.push(next);
        }
        Self::from_texels(size, mips)
    }

    /// An array of `size`-sided layers from its sRGB8 texels, `mips[level][layer]` (e.g. read
    /// back from the GPU).
    pub(crate) fn from_texels(size: u32, mips: Vec<Vec<Vec<u8>>>) -> Self {
        Self {
            size,
            layers: mips.first().map_or(0, |l| l.len() as u32),
            mips,
            lut: (0..256).map(|v| srgb_to_linear(v as f32 / 255.0)).collect(),
        }
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
        let layers = ArrayLayers::new(&scene);
        let t = TextureArray::new(&scene, &layers, layers.side(&scene, 1024));
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
