//! The light accumulation on the GPU: one compute pass per frame of `tiled.wgsl` — its
//! `brute_force` entry point (8 × 8 invocations per workgroup, every light per pixel) or
//! `shade_tiles` (one workgroup per tile, [`Method::Tiled`], [`Method::TiledCones`] or
//! [`Method::Clustered`]). Pipelines,
//! buffers and bind groups are built once; [`LightShading::set_lights`] and
//! [`LightShading::set_camera`] only write buffers.
//!
//! ```no_run
//! use tiled_shading::{Method, ShadingConfig, gpu::run};
//! # let gpu = gpu::Gpu::from_env()?;
//! let scene = scene::spheres_on_plane(4);
//! let camera = scene.camera_or_framed();
//! let gb = gbuffer::cpu::rasterize(&scene, &camera, 320, 240)?.gbuffer;
//! let frame = gbuffer::Frame::new(&camera, 320, 240);
//! let lights = tiled_shading::gpu_lights(&scene::scatter_point_lights(scene.bounds(), 1024, 3))?;
//! let config = ShadingConfig { method: Method::TiledCones, ..Default::default() };
//! let shaded = run(&gpu, &gb, &frame, &camera, &lights, &config)?;
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use ::gpu::{Gpu, GpuError, PassTimer, shader, transfer};
use gbuffer::{Frame, GBuffer, Image, gpu::GBufferTextures, gpu::UploadedGBuffer};
use glam::{Vec3, Vec4};
use scene::Camera;

use crate::cpu::Shaded;
use crate::{GpuLight, Method, ShadingConfig, ShadingError, Slicing};

/// Format of the diffuse and specular accumulation textures.
pub const ACCUMULATION_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;

/// Uniform block of `tiled.wgsl` (`Params`).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct ShadingParams {
    /// Lights in the light buffer.
    pub light_count: u32,
    /// Tiles across.
    pub tiles_x: u32,
    /// 1 when every tile's list is written out (tests).
    pub record_lists: u32,
    /// List entries per tile in the list buffer.
    pub list_stride: u32,
    /// [`Slicing::near`].
    pub slice_near: f32,
    /// [`Slicing::scale`].
    pub slice_scale: f32,
    /// Padding to 32 bytes.
    pub _pad: [u32; 2],
}

/// Light accumulation for one G-buffer resolution, one [`ShadingConfig`] and up to
/// `capacity` lights.
pub struct LightShading {
    config: ShadingConfig,
    pipeline: wgpu::ComputePipeline,
    group: wgpu::BindGroup,
    params: ShadingParams,
    params_buffer: wgpu::Buffer,
    lights: wgpu::Buffer,
    capacity: usize,
    counts: wgpu::Buffer,
    lists: wgpu::Buffer,
    output: [wgpu::Texture; 2],
    size: (u32, u32),
}

fn tiled_module(
    device: &wgpu::Device,
    config: &ShadingConfig,
) -> Result<wgpu::ShaderModule, GpuError> {
    let name = "tiled-shading/tiled.wgsl";
    let method = match config.method {
        Method::TiledCones => 2,
        Method::Clustered => 3,
        _ => 1,
    };
    let wg = config.tile_size.min(16);
    let mut src = shader::source(name)?;
    for (from, to) in [
        (
            "const METHOD: u32 = 1u;".to_string(),
            format!("const METHOD: u32 = {method}u;"),
        ),
        (
            "const TILE: u32 = 16u;".to_string(),
            format!("const TILE: u32 = {}u;", config.tile_size),
        ),
        (
            "const WG: u32 = 16u;".to_string(),
            format!("const WG: u32 = {wg}u;"),
        ),
        (
            "@workgroup_size(16, 16)".to_string(),
            format!("@workgroup_size({wg}, {wg})"),
        ),
    ] {
        if !src.contains(&from) {
            return Err(GpuError::Shader {
                name: name.into(),
                message: format!("`{from}` not found"),
            });
        }
        src = src.replace(&from, &to);
    }
    Ok(shader::module_from_source(device, name, src))
}

fn storage(device: &wgpu::Device, label: &str, bytes: u64) -> Result<wgpu::Buffer, GpuError> {
    let usage =
        wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST;
    transfer::check_buffer_size(device, label, bytes, usage)?;
    Ok(device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: bytes.max(16),
        usage,
        mapped_at_creation: false,
    }))
}

impl LightShading {
    /// Builds the pass reading `frame` (a `gbuffer::Frame` uniform) and `gbuffer`, with a light
    /// buffer for `capacity` lights, initially `lights`. With `record_lists`, every tile's
    /// list is kept for [`LightShading::read_lists`] (tiles × capacity entries: for tests).
    pub fn new(
        device: &wgpu::Device,
        frame: &wgpu::Buffer,
        gbuffer: GBufferTextures<'_>,
        config: &ShadingConfig,
        capacity: usize,
        record_lists: bool,
    ) -> Result<Self, ShadingError> {
        config.validate()?;
        let size = (gbuffer.linear_depth.width(), gbuffer.linear_depth.height());
        let (tiles_x, tiles_y) = config.tiles(size.0, size.1);
        let tiles = u64::from(tiles_x) * u64::from(tiles_y);
        let capacity = capacity.max(1);
        let lights = storage(device, "lights", (capacity * size_of::<GpuLight>()) as u64)?;
        let counts = storage(device, "tile light counts", tiles * 4)?;
        let stride = if record_lists { capacity as u64 } else { 0 };
        let lists = storage(device, "tile light lists", tiles * stride * 8)?;
        let params = ShadingParams {
            light_count: 0,
            tiles_x,
            record_lists: u32::from(record_lists),
            list_stride: stride as u32,
            slice_near: 1.0,
            slice_scale: 1.0,
            _pad: [0; 2],
        };
        let params_buffer = transfer::buffer_init(
            device,
            "tiled shading params",
            bytemuck::bytes_of(&params),
            wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        )?;
        let output = ["diffuse accumulation", "specular accumulation"].map(|label| {
            transfer::texture_2d(
                device,
                label,
                size.0,
                size.1,
                ACCUMULATION_FORMAT,
                wgpu::TextureUsages::STORAGE_BINDING
                    | wgpu::TextureUsages::TEXTURE_BINDING
                    | wgpu::TextureUsages::COPY_SRC,
            )
        });
        let (module, entry) = if config.method == Method::BruteForce {
            (
                shader::module(device, "tiled-shading/tiled.wgsl")?,
                "brute_force",
            )
        } else {
            (tiled_module(device, config)?, "shade_tiles")
        };
        let pipeline = shader::compute_pipeline(device, &module, entry, &[]);
        let view = |t: &wgpu::Texture| t.create_view(&Default::default());
        let views = [
            view(gbuffer.linear_depth),
            view(gbuffer.normal),
            view(gbuffer.albedo),
            view(gbuffer.material),
            view(&output[0]),
            view(&output[1]),
        ];
        let mut entries = vec![
            wgpu::BindGroupEntry {
                binding: 0,
                resource: frame.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 1,
                resource: params_buffer.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 2,
                resource: lights.as_entire_binding(),
            },
        ];
        entries.extend(views.iter().enumerate().map(|(i, v)| wgpu::BindGroupEntry {
            binding: i as u32 + 3,
            resource: wgpu::BindingResource::TextureView(v),
        }));
        if config.method != Method::BruteForce {
            entries.push(wgpu::BindGroupEntry {
                binding: 9,
                resource: counts.as_entire_binding(),
            });
            entries.push(wgpu::BindGroupEntry {
                binding: 10,
                resource: lists.as_entire_binding(),
            });
        }
        let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("light shading"),
            layout: &pipeline.get_bind_group_layout(0),
            entries: &entries,
        });
        Ok(Self {
            config: *config,
            pipeline,
            group,
            params,
            params_buffer,
            lights,
            capacity,
            counts,
            lists,
            output,
            size,
        })
    }

    /// The configuration.
    pub fn config(&self) -> &ShadingConfig {
        &self.config
    }

    /// Replaces the lights (at most the capacity given at creation).
    pub fn set_lights(
        &mut self,
        queue: &wgpu::Queue,
        lights: &[GpuLight],
    ) -> Result<(), ShadingError> {
        if lights.len() > self.capacity {
            return Err(ShadingError::TooManyLights {
                count: lights.len(),
                capacity: self.capacity,
            });
        }
        queue.write_buffer(&self.lights, 0, bytemuck::cast_slice(lights));
        self.params.light_count = lights.len() as u32;
        queue.write_buffer(&self.params_buffer, 0, bytemuck::bytes_of(&self.params));
        Ok(())
    }

    /// Sets the cluster slicing for `camera`'s near and far planes ([`Method::Clustered`]).
    pub fn set_camera(&mut self, queue: &wgpu::Queue, camera: &Camera) {
        let slicing = Slicing::new(camera);
        self.params.slice_near = slicing.near;
        self.params.slice_scale = slicing.scale;
        queue.write_buffer(&self.params_buffer, 0, bytemuck::bytes_of(&self.params));
    }

    /// The pass name in timings: `light accumulation (METHOD)`.
    pub fn pass_name(&self) -> String {
        format!("light accumulation ({})", self.config.method)
    }

    /// Records the pass, timed by `timer` under [`LightShading::pass_name`].
    pub fn encode(&self, encoder: &mut wgpu::CommandEncoder, timer: Option<&PassTimer>) {
        let name = self.pass_name();
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some(&name),
            timestamp_writes: timer.and_then(|t| t.compute_pass(&name)),
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &self.group, &[]);
        let (x, y) = if self.config.method == Method::BruteForce {
            (self.size.0.div_ceil(8), self.size.1.div_ceil(8))
        } else {
            self.config.tiles(self.size.0, self.size.1)
        };
        pass.dispatch_workgroups(x, y, 1);
    }

    /// The diffuse and specular accumulation textures (`Rgba32Float`).
    pub fn output(&self) -> [&wgpu::Texture; 2] {
        [&self.output[0], &self.output[1]]
    }

    /// Reads back each tile's list length (`None` for brute force, which has no lists).
    pub fn read_counts(&self, gpu: &Gpu) -> Result<Option<Vec<u32>>, ShadingError> {
        if self.config.method == Method::BruteForce {
            return Ok(None);
        }
        let bytes = transfer::read_buffer(&gpu.device, &gpu.queue, &self.counts)?;
        let (tx, ty) = self.config.tiles(self.size.0, self.size.1);
        Ok(Some(
            bytemuck::cast_slice::<u8, u32>(&bytes)[..(tx * ty) as usize].to_vec(),
        ))
    }

    /// Reads back every tile's list of (light index, slice mask), sorted by light index;
    /// `None` unless built with `record_lists` (and for brute force).
    pub fn read_lists(&self, gpu: &Gpu) -> Result<Option<Vec<Vec<(u32, u32)>>>, ShadingError> {
        let Some(counts) = self.read_counts(gpu)? else {
            return Ok(None);
        };
        if self.params.record_lists == 0 {
            return Ok(None);
        }
        let bytes = transfer::read_buffer(&gpu.device, &gpu.queue, &self.lists)?;
        let entries: &[[u32; 2]] = bytemuck::cast_slice(&bytes);
        let stride = self.params.list_stride as usize;
        Ok(Some(
            counts
                .iter()
                .enumerate()
                .map(|(t, &n)| {
                    let mut list: Vec<(u32, u32)> = entries[t * stride..t * stride + n as usize]
                        .iter()
                        .map(|e| (e[0], e[1]))
                        .collect();
                    list.sort_unstable();
                    list
                })
                .collect(),
        ))
    }

    /// Reads back the diffuse and specular sums.
    pub fn read_output(&self, gpu: &Gpu) -> Result<[Image<Vec3>; 2], ShadingError> {
        let read = |t: &wgpu::Texture| -> Result<Image<Vec3>, ShadingError> {
            let bytes =
                transfer::read_texture(&gpu.device, &gpu.queue, t, wgpu::TextureAspect::All)?;
            let pixels = bytemuck::cast_slice::<u8, Vec4>(&bytes)
                .iter()
                .map(|v| v.truncate())
                .collect();
            Image::from_vec(self.size.0, self.size.1, pixels)
                .map_err(|e| GpuError::Readback(e.to_string()).into())
        };
        Ok([read(&self.output[0])?, read(&self.output[1])?])
    }
}

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
    let uploaded = UploadedGBuffer::new(gpu, gb, frame)?;
    let mut stage = LightShading::new(
        &gpu.device,
        &uploaded.frame,
        uploaded.textures(),
        config,
        lights.len(),
        true,
    )?;
    stage.set_lights(&gpu.queue, lights)?;
    stage.set_camera(&gpu.queue, camera);
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    stage.encode(&mut encoder, None);
    gpu.queue.submit([encoder.finish()]);
    let [diffuse, specular] = stage.read_output(gpu)?;
    let tiles = config.tiles(gb.width(), gb.height());
    let lists = match stage.read_lists(gpu)? {
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
