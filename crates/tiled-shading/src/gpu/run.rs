//! Convenience for tests and examples: upload, run, read back.

use ::gpu::Gpu;
use gbuffer::gpu::{GBufferPass, GpuScene, UploadedGBuffer};
use gbuffer::{Frame, GBuffer};
use scene::{Camera, Scene};

use super::shadows::{ShadowInputs, ShadowMapPass};
use super::{LightShading, read_outputs};
use crate::cpu::Shaded;
use crate::shadows::{self, ShadowMapConfig, ShadowMaps};
use crate::{GpuLight, ShadingConfig, ShadingError};

/// [`run`] with every light shadowed: plans the views ([`shadows::plan`]) of `lights` over
/// `scene` (the scene `gb` shows), renders the maps on the GPU and returns them read back
/// with the result and the lights (their shadow views assigned): the GPU twin of
/// `cpu::shade(…, Some(&maps))`.
#[allow(clippy::too_many_arguments)]
pub fn run_shadowed(
    gpu: &Gpu,
    scene: &Scene,
    gb: &GBuffer,
    frame: &Frame,
    camera: &Camera,
    lights: &[GpuLight],
    config: &ShadingConfig,
    shadow_config: &ShadowMapConfig,
) -> Result<(Shaded, ShadowMaps, Vec<GpuLight>), ShadingError> {
    let (device, queue) = (&gpu.device, &gpu.queue);
    let aspect = gb.width() as f32 / gb.height() as f32;
    let layers = device.limits().max_texture_array_layers;
    let everything = vec![true; lights.len()];
    let plan = shadows::plan(
        lights,
        &everything,
        camera,
        aspect,
        scene.bounds(),
        shadow_config,
        layers,
    )?;
    let mut lights = lights.to_vec();
    plan.assign(&mut lights);
    let pass = ShadowMapPass::new(device)?;
    let mut maps = pass.bind(device, shadow_config, plan.views.len())?;
    maps.set_views(queue, &plan.views)?;
    let gbuffer_pass = GBufferPass::new(device)?;
    let uploaded = GpuScene::upload(device, queue, scene, &gbuffer_pass).map_err(|e| {
        ShadingError::InvalidShadows(format!("the scene could not be uploaded: {e}"))
    })?;
    let mut encoder = device.create_command_encoder(&Default::default());
    pass.encode(&maps, &uploaded, &mut encoder, None);
    queue.submit([encoder.finish()]);
    let inputs = ShadowInputs {
        maps: Some(&maps),
        atlas: None,
        rays: None,
    };
    let shaded = run(gpu, gb, frame, camera, &lights, config, inputs)?;
    Ok((shaded, maps.read(device, queue, &plan.views)?, lights))
}

/// Uploads `gb`, `frame` and `lights`, runs one light accumulation with `config` (looking
/// shadows up in `shadows`) and reads everything back: the GPU twin of [`crate::cpu::shade`] (lists sorted by light index; for
/// brute force the lists and counts are those the CPU reports: every light for every tile
/// with a surface — the shader keeps none).
pub fn run(
    gpu: &Gpu,
    gb: &GBuffer,
    frame: &Frame,
    camera: &Camera,
    lights: &[GpuLight],
    config: &ShadingConfig,
    shadows: ShadowInputs<'_>,
) -> Result<Shaded, ShadingError> {
    let (device, queue) = (&gpu.device, &gpu.queue);
    let uploaded = UploadedGBuffer::new(&gpu.device, &gpu.queue, gb, frame)?;
    let stage = LightShading::new(device, config)?;
    let outputs = LightShading::output_textures(device, gb.width(), gb.height());
    let outputs = [&outputs[0], &outputs[1]];
    let mut bound = stage.bind(
        device,
        &uploaded.frame,
        uploaded.textures(),
        outputs,
        lights.len(),
        true,
    )?;
    bound.set_lights(queue, lights)?;
    bound.set_camera(queue, camera);
    stage.bind_shadows(device, &mut bound, shadows)?;
    let mut encoder = device.create_command_encoder(&Default::default());
    stage.encode(&bound, &mut encoder, None);
    queue.submit([encoder.finish()]);
    let [diffuse, specular] = read_outputs(device, queue, outputs)?;
    let tiles = config.tiles(gb.width(), gb.height());
    let lists = match bound.read_lists(device, queue)? {
        Some(lists) => lists,
        None => (0..tiles.0 * tiles.1)
            .map(|t| {
                let rect = crate::cpu::tile_pixels(
                    config.tile_size,
                    gb.width(),
                    gb.height(),
                    t % tiles.0,
                    t / tiles.0,
                );
                let surface = (rect[2]..rect[3])
                    .any(|y| (rect[0]..rect[1]).any(|x| gb.linear_depth.get(x, y) > 0.0));
                if surface {
                    (0..lights.len() as u32)
                        .map(|i| (i, crate::cpu::ALL_SLICES))
                        .collect()
                } else {
                    Vec::new()
                }
            })
            .collect(),
    };
    Ok(Shaded {
        diffuse,
        specular,
        tiles,
        counts: lists.iter().map(|l| l.len() as u32).collect(),
        lists,
    })
}
