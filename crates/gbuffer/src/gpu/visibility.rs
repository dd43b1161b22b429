//! A visibility buffer written by a compute rasteriser (Burns & Hunt 2013): per pixel the
//! nearest triangle's depth and id in 64 bits, `(depth bits << 32) | id`, merged with 64-bit
//! `atomicMin` (`visibility.wgsl`). Coverage and depth are [`crate::cpu::rasterize`]'s — same
//! clip planes, snapping, top-left rule and depth test in submission order — so its triangle
//! ids are the CPU's ([`crate::cpu::Rasterized::triangle_id`]) but for pixels on triangle
//! edges where the two compute a vertex's clip position or depth one rounding apart.
//!
//! **Split rule.** One invocation per triangle covers the pixels of its bounding box when the
//! box has at most 64 pixels and no vertex lies outside a clip plane (near, far, the 4w guard
//! band); every other triangle is deferred to a workgroup of 64 invocations, which clips it
//! into a fan and covers each fan triangle's box together.
//!
//! **Scope (first step of issue 29).** Meshes whose material discards fragments by alpha (mask
//! or blend) are not rasterised here: [`Visibility::skipped`] names them. The device needs
//! 64-bit integers and 64-bit atomic min ([`FEATURES`]).
//!
//! ```no_run
//! use gbuffer::{Frame, gpu::{GBufferPass, GpuScene, visibility::{self, VisibilityPass}}};
//! # let gpu = gpu::Gpu::from_env_with(&visibility::device_needs())?;
//! let scene = scene::spheres_on_plane(4);
//! let camera = scene.camera_or_framed();
//! let gpass = GBufferPass::new(&gpu.device)?;
//! let uploaded = GpuScene::upload(&gpu.device, &gpu.queue, &scene, &gpass)?;
//! let pass = VisibilityPass::new(&gpu.device)?;
//! let buffer = VisibilityPass::buffer(&gpu.device, 640, 480)?;
//! let frame = Frame::new(&camera, 640, 480);
//! let vis = pass.bind(&gpu.device, &uploaded, &scene, &frame, &buffer)?;
//! let mut encoder = gpu.device.create_command_encoder(&Default::default());
//! vis.passes.encode(&mut encoder, None);
//! gpu.queue.submit([encoder.finish()]);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use ::gpu::kernel::{self, Binding, Dispatch, Layout, Passes, Workgroups};
use ::gpu::{transfer, wgpu};
use bytemuck::{Pod, Zeroable};
use scene::{AlphaMode, Scene};

use super::upload::GpuScene;
use crate::{Frame, GBufferError};

/// What the kernels need beyond `wgpu::Limits::default()`: 64-bit integers and 64-bit
/// atomic min/max on storage buffers.
pub const FEATURES: wgpu::Features =
    wgpu::Features::SHADER_INT64.union(wgpu::Features::SHADER_INT64_ATOMIC_MIN_MAX);

/// The device this module's kernels need.
pub fn device_needs() -> ::gpu::DeviceNeeds {
    ::gpu::DeviceNeeds {
        features: FEATURES,
        ..Default::default()
    }
}

/// The id of a pixel no triangle covers.
pub const NO_TRIANGLE: u32 = u32::MAX;

/// How many triangles of one mesh a frame may defer to the workgroup path.
const DEFERRED: u64 = 1 << 20;
/// Workgroups of the deferred path (each loops over the deferred triangles).
const LARGE_GROUPS: u32 = 4096;
const WORKGROUP: u32 = 64;

/// Uniform block `Raster` of `visibility.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct RasterUniform {
    view_proj: [[f32; 4]; 4],
    size: [u32; 2],
    first_id: u32,
    triangle_count: u32,
    base_vertex: u32,
    first_index: u32,
    cull_back: u32,
    _pad: u32,
}

/// The visibility buffer's kernels (phase `new`).
pub struct VisibilityPass {
    layout: Layout,
    clear: wgpu::ComputePipeline,
    reset: wgpu::ComputePipeline,
    small: wgpu::ComputePipeline,
    large: wgpu::ComputePipeline,
}

/// The passes writing one scene's visibility buffer (phase `bind`), and the meshes they leave
/// out.
pub struct Visibility {
    /// Clear, then per mesh: the per-triangle and the deferred rasterisation.
    pub passes: Passes,
    /// Meshes (indices in [`Scene::meshes`]) not rasterised: their material discards fragments
    /// by alpha.
    pub skipped: Vec<usize>,
    /// The deferred-triangle list the passes share (kept alive with them).
    _deferred: wgpu::Buffer,
}

impl VisibilityPass {
    /// Builds the kernels; the device must have [`FEATURES`].
    pub fn new(device: &wgpu::Device) -> Result<Self, GBufferError> {
        let missing = FEATURES - device.features();
        if !missing.is_empty() {
            return Err(GBufferError::InvalidOptions(format!(
                "the visibility buffer needs device features {missing:?}"
            )));
        }
        let module = crate::SHADERS.module(device, "visibility.wgsl")?;
        let layout = Layout::compute(
            device,
            "visibility",
            &[
                Binding::Uniform,
                Binding::StorageRead,
                Binding::StorageRead,
                Binding::Storage,
                Binding::Storage,
            ],
        );
        let pipeline = |entry| kernel::pipeline(device, &module, entry, &[&layout], &[]);
        Ok(Self {
            clear: pipeline("clear"),
            reset: pipeline("reset"),
            small: pipeline("raster_small"),
            large: pipeline("raster_large"),
            layout,
        })
    }

    /// A visibility buffer for `width × height` pixels (8 bytes each, row-major; `STORAGE |
    /// COPY_SRC`).
    pub fn buffer(
        device: &wgpu::Device,
        width: u32,
        height: u32,
    ) -> Result<wgpu::Buffer, GBufferError> {
        crate::validate_size(width, height)?;
        Ok(transfer::buffer(
            device,
            "visibility buffer",
            u64::from(width) * u64::from(height) * 8,
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        )?)
    }

    /// The passes writing `visibility` (a [`VisibilityPass::buffer`] of `frame`'s size) for
    /// `uploaded` (`scene` uploaded) seen through `frame`.
    pub fn bind(
        &self,
        device: &wgpu::Device,
        uploaded: &GpuScene,
        scene: &Scene,
        frame: &Frame,
        visibility: &wgpu::Buffer,
    ) -> Result<Visibility, GBufferError> {
        let size = [frame.viewport.x as u32, frame.viewport.y as u32];
        let pixels = u64::from(size[0]) * u64::from(size[1]);
        if visibility.size() != pixels * 8 {
            return Err(GBufferError::InvalidOptions(format!(
                "a visibility buffer of {} bytes for {}×{} pixels (needs {})",
                visibility.size(),
                size[0],
                size[1],
                pixels * 8
            )));
        }
        let deferred = transfer::buffer(
            device,
            "visibility deferred triangles",
            (DEFERRED + 1) * 4,
            wgpu::BufferUsages::STORAGE,
        )?;
        let group = |uniform: &RasterUniform| -> Result<wgpu::BindGroup, GBufferError> {
            let buffer = transfer::buffer_init(
                device,
                "visibility raster",
                bytemuck::bytes_of(uniform),
                wgpu::BufferUsages::UNIFORM,
            )?;
            let (positions, indices) = (&uploaded.positions, &uploaded.indices);
            Ok(self.layout.bind_buffers(
                device,
                &[&buffer, positions, indices, visibility, &deferred],
            ))
        };
        let dispatch =
            |pipeline: &wgpu::ComputePipeline, group: &wgpu::BindGroup, workgroups| Dispatch {
                pipeline: pipeline.clone(),
                groups: vec![group.clone()],
                workgroups,
            };
        let base = RasterUniform {
            view_proj: frame.view_proj.to_cols_array_2d(),
            size,
            first_id: 0,
            triangle_count: 0,
            base_vertex: 0,
            first_index: 0,
            cull_back: 0,
            _pad: 0,
        };
        let mut dispatches = vec![dispatch(
            &self.clear,
            &group(&base)?,
            Workgroups::linear(pixels as u32, WORKGROUP),
        )];
        let mut skipped = Vec::new();
        let mut first_id = 0u32;
        for (m, mesh) in scene.meshes.iter().enumerate() {
            let draw = uploaded.draws.get(m).ok_or_else(|| {
                GBufferError::InvalidOptions(format!("mesh {m} is not in the uploaded scene"))
            })?;
            let material = &scene.materials[mesh.material as usize];
            let id = first_id;
            first_id += mesh.triangle_count() as u32;
            if !matches!(material.alpha_mode, AlphaMode::Opaque) {
                skipped.push(m);
                continue;
            }
            let triangle_count = draw.index_count / 3;
            if triangle_count == 0 {
                continue;
            }
            let g = group(&RasterUniform {
                first_id: id,
                triangle_count,
                base_vertex: draw.base_vertex as u32,
                first_index: draw.first_index,
                cull_back: u32::from(!material.double_sided),
                ..base
            })?;
            dispatches.push(dispatch(&self.reset, &g, Workgroups::Direct([1, 1, 1])));
            dispatches.push(dispatch(
                &self.small,
                &g,
                Workgroups::linear(triangle_count, WORKGROUP),
            ));
            dispatches.push(dispatch(
                &self.large,
                &g,
                Workgroups::Direct([LARGE_GROUPS, 1, 1]),
            ));
        }
        Ok(Visibility {
            passes: Passes::new().pass("visibility", dispatches),
            skipped,
            _deferred: deferred,
        })
    }
}

/// A read-back visibility buffer's triangle ids ([`NO_TRIANGLE`] where none), row-major.
pub fn triangle_ids(words: &[u64]) -> Vec<u32> {
    words.iter().map(|&w| w as u32).collect()
}
