//! The main step of Figure 2.5 (`shaders/subdiv-bft/evaluate.wgsl`, uniform level; CPU twin
//! [`crate::patch`]): every patch of M¹ evaluated with the basis-function tables into the
//! level's vertex buffers.

use ::gpu::kernel;
use ::gpu::{PassTimer, transfer};

use super::{EvaluateParams, GpuLevel, GpuSubdivider, pass, read_mesh, storage};
use crate::patch::{grid_walk, inner_count};
use crate::{Refined, SubdivError, Subdivider, bft::grid_count};

impl GpuSubdivider {
    /// Allocates the output buffers of `level` (`VERTEX | STORAGE | COPY_SRC | COPY_DST`) and
    /// binds them ([`GpuSubdivider::bind_level`]).
    pub fn level(
        &self,
        device: &wgpu::Device,
        sub: &Subdivider,
        level: u32,
    ) -> Result<GpuLevel, SubdivError> {
        let bytes = self.level_size(sub, level)?.0 * 16;
        let out = wgpu::BufferUsages::VERTEX
            | wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::COPY_SRC
            | wgpu::BufferUsages::COPY_DST;
        let positions = transfer::buffer(device, "fine positions", bytes, out)?;
        let normals = transfer::buffer(device, "fine normals", bytes, out)?;
        self.bind_level(device, sub, level, &positions, &normals)
    }

    /// Vertices and indices of `level`, checked to fit 32-bit indices.
    fn level_size(&self, sub: &Subdivider, level: u32) -> Result<(u64, u64), SubdivError> {
        let s = sub.segments(level)?;
        let vertex_count = sub.patches.output_vertex_count(s) as u64;
        let index_count = sub.patches.patches.len() as u64 * u64::from(s * s) * 3;
        if vertex_count >= u64::from(u32::MAX) || index_count >= u64::from(u32::MAX) {
            return Err(SubdivError::TooLarge(format!(
                "level {level}: {vertex_count} vertices, {index_count} indices exceed 32 bits"
            )));
        }
        Ok((vertex_count, index_count))
    }

    /// Binds the main step of `level` to the caller's vertex buffers `positions` and `normals`
    /// (each at least 16 bytes per fine vertex, `STORAGE`; add `VERTEX` to draw them), and
    /// uploads the level's index buffer. Buffers too small or without `STORAGE` are an `Err`.
    pub fn bind_level(
        &self,
        device: &wgpu::Device,
        sub: &Subdivider,
        level: u32,
        positions: &wgpu::Buffer,
        normals: &wgpu::Buffer,
    ) -> Result<GpuLevel, SubdivError> {
        let s = sub.segments(level)?;
        let (vertex_count, index_count) = self.level_size(sub, level)?;
        for (what, buffer) in [("fine positions", positions), ("fine normals", normals)] {
            kernel::check_buffer(what, buffer, vertex_count * 16, wgpu::BufferUsages::STORAGE)?;
        }
        let indices = transfer::buffer_init(
            device,
            "fine indices",
            bytemuck::cast_slice(&sub.patches.triangulate(s)),
            wgpu::BufferUsages::INDEX | wgpu::BufferUsages::COPY_SRC,
        )?;
        let params = self.evaluate_params(device, s)?;
        let walk = storage(device, "grid walk", bytemuck::cast_slice(&grid_walk(s)))?;
        let bind = self.evaluate.1.bind_buffers(
            device,
            &self.evaluate_bindings(&params, &walk, positions, normals),
        );
        Ok(GpuLevel {
            level,
            segments: s,
            positions: positions.clone(),
            normals: normals.clone(),
            indices,
            vertex_count: vertex_count as u32,
            index_count: index_count as u32,
            bind,
            groups: self.main_step_groups(s),
        })
    }

    /// Bindings 0–8 of `evaluate.wgsl`, shared by the uniform and the adaptive kernel.
    pub(super) fn evaluate_bindings<'a>(
        &'a self,
        params: &'a wgpu::Buffer,
        walk: &'a wgpu::Buffer,
        positions: &'a wgpu::Buffer,
        normals: &'a wgpu::Buffer,
    ) -> Vec<&'a wgpu::Buffer> {
        vec![
            params,
            &self.patches,
            &self.rings,
            &self.tables,
            &self.m1_positions,
            &self.m1_normals,
            walk,
            positions,
            normals,
        ]
    }

    /// The uniform block of `evaluate.wgsl` for `s` segments (adaptive: the layout's `s_max`).
    pub(super) fn evaluate_params(
        &self,
        device: &wgpu::Device,
        s: u32,
    ) -> Result<wgpu::Buffer, SubdivError> {
        let params = EvaluateParams {
            s,
            table_segments: 1 << self.table_level,
            vertex_count: self.m1_count,
            edge_count: self.edge_count,
            patch_count: self.patch_count,
            grid_count: grid_count(s) as u32,
            inner_count: inner_count(s) as u32,
        };
        Ok(transfer::buffer_init(
            device,
            "evaluate params",
            bytemuck::bytes_of(&params),
            wgpu::BufferUsages::UNIFORM,
        )?)
    }

    /// Records the main step for `level` (after [`GpuSubdivider::encode_initial`]).
    pub fn encode_evaluate(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        level: &GpuLevel,
        timer: Option<&PassTimer>,
    ) {
        let pipeline = if super::patch_slots(level.segments) == 1 {
            &self.evaluate.0
        } else {
            &self.evaluate_slots
        };
        pass(
            "main step: evaluate",
            pipeline,
            &[&level.bind],
            level.groups.clone(),
        )
        .encode(encoder, timer);
    }

    /// Reads back a level's mesh (tests, the `subdivide` command).
    pub fn read_level(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        level: &GpuLevel,
    ) -> Result<Refined, SubdivError> {
        let buffers = [&level.positions, &level.normals, &level.indices];
        read_mesh(
            device,
            queue,
            buffers,
            level.vertex_count,
            level.index_count,
        )
    }
}
