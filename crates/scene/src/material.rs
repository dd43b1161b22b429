//! The parts of the glTF 2.0 metallic-roughness material (§3.9) beyond its factors: how a
//! material reads a texture (which one, which texture-coordinate set, the
//! `KHR_texture_transform` of its coordinates), how a texture is sampled, and how alpha is
//! used. OBJ/MTL materials map onto the same model (`map_Kd`, `norm`/`map_Bump`, `map_Ke`, `d`).

use glam::{Mat3, Vec2, Vec3, Vec4};
use rayon::prelude::*;

use crate::{ColorSpace, LinearTexture, Material, Mesh, Scene};

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

impl AlphaMode {
    /// Whether a fragment of `alpha` is kept: always when opaque, at or above the cutoff when
    /// masked, and — the deferred renderer's policy for `BLEND`, dithered (stochastic)
    /// transparency — above `threshold` when blended. The G-buffer passes a 4 × 4 ordered
    /// dither per pixel ([`dither_threshold`]), the path tracer a random number, so both see a
    /// blended surface with probability `alpha`.
    pub fn keeps(&self, alpha: f32, threshold: f32) -> bool {
        match *self {
            Self::Opaque => true,
            Self::Mask { cutoff } => alpha >= cutoff,
            Self::Blend => alpha > threshold,
        }
    }
}

/// The ordered-dither threshold of pixel (x, y) for blended materials: the 4 × 4 Bayer
/// matrix, (index + ½) / 16.
pub fn dither_threshold(x: u32, y: u32) -> f32 {
    const BAYER: [u32; 16] = [0, 8, 2, 10, 12, 4, 14, 6, 3, 11, 1, 9, 15, 7, 13, 5];
    (BAYER[((y % 4) * 4 + x % 4) as usize] as f32 + 0.5) / 16.0
}

/// The scene's textures decoded for the roles that read them (a texture read as colour and
/// as data is decoded twice), with mip chains where the renderer filters by footprint.
pub struct SceneTextures {
    srgb: Vec<Option<LinearTexture>>,
    linear: Vec<Option<LinearTexture>>,
}

impl SceneTextures {
    /// Decodes every texture some material reads; `mipmaps` builds their mip chains
    /// ([`LinearTexture::mipmapped`]) for [`Material::evaluate`] with derivatives.
    pub fn new(scene: &Scene, mipmaps: bool) -> Self {
        let used = texture_spaces(scene);
        let decode = |space: ColorSpace, k: usize| -> Vec<Option<LinearTexture>> {
            scene
                .textures
                .par_iter()
                .zip(&used)
                .map(|(t, u)| {
                    u[k].then(|| {
                        let t = LinearTexture::with_space(t, space);
                        if mipmaps { t.mipmapped() } else { t }
                    })
                })
                .collect()
        };
        Self {
            srgb: decode(ColorSpace::Srgb, 0),
            linear: decode(ColorSpace::Linear, 1),
        }
    }

    /// Texture `texture` as decoded for `space`, if some material reads it so.
    pub fn get(&self, texture: u32, space: ColorSpace) -> Option<&LinearTexture> {
        let list = match space {
            ColorSpace::Srgb => &self.srgb,
            ColorSpace::Linear => &self.linear,
        };
        list.get(texture as usize).and_then(Option::as_ref)
    }
}

/// For each texture of `scene`, whether some material reads it as colour (sRGB, index 0) and
/// as data (linear, index 1).
pub fn texture_spaces(scene: &Scene) -> Vec<[bool; 2]> {
    let mut used = vec![[false; 2]; scene.textures.len()];
    for m in &scene.materials {
        for (role, t) in m.textures() {
            if let Some(u) = used.get_mut(t.texture as usize) {
                u[usize::from(role_space(role) == ColorSpace::Linear)] = true;
            }
        }
    }
    used
}

/// The colour space a role's texture is stored in (glTF §3.9): base colour and emissive
/// sRGB, the rest linear.
pub fn role_space(role: &str) -> ColorSpace {
    match role {
        "base colour" | "emissive" => ColorSpace::Srgb,
        _ => ColorSpace::Linear,
    }
}

/// A surface point's interpolated vertex attributes, as the material reads them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceAttributes {
    /// Texture coordinates of sets 0 and 1.
    pub uv: [Vec2; 2],
    /// Their screen derivatives along x and y, per set (zero: sample level 0, as the path
    /// tracer does).
    pub uv_dx: [Vec2; 2],
    /// Along y.
    pub uv_dy: [Vec2; 2],
    /// The unit shading normal, turned to the viewer ([`crate::facing_shading_normal`]).
    pub normal: Vec3,
    /// Whether the vertex normal was turned to face the viewer (a back face): the tangent
    /// frame turns with it.
    pub back_face: bool,
    /// The interpolated tangent (xyz) and bitangent sign (w); zero without tangents.
    pub tangent: Vec4,
    /// The interpolated vertex colour (white without one).
    pub color: Vec4,
}

impl SurfaceAttributes {
    /// The attributes of `mesh`'s vertices `idx` blended with weights `w` (barycentric or
    /// perspective-corrected), with `normal` and `back_face` from the caller's facing rule
    /// and no derivatives.
    pub fn blend(mesh: &Mesh, idx: [usize; 3], w: [f32; 3], normal: Vec3, back_face: bool) -> Self {
        let mix2 = |a: &[Vec2]| -> Vec2 {
            if a.is_empty() {
                Vec2::ZERO
            } else {
                (0..3).map(|k| a[idx[k]] * w[k]).sum()
            }
        };
        let mix4 = |a: &[Vec4], none: Vec4| -> Vec4 {
            if a.is_empty() {
                none
            } else {
                (0..3).map(|k| a[idx[k]] * w[k]).sum()
            }
        };
        Self {
            uv: [mix2(&mesh.uvs), mix2(&mesh.uvs1)],
            uv_dx: [Vec2::ZERO; 2],
            uv_dy: [Vec2::ZERO; 2],
            normal,
            back_face,
            tangent: mix4(&mesh.tangents, Vec4::ZERO),
            color: mix4(&mesh.colors, Vec4::ONE),
        }
    }
}

/// A material evaluated at a surface point: what the G-buffer stores and the path tracer's
/// BRDF reads.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MaterialSample {
    /// Linear base colour (factor × texture × vertex colour), clamped to \[0, 1\], times
    /// 1 − [`Material::transmission`]: the light that glass transmits leaves its diffuse lobe
    /// (and, for the rare metal that transmits, its tint too).
    pub albedo: Vec3,
    /// Alpha (factor × texture × vertex colour).
    pub alpha: f32,
    /// Perceptual roughness (factor × texture G).
    pub roughness: f32,
    /// Metalness (factor × texture B).
    pub metallic: f32,
    /// Dielectric specular scale.
    pub specular: f32,
    /// The shading normal: the normal map's, in the tangent frame, or the interpolated one.
    pub normal: Vec3,
    /// The ambient occlusion factor `1 + strength · (R − 1)`, scaling the light that does not
    /// come straight from the lights (ambient and indirect).
    pub occlusion: f32,
    /// Emitted radiance (factor × texture).
    pub emission: Vec3,
}

impl Material {
    /// The material at a surface point (glTF 2.0 §3.9.2–3.9.5): each texture read through its
    /// coordinate set and transform, filtered by the derivatives of `at` with anisotropy up
    /// to `max_anisotropy` ([`LinearTexture::sample_grad`]). Twin of `evaluate_material` in
    /// `shaders/gbuffer/material.wgsl`.
    pub fn evaluate(
        &self,
        textures: &SceneTextures,
        at: &SurfaceAttributes,
        max_anisotropy: u32,
    ) -> MaterialSample {
        let read = |role: &str, t: Option<TextureRef>| -> Vec4 {
            let Some(t) = t else { return Vec4::ONE };
            let Some(texture) = textures.get(t.texture, role_space(role)) else {
                return Vec4::ONE;
            };
            let set = (t.uv_set as usize).min(1);
            let m = t.transform.matrix();
            let uv = (m * at.uv[set].extend(1.0)).truncate();
            let dx = (m * at.uv_dx[set].extend(0.0)).truncate();
            let dy = (m * at.uv_dy[set].extend(0.0)).truncate();
            texture.sample_grad(uv, dx, dy, max_anisotropy)
        };
        let base = self.base_color * read("base colour", self.base_color_texture) * at.color;
        let mr = read("metallic-roughness", self.metallic_roughness_texture);
        let occlusion = read("occlusion", self.occlusion_texture).x;
        let emission = self.emissive * read("emissive", self.emissive_texture).truncate();
        let normal = match self.normal_texture {
            Some(t) => {
                let c = read("normal", Some(t)).truncate() * 2.0 - 1.0;
                let c = c * Vec3::new(self.normal_scale, self.normal_scale, 1.0);
                perturb_normal(at, c)
            }
            None => at.normal,
        };
        MaterialSample {
            albedo: base.truncate().clamp(Vec3::ZERO, Vec3::ONE) * (1.0 - self.transmission),
            alpha: base.w,
            roughness: (self.roughness * mr.y).clamp(0.0, 1.0),
            metallic: (self.metallic * mr.z).clamp(0.0, 1.0),
            specular: self.specular,
            normal,
            occlusion: 1.0 + self.occlusion_strength * (occlusion - 1.0),
            emission,
        }
    }
}

/// The normal map's tangent-space normal `c` (scaled, not unit) in the surface's tangent frame
/// (glTF §3.9.3: bitangent = w · normal × tangent, with the tangent made perpendicular to
/// the normal); a back face turns the whole frame. Without a usable tangent, `at.normal`.
fn perturb_normal(at: &SurfaceAttributes, c: Vec3) -> Vec3 {
    let turn = if at.back_face { -1.0 } else { 1.0 };
    let n0 = at.normal * turn;
    let t = at.tangent.truncate();
    let t0 = t - n0 * n0.dot(t);
    if t0.length_squared() < 1e-12 || at.tangent.w == 0.0 {
        return at.normal;
    }
    let t0 = t0.normalize();
    let b0 = n0.cross(t0) * at.tangent.w.signum();
    (turn * (t0 * c.x + b0 * c.y) + at.normal * c.z).normalize_or(at.normal)
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
