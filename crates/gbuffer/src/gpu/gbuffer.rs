//! The G-buffer pass (`shaders/gbuffer/gbuffer.wgsl`): a render pipeline writing every target
//! at once (MRT), optionally after a z-prepass; the twin of [`crate::cpu::rasterize`].

use ::gpu::GpuError;
use ::gpu::kernel::{self, Binding, Layout};

use super::upload::{BlendedSurfaces, Draw, DrawState};
use super::{GBufferTargets, GpuAttributes, GpuScene};
use crate::{
    ALBEDO_FORMAT, DEPTH_FORMAT, EMISSION_FORMAT, Frame, LINEAR_DEPTH_FORMAT, MATERIAL_FORMAT,
    NO_MATERIAL, NORMAL_FORMAT,
};

/// A pipeline per face culling: two-sided materials draw every face, one-sided ones cull
/// back faces (glTF `doubleSided`).
struct BySides {
    two_sided: wgpu::RenderPipeline,
    one_sided: wgpu::RenderPipeline,
}

impl BySides {
    fn get(&self, cull: bool) -> &wgpu::RenderPipeline {
        if cull {
            &self.one_sided
        } else {
            &self.two_sided
        }
    }
}

/// The G-buffer pass: pipelines and frame uniforms, built once.
pub struct GBufferPass {
    single: BySides,
    prepass: BySides,
    /// The z-prepass of alpha-tested materials (`fs_alpha_depth`).
    alpha_prepass: BySides,
    after_prepass: BySides,
    frame_layout: Layout,
    pub(super) material_layout: Layout,
    frame: FrameUniform,
}

/// A [`Frame`] uniform buffer and its bind group for [`GBufferPass`]'s pipelines: the pass
/// holds one ([`GBufferPass::frame_buffer`]); [`GBufferPass::frame_uniform`] makes more, to
/// draw the same scene at another size in the same encoder (e.g. a supersampled G-buffer).
pub struct FrameUniform {
    buffer: wgpu::Buffer,
    group: wgpu::BindGroup,
}

impl FrameUniform {
    fn new(device: &wgpu::Device, layout: &Layout) -> Self {
        let buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("frame"),
            size: size_of::<Frame>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let group = layout.bind_buffers(device, &[&buffer]);
        Self { buffer, group }
    }

    /// The uniform buffer; screen-space passes of the same size bind it too.
    pub fn buffer(&self) -> &wgpu::Buffer {
        &self.buffer
    }

    /// Writes `frame`.
    pub fn write(&self, queue: &wgpu::Queue, frame: &Frame) {
        queue.write_buffer(&self.buffer, 0, bytemuck::bytes_of(frame));
    }
}

impl GBufferPass {
    /// Builds the pipelines.
    pub fn new(device: &wgpu::Device) -> Result<Self, GpuError> {
        let module = crate::SHADERS.module(device, "gbuffer.wgsl")?;
        let frame_layout = Layout::new(
            device,
            "gbuffer frame",
            wgpu::ShaderStages::VERTEX_FRAGMENT,
            &[Binding::Uniform],
        );
        let mut material = vec![Binding::Uniform];
        for _ in 0..5 {
            material.extend([Binding::Texture, Binding::Sampler]);
        }
        // Compute too: the visibility buffer's resolve evaluates the materials.
        let material_layout = Layout::new(
            device,
            "gbuffer material",
            wgpu::ShaderStages::FRAGMENT | wgpu::ShaderStages::COMPUTE,
            &material,
        );
        let layout = kernel::pipeline_layout(device, "gbuffer", &[&frame_layout, &material_layout]);
        let targets = [
            LINEAR_DEPTH_FORMAT,
            NORMAL_FORMAT,
            ALBEDO_FORMAT,
            MATERIAL_FORMAT,
            EMISSION_FORMAT,
        ];
        // One pipeline shape, four uses: single-pass G-buffer (depth Less, write), z-prepass
        // (depth only, or alpha-tested), and the G-buffer after a prepass (depth Equal, no
        // write); each for two-sided and one-sided materials.
        let make =
            |label: &str, compare, write, fragment: Option<(&str, &[wgpu::TextureFormat])>| {
                let vertex = if fragment.is_some() {
                    "vs_main"
                } else {
                    "vs_depth"
                };
                let pipeline = |cull| {
                    scene_pipeline(
                        device,
                        label,
                        &layout,
                        &module,
                        (vertex, fragment),
                        (compare, write),
                        cull,
                    )
                };
                BySides {
                    two_sided: pipeline(false),
                    one_sided: pipeline(true),
                }
            };
        use wgpu::CompareFunction::{Equal, Less};
        let single = make("gbuffer", Less, true, Some(("fs_main", &targets[..])));
        let prepass = make("gbuffer z-prepass", Less, true, None);
        let alpha_prepass = make(
            "gbuffer z-prepass (alpha)",
            Less,
            true,
            Some(("fs_alpha_depth", &[][..])),
        );
        let after_prepass = make(
            "gbuffer after z-prepass",
            Equal,
            false,
            Some(("fs_main", &targets[..])),
        );
        let frame = FrameUniform::new(device, &frame_layout);
        Ok(Self {
            single,
            prepass,
            alpha_prepass,
            after_prepass,
            frame_layout,
            material_layout,
            frame,
        })
    }

    /// The bind group layouts of the frame uniform (group 0) and of a material (group 1), for
    /// pipelines that draw the same [`GpuScene`] with another fragment stage
    /// ([`GBufferPass::draw_scene`]).
    pub fn layouts(&self) -> [&Layout; 2] {
        [&self.frame_layout, &self.material_layout]
    }

    /// Draws `scene` into an open render pass with `pipelines` = [two-sided, one-sided]
    /// (built on [`GBufferPass::layouts`], the one-sided with back faces culled, as
    /// [`scene_pipeline`] builds them), each draw with the one its material's `doubleSided`
    /// picks, binding this pass's frame uniform and each draw's material.
    pub fn draw_scene(
        &self,
        pass: &mut wgpu::RenderPass<'_>,
        pipelines: [&wgpu::RenderPipeline; 2],
        scene: &GpuScene,
    ) {
        self.draw(pass, &self.frame, scene, |s| pipelines[usize::from(s.cull)]);
    }

    /// Draws only `scene`'s alpha-blended meshes (whatever [`GpuScene::blended`] says), back
    /// to front: by the distance from `eye` to the centre of each mesh's bounding box at
    /// upload (an order per mesh, not per triangle), with `pipelines` as
    /// [`GBufferPass::draw_scene`] takes them.
    pub fn draw_blended(
        &self,
        pass: &mut wgpu::RenderPass<'_>,
        pipelines: [&wgpu::RenderPipeline; 2],
        scene: &GpuScene,
        eye: glam::Vec3,
    ) {
        let mut order: Vec<&Draw> = scene.draws.iter().filter(|d| d.state.blended).collect();
        order.sort_by(|a, b| {
            eye.distance_squared(b.center())
                .total_cmp(&eye.distance_squared(a.center()))
        });
        self.draw_each(pass, &self.frame, scene, order, |s| {
            pipelines[usize::from(s.cull)]
        });
    }

    /// The uniform buffer holding the [`Frame`]; later screen-space passes bind it too.
    pub fn frame_buffer(&self) -> &wgpu::Buffer {
        &self.frame.buffer
    }

    /// Another frame uniform for this pass's pipelines ([`GBufferPass::encode_with_prepass_at`]).
    pub fn frame_uniform(&self, device: &wgpu::Device) -> FrameUniform {
        FrameUniform::new(device, &self.frame_layout)
    }

    /// Writes the camera for the next [`GBufferPass::encode`].
    pub fn write_frame(&self, queue: &wgpu::Queue, frame: &Frame) {
        self.frame.write(queue, frame);
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
        self.draw(&mut pass, &self.frame, scene, |s| self.single.get(s.cull));
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
        let timestamps = (prepass_timestamps, gbuffer_timestamps);
        self.encode_with_prepass_at(encoder, &self.frame, scene, targets, timestamps);
    }

    /// [`GBufferPass::encode_with_prepass`] with the camera of `frame` (a
    /// [`GBufferPass::frame_uniform`] of `targets`' size) and the (z-prepass, G-buffer) timestamps.
    pub fn encode_with_prepass_at(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        frame: &FrameUniform,
        scene: &GpuScene,
        targets: &GBufferTargets,
        (prepass_timestamps, gbuffer_timestamps): (
            Option<wgpu::RenderPassTimestampWrites<'_>>,
            Option<wgpu::RenderPassTimestampWrites<'_>>,
        ),
    ) {
        let mut pass = Self::begin(
            encoder,
            targets,
            "gbuffer z-prepass",
            false,
            true,
            prepass_timestamps,
        );
        self.draw(&mut pass, frame, scene, |s| {
            if s.alpha_tested {
                self.alpha_prepass.get(s.cull)
            } else {
                self.prepass.get(s.cull)
            }
        });
        drop(pass);
        let mut pass = Self::begin(
            encoder,
            targets,
            "gbuffer after z-prepass",
            true,
            false,
            gbuffer_timestamps,
        );
        self.draw(&mut pass, frame, scene, |s| self.after_prepass.get(s.cull));
    }

    /// Draws every draw of `scene` (but the blended ones when it draws them forward) with the
    /// pipeline `pick` chooses for its state, binding `frame` and each draw's material.
    fn draw<'p>(
        &self,
        pass: &mut wgpu::RenderPass<'_>,
        frame: &FrameUniform,
        scene: &GpuScene,
        pick: impl Fn(DrawState) -> &'p wgpu::RenderPipeline,
    ) {
        let forward = scene.blended == BlendedSurfaces::Forward;
        let draws = scene.draws.iter().filter(|d| !(forward && d.state.blended));
        self.draw_each(pass, frame, scene, draws, pick);
    }

    /// Draws `draws` of `scene` in order.
    fn draw_each<'d, 'p>(
        &self,
        pass: &mut wgpu::RenderPass<'_>,
        frame: &FrameUniform,
        scene: &GpuScene,
        draws: impl IntoIterator<Item = &'d Draw>,
        pick: impl Fn(DrawState) -> &'p wgpu::RenderPipeline,
    ) {
        pass.set_bind_group(0, &frame.group, &[]);
        pass.set_vertex_buffer(0, scene.positions.slice(..));
        pass.set_vertex_buffer(1, scene.attributes.slice(..));
        pass.set_index_buffer(scene.indices.slice(..), wgpu::IndexFormat::Uint32);
        let mut bound: Option<&wgpu::RenderPipeline> = None;
        for d in draws {
            let pipeline = pick(d.state);
            if !bound.is_some_and(|b| std::ptr::eq(b, pipeline)) {
                pass.set_pipeline(pipeline);
                bound = Some(pipeline);
            }
            pass.set_bind_group(1, &scene.material_groups[d.material], &[]);
            match &d.indirect {
                Some(args) if d.index_count > 0 => pass.draw_indexed_indirect(args, 0),
                _ => pass.draw_indexed(
                    d.first_index..d.first_index + d.index_count,
                    d.base_vertex,
                    0..1,
                ),
            }
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
            (&targets.emission, 0.0),
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

/// A render pipeline drawing an uploaded [`GpuScene`] into the G-buffer's depth target:
/// `stages` = (vertex entry, optional (fragment entry, colour target formats)) of `module`,
/// `depth` = (compare, write), back faces culled where `cull_back`. With a fragment stage the
/// vertex stage reads the positions (slot 0) and every [`GpuAttributes`] (slot 1, `vs_main`),
/// without one only the positions (a depth-only pass).
pub fn scene_pipeline(
    device: &wgpu::Device,
    label: &str,
    layout: &wgpu::PipelineLayout,
    module: &wgpu::ShaderModule,
    (vertex, fragment): (&str, Option<(&str, &[wgpu::TextureFormat])>),
    depth: (wgpu::CompareFunction, bool),
    cull_back: bool,
) -> wgpu::RenderPipeline {
    let targets: Vec<Option<wgpu::ColorTargetState>> = fragment
        .map_or(&[][..], |(_, formats)| formats)
        .iter()
        .map(|&format| Some(format.into()))
        .collect();
    let fragment = fragment.map(|(entry, _)| (entry, &targets[..]));
    scene_pipeline_with(
        device,
        label,
        layout,
        module,
        (vertex, fragment),
        depth,
        cull_back,
    )
}

/// A fragment stage of [`scene_pipelines`]: its entry point and colour target states.
pub type FragmentTargets<'a> = (&'a str, &'a [Option<wgpu::ColorTargetState>]);

/// [`scene_pipeline`] for both sides, with the fragment stage's colour target states (blending,
/// write masks): [two-sided, one-sided], as [`GBufferPass::draw_scene`] takes them.
pub fn scene_pipelines(
    device: &wgpu::Device,
    label: &str,
    layout: &wgpu::PipelineLayout,
    module: &wgpu::ShaderModule,
    stages: (&str, Option<FragmentTargets<'_>>),
    depth: (wgpu::CompareFunction, bool),
) -> [wgpu::RenderPipeline; 2] {
    [false, true]
        .map(|cull| scene_pipeline_with(device, label, layout, module, stages, depth, cull))
}

/// [`scene_pipeline`] with the fragment stage's colour target states.
fn scene_pipeline_with(
    device: &wgpu::Device,
    label: &str,
    layout: &wgpu::PipelineLayout,
    module: &wgpu::ShaderModule,
    (vertex, fragment): (&str, Option<FragmentTargets<'_>>),
    (compare, write): (wgpu::CompareFunction, bool),
    cull_back: bool,
) -> wgpu::RenderPipeline {
    let position = wgpu::vertex_attr_array![0 => Float32x3];
    let attributes = wgpu::vertex_attr_array![
        1 => Float32x3, 2 => Float32x2, 3 => Float32x2, 4 => Float32x4, 5 => Float32x4
    ];
    let mut buffers = vec![Some(wgpu::VertexBufferLayout {
        array_stride: 12,
        step_mode: wgpu::VertexStepMode::Vertex,
        attributes: &position,
    })];
    if fragment.is_some() {
        buffers.push(Some(wgpu::VertexBufferLayout {
            array_stride: size_of::<GpuAttributes>() as u64,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &attributes,
        }));
    }
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(label),
        layout: Some(layout),
        vertex: wgpu::VertexState {
            module,
            entry_point: Some(vertex),
            compilation_options: Default::default(),
            buffers: &buffers,
        },
        primitive: wgpu::PrimitiveState {
            // glTF's front faces wind counter-clockwise.
            front_face: wgpu::FrontFace::Ccw,
            cull_mode: cull_back.then_some(wgpu::Face::Back),
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
        fragment: fragment.map(|(entry, targets)| wgpu::FragmentState {
            module,
            entry_point: Some(entry),
            compilation_options: Default::default(),
            targets,
        }),
        multiview_mask: None,
        cache: None,
    })
}
