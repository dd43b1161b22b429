//! G-buffer layout and creation: compact normal encodings, position from depth, a CPU
//! reference rasterizer and the GPU pass that writes every target at once (MRT).
//!
//! Papers: Ishmukhametov 2013 §1.3 (deferred shading, G-buffer creation), ch. 3 (G-buffer
//! layouts of S.T.A.L.K.E.R., Killzone 2, Battlefield 3; §3.6 position from depth and compact
//! normal storage); Holländer 2013 §4.2.
//!
//! # Layout
//!
//! | target | format | bits/pixel | content |
//! |---|---|---|---|
//! | `depth` | `Depth32Float` | 32 | hardware depth z/w in \[0, 1\] (cleared to 1) |
//! | `linear_depth` | `R32Float` | 32 | view-space depth (distance along the view axis); 0 = no surface |
//! | `normal` | `R32Uint` | 32 | world-space shading normal (normal-mapped), octahedral, two snorm16 (`pack2x16snorm`) |
//! | `albedo` | `Rgba8Unorm` | 32 | linear base colour (factor × texture × vertex colour); alpha: the specular factor |
//! | `material` | `R32Uint` | 32 | roughness unorm8 \| metallic unorm8 ≪ 8 \| material id ≪ 16; `u32::MAX` = none |
//! | `emission` | `Rgba16Float` | 64 | emitted radiance (factor × texture, clamped to 65504); alpha: ambient occlusion |
//!
//! 224 bits per pixel: S.T.A.L.K.E.R.'s (2005) 160 with hardware depth instead of a stored
//! position and 32-bit octahedral normals (0.004° worst error, see [`normal`]), plus the glTF
//! material's emission and occlusion (issue 22: textured, so per pixel, not per material).
//! Materials are evaluated as [`scene::Material::evaluate`] describes (`material.wgsl`).
//!
//! ```no_run
//! let scene = scene::cornell_box();
//! let camera = scene.camera_or_framed();
//! let gb = gbuffer::cpu::rasterize(&scene, &camera, 320, 240)?;
//! let p = gbuffer::position::from_depth(&gbuffer::Frame::new(&camera, 320, 240), 160, 120, gb.gbuffer.depth.get(160, 120));
//! # Ok::<(), gbuffer::GBufferError>(())
//! ```

pub mod cpu;
pub mod gpu;
mod image;
pub mod normal;
pub mod position;

pub use image::{
    Accuracy, Image, ImageError, accuracy, linear_to_srgb, psnr, srgb_to_linear, write_atomically,
};

use glam::{Mat4, Vec4};
use scene::Camera;

/// This crate's WGSL (`shaders/gbuffer/`, carried into the package by the `shaders` link).
pub static SHADERS: ::gpu::shader::Library = ::gpu::shader_library!(
    "gbuffer",
    imports: [],
    files: [
        "encode_normals.wgsl",
        "frame.wgsl",
        "gbuffer.wgsl",
        "material.wgsl",
        "meshes.wgsl",
        "mips.wgsl",
        "normal_encoding.wgsl",
        "resolve.wgsl",
        "resolve_bindless.wgsl",
        "visibility.wgsl",
        "visibility_hardware.wgsl",
        "visibility_word.wgsl",
    ],
);

/// What this crate's kernels need of a device: wgpu's default limits suffice.
pub fn device_needs() -> ::gpu::DeviceNeeds {
    ::gpu::DeviceNeeds::default()
}

/// Depth target format.
pub const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
/// Linear view depth target format.
pub const LINEAR_DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R32Float;
/// Packed normal target format.
pub const NORMAL_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R32Uint;
/// Albedo target format.
pub const ALBEDO_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;
/// Packed material target format.
pub const MATERIAL_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R32Uint;
/// Emission and occlusion target format.
pub const EMISSION_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;
/// Material word of pixels no surface covers.
pub const NO_MATERIAL: u32 = u32::MAX;
/// Largest image side accepted by the CPU rasterizer (the GPU path checks the device limit).
pub const MAX_SIZE: u32 = 16384;

/// A G-buffer on the CPU, texel for texel what the GPU targets hold.
#[derive(Clone, Debug, PartialEq)]
pub struct GBuffer {
    /// Hardware depth z/w, 1 where nothing was drawn.
    pub depth: Image<f32>,
    /// View-space depth, 0 where nothing was drawn.
    pub linear_depth: Image<f32>,
    /// Octahedral normal as two snorm16 ([`normal::pack_octahedral`]).
    pub normal: Image<u32>,
    /// Linear albedo, RGBA8.
    pub albedo: Image<[u8; 4]>,
    /// Packed roughness, metallic, material id ([`pack_material`]).
    pub material: Image<u32>,
    /// Emitted radiance (rgb) and ambient occlusion (a), each a half float ([`to_half`]).
    pub emission: Image<[f32; 4]>,
}

impl GBuffer {
    /// An empty (cleared) G-buffer.
    pub fn cleared(width: u32, height: u32) -> Self {
        Self {
            depth: Image::filled(width, height, 1.0),
            linear_depth: Image::filled(width, height, 0.0),
            normal: Image::filled(width, height, 0),
            albedo: Image::filled(width, height, [0; 4]),
            material: Image::filled(width, height, NO_MATERIAL),
            emission: Image::filled(width, height, [0.0; 4]),
        }
    }

    /// Width in pixels.
    pub fn width(&self) -> u32 {
        self.depth.width()
    }

    /// Height in pixels.
    pub fn height(&self) -> u32 {
        self.depth.height()
    }
}

/// Packs roughness and metallic (unorm8, round half to even like WGSL `round`) and a 16-bit
/// material id into the `material` target's word.
pub fn pack_material(roughness: f32, metallic: f32, id: u32) -> u32 {
    let q = |v: f32| (v.clamp(0.0, 1.0) * 255.0).round_ties_even() as u32;
    q(roughness) | (q(metallic) << 8) | (id << 16)
}

/// `v` rounded to the nearest half float, as the `emission` target stores it.
pub fn to_half(v: f32) -> f32 {
    half::f16::from_f32(v).to_f32()
}

/// Unpacks [`pack_material`]: (roughness, metallic, material id).
pub fn unpack_material(word: u32) -> (f32, f32, u32) {
    (
        (word & 0xff) as f32 / 255.0,
        ((word >> 8) & 0xff) as f32 / 255.0,
        word >> 16,
    )
}

/// A G-buffer albedo texel as the shading reads it: the linear albedo and, in the alpha, the
/// material's specular factor ([`scene::Material::specular`]).
pub fn unpack_albedo(texel: [u8; 4]) -> (glam::Vec3, f32) {
    let [r, g, b, a] = texel.map(|c| f32::from(c) / 255.0);
    (glam::Vec3::new(r, g, b), a)
}

/// Per-frame camera data shared by screen-space passes (WGSL `Frame` in `gbuffer/frame.wgsl`).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct Frame {
    /// World → clip (the G-buffer pass's; shifted by the jitter).
    pub view_proj: Mat4,
    /// World → view.
    pub view: Mat4,
    /// Clip → world of the unjittered projection (with the NDC of the sample positions
    /// [`position::pixel_to_ndc`] gives).
    pub inv_view_proj: Mat4,
    /// View → world.
    pub inv_view: Mat4,
    /// Eye position (xyz).
    pub eye: Vec4,
    /// Width, height, 1 / width, 1 / height.
    pub viewport: Vec4,
    /// tan(fov_y / 2) × aspect, tan(fov_y / 2): the view ray at unit view depth.
    pub tan_half_fov: Vec4,
    /// Where the pixels sample: x, y, the offset of the sample positions from the pixel centres
    /// in pixels, x right, y down ([`Frame::with_jitter`]); z, the texture footprint in
    /// G-buffer pixels ([`Frame::with_texture_footprint`]; 0 and 1 both mean one pixel); w, 0.
    pub sampling: Vec4,
}

impl Frame {
    /// Frame data for `camera` rendering a `width × height` image.
    pub fn new(camera: &Camera, width: u32, height: u32) -> Self {
        let aspect = width as f32 / height.max(1) as f32;
        let view = camera.view();
        let view_proj = camera.projection(aspect) * view;
        let t = (camera.fov_y * 0.5).tan();
        Self {
            view_proj,
            view,
            inv_view_proj: view_proj.inverse(),
            inv_view: view.inverse(),
            eye: camera.eye.extend(1.0),
            viewport: Vec4::new(
                width as f32,
                height as f32,
                1.0 / width as f32,
                1.0 / height as f32,
            ),
            tan_half_fov: Vec4::new(t * aspect, t, 0.0, 0.0),
            sampling: Vec4::new(0.0, 0.0, 1.0, 0.0),
        }
    }

    /// The frame with every pixel sampling at `offset` pixels from its centre (x right, y
    /// down; each within ±½): the G-buffer pass's projection is shifted so the rasteriser's
    /// pixel centres land there, and positions are reconstructed there. A supersampled
    /// G-buffer's sample k of every pixel is then the G-buffer of this frame.
    pub fn with_jitter(mut self, offset: glam::Vec2) -> Self {
        let shift = glam::Vec3::new(
            -2.0 * offset.x * self.viewport.z,
            2.0 * offset.y * self.viewport.w,
            0.0,
        );
        self.view_proj = Mat4::from_translation(shift) * self.view_proj;
        self.sampling.x = offset.x;
        self.sampling.y = offset.y;
        self
    }

    /// The frame with textures filtered over `pixels` G-buffer pixels on a side instead of
    /// one: a supersampled G-buffer of `m × m` samples per image pixel takes `m`, so each
    /// sample's texture lookup covers its whole image pixel (the G-buffer pass scales the
    /// texture-coordinate derivatives; Holländer 2013 §4.3.4 filters over the pixel too).
    pub fn with_texture_footprint(mut self, pixels: f32) -> Self {
        self.sampling.z = pixels;
        self
    }
}

/// How the G-buffer filters textures (both the GPU pass and its CPU twin).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TextureOptions {
    /// Largest anisotropy (1..=[`scene::MAX_ANISOTROPY`]; 16 by default), used by samplers
    /// that filter linearly between mip levels (wgpu allows anisotropy only there).
    pub max_anisotropy: u32,
}

impl Default for TextureOptions {
    fn default() -> Self {
        Self {
            max_anisotropy: scene::MAX_ANISOTROPY,
        }
    }
}

impl TextureOptions {
    /// Rejects an anisotropy outside 1..=16.
    pub fn validate(&self) -> Result<(), GBufferError> {
        if !(1..=scene::MAX_ANISOTROPY).contains(&self.max_anisotropy) {
            return Err(GBufferError::InvalidOptions(format!(
                "the anisotropy must be 1..={}, got {}",
                scene::MAX_ANISOTROPY,
                self.max_anisotropy
            )));
        }
        Ok(())
    }
}

/// Errors of G-buffer creation.
#[derive(Debug, thiserror::Error)]
pub enum GBufferError {
    /// Width or height is zero or too large.
    #[error("invalid G-buffer size {width}×{height} (each side must be 1..={max})")]
    InvalidSize {
        /// Requested width.
        width: u32,
        /// Requested height.
        height: u32,
        /// Largest allowed side.
        max: u32,
    },
    /// The camera is unusable (non-finite, zero field of view, near >= far ...).
    #[error("invalid camera: {0}")]
    InvalidCamera(String),
    /// The scene breaks an invariant (see `scene::Scene::validate`).
    #[error("invalid scene: {0}")]
    InvalidScene(#[from] scene::SceneErrorKind),
    /// Too many materials for the 16-bit material id.
    #[error("{0} materials exceed the 65535 the G-buffer's 16-bit material id can address")]
    TooManyMaterials(usize),
    /// An option is out of its range.
    #[error("invalid G-buffer option: {0}")]
    InvalidOptions(String),
    /// A GPU resource could not be created or read.
    #[error(transparent)]
    Gpu(#[from] ::gpu::GpuError),
}

/// Rejects cameras that cannot project (non-finite, eye at the target, up along the view,
/// field of view outside (0, π), planes not 0 < near < far < ∞), saying which.
pub fn validate_camera(camera: &Camera) -> Result<(), GBufferError> {
    let c = camera;
    let problem = if !(c.eye.is_finite() && c.target.is_finite() && c.up.is_finite()) {
        format!(
            "eye {}, target {} and up {} must be finite",
            c.eye, c.target, c.up
        )
    } else if !(c.target - c.eye).is_finite() || (c.target - c.eye).length_squared() == 0.0 {
        format!(
            "eye {} and target {} must be distinct points a finite distance apart",
            c.eye, c.target
        )
    } else if (c.target - c.eye)
        .normalize()
        .cross(c.up.normalize_or_zero())
        .length()
        < 1e-6
    {
        format!("up {} is parallel to the view direction", c.up)
    } else if !(c.fov_y > 0.0 && c.fov_y < std::f32::consts::PI) {
        format!(
            "vertical field of view {}° is outside (0°, 180°)",
            c.fov_y.to_degrees()
        )
    } else if !(c.near > 0.0 && c.far > c.near && c.far.is_finite()) {
        format!(
            "clip planes near {} and far {} are not 0 < near < far < ∞ (a scene whose extent \
             is beyond f32 depth precision also lands here)",
            c.near, c.far
        )
    } else {
        return Ok(());
    };
    Err(GBufferError::InvalidCamera(problem))
}

/// Rejects image sizes of zero or above [`MAX_SIZE`] on a side.
pub(crate) fn validate_size(width: u32, height: u32) -> Result<(), GBufferError> {
    if width == 0 || height == 0 || width > MAX_SIZE || height > MAX_SIZE {
        return Err(GBufferError::InvalidSize {
            width,
            height,
            max: MAX_SIZE,
        });
    }
    Ok(())
}

/// Checks the scene's invariants and that its material ids fit the 16-bit field.
pub(crate) fn validate_scene(scene: &scene::Scene) -> Result<(), GBufferError> {
    scene.validate()?;
    if scene.materials.len() >= 0xffff {
        return Err(GBufferError::TooManyMaterials(scene.materials.len()));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_matches_wgsl_layout() {
        // 4 mat4 + 4 vec4, no padding: WGSL `Frame` is 336 bytes with these offsets.
        assert_eq!(size_of::<Frame>(), 4 * 64 + 4 * 16);
        assert_eq!(std::mem::offset_of!(Frame, eye), 256);
        assert_eq!(std::mem::offset_of!(Frame, tan_half_fov), 288);
        assert_eq!(std::mem::offset_of!(Frame, sampling), 304);
    }

    #[test]
    fn material_word_round_trips() {
        let w = pack_material(0.5, 1.0, 1234);
        let (r, m, id) = unpack_material(w);
        assert!((r - 128.0 / 255.0).abs() < 1e-6 && m == 1.0 && id == 1234);
        assert_eq!(pack_material(2.0, -1.0, 0), 255);
    }
}
