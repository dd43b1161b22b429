//! Shadow maps of the direct lights on the GPU ([`crate::shadows`] says what they hold):
//! `shadow_raster.wgsl` draws the scene's depth into one layer of a `Depth32Float` array per
//! view, one depth-only render pass per layer; the light accumulation reads them through its
//! bind group 1 (`shadows.wgsl`, [`super::LightShading::bind_shadows`]).
//!
//! ```no_run
//! use tiled_shading::{gpu::shadows::{GpuShadowMaps, ShadowMapPass}, shadows::{self, ShadowMapConfig}};
//! # let gpu = gpu::Gpu::from_env()?;
//! # let (device, queue) = (&gpu.device, &gpu.queue);
//! let scene = scene::cornell_box();
//! let camera = scene.camera_or_framed();
//! let mut lights = tiled_shading::gpu_lights(&scene.lights)?;
//! let config = ShadowMapConfig::default();
//! let plan = shadows::plan(&lights, &vec![true; lights.len()], &camera, 1.0, scene.bounds(), &config, 256)?;
//! plan.assign(&mut lights);
//! let pass = ShadowMapPass::new(device)?;
//! let mut maps = pass.bind(device, &config, plan.views.len())?;
//! maps.set_views(queue, &plan.views)?;
//! let pass_scene = gbuffer::gpu::GBufferPass::new(device)?;
//! let gpu_scene = gbuffer::gpu::GpuScene::upload(device, queue, &scene, &pass_scene)?;
//! let mut encoder = device.create_command_encoder(&Default::default());
//! pass.encode(&maps, &gpu_scene, &mut encoder, None);
//! queue.submit([encoder.finish()]);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use ::gpu::kernel::{Binding, Layout};
use ::gpu::{PassTimer, transfer};
use gbuffer::gpu::GpuScene;

use crate::ShadingError;
use crate::rays::{RayBvh, RayNode, RayParams, RayTriangle};
use crate::shadows::{ShadowMapConfig, ShadowMaps, ShadowView};

/// Format of the shadow-map array.
pub const SHADOW_FORMAT: wgpu::TextureFormat = gbuffer::DEPTH_FORMAT;

/// Group 1 of the light accumulation (`shadows.wgsl`): views, bias and offset, the depth
/// array, its sampler; the ManyLoD atlas of paraboloid-shadowed lights and its parameters;
/// the BVH of ray-shadowed lights (nodes, triangles, [`crate::rays::RayParams`]).
pub const LOOKUP_BINDINGS: [Binding; 9] = [
    Binding::StorageRead,
    Binding::Uniform,
    Binding::TextureDepthArray,
    Binding::SamplerNonFiltering,
    Binding::StorageRead,
    Binding::Uniform,
    Binding::StorageRead,
    Binding::StorageRead,
    Binding::Uniform,
];

/// The scene's BVH on the GPU for visibility by rays ([`crate::rays`]): its nodes, its
/// triangles and the shadow rays' [`RayParams`] (`rays.wgsl`, `shadows.wgsl`).
pub struct GpuRays {
    /// [`crate::rays::RayNode`]s.
    pub nodes: wgpu::Buffer,
    /// [`crate::rays::RayTriangle`]s.
    pub triangles: wgpu::Buffer,
    /// Uniform [`RayParams`].
    pub params: wgpu::Buffer,
}

impl GpuRays {
    /// Uploads `bvh` with `params`.
    pub fn new(
        device: &wgpu::Device,
        bvh: &RayBvh,
        params: RayParams,
    ) -> Result<Self, ShadingError> {
        let storage = |label, bytes: &[u8]| {
            transfer::buffer_init(device, label, bytes, wgpu::BufferUsages::STORAGE)
        };
        Ok(Self {
            nodes: storage("ray nodes", bytemuck::cast_slice(&bvh.nodes))?,
            triangles: storage("ray triangles", bytemuck::cast_slice(&bvh.triangles))?,
            params: transfer::buffer_init(
                device,
                "ray params",
                bytemuck::bytes_of(&params),
                wgpu::BufferUsages::UNIFORM,
            )?,
        })
    }

    /// Stand-ins for shading that casts no rays (one zeroed node and triangle).
    pub fn none(device: &wgpu::Device) -> Result<Self, ShadingError> {
        let zeroed =
            |label, size: usize, usage| transfer::buffer(device, label, size as u64, usage);
        Ok(Self {
            nodes: zeroed(
                "no ray nodes",
                size_of::<RayNode>(),
                wgpu::BufferUsages::STORAGE,
            )?,
            triangles: zeroed(
                "no ray triangles",
                size_of::<RayTriangle>(),
                wgpu::BufferUsages::STORAGE,
            )?,
            params: zeroed(
                "no ray params",
                size_of::<RayParams>(),
                wgpu::BufferUsages::UNIFORM,
            )?,
        })
    }
}

/// A ManyLoD atlas of paraboloid shadow views as the lookup binds it: the packed depths
/// (`manylod::gpu`'s atlas buffer) and a uniform `manylod::lookup::AtlasParams`.
#[derive(Clone, Copy)]
pub struct AtlasBindings<'a> {
    /// The atlas (one `u32` per pixel).
    pub atlas: &'a wgpu::Buffer,
    /// Its `AtlasParams`.
    pub params: &'a wgpu::Buffer,
}

/// The depth-only pipeline that renders shadow views (`shadow_raster.wgsl`).
pub struct ShadowMapPass {
    pipeline: wgpu::RenderPipeline,
    layout: Layout,
}

/// Shadow maps: a depth array of `capacity` layers, the views buffer and the raster pass's
/// bind group ([`ShadowMapPass::bind`]); the light accumulation binds them with
/// [`super::LightShading::bind_shadows`].
pub struct GpuShadowMaps {
    texture: wgpu::Texture,
    layers: Vec<wgpu::TextureView>,
    views: wgpu::Buffer,
    params: wgpu::Buffer,
    sampler: wgpu::Sampler,
    group: wgpu::BindGroup,
    count: usize,
    config: ShadowMapConfig,
}

impl ShadowMapPass {
    /// Builds the pipeline.
    pub fn new(device: &wgpu::Device) -> Result<Self, ShadingError> {
        let module = crate::SHADERS.module(device, "shadow_raster.wgsl")?;
        let layout = Layout::new(
            device,
            "shadow views",
            wgpu::ShaderStages::VERTEX,
            &[Binding::StorageRead],
        );
        let pipeline_layout = ::gpu::kernel::pipeline_layout(device, "shadow maps", &[&layout]);
        let pipeline = gbuffer::gpu::scene_pipeline(
            device,
            "shadow maps",
            &pipeline_layout,
            &module,
            ("shadow_depth", None),
            (wgpu::CompareFunction::Less, true),
            false,
        );
        Ok(Self { pipeline, layout })
    }

    /// Records one depth pass per view of `maps` (cleared to the far plane, then `scene`
    /// drawn as that view's instance), timed as one pass `shadow maps` by `timer`.
    pub fn encode(
        &self,
        maps: &GpuShadowMaps,
        scene: &GpuScene,
        encoder: &mut wgpu::CommandEncoder,
        timer: Option<&PassTimer>,
    ) {
        let timestamps = timer.and_then(|t| t.render_pass("shadow maps"));
        let last = maps.count.saturating_sub(1);
        for (v, layer) in maps.layers[..maps.count].iter().enumerate() {
            // The timer's begin stamp goes to the first pass, its end stamp to the last.
            let stamps = timestamps
                .as_ref()
                .filter(|_| v == 0 || v == last)
                .map(|t| wgpu::RenderPassTimestampWrites {
                    query_set: t.query_set,
                    beginning_of_pass_write_index: t
                        .beginning_of_pass_write_index
                        .filter(|_| v == 0),
                    end_of_pass_write_index: t.end_of_pass_write_index.filter(|_| v == last),
                });
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("shadow map"),
                color_attachments: &[],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: layer,
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(1.0),
                        store: wgpu::StoreOp::Store,
                    }),
                    stencil_ops: None,
                }),
                timestamp_writes: stamps,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, &maps.group, &[]);
            scene.draw_geometry(&mut pass, v as u32..v as u32 + 1);
        }
    }
}

impl ShadowMapPass {
    /// The depth-only pipeline: vertex stage `shadow_depth` draws the scene's positions
    /// (`GpuScene::draw_geometry`: vertex buffer slot 0) into the view its instance index names.
    pub fn pipeline(&self) -> &wgpu::RenderPipeline {
        &self.pipeline
    }

    /// The pipeline's bind group over `views` (a storage buffer of [`ShadowView`]s).
    pub fn bind_views(&self, device: &wgpu::Device, views: &wgpu::Buffer) -> wgpu::BindGroup {
        self.layout.bind(device, &[views.as_entire_binding()])
    }

    /// Allocates shadow maps of `config.resolution` for `capacity` views (at least one
    /// layer; no views until [`GpuShadowMaps::set_views`]). More layers than the device's
    /// `max_texture_array_layers` is an error naming both.
    pub fn bind(
        &self,
        device: &wgpu::Device,
        config: &ShadowMapConfig,
        capacity: usize,
    ) -> Result<GpuShadowMaps, ShadingError> {
        config.validate()?;
        let layers = capacity.max(1) as u32;
        let limits = device.limits();
        if layers > limits.max_texture_array_layers {
            return Err(ShadingError::InvalidShadows(format!(
                "{layers} shadow views exceed the device's {} texture array layers",
                limits.max_texture_array_layers
            )));
        }
        if config.resolution > limits.max_texture_dimension_2d {
            return Err(ShadingError::InvalidShadows(format!(
                "resolution {} exceeds the device's {} texels",
                config.resolution, limits.max_texture_dimension_2d
            )));
        }
        let texture = transfer::allocation(device, "the shadow maps", || {
            Ok::<_, ShadingError>(device.create_texture(&wgpu::TextureDescriptor {
                label: Some("shadow maps"),
                size: wgpu::Extent3d {
                    width: config.resolution,
                    height: config.resolution,
                    depth_or_array_layers: layers,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: SHADOW_FORMAT,
                usage: wgpu::TextureUsages::RENDER_ATTACHMENT
                    | wgpu::TextureUsages::TEXTURE_BINDING
                    | wgpu::TextureUsages::COPY_SRC,
                view_formats: &[],
            }))
        })?;
        let layer_views = (0..layers)
            .map(|layer| {
                texture.create_view(&wgpu::TextureViewDescriptor {
                    label: Some("shadow map layer"),
                    dimension: Some(wgpu::TextureViewDimension::D2),
                    base_array_layer: layer,
                    array_layer_count: Some(1),
                    ..Default::default()
                })
            })
            .collect();
        let views = transfer::buffer(
            device,
            "shadow views",
            u64::from(layers) * size_of::<ShadowView>() as u64,
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
        )?;
        let params = transfer::buffer_init(
            device,
            "shadow params",
            bytemuck::cast_slice(&[config.bias, config.normal_offset, 0.0, 0.0]),
            wgpu::BufferUsages::UNIFORM,
        )?;
        let sampler = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("shadow maps"),
            ..Default::default()
        });
        let group = self.bind_views(device, &views);
        Ok(GpuShadowMaps {
            texture,
            layers: layer_views,
            views,
            params,
            sampler,
            group,
            count: 0,
            config: *config,
        })
    }
}

impl GpuShadowMaps {
    /// Sets the views the next [`ShadowMapPass::encode`] renders (at most the capacity).
    pub fn set_views(
        &mut self,
        queue: &wgpu::Queue,
        views: &[ShadowView],
    ) -> Result<(), ShadingError> {
        if views.len() > self.layers.len() {
            return Err(ShadingError::InvalidShadows(format!(
                "{} views do not fit the {} layers made",
                views.len(),
                self.layers.len()
            )));
        }
        queue.write_buffer(&self.views, 0, bytemuck::cast_slice(views));
        self.count = views.len();
        Ok(())
    }

    /// Layers made: the most views [`GpuShadowMaps::set_views`] takes.
    pub fn capacity(&self) -> usize {
        self.layers.len()
    }

    /// Views set.
    pub fn count(&self) -> usize {
        self.count
    }

    /// The configuration they were made with.
    pub fn config(&self) -> &ShadowMapConfig {
        &self.config
    }

    /// The depth array (`SHADOW_FORMAT`, a layer per view).
    pub fn texture(&self) -> &wgpu::Texture {
        &self.texture
    }

    /// Reads the rendered maps back for the CPU lookup ([`crate::shadows::visibility`]),
    /// with `views` (those given to [`GpuShadowMaps::set_views`]).
    pub fn read(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        views: &[ShadowView],
    ) -> Result<ShadowMaps, ShadingError> {
        let bytes =
            transfer::read_texture(device, queue, &self.texture, wgpu::TextureAspect::DepthOnly)?;
        let depth: Vec<f32> = bytemuck::pod_collect_to_vec(&bytes);
        Ok(ShadowMaps {
            views: views.to_vec(),
            depth,
            resolution: self.config.resolution,
            bias: self.config.bias,
            normal_offset: self.config.normal_offset,
            atlas: None,
            rays: None,
        })
    }
}

/// What the light accumulation looks shadows up in: depth-array views
/// ([`GpuShadowMaps`]) for the lights whose `shadow_count` names layers, a ManyLoD atlas
/// for those with [`crate::shadows::PARABOLOID_SHADOW`], the scene's BVH for those with
/// [`crate::shadows::RAY_SHADOW`]. `Default`: none (every light unshadowed).
#[derive(Clone, Copy, Default)]
pub struct ShadowInputs<'a> {
    /// The rasterised shadow maps.
    pub maps: Option<&'a GpuShadowMaps>,
    /// The ManyLoD atlas.
    pub atlas: Option<AtlasBindings<'a>>,
    /// The BVH for rays.
    pub rays: Option<&'a GpuRays>,
}

/// The lookup group ([`LOOKUP_BINDINGS`]) of `inputs` on `layout`, 1×1 stand-ins (no light
/// reads them) for what is `None`.
pub(super) fn lookup_group(
    device: &wgpu::Device,
    layout: &Layout,
    ShadowInputs { maps, atlas, rays }: ShadowInputs<'_>,
) -> Result<wgpu::BindGroup, ShadingError> {
    let stand_in_rays;
    let rays = match rays {
        Some(r) => r,
        None => {
            stand_in_rays = GpuRays::none(device)?;
            &stand_in_rays
        }
    };
    let stand_in_maps;
    let (views, params, texture, sampler) = match maps {
        Some(m) => (&m.views, &m.params, &m.texture, &m.sampler),
        None => {
            stand_in_maps = (
                transfer::buffer(
                    device,
                    "no shadow views",
                    size_of::<ShadowView>() as u64,
                    wgpu::BufferUsages::STORAGE,
                )?,
                transfer::buffer(device, "no shadow params", 16, wgpu::BufferUsages::UNIFORM)?,
                transfer::texture_2d(
                    device,
                    "no shadow maps",
                    1,
                    1,
                    SHADOW_FORMAT,
                    wgpu::TextureUsages::TEXTURE_BINDING,
                ),
                device.create_sampler(&Default::default()),
            );
            let (v, p, t, s) = &stand_in_maps;
            (v, p, t, s)
        }
    };
    let stand_in_atlas;
    let atlas = match atlas {
        Some(a) => a,
        None => {
            stand_in_atlas = (
                transfer::buffer(device, "no atlas", 16, wgpu::BufferUsages::STORAGE)?,
                transfer::buffer(
                    device,
                    "no atlas params",
                    size_of::<manylod::lookup::AtlasParams>() as u64,
                    wgpu::BufferUsages::UNIFORM,
                )?,
            );
            AtlasBindings {
                atlas: &stand_in_atlas.0,
                params: &stand_in_atlas.1,
            }
        }
    };
    let array = texture.create_view(&wgpu::TextureViewDescriptor {
        label: Some("shadow maps"),
        dimension: Some(wgpu::TextureViewDimension::D2Array),
        ..Default::default()
    });
    Ok(layout.bind(
        device,
        &[
            views.as_entire_binding(),
            params.as_entire_binding(),
            wgpu::BindingResource::TextureView(&array),
            wgpu::BindingResource::Sampler(sampler),
            atlas.atlas.as_entire_binding(),
            atlas.params.as_entire_binding(),
            rays.nodes.as_entire_binding(),
            rays.triangles.as_entire_binding(),
            rays.params.as_entire_binding(),
        ],
    ))
}
