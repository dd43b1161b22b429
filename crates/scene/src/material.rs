//! The parts of the glTF 2.0 metallic-roughness material (§3.9) beyond its factors: how a
//! material reads a texture (which one, which texture-coordinate set, the
//! `KHR_texture_transform` of its coordinates), how a texture is sampled, and how alpha is
//! used. OBJ/MTL materials map onto the same model (`map_Kd`, `norm`/`map_Bump`, `map_Ke`, `d`).

use glam::{Mat3, Vec2};

/// A material's use of a texture (glTF `textureInfo`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TextureRef {
    /// Index into [`crate::Scene::textures`].
    pub texture: u32,
    /// Texture-coordinate set read: 0 ([`crate::Mesh::uvs`]) or 1 ([`crate::Mesh::uvs1`]).
    pub uv_set: u32,
    /// `KHR_texture_transform` of the coordinates (identity without it).
    pub transform: UvTransform,
}

impl TextureRef {
    /// Texture `texture` through set 0, untransformed.
    pub fn new(texture: u32) -> Self {
        Self {
            texture,
            uv_set: 0,
            transform: UvTransform::IDENTITY,
        }
    }
}

/// `KHR_texture_transform`: coordinates are scaled, then rotated by `rotation` radians
/// (counter-clockwise in UV space), then offset.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UvTransform {
    /// Added last.
    pub offset: Vec2,
    /// Radians.
    pub rotation: f32,
    /// Applied first.
    pub scale: Vec2,
}

impl UvTransform {
    /// No transform.
    pub const IDENTITY: Self = Self {
        offset: Vec2::ZERO,
        rotation: 0.0,
        scale: Vec2::ONE,
    };

    /// The extension's matrix: translation × rotation × scale, acting on (u, v, 1).
    pub fn matrix(&self) -> Mat3 {
        let (s, c) = self.rotation.sin_cos();
        Mat3::from_cols(
            (Vec2::new(c, s) * self.scale.x).extend(0.0),
            (Vec2::new(-s, c) * self.scale.y).extend(0.0),
            self.offset.extend(1.0),
        )
    }

    /// The transformed coordinates of `uv`.
    pub fn apply(&self, uv: Vec2) -> Vec2 {
        (self.matrix() * uv.extend(1.0)).truncate()
    }
}

/// How a material's alpha (base colour alpha × texture alpha) is used (glTF `alphaMode`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum AlphaMode {
    /// Alpha is ignored.
    Opaque,
    /// Fragments with alpha below the cutoff are discarded; the rest are opaque.
    Mask {
        /// `alphaCutoff` (0.5 by default).
        cutoff: f32,
    },
    /// Alpha blends the surface over what is behind it.
    Blend,
}

/// What a texture coordinate outside \[0, 1\] reads (glTF sampler `wrapS`/`wrapT`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Wrap {
    /// The texture repeats (the default).
    Repeat,
    /// Each repeat is mirrored.
    MirroredRepeat,
    /// The edge texel continues.
    ClampToEdge,
}

/// How a texture is sampled (glTF `sampler`; without one: repeat, linear filtering with
/// mipmaps).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Sampler {
    /// Along u.
    pub wrap_u: Wrap,
    /// Along v.
    pub wrap_v: Wrap,
    /// Magnification: linear (true) or nearest.
    pub mag_linear: bool,
    /// Minification within a mip level: linear (true) or nearest.
    pub min_linear: bool,
    /// Mip levels: `None` samples level 0 only; `Some(true)` blends levels linearly, `Some(false)`
    /// takes the nearest level.
    pub mipmaps: Option<bool>,
}

impl Default for Sampler {
    fn default() -> Self {
        Self {
            wrap_u: Wrap::Repeat,
            wrap_v: Wrap::Repeat,
            mag_linear: true,
            min_linear: true,
            mipmaps: Some(true),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The extension's GLSL: `translation * rotation * scale` with the rotation's columns
    /// (cos, sin) and (−sin, cos): scale first, then rotate, then offset.
    #[test]
    fn uv_transform_scales_rotates_then_offsets() {
        let t = UvTransform {
            offset: Vec2::new(0.0, 1.0),
            rotation: std::f32::consts::FRAC_PI_2,
            scale: Vec2::new(2.0, 3.0),
        };
        // (1, 0) → scale (2, 0) → rotate (c·2, s·2) = (0, 2) → offset (0, 3).
        let got = t.apply(Vec2::new(1.0, 0.0));
        assert!((got - Vec2::new(0.0, 3.0)).length() < 1e-6, "{got}");
        // (0, 1) → (0, 3) → (−s·3, c·3) = (−3, 0) → (−3, 1).
        let got = t.apply(Vec2::new(0.0, 1.0));
        assert!((got - Vec2::new(-3.0, 1.0)).length() < 1e-6, "{got}");
        assert_eq!(
            UvTransform::IDENTITY.apply(Vec2::new(0.3, 0.7)),
            Vec2::new(0.3, 0.7)
        );
    }
}
