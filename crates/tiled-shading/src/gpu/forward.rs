//! Forward+ ([`Method::ForwardPlus`], thesis §2.4.2 after Harada et al. 2012): the culling pass
//! of `tiled.wgsl` keeps every tile's list in memory ([`LightShading::bind`] sizes them with
//! [`list_stride`]); `forward.wgsl` then draws the scene's geometry with the G-buffer pass's
//! vertex stage and materials, each fragment lit from its tile's list:
//! [`ForwardPass::encode_opaque`] after the depth pre-pass (depth test `Equal`, one fragment per
//! pixel) into the light accumulation, and [`ForwardPass::encode_blended`] the alpha-blended
//! meshes back to front over the composed frame (`SrcAlpha, OneMinusSrcAlpha`, depth-tested
//! against the opaque surfaces, not written) — the renderer's transparency.
//!
//! ```no_run
//! use tiled_shading::{Method, ShadingConfig, gpu::{LightShading, forward::ForwardPass}};
//! # fn frame(device: &wgpu::Device, gbuffer: &gbuffer::gpu::GBufferPass,
//! #     scene: &gbuffer::gpu::GpuScene, targets: &gbuffer::gpu::GBufferTargets,
//! #     outputs: [&wgpu::Texture; 2], ambient: &wgpu::Buffer) -> Result<(), tiled_shading::ShadingError> {
//! let config = ShadingConfig { method: Method::ForwardPlus, ..Default::default() };
//! let cull = LightShading::new(device, &config)?;
//! let lists = cull.bind(device, gbuffer.frame_buffer(), targets.into(), outputs, 1024, false)?;
//! let forward = ForwardPass::new(device, gbuffer, &config)?;
//! let bound = forward.bind(device, &lists, ambient)?;
//! let mut encoder = device.create_command_encoder(&Default::default());
//! // … the z-prepass and G-buffer pass into `targets`, then:
//! cull.encode(&lists, &mut encoder, None);
//! forward.encode_opaque(&bound, &mut encoder, (gbuffer, scene), &targets.depth, outputs, None);
//! # Ok(()) }
//! ```

use ::gpu::kernel::{self, Binding, Layout};
use ::gpu::shader::Specialisation;
use ::gpu::{DeviceNeeds, PassTimer};
use gbuffer::gpu::{GBufferPass, GpuScene, scene_pipelines};
use glam::Vec3;

use super::shadows::{self, ShadowInputs};
use super::{ACCUMULATION_FORMAT, BoundShading};
use crate::{Method, ShadingConfig, ShadingError};

/// List entries per tile for `capacity` lights over `tiles` tiles: every light where the
/// device's largest storage binding holds them (8 bytes an entry), else as many as it holds.
/// A tile that meets more lights is shaded from the first this many (its count in the
/// heatmap still says how many met it).
pub fn list_stride(device: &wgpu::Device, tiles: u64, capacity: usize) -> u64 {
    let limits = device.limits();
    let binding = limits
        .max_storage_buffer_binding_size
        .min(limits.max_buffer_size);
    (capacity as u64).min(binding / (tiles.max(1) * 8)).max(1)
}

/// The compile-time constants of `forward.wgsl` for tiles of `tile_size` pixels: the shadow
/// lookup (and its rays) at group 3, after the G-buffer pass's frame, material and the lists.
pub fn specialisation(tile_size: u32) -> Specialisation {
    Specialisation::default()
        .set("TILE", format!("{tile_size}u"))
        .set("SHADOW_GROUP", "3u")
        .set("RAY_GROUP", "3u")
}

/// The Forward+ geometry passes for one tile size: built once on a [`GBufferPass`]'s layouts.
pub struct ForwardPass {
    /// [two-sided, one-sided] pipelines of `fs_forward`.
    opaque: [wgpu::RenderPipeline; 2],
    /// [two-sided, one-sided] pipelines of `fs_blended` (`None` without `FLOAT32_BLENDABLE`).
    blended: Option<[wgpu::RenderPipeline; 2]>,
    lists_layout: Layout,
    shadow_layout: Layout,
}

/// A [`ForwardPass`] bound to a Forward+ culling pass's lists and shadow lookup.
pub struct BoundForward {
    lists: wgpu::BindGroup,
    shadows: wgpu::BindGroup,
}

/// The blending of [`ForwardPass::encode_blended`]: colour over the frame by the surface's
/// alpha; the frame's alpha (its coverage) kept where the surface adds none.
const OVER: wgpu::BlendState = wgpu::BlendState {
    color: wgpu::BlendComponent {
        src_factor: wgpu::BlendFactor::SrcAlpha,
        dst_factor: wgpu::BlendFactor::OneMinusSrcAlpha,
        operation: wgpu::BlendOperation::Add,
    },
    alpha: wgpu::BlendComponent {
        src_factor: wgpu::BlendFactor::One,
        dst_factor: wgpu::BlendFactor::OneMinusSrcAlpha,
        operation: wgpu::BlendOperation::Add,
    },
};

impl ForwardPass {
    /// Builds the pipelines for `config`'s tile size (which must be [`Method::ForwardPlus`]'s,
    /// the culling pass's) on `gbuffer`'s frame and material layouts. The blended pipelines
    /// need `FLOAT32_BLENDABLE` (blending into the `Rgba32Float` frame); without it only
    /// [`ForwardPass::encode_opaque`] works ([`ForwardPass::blends`]).
    pub fn new(
        device: &wgpu::Device,
        gbuffer: &GBufferPass,
        config: &ShadingConfig,
    ) -> Result<Self, ShadingError> {
        config.validate()?;
        if config.method != Method::ForwardPlus {
            return Err(ShadingError::Incompatible(format!(
                "Forward+: the forward pass reads Forward+ lists, not {} ones",
                config.method
            )));
        }
        let spec = specialisation(config.tile_size);
        let module = crate::SHADERS.module_with(device, "forward.wgsl", &spec)?;
        let stages = wgpu::ShaderStages::FRAGMENT;
        // Params, lights, counts, lists, ambient.
        let lists_layout = Layout::new(
            device,
            "forward+ lists",
            stages,
            &[
                Binding::Uniform,
                Binding::StorageRead,
                Binding::StorageRead,
                Binding::StorageRead,
                Binding::Uniform,
            ],
        );
        let shadow_layout = Layout::new(
            device,
            "forward+ shadow lookup",
            stages,
            &shadows::LOOKUP_BINDINGS,
        );
        let [frame, material] = gbuffer.layouts();
        let layout = kernel::pipeline_layout(
            device,
            "forward+",
            &[frame, material, &lists_layout, &shadow_layout],
        );
        let pipelines = |label, entry, targets: &[Option<wgpu::ColorTargetState>], depth| {
            let stages = ("vs_main", Some((entry, targets)));
            scene_pipelines(device, label, &layout, &module, stages, depth)
        };
        let accumulation = Some(wgpu::ColorTargetState::from(ACCUMULATION_FORMAT));
        let opaque = pipelines(
            "forward+ opaque",
            "fs_forward",
            &[accumulation.clone(), accumulation],
            (wgpu::CompareFunction::Equal, false),
        );
        let blendable = DeviceNeeds {
            features: wgpu::Features::FLOAT32_BLENDABLE,
            ..Default::default()
        }
        .check(device.features(), &device.limits())
        .is_ok();
        let blended = blendable.then(|| {
            let over = Some(wgpu::ColorTargetState {
                format: ACCUMULATION_FORMAT,
                blend: Some(OVER),
                write_mask: wgpu::ColorWrites::ALL,
            });
            pipelines(
                "forward+ blended",
                "fs_blended",
                &[over],
                (wgpu::CompareFunction::Less, false),
            )
        });
        Ok(Self {
            opaque,
            blended,
            lists_layout,
            shadow_layout,
        })
    }

    /// Whether [`ForwardPass::encode_blended`] draws (the device has `FLOAT32_BLENDABLE`).
    pub fn blends(&self) -> bool {
        self.blended.is_some()
    }

    /// Binds the pass to the lists of `lists` (a [`Method::ForwardPlus`] culling pass's
    /// binding: its parameters, lights, counts and lists) and `ambient` (a uniform whose xyz
    /// is the ambient radiance blended surfaces are lit by), without shadows.
    pub fn bind(
        &self,
        device: &wgpu::Device,
        lists: &BoundShading,
        ambient: &wgpu::Buffer,
    ) -> Result<BoundForward, ShadingError> {
        if lists.params.list_stride == 0 || lists.listless {
            return Err(ShadingError::Incompatible(
                "Forward+: the forward pass needs the lists of a Forward+ culling pass".into(),
            ));
        }
        let group = self.lists_layout.bind_buffers(
            device,
            &[
                &lists.params_buffer,
                &lists.lights,
                &lists.counts,
                &lists.lists,
                ambient,
            ],
        );
        Ok(BoundForward {
            lists: group,
            shadows: shadows::lookup_group(device, &self.shadow_layout, Default::default())?,
        })
    }

    /// Makes `bound` look shadows up in `inputs` (as [`super::LightShading::bind_shadows`]).
    pub fn bind_shadows(
        &self,
        device: &wgpu::Device,
        bound: &mut BoundForward,
        inputs: ShadowInputs<'_>,
    ) -> Result<(), ShadingError> {
        bound.shadows = shadows::lookup_group(device, &self.shadow_layout, inputs)?;
        Ok(())
    }

    /// Records the opaque pass: `outputs` (the light accumulation's diffuse and specular,
    /// render attachments of [`ACCUMULATION_FORMAT`]) cleared, then every mesh of `scene` but
    /// the blended ones drawn forward with the camera of `gbuffer`'s frame against `depth`, the
    /// depth pre-pass's buffer (loaded, `Equal`), timed as `forward+ opaque`.
    pub fn encode_opaque(
        &self,
        bound: &BoundForward,
        encoder: &mut wgpu::CommandEncoder,
        (gbuffer, scene): (&GBufferPass, &GpuScene),
        depth: &wgpu::Texture,
        outputs: [&wgpu::Texture; 2],
        timer: Option<&PassTimer>,
    ) {
        super::draw_into_accumulation(
            encoder,
            "forward+ opaque",
            (gbuffer, scene),
            depth,
            outputs,
            &[&bound.lists, &bound.shadows],
            &self.opaque,
            timer,
        );
    }

    /// Records the blended pass: `scene`'s alpha-blended meshes, back to front from `eye`,
    /// blended over `frame` (the composed radiance, [`ACCUMULATION_FORMAT`], render
    /// attachment) where they lie in front of `depth`, timed as `forward+ blended`. Nothing
    /// without blended meshes or without [`ForwardPass::blends`].
    #[allow(clippy::too_many_arguments)]
    pub fn encode_blended(
        &self,
        bound: &BoundForward,
        encoder: &mut wgpu::CommandEncoder,
        (gbuffer, scene): (&GBufferPass, &GpuScene),
        depth: &wgpu::Texture,
        frame: &wgpu::Texture,
        eye: Vec3,
        timer: Option<&PassTimer>,
    ) {
        let Some(blended) = &self.blended else {
            return;
        };
        if !scene.has_blended() {
            return;
        }
        let name = "forward+ blended";
        let frame_view = frame.create_view(&Default::default());
        let depth_view = depth.create_view(&Default::default());
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some(name),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: &frame_view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Load,
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &depth_view,
                depth_ops: None,
                stencil_ops: None,
            }),
            timestamp_writes: timer.and_then(|t| t.render_pass(name)),
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_bind_group(2, &bound.lists, &[]);
        pass.set_bind_group(3, &bound.shadows, &[]);
        gbuffer.draw_blended(&mut pass, [&blended[0], &blended[1]], scene, eye);
    }
}
