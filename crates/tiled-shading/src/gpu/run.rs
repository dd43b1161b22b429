//! Convenience for tests and examples: upload, run, read back.

use ::gpu::Gpu;
use gbuffer::gpu::UploadedGBuffer;
use gbuffer::{Frame, GBuffer};
use scene::Camera;

use super::{LightShading, read_outputs};
use crate::cpu::Shaded;
use crate::{GpuLight, ShadingConfig, ShadingError};

/// Uploads `gb`, `frame` and `lights`, runs one light accumulation with `config` and reads
/// everything back: the GPU twin of [`crate::cpu::shade`] (lists sorted by light index; for
/// brute force the lists and counts are those the CPU reports: every light for every tile
/// with a surface — the shader keeps none).
pub fn run(
    gpu: &Gpu,
    gb: &GBuffer,
    frame: &Frame,
    camera: &Camera,
    lights: &[GpuLight],
    config: &ShadingConfig,
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
