//! GPU G-buffer creation: a render pipeline writing all targets at once (MRT), the twin of
//! [`crate::cpu::rasterize`]. Shader: `shaders/gbuffer/gbuffer.wgsl`.

use ::gpu::kernel::{self, Binding, Layout};
use ::gpu::{Gpu, GpuError, transfer};
use glam::Vec4;
use scene::{Camera, Scene};

use crate::{
    ALBEDO_FORMAT, DEPTH_FORMAT, Frame, GBuffer, GBufferError, Image, LINEAR_DEPTH_FORMAT,
    MATERIAL_FORMAT, NO_MATERIAL, NORMAL_FORMAT,
};

/// Vertex layout of the uploaded scene (WGSL `vs_main` inputs).
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuVertex {
    /// World position.
    pub position: [f32; 3],
    /// Normal.
    pub normal: [f32; 3],
    /// Texture coordinate.
    pub uv: [f32; 2],
}

/// A material as the shaders see it (WGSL `Material`).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuMaterial {
    /// Linear base colour factor.
    pub base_color: Vec4,
    /// Emitted radiance.
    pub emissive: [f32; 3],
    /// Perceptual roughness.
    pub roughness: f32,
    /// Metalness.
    pub metallic: f32,
    /// Index in the scene's material list (the G-buffer's material id).
    pub id: u32,
    /// Padding to 16-byte alignment.
    pub _pad: [u32; 2],
}

impl GpuMaterial {
    /// The GPU form of material `id` of a scene.
    pub fn new(m: &scene::Material, id: u32) -> Self {
        Self {
            base_color: m.base_color,
            emissive: m.emissive.to_array(),
            roughness: m.roughness,
            metallic: m.metallic,
            id,
            _pad: [0; 2],
        }
    }
}

/// How a compute kernel binds [`GBufferTextures`] (read with `textureLoad`): linear depth,
/// normal, albedo, material — the order of their bindings in every shading kernel.
pub const GBUFFER_BINDINGS: [Binding; 4] = [
    Binding::TextureUnfilterable,
    Binding::TextureUint,
    Binding::TextureUnfilterable,
    Binding::TextureUint,
];

/// The five G-buffer textures of one resolution (see the layout table in the crate docs).
#[derive(Clone)]
pub struct GBufferTargets {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Hardware depth.
    pub depth: wgpu::Texture,
    /// View-space depth.
    pub linear_depth: wgpu::Texture,
    /// Octahedral normal word.
    pub normal: wgpu::Texture,
    /// Albedo.
    pub albedo: wgpu::Texture,
    /// Material word.
    pub material: wgpu::Texture,
}

impl GBufferTargets {
    /// Creates the targets; they can be rendered to, sampled, bound as storage (colour
    /// targets) and copied.
    pub fn new(device: &wgpu::Device, width: u32, height: u32) -> Result<Self, GpuError> {
        transfer::check_texture_size(device, "G-buffer", width, height)?;
        let make = |label: &str, format: wgpu::TextureFormat, storage: bool| {
            let mut usage = wgpu::TextureUsages::RENDER_ATTACHMENT
                | wgpu::TextureUsages::TEXTURE_BINDING
                | wgpu::TextureUsages::COPY_SRC;
            if storage {
                usage |= wgpu::TextureUsages::STORAGE_BINDING;
            }
            transfer::texture_2d(device, label, width, height, format, usage)
        };
        Ok(Self {
            width,
            height,
            depth: make("gbuffer depth", DEPTH_FORMAT, false),
            linear_depth: make("gbuffer linear depth", LINEAR_DEPTH_FORMAT, true),
            normal: make("gbuffer normal", NORMAL_FORMAT, true),
            albedo: make("gbuffer albedo", ALBEDO_FORMAT, true),
            material: make("gbuffer material", MATERIAL_FORMAT, true),
        })
    }

    /// Total bytes of all targets (for bandwidth figures).
    pub fn bytes(&self) -> u64 {
        u64::from(self.width) * u64::from(self.height) * 20
    }

    /// Reads every target back into a CPU [`GBuffer`].
    pub fn read(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
    ) -> Result<GBuffer, GBufferError> {
        let read = |t: &wgpu::Texture, aspect| transfer::read_texture(device, queue, t, aspect);
        let all = wgpu::TextureAspect::All;
        let img = |bytes: Vec<u8>| -> Result<Image<u32>, GBufferError> {
            Image::from_vec(
                self.width,
                self.height,
                bytemuck::cast_slice(&bytes).to_vec(),
            )
            .map_err(|e| GBufferError::Gpu(GpuError::Readback(e.to_string())))
        };
        let as_f32 = |i: Image<u32>| i.map(f32::from_bits);
        Ok(GBuffer {
            depth: as_f32(img(read(&self.depth, wgpu::TextureAspect::DepthOnly)?)?),
            linear_depth: as_f32(img(read(&self.linear_depth, all)?)?),
            normal: img(read(&self.normal, all)?)?,
            albedo: img(read(&self.albedo, all)?)?.map(u32::to_le_bytes),
            material: img(read(&self.material, all)?)?,
        })
    }
}

/// The G-buffer textures a screen-space pass reads (linear depth, normal, albedo, material),
/// borrowed from [`GBufferTargets`] or from an [`UploadedGBuffer`].
#[derive(Clone, Copy)]
pub struct GBufferTextures<'a> {
    /// `R32Float` view depth (0 where no surface).
    pub linear_depth: &'a wgpu::Texture,
    /// `R32Uint` octahedral normals.
    pub normal: &'a wgpu::Texture,
    /// `Rgba8Unorm` albedo.
    pub albedo: &'a wgpu::Texture,
    /// `R32Uint` material words.
    pub material: &'a wgpu::Texture,
}

impl<'a> From<&'a GBufferTargets> for GBufferTextures<'a> {
    fn from(t: &'a GBufferTargets) -> Self {
        Self {
            linear_depth: &t.linear_depth,
            normal: &t.normal,
            albedo: &t.albedo,
            material: &t.material,
        }
    }
}

/// A CPU [`GBuffer`]'s screen-space textures and its [`Frame`] uniform, uploaded as they are
/// (for running a pass on the same input as its CPU twin).
pub struct UploadedGBuffer {
    /// The frame uniform (`gbuffer/frame.wgsl`).
    pub frame: wgpu::Buffer,
    /// View depth.
    pub linear_depth: wgpu::Texture,
    /// Octahedral normal words.
    pub normal: wgpu::Texture,
    /// Albedo.
    pub albedo: wgpu::Texture,
    /// Material words.
    pub material: wgpu::Texture,
}

impl UploadedGBuffer {
    /// Uploads `frame` and `gb`'s linear depth, normal, albedo and material images (sampled
    /// and copied).
    pub fn new(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        gb: &GBuffer,
        frame: &Frame,
    ) -> Result<Self, GpuError> {
        let usage = wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_SRC;
        let upload = |label: &str, format, bytes: &[u8]| {
            transfer::texture_init(
                device,
                queue,
                label,
                gb.width(),
                gb.height(),
                format,
                usage,
                bytes,
            )
        };
        Ok(Self {
            frame: transfer::buffer_init(
                device,
                "frame",
                bytemuck::bytes_of(frame),
                wgpu::BufferUsages::UNIFORM,
            )?,
            linear_depth: upload(
                "linear depth",
                LINEAR_DEPTH_FORMAT,
                bytemuck::cast_slice(gb.linear_depth.pixels()),
            )?,
            normal: upload(
                "normal",
                NORMAL_FORMAT,
                bytemuck::cast_slice(gb.normal.pixels()),
            )?,
            albedo: upload(
                "albedo",
                ALBEDO_FORMAT,
                bytemuck::cast_slice(gb.albedo.pixels()),
            )?,
            material: upload(
                "material",
                MATERIAL_FORMAT,
                bytemuck::cast_slice(gb.material.pixels()),
            )?,
        })
    }

    /// The textures to bind.
    pub fn textures(&self) -> GBufferTextures<'_> {
        GBufferTextures {
            linear_depth: &self.linear_depth,
            normal: &self.normal,
            albedo: &self.albedo,
            material: &self.material,
        }
    }
}

struct Draw {
    first_index: u32,
    index_count: u32,
    base_vertex: i32,
    material: usize,
}

/// A scene uploaded for the G-buffer pass: one vertex and one index buffer, a bind group per
/// material, and the materials as a storage buffer for later passes.
pub struct GpuScene {
    vertices: wgpu::Buffer,
    indices: wgpu::Buffer,
    draws: Vec<Draw>,
    material_groups: Vec<wgpu::BindGroup>,
    /// All materials ([`GpuMaterial`]), indexed by material id.
    pub materials: wgpu::Buffer,
    /// Number of triangles.
    pub triangle_count: u64,
}

impl GpuScene {
    /// Uploads `scene` (textures as `Rgba8UnormSrgb`, mip 0) for `pass`.
    pub fn upload(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        scene: &Scene,
        pass: &GBufferPass,
    ) -> Result<Self, GBufferError> {
        crate::validate_scene(scene)?;
        let mut vertices = Vec::new();
        let mut indices = Vec::new();
        let mut draws = Vec::new();
        for m in &scene.meshes {
            draws.push(Draw {
                first_index: indices.len() as u32,
                index_count: m.indices.len() as u32,
                base_vertex: vertices.len() as i32,
                material: m.material as usize,
            });
            indices.extend_from_slice(&m.indices);
            vertices.extend(
                m.positions
                    .iter()
                    .zip(&m.normals)
                    .zip(&m.uvs)
                    .map(|((p, n), uv)| GpuVertex {
                        position: p.to_array(),
                        normal: n.to_array(),
                        uv: uv.to_array(),
                    }),
            );
        }
        let vertices = transfer::buffer_init(
            device,
            "scene vertices",
            bytemuck::cast_slice(&vertices),
            wgpu::BufferUsages::VERTEX,
        )?;
        let indices = transfer::buffer_init(
            device,
            "scene indices",
            bytemuck::cast_slice(&indices),
            wgpu::BufferUsages::INDEX,
        )?;

        let white = scene::Texture {
            name: "white".into(),
            width: 1,
            height: 1,
            rgba8: vec![255; 4],
        };
        let textures = scene
            .textures
            .iter()
            .map(|t| upload_texture(device, queue, t))
            .collect::<Result<Vec<_>, _>>()?;
        let white = upload_texture(device, queue, &white)?;
        let gpu_materials: Vec<GpuMaterial> = scene
            .materials
            .iter()
            .enumerate()
            .map(|(i, m)| GpuMaterial::new(m, i as u32))
            .collect();
        let material_groups = scene
            .materials
            .iter()
            .zip(&gpu_materials)
            .map(|(m, g)| {
                let uniform = transfer::buffer_init(
                    device,
                    "material",
                    bytemuck::bytes_of(g),
                    wgpu::BufferUsages::UNIFORM,
                )?;
                let texture = m
                    .base_color_texture
                    .map_or(&white, |t| &textures[t as usize]);
                let view = texture.create_view(&Default::default());
                Ok(pass.material_layout.bind(
                    device,
                    &[
                        uniform.as_entire_binding(),
                        wgpu::BindingResource::TextureView(&view),
                        wgpu::BindingResource::Sampler(&pass.sampler),
                    ],
                ))
            })
            .collect::<Result<Vec<_>, GpuError>>()?;
        let materials = transfer::buffer_init(
            device,
            "materials",
            bytemuck::cast_slice(&gpu_materials),
            wgpu::BufferUsages::STORAGE,
        )?;
        Ok(Self {
            vertices,
            indices,
            draws,
            material_groups,
            materials,
            triangle_count: scene.triangle_count() as u64,
        })
    }
}

fn upload_texture(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    t: &scene::Texture,
) -> Result<wgpu::Texture, GpuError> {
    transfer::check_texture_size(device, &format!("texture {:?}", t.name), t.width, t.height)?;
    transfer::texture_init(
        device,
        queue,
        &t.name,
        t.width,
        t.height,
        wgpu::TextureFormat::Rgba8UnormSrgb,
        wgpu::TextureUsages::TEXTURE_BINDING,
        &t.rgba8,
    )
}

/// The G-buffer pass: pipeline and frame uniforms, built once.
pub struct GBufferPass {
    pipeline: wgpu::RenderPipeline,
    prepass: wgpu::RenderPipeline,
    after_prepass: wgpu::RenderPipeline,
    frame_layout: Layout,
    material_layout: Layout,
    sampler: wgpu::Sampler,
    frame: wgpu::Buffer,
    frame_group: wgpu::BindGroup,
}

impl GBufferPass {
    /// Builds the pipeline.
    pub fn new(device: &wgpu::Device) -> Result<Self, GpuError> {
        let module = crate::SHADERS.module(device, "gbuffer.wgsl")?;
        let frame_layout = Layout::new(
            device,
            "gbuffer frame",
            wgpu::ShaderStages::VERTEX_FRAGMENT,
            &[Binding::Uniform],
        );
        let material_layout = Layout::new(
            device,
            "gbuffer material",
            wgpu::ShaderStages::FRAGMENT,
            &[Binding::Uniform, Binding::Texture, Binding::Sampler],
        );
        let layout = kernel::pipeline_layout(device, "gbuffer", &[&frame_layout, &material_layout]);
        let depth_layout = kernel::pipeline_layout(device, "gbuffer z-prepass", &[&frame_layout]);
        let targets = [
            LINEAR_DEPTH_FORMAT,
            NORMAL_FORMAT,
            ALBEDO_FORMAT,
            MATERIAL_FORMAT,
        ];
        // One pipeline shape, three uses: single-pass G-buffer (depth Less, write), z-prepass
        // (depth only), and the G-buffer after a prepass (depth Equal, no write).
        let make = |label, compare, write, fragment: bool| {
            let stages = if fragment {
                ("vs_main", Some(("fs_main", &targets[..])))
            } else {
                ("vs_depth", None)
            };
            let layout = if fragment { &layout } else { &depth_layout };
            scene_pipeline(device, label, layout, &module, stages, (compare, write))
        };
        let pipeline = make("gbuffer", wgpu::CompareFunction::Less, true, true);
        let prepass = make(
            "gbuffer z-prepass",
            wgpu::CompareFunction::Less,
            true,
            false,
        );
        let after_prepass = make(
            "gbuffer after z-prepass",
            wgpu::CompareFunction::Equal,
            false,
            true,
        );
        let sampler = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("base colour"),
            address_mode_u: wgpu::AddressMode::Repeat,
            address_mode_v: wgpu::AddressMode::Repeat,
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            ..Default::default()
        });
        let frame = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("frame"),
            size: size_of::<Frame>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let frame_group = frame_layout.bind_buffers(device, &[&frame]);
        Ok(Self {
            pipeline,
            prepass,
            after_prepass,
            frame_layout,
            material_layout,
            sampler,
            frame,
            frame_group,
        })
    }

    /// The bind group layouts of the frame uniform (group 0) and of a material (group 1), for
    /// pipelines that draw the same [`GpuScene`] with another fragment stage
    /// ([`GBufferPass::draw_scene`]).
    pub fn layouts(&self) -> [&Layout; 2] {
        [&self.frame_layout, &self.material_layout]
    }

    /// Draws `scene` with `pipeline` (built on [`GBufferPass::layouts`] and
    /// [`GBufferPass::vertex_attributes`]) into an open render pass, binding this pass's frame
    /// uniform and each draw's material.
    pub fn draw_scene(
        &self,
        pass: &mut wgpu::RenderPass<'_>,
        pipeline: &wgpu::RenderPipeline,
        scene: &GpuScene,
    ) {
        self.draw(pass, pipeline, scene, true);
    }

    /// The uniform buffer holding the [`Frame`]; later screen-space passes bind it too.
    pub fn frame_buffer(&self) -> &wgpu::Buffer {
        &self.frame
    }

    /// Writes the camera for the next [`GBufferPass::encode`].
    pub fn write_frame(&self, queue: &wgpu::Queue, frame: &Frame) {
        queue.write_buffer(&self.frame, 0, bytemuck::bytes_of(frame));
    }

    /// Records the G-buffer pass: clears every target and draws the scene.
    pub fn encode(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        scene: &GpuScene,
        targets: &GBufferTargets,
        timestamp_writes: Option<wgpu::RenderPassTimestampWrites<'_>>,
    ) {
        let mut pass = Self::begin(encoder, targets, "gbuffer", true, true, timestamp_writes);
        self.draw(&mut pass, &self.pipeline, scene, true);
    }

    /// Records a z-prepass (depth only, Holländer 2013 §4.2) and then the G-buffer pass with
    /// depth test `Equal`, so each pixel runs the G-buffer fragment shader once. The result
    /// equals [`GBufferPass::encode`]'s except where two surfaces have exactly equal depth
    /// (there the last drawn wins instead of the first).
    pub fn encode_with_prepass(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        scene: &GpuScene,
        targets: &GBufferTargets,
        prepass_timestamps: Option<wgpu::RenderPassTimestampWrites<'_>>,
        gbuffer_timestamps: Option<wgpu::RenderPassTimestampWrites<'_>>,
    ) {
        let mut pass = Self::begin(
            encoder,
            targets,
            "gbuffer z-prepass",
            false,
            true,
            prepass_timestamps,
        );
        self.draw(&mut pass, &self.prepass, scene, false);
        drop(pass);
        let mut pass = Self::begin(
            encoder,
            targets,
            "gbuffer after z-prepass",
            true,
            false,
            gbuffer_timestamps,
        );
        self.draw(&mut pass, &self.after_prepass, scene, true);
    }

    fn draw(
        &self,
        pass: &mut wgpu::RenderPass<'_>,
        pipeline: &wgpu::RenderPipeline,
        scene: &GpuScene,
        materials: bool,
    ) {
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, &self.frame_group, &[]);
        pass.set_vertex_buffer(0, scene.vertices.slice(..));
        pass.set_index_buffer(scene.indices.slice(..), wgpu::IndexFormat::Uint32);
        for d in &scene.draws {
            if materials {
                pass.set_bind_group(1, &scene.material_groups[d.material], &[]);
            }
            pass.draw_indexed(
                d.first_index..d.first_index + d.index_count,
                d.base_vertex,
                0..1,
            );
        }
    }

    /// Records a pass that only clears and stores every target: the write-bandwidth
    /// baseline the benchmark compares the G-buffer pass against.
    pub fn encode_clear(
        encoder: &mut wgpu::CommandEncoder,
        targets: &GBufferTargets,
        timestamp_writes: Option<wgpu::RenderPassTimestampWrites<'_>>,
    ) {
        drop(Self::begin(
            encoder,
            targets,
            "gbuffer clear",
            true,
            true,
            timestamp_writes,
        ));
    }

    /// Begins a render pass over the depth target and, with `color`, the colour targets
    /// (cleared); `clear_depth` clears depth, else it is loaded.
    fn begin<'e>(
        encoder: &'e mut wgpu::CommandEncoder,
        targets: &GBufferTargets,
        label: &str,
        color: bool,
        clear_depth: bool,
        timestamp_writes: Option<wgpu::RenderPassTimestampWrites<'_>>,
    ) -> wgpu::RenderPass<'e> {
        let colour = [
            (&targets.linear_depth, 0.0),
            (&targets.normal, 0.0),
            (&targets.albedo, 0.0),
            (&targets.material, f64::from(NO_MATERIAL)),
        ];
        let colour = if color { &colour[..] } else { &[] };
        let depth = (&targets.depth, clear_depth);
        begin_scene_pass(encoder, label, colour, depth, timestamp_writes)
    }
}

/// Begins a render pass over `colour` targets, each cleared to its value (red channel; the
/// G-buffer's material target clears to [`NO_MATERIAL`]), and `depth` = (depth target,
/// cleared to 1 or else loaded).
pub fn begin_scene_pass<'e>(
    encoder: &'e mut wgpu::CommandEncoder,
    label: &str,
    colour: &[(&wgpu::Texture, f64)],
    (depth, clear_depth): (&wgpu::Texture, bool),
    timestamp_writes: Option<wgpu::RenderPassTimestampWrites<'_>>,
) -> wgpu::RenderPass<'e> {
    let views: Vec<_> = colour
        .iter()
        .map(|(t, clear)| (t.create_view(&Default::default()), *clear))
        .collect();
    let attachments: Vec<_> = views
        .iter()
        .map(|(view, r)| {
            Some(wgpu::RenderPassColorAttachment {
                view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color {
                        r: *r,
                        ..wgpu::Color::TRANSPARENT
                    }),
                    store: wgpu::StoreOp::Store,
                },
            })
        })
        .collect();
    let depth_view = depth.create_view(&Default::default());
    encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some(label),
        color_attachments: &attachments,
        depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
            view: &depth_view,
            depth_ops: Some(wgpu::Operations {
                load: if clear_depth {
                    wgpu::LoadOp::Clear(1.0)
                } else {
                    wgpu::LoadOp::Load
                },
                store: wgpu::StoreOp::Store,
            }),
            stencil_ops: None,
        }),
        timestamp_writes,
        occlusion_query_set: None,
        multiview_mask: None,
    })
}

/// Convenience for tests and examples: uploads `scene`, renders its G-buffer on `gpu` and
/// reads it back.
pub fn run(
    gpu: &Gpu,
    scene: &Scene,
    camera: &Camera,
    width: u32,
    height: u32,
) -> Result<GBuffer, GBufferError> {
    run_with(gpu, scene, camera, width, height, false)
}

/// Like [`run`]; with `prepass`, through [`GBufferPass::encode_with_prepass`].
pub fn run_with(
    gpu: &Gpu,
    scene: &Scene,
    camera: &Camera,
    width: u32,
    height: u32,
    prepass: bool,
) -> Result<GBuffer, GBufferError> {
    crate::validate_size(width, height)?;
    crate::validate_camera(camera)?;
    let pass = GBufferPass::new(&gpu.device)?;
    let gpu_scene = GpuScene::upload(&gpu.device, &gpu.queue, scene, &pass)?;
    let targets = GBufferTargets::new(&gpu.device, width, height)?;
    pass.write_frame(&gpu.queue, &Frame::new(camera, width, height));
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    if prepass {
        pass.encode_with_prepass(&mut encoder, &gpu_scene, &targets, None, None);
    } else {
        pass.encode(&mut encoder, &gpu_scene, &targets, None);
    }
    gpu.queue.submit([encoder.finish()]);
    targets.read(&gpu.device, &gpu.queue)
}

/// A render pipeline drawing an uploaded [`GpuScene`] into the G-buffer's depth target:
/// `stages` = (vertex entry, optional (fragment entry, colour target formats)) of `module`,
/// `depth` = (compare, write). With a fragment stage the vertex stage reads every
/// [`GpuVertex`] attribute (`vs_main`), without one only the position (a depth-only pass).
pub fn scene_pipeline(
    device: &wgpu::Device,
    label: &str,
    layout: &wgpu::PipelineLayout,
    module: &wgpu::ShaderModule,
    (vertex, fragment): (&str, Option<(&str, &[wgpu::TextureFormat])>),
    (compare, write): (wgpu::CompareFunction, bool),
) -> wgpu::RenderPipeline {
    let attributes = wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3, 2 => Float32x2];
    let used = if fragment.is_some() {
        &attributes[..]
    } else {
        &attributes[..1]
    };
    let targets: Vec<Option<wgpu::ColorTargetState>> = fragment
        .map_or(&[][..], |(_, formats)| formats)
        .iter()
        .map(|&format| Some(format.into()))
        .collect();
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(label),
        layout: Some(layout),
        vertex: wgpu::VertexState {
            module,
            entry_point: Some(vertex),
            compilation_options: Default::default(),
            buffers: &[Some(wgpu::VertexBufferLayout {
                array_stride: size_of::<GpuVertex>() as u64,
                step_mode: wgpu::VertexStepMode::Vertex,
                attributes: used,
            })],
        },
        primitive: wgpu::PrimitiveState {
            cull_mode: None,
            ..Default::default()
        },
        depth_stencil: Some(wgpu::DepthStencilState {
            format: DEPTH_FORMAT,
            depth_write_enabled: Some(write),
            depth_compare: Some(compare),
            stencil: Default::default(),
            bias: Default::default(),
        }),
        multisample: Default::default(),
        fragment: fragment.map(|(entry, _)| wgpu::FragmentState {
            module,
            entry_point: Some(entry),
            compilation_options: Default::default(),
            targets: &targets,
        }),
        multiview_mask: None,
        cache: None,
    })
}
