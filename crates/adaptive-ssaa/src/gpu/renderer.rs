//! A whole scene set up for adaptive supersampling at one size.

use ::gbuffer::Frame;
use ::gbuffer::gpu::{GBufferPass, GpuScene};
use ::gpu::{PassTimer, transfer};
use scene::{Camera, Scene};
use tiled_shading::GpuLight;

use super::{GpuTextures, SsGBufferPass, SsGBufferTargets, Ssaa, SsaaInputs, TEXTURE_SIZE};
use crate::{ArrayLayers, SsaaConfig, SsaaError, SsaaMaterial};

/// A scene set up for adaptive supersampling at one size: G-buffer passes, the uploaded scene
/// (with its texture store), the texture array drawn from the store, materials, targets and
/// the [`Ssaa`] passes.
pub struct SsaaRenderer {
    gbuffer_pass: GBufferPass,
    ss_pass: SsGBufferPass,
    scene: GpuScene,
    /// The texture array (the scene's base colour and emissive textures).
    pub textures: GpuTextures,
    /// The supersampled G-buffer.
    pub targets: SsGBufferTargets,
    /// The adaptive supersampling passes.
    pub ssaa: Ssaa,
    width: u32,
    height: u32,
}

impl SsaaRenderer {
    /// Uploads `scene` (its texture store filtered with `config.anisotropy`; the array's layers
    /// at most [`TEXTURE_SIZE`] on a side) and builds every pass for a `width × height` image.
    pub fn new(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        scene: &Scene,
        lights: &[GpuLight],
        width: u32,
        height: u32,
        config: &SsaaConfig,
    ) -> Result<Self, SsaaError> {
        config.validate()?;
        let (sw, sh) = (width.checked_mul(config.m), height.checked_mul(config.m));
        let (Some(sw), Some(sh)) = (sw, sh) else {
            return Err(SsaaError::InvalidSize {
                width,
                height,
                m: config.m,
            });
        };
        if width == 0 || height == 0 || sw > ::gbuffer::MAX_SIZE || sh > ::gbuffer::MAX_SIZE {
            return Err(SsaaError::InvalidSize {
                width,
                height,
                m: config.m,
            });
        }
        let gbuffer_pass = GBufferPass::new(device)?;
        let ss_pass = SsGBufferPass::new(device, &gbuffer_pass)?;
        let options = ::gbuffer::TextureOptions {
            max_anisotropy: config.anisotropy,
        };
        let gpu_scene = GpuScene::upload_with(device, queue, scene, &gbuffer_pass, &options)?;
        let layers = ArrayLayers::new(scene);
        let textures = GpuTextures::new(
            device,
            queue,
            &gpu_scene.textures,
            &layers,
            layers.side(scene, TEXTURE_SIZE),
            config.anisotropy,
        )?;
        let materials = transfer::buffer_init(
            device,
            "ssaa materials",
            bytemuck::cast_slice(&SsaaMaterial::of_scene(scene, &layers)),
            wgpu::BufferUsages::STORAGE,
        )?;
        let targets = SsGBufferTargets::new(device, sw, sh)?;
        let inputs = SsaaInputs {
            frame: gbuffer_pass.frame_buffer(),
            targets: &targets,
            textures: &textures,
            materials: &materials,
            output: None,
        };
        let mut ssaa = Ssaa::new(device, &inputs, config, width, height, lights.len())?;
        ssaa.set_lights(queue, lights)?;
        Ok(Self {
            gbuffer_pass,
            ss_pass,
            scene: gpu_scene,
            textures,
            targets,
            ssaa,
            width,
            height,
        })
    }

    /// Writes the camera (frame at the sample resolution, far distance).
    pub fn set_camera(&mut self, queue: &wgpu::Queue, camera: &Camera) -> Result<(), SsaaError> {
        ::gbuffer::validate_camera(camera)?;
        let m = self.ssaa.config().m;
        self.gbuffer_pass
            .write_frame(queue, &Frame::new(camera, self.width * m, self.height * m));
        self.ssaa.set_far(queue, camera.far);
        Ok(())
    }

    /// Records the supersampled G-buffer pass.
    pub fn encode_gbuffer(&self, encoder: &mut wgpu::CommandEncoder, timer: Option<&PassTimer>) {
        self.ss_pass.encode(
            encoder,
            &self.gbuffer_pass,
            &self.scene,
            &self.targets,
            timer.and_then(|t| t.render_pass("ss gbuffer")),
        );
    }
}
