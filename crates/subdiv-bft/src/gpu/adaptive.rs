//! GPU adaptive tessellation ([`crate::adaptive`]): `factors.wgsl` (`edge_factors`, optional)
//! then `evaluate.wgsl` (`evaluate_adaptive`), which appends every patch's `s²` triangles to an
//! index buffer and their count to `DrawIndexedIndirect` arguments, so a frame's tessellation
//! never goes through the CPU.

use ::gpu::{PassTimer, kernel::Workgroups, transfer};
use bytemuck::{Pod, Zeroable};

use super::{
    ADAPTIVE_STORAGE_BUFFERS, GpuSubdivider, WORKGROUP, adaptive_chunks, pass, read_mesh, storage,
};
use crate::{
    Refined, SubdivError, Subdivider,
    adaptive::{ScreenView, check_factors},
    patch::{grid_walk, triangle_walk},
};

/// Most segments per patch edge of the GPU adaptive tessellation (its triangle walk packs grid
/// coordinates in 8 bits).
pub const MAX_SEGMENTS: u32 = 128;

/// Uniform block of `factors.wgsl` (`FactorParams`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
struct FactorParams {
    view_proj: [[f32; 4]; 4],
    viewport: [f32; 2],
    target_pixels: f32,
    max_factor: f32,
    edge_count: u32,
    _pad: [u32; 3],
}

/// Output of the adaptive tessellation up to a maximum level: vertex buffers laid out for the
/// maximum level's segments (the tessellation uses a subset), an index buffer with room for
/// every patch at the maximum, and the indirect draw arguments the kernel fills.
pub struct GpuAdaptive {
    /// Finest surface level (from M⁰).
    pub max_level: u32,
    /// Segments per patch edge at the finest level (`s_max`).
    pub max_segments: u32,
    /// Per-M¹-edge factors (f32; `STORAGE | COPY_DST`): [`GpuAdaptive::set_factors`] or
    /// [`GpuSubdivider::encode_screen_factors`].
    pub factors: wgpu::Buffer,
    /// Positions (xyz, 1); `VERTEX | STORAGE | COPY_SRC`.
    pub positions: wgpu::Buffer,
    /// Unit normals (xyz, 0); `VERTEX | STORAGE | COPY_SRC`.
    pub normals: wgpu::Buffer,
    /// Triangle list (u32; collapsed triangles included); `INDEX | STORAGE | COPY_SRC |
    /// COPY_DST` (clear it to draw a fixed count: the slots past the appended triangles are
    /// then degenerate).
    pub indices: wgpu::Buffer,
    /// `DrawIndexedIndirect` arguments (index count, 1, 0, 0, 0) for `draw_indexed_indirect`.
    pub draw_args: wgpu::Buffer,
    /// Slots in the vertex buffers.
    pub vertex_capacity: u32,
    edge_count: u32,
    factor_params: wgpu::Buffer,
    factor_bind: wgpu::BindGroup,
    bind: wgpu::BindGroup,
    groups: Workgroups,
}

impl GpuAdaptive {
    /// Uploads one factor per M¹ edge (validated: count, finite).
    pub fn set_factors(&self, queue: &wgpu::Queue, factors: &[f32]) -> Result<(), SubdivError> {
        check_factors(factors, self.edge_count)?;
        queue.write_buffer(&self.factors, 0, bytemuck::cast_slice(factors));
        Ok(())
    }

    /// Sets the view for [`GpuSubdivider::encode_screen_factors`].
    pub fn set_view(&self, queue: &wgpu::Queue, view: &ScreenView) -> Result<(), SubdivError> {
        view.check()?;
        let params = FactorParams {
            view_proj: view.view_proj.to_cols_array_2d(),
            viewport: [view.viewport.0 as f32, view.viewport.1 as f32],
            target_pixels: view.target_pixels,
            max_factor: self.max_segments.ilog2() as f32,
            edge_count: self.edge_count,
            _pad: [0; 3],
        };
        queue.write_buffer(&self.factor_params, 0, bytemuck::bytes_of(&params));
        Ok(())
    }
}

impl GpuSubdivider {
    /// Output buffers for adaptive tessellation up to surface level `max_level`; factors start
    /// at 0 (one segment per patch edge).
    pub fn adaptive(
        &self,
        device: &wgpu::Device,
        sub: &Subdivider,
        max_level: u32,
    ) -> Result<GpuAdaptive, SubdivError> {
        let Some([evaluate, factors_kernel]) = &self.adaptive else {
            return Err(::gpu::GpuError::Unsupported(format!(
                "adaptive tessellation binds {ADAPTIVE_STORAGE_BUFFERS} storage buffers per shader stage; the device allows {} (request crate::adaptive_device_needs())",
                device.limits().max_storage_buffers_per_shader_stage
            ))
            .into());
        };
        let s = sub.segments(max_level)?;
        if s > MAX_SEGMENTS {
            return Err(SubdivError::Level {
                level: max_level,
                max: MAX_SEGMENTS.ilog2() + 1,
                table_level: self.table_level,
            });
        }
        let vertex_count = sub.patches.output_vertex_count(s);
        let index_count = sub.patches.patches.len() as u64 * u64::from(s * s) * 3;
        if vertex_count as u64 >= u64::from(u32::MAX) || index_count >= u64::from(u32::MAX) {
            return Err(SubdivError::TooLarge(format!(
                "adaptive up to level {max_level}: {vertex_count} vertices, {index_count} indices exceed 32 bits"
            )));
        }
        let workgroups = self
            .patch_count
            .checked_mul(adaptive_chunks(s))
            .ok_or_else(|| {
                SubdivError::TooLarge(format!(
                    "adaptive up to level {max_level}: {} patches of {} chunks exceed 32 bits of workgroups",
                    self.patch_count,
                    adaptive_chunks(s)
                ))
            })?;
        let out =
            wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC;
        let positions =
            transfer::buffer(device, "adaptive positions", vertex_count as u64 * 16, out)?;
        let normals = transfer::buffer(device, "adaptive normals", vertex_count as u64 * 16, out)?;
        let indices = transfer::buffer(
            device,
            "adaptive indices",
            index_count * 4,
            wgpu::BufferUsages::INDEX
                | wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_SRC
                | wgpu::BufferUsages::COPY_DST,
        )?;
        let draw_args = transfer::buffer_init(
            device,
            "adaptive draw arguments",
            bytemuck::cast_slice(&[0u32, 1, 0, 0, 0]),
            wgpu::BufferUsages::INDIRECT
                | wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_DST
                | wgpu::BufferUsages::COPY_SRC,
        )?;
        let factors = transfer::buffer(
            device,
            "tessellation factors",
            u64::from(self.edge_count) * 4,
            wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_DST
                | wgpu::BufferUsages::COPY_SRC,
        )?;
        let params = self.evaluate_params(device, s)?;
        let walks: Vec<u32> = (0..=s.ilog2()).flat_map(|l| grid_walk(1 << l)).collect();
        let walk = storage(device, "grid walks", bytemuck::cast_slice(&walks))?;
        let triangles: Vec<u32> = (0..=s.ilog2())
            .flat_map(|l| triangle_walk(1 << l))
            .collect();
        let triangle_walk = storage(device, "triangle walks", bytemuck::cast_slice(&triangles))?;
        let mut bindings = self.evaluate_bindings(&params, &walk, &positions, &normals);
        bindings.extend([&factors, &indices, &draw_args, &triangle_walk]);
        let evaluate_bind = evaluate.1.bind_buffers(device, &bindings);
        let factor_params = transfer::buffer(
            device,
            "factor params",
            size_of::<FactorParams>() as u64,
            wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        )?;
        let factor_bind = factors_kernel.1.bind_buffers(
            device,
            &[
                &factor_params,
                &self.m1_positions,
                &self.edge_ends,
                &factors,
            ],
        );
        Ok(GpuAdaptive {
            max_level,
            max_segments: s,
            factors,
            positions,
            normals,
            indices,
            draw_args,
            vertex_capacity: vertex_count as u32,
            edge_count: self.edge_count,
            factor_params,
            factor_bind,
            bind: evaluate_bind,
            groups: Workgroups::linear(workgroups, 1),
        })
    }

    /// Records the screen-space metric (after [`GpuSubdivider::encode_initial`], with the view
    /// of [`GpuAdaptive::set_view`]): the factors of every M¹ edge from the M¹ positions.
    pub fn encode_screen_factors(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        adaptive: &GpuAdaptive,
        timer: Option<&PassTimer>,
    ) {
        let Some([_, (edge_factors, _)]) = &self.adaptive else {
            return; // `adaptive` refused to make `adaptive` without the kernels.
        };
        let groups = Workgroups::linear(self.edge_count, WORKGROUP);
        pass(
            "adaptive: edge factors",
            edge_factors,
            &[&adaptive.factor_bind],
            groups,
        )
        .encode(encoder, timer);
    }

    /// Records the adaptive main step (after [`GpuSubdivider::encode_initial`]): resets the
    /// draw's index count, then tessellates every patch with the current factors.
    pub fn encode_adaptive(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        adaptive: &GpuAdaptive,
        timer: Option<&PassTimer>,
    ) {
        let Some([(evaluate_adaptive, _), _]) = &self.adaptive else {
            return; // `adaptive` refused to make `adaptive` without the kernels.
        };
        encoder.clear_buffer(&adaptive.draw_args, 0, Some(4));
        pass(
            "main step: evaluate adaptive",
            evaluate_adaptive,
            &[&adaptive.bind],
            adaptive.groups.clone(),
        )
        .encode(encoder, timer);
    }

    /// Reads back the factors (tests).
    pub fn read_factors(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        adaptive: &GpuAdaptive,
    ) -> Result<Vec<f32>, SubdivError> {
        let mut factors: Vec<f32> = transfer::read_pod(device, queue, &adaptive.factors)?;
        factors.truncate(self.edge_count as usize);
        Ok(factors)
    }

    /// Reads back the adaptive mesh: the whole vertex layout (unused slots hold whatever was
    /// there) and the triangles the kernel wrote, in the order the patches appended them.
    pub fn read_adaptive(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        adaptive: &GpuAdaptive,
    ) -> Result<Refined, SubdivError> {
        let args: Vec<u32> = transfer::read_pod(device, queue, &adaptive.draw_args)?;
        let index_count = args.first().copied().unwrap_or(0);
        let buffers = [&adaptive.positions, &adaptive.normals, &adaptive.indices];
        read_mesh(
            device,
            queue,
            buffers,
            adaptive.vertex_capacity,
            index_count,
        )
    }
}
