//! The GPU pipeline of Figure 2.5: `initial.wgsl` (`refine_m1`, `normals_m1`: computational
//! entries M⁰ → M¹) then `evaluate.wgsl` (`evaluate`: every patch with the tables, or
//! `evaluate_adaptive` with per-edge factors, given or computed by `factors.wgsl`). Static
//! data (entries, patches, tables) is uploaded once; an animated M⁰ only rewrites its position
//! buffer ([`GpuSubdivider::set_positions`]). Nothing is read back between passes.

mod adaptive;

pub use adaptive::{GpuAdaptive, MAX_SEGMENTS};

use ::gpu::{Gpu, PassTimer, shader, transfer};
use bytemuck::{Pod, Zeroable};
use glam::Vec3;

use crate::patch::{grid_walk, inner_count, padded_weights};
use crate::{BftSet, Refined, SubdivError, Subdivider, bft::grid_count};

/// Uniform block of `evaluate.wgsl` (`Params`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct EvaluateParams {
    /// Segments per patch edge.
    pub s: u32,
    /// Segments of the tables' grid.
    pub table_segments: u32,
    /// M¹ vertices.
    pub vertex_count: u32,
    /// M¹ edges.
    pub edge_count: u32,
    /// Patches (M¹ faces).
    pub patch_count: u32,
    /// Grid vertices per patch.
    pub grid_count: u32,
    /// Inner vertices per patch.
    pub inner_count: u32,
}

const WORKGROUP: u32 = 64;
const MAX_GROUPS_X: u32 = 65_535;

fn storage(device: &wgpu::Device, label: &str, bytes: &[u8]) -> Result<wgpu::Buffer, SubdivError> {
    Ok(transfer::buffer_init(
        device,
        label,
        bytes,
        wgpu::BufferUsages::STORAGE,
    )?)
}

fn empty(
    device: &wgpu::Device,
    label: &str,
    size: u64,
    usage: wgpu::BufferUsages,
) -> Result<wgpu::Buffer, SubdivError> {
    Ok(transfer::buffer(device, label, size, usage)?)
}

fn bind(
    device: &wgpu::Device,
    pipeline: &wgpu::ComputePipeline,
    entries: &[(u32, &wgpu::Buffer)],
) -> wgpu::BindGroup {
    shader::bind_buffers(device, "subdiv-bft", pipeline, entries)
}

/// One tessellation level's output: a vertex and index buffer ready to draw (positions and
/// normals as `vec4<f32>`, stride 16), with the bind group that fills them.
pub struct GpuLevel {
    /// Surface level (from M⁰).
    pub level: u32,
    /// Segments per patch edge.
    pub segments: u32,
    /// Fine vertex positions (xyz, 1); `VERTEX | STORAGE | COPY_SRC`.
    pub positions: wgpu::Buffer,
    /// Unit normals (xyz, 0); `VERTEX | STORAGE | COPY_SRC`.
    pub normals: wgpu::Buffer,
    /// Triangle list (u32); `INDEX | COPY_SRC`.
    pub indices: wgpu::Buffer,
    /// Fine vertices.
    pub vertex_count: u32,
    /// Indices.
    pub index_count: u32,
    bind: wgpu::BindGroup,
    groups: (u32, u32),
}

/// The GPU subdivision of one control mesh: pipelines, static buffers, M¹ buffers.
pub struct GpuSubdivider {
    refine: wgpu::ComputePipeline,
    normals: wgpu::ComputePipeline,
    evaluate: wgpu::ComputePipeline,
    evaluate_adaptive: wgpu::ComputePipeline,
    edge_factors: wgpu::ComputePipeline,
    /// End vertices of each M¹ edge (`factors.wgsl`).
    edge_ends: wgpu::Buffer,
    /// M⁰ positions (`vec4<f32>`, `COPY_DST`): rewrite them to animate.
    pub m0_positions: wgpu::Buffer,
    /// M¹ positions.
    pub m1_positions: wgpu::Buffer,
    /// M¹ normals.
    pub m1_normals: wgpu::Buffer,
    refine_bind: wgpu::BindGroup,
    normals_bind: wgpu::BindGroup,
    patches: wgpu::Buffer,
    rings: wgpu::Buffer,
    tables: wgpu::Buffer,
    m0_count: u32,
    m1_count: u32,
    patch_count: u32,
    edge_count: u32,
    table_level: u32,
}

impl GpuSubdivider {
    /// Builds the pipelines and uploads entries, patches and tables of `sub`.
    pub fn new(device: &wgpu::Device, sub: &Subdivider, bft: &BftSet) -> Result<Self, SubdivError> {
        if bft.level != sub.table_level {
            return Err(SubdivError::Table(format!(
                "patches were made for level-{} tables, these are level {}",
                sub.table_level, bft.level
            )));
        }
        let initial = shader::module(device, "subdiv-bft/initial.wgsl")?;
        let evaluate_module = shader::module(device, "subdiv-bft/evaluate.wgsl")?;
        let refine = shader::compute_pipeline(device, &initial, "refine_m1", &[]);
        let normals = shader::compute_pipeline(device, &initial, "normals_m1", &[]);
        let evaluate = shader::compute_pipeline(device, &evaluate_module, "evaluate", &[]);
        let evaluate_adaptive =
            shader::compute_pipeline(device, &evaluate_module, "evaluate_adaptive", &[]);
        let factors_module = shader::module(device, "subdiv-bft/factors.wgsl")?;
        let edge_factors = shader::compute_pipeline(device, &factors_module, "edge_factors", &[]);
        let ends: Vec<[u32; 2]> = sub
            .m1
            .edges
            .iter()
            .map(|&h| [sub.m1.origin(h), sub.m1.dest(h)])
            .collect();
        let edge_ends = storage(device, "M1 edge ends", bytemuck::cast_slice(&ends))?;

        let m0_count = sub.m0.vertex_count() as u32;
        let m1_count = sub.m1.vertex_count() as u32;
        let rw = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC;
        let m0_positions = empty(
            device,
            "M0 positions",
            u64::from(m0_count) * 16,
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
        )?;
        let m1_positions = empty(device, "M1 positions", u64::from(m1_count) * 16, rw)?;
        let m1_normals = empty(device, "M1 normals", u64::from(m1_count) * 16, rw)?;
        let counts = transfer::buffer_init(
            device,
            "M1 counts",
            bytemuck::bytes_of(&[m1_count, 0, 0, 0]),
            wgpu::BufferUsages::UNIFORM,
        )?;
        let e = &sub.entries;
        let entries: Vec<[u32; 2]> = e
            .indices
            .iter()
            .zip(&e.weights)
            .map(|(&i, &w)| [i, (w as f32).to_bits()])
            .collect();
        let entry_offsets = storage(device, "entry offsets", bytemuck::cast_slice(&e.offsets))?;
        let entries = storage(
            device,
            "computational entries",
            bytemuck::cast_slice(&entries),
        )?;
        let mut ring_offsets = Vec::with_capacity(sub.normal_entries.len() + 1);
        let mut ring = Vec::new();
        for fan in &sub.normal_entries {
            ring_offsets.push(ring.len() as u32 | if fan.boundary { 1 << 31 } else { 0 });
            ring.extend_from_slice(&fan.ring);
        }
        ring_offsets.push(ring.len() as u32);
        let ring_offsets = storage(
            device,
            "normal entry offsets",
            bytemuck::cast_slice(&ring_offsets),
        )?;
        let ring = storage(device, "normal entries", bytemuck::cast_slice(&ring))?;
        let refine_bind = bind(
            device,
            &refine,
            &[
                (0, &counts),
                (1, &m0_positions),
                (2, &entry_offsets),
                (3, &entries),
                (4, &m1_positions),
            ],
        );
        let normals_bind = bind(
            device,
            &normals,
            &[
                (0, &counts),
                (5, &m1_positions),
                (6, &ring_offsets),
                (7, &ring),
                (8, &m1_normals),
            ],
        );
        let (weights, _) = padded_weights(bft);
        Ok(Self {
            patches: storage(
                device,
                "patches",
                bytemuck::cast_slice(&sub.patches.patches),
            )?,
            rings: storage(
                device,
                "patch rings",
                bytemuck::cast_slice(&sub.patches.rings),
            )?,
            tables: storage(
                device,
                "basis-function tables",
                bytemuck::cast_slice(&weights),
            )?,
            refine,
            normals,
            evaluate,
            evaluate_adaptive,
            edge_factors,
            edge_ends,
            m0_positions,
            m1_positions,
            m1_normals,
            refine_bind,
            normals_bind,
            m0_count,
            m1_count,
            patch_count: sub.patches.patches.len() as u32,
            edge_count: sub.patches.edge_count,
            table_level: bft.level,
        })
    }

    /// Uploads new M⁰ positions (one per M⁰ vertex): animation needs nothing else.
    pub fn set_positions(
        &self,
        queue: &wgpu::Queue,
        positions: &[Vec3],
    ) -> Result<(), SubdivError> {
        if positions.len() != self.m0_count as usize {
            return Err(SubdivError::PositionCount {
                given: positions.len(),
                expected: self.m0_count as usize,
            });
        }
        queue.write_buffer(
            &self.m0_positions,
            0,
            bytemuck::cast_slice(&transfer::vec4s(positions, 1.0)),
        );
        Ok(())
    }

    /// Output buffers for surface level `level` (1..=L + 1) with the static index buffer of
    /// `sub`'s patches.
    pub fn level(
        &self,
        device: &wgpu::Device,
        sub: &Subdivider,
        level: u32,
    ) -> Result<GpuLevel, SubdivError> {
        let s = sub.segments(level)?;
        let vertex_count = sub.patches.output_vertex_count(s);
        let index_count = sub.patches.patches.len() as u64 * u64::from(s * s) * 3;
        if vertex_count as u64 >= u64::from(u32::MAX) || index_count >= u64::from(u32::MAX) {
            return Err(SubdivError::TooLarge(format!(
                "level {level}: {vertex_count} vertices, {index_count} indices exceed 32 bits"
            )));
        }
        let out = wgpu::BufferUsages::VERTEX
            | wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::COPY_SRC
            | wgpu::BufferUsages::COPY_DST;
        let positions = empty(device, "fine positions", vertex_count as u64 * 16, out)?;
        let normals = empty(device, "fine normals", vertex_count as u64 * 16, out)?;
        let indices = transfer::buffer_init(
            device,
            "fine indices",
            bytemuck::cast_slice(&sub.patches.triangulate(s)),
            wgpu::BufferUsages::INDEX | wgpu::BufferUsages::COPY_SRC,
        )?;
        let params = self.evaluate_params(device, s)?;
        let walk = storage(device, "grid walk", bytemuck::cast_slice(&grid_walk(s)))?;
        let bind = bind(
            device,
            &self.evaluate,
            &self.evaluate_bindings(&params, &walk, &positions, &normals),
        );
        Ok(GpuLevel {
            level,
            segments: s,
            positions,
            normals,
            indices,
            vertex_count: vertex_count as u32,
            index_count: index_count as u32,
            bind,
            groups: self.patch_groups(),
        })
    }

    /// Bindings 0–8 of `evaluate.wgsl`, shared by the uniform and the adaptive kernel.
    fn evaluate_bindings<'a>(
        &'a self,
        params: &'a wgpu::Buffer,
        walk: &'a wgpu::Buffer,
        positions: &'a wgpu::Buffer,
        normals: &'a wgpu::Buffer,
    ) -> Vec<(u32, &'a wgpu::Buffer)> {
        vec![
            (0, params),
            (1, &self.patches),
            (2, &self.rings),
            (3, &self.tables),
            (4, &self.m1_positions),
            (5, &self.m1_normals),
            (6, walk),
            (7, positions),
            (8, normals),
        ]
    }

    /// Workgroups of a dispatch with one per patch (x at most 65 535).
    fn patch_groups(&self) -> (u32, u32) {
        let x = self.patch_count.clamp(1, MAX_GROUPS_X);
        (x, self.patch_count.div_ceil(x).max(1))
    }

    /// The uniform block of `evaluate.wgsl` for `s` segments (adaptive: the layout's `s_max`).
    fn evaluate_params(&self, device: &wgpu::Device, s: u32) -> Result<wgpu::Buffer, SubdivError> {
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

    /// Records the initial step (M⁰ → M¹ positions, then normals).
    pub fn encode_initial(&self, encoder: &mut wgpu::CommandEncoder, timer: Option<&PassTimer>) {
        let groups = self.m1_count.div_ceil(WORKGROUP).max(1);
        for (name, pipeline, bind) in [
            ("initial step: positions", &self.refine, &self.refine_bind),
            ("initial step: normals", &self.normals, &self.normals_bind),
        ] {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some(name),
                timestamp_writes: timer.and_then(|t| t.compute_pass(name)),
            });
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, bind, &[]);
            pass.dispatch_workgroups(groups, 1, 1);
        }
    }

    /// Records the main step for `level` (after [`GpuSubdivider::encode_initial`]).
    pub fn encode_evaluate(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        level: &GpuLevel,
        timer: Option<&PassTimer>,
    ) {
        let name = "main step: evaluate";
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some(name),
            timestamp_writes: timer.and_then(|t| t.compute_pass(name)),
        });
        pass.set_pipeline(&self.evaluate);
        pass.set_bind_group(0, &level.bind, &[]);
        pass.dispatch_workgroups(level.groups.0, level.groups.1, 1);
    }

    /// Records both steps.
    pub fn encode(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        level: &GpuLevel,
        timer: Option<&PassTimer>,
    ) {
        self.encode_initial(encoder, timer);
        self.encode_evaluate(encoder, level, timer);
    }

    /// Reads back M¹ positions and normals (tests).
    pub fn read_m1(&self, gpu: &Gpu) -> Result<(Vec<Vec3>, Vec<Vec3>), SubdivError> {
        Ok((
            read_vec3(gpu, &self.m1_positions, self.m1_count)?,
            read_vec3(gpu, &self.m1_normals, self.m1_count)?,
        ))
    }

    /// Reads back a level's mesh (tests, the `subdivide` command).
    pub fn read_level(&self, gpu: &Gpu, level: &GpuLevel) -> Result<Refined, SubdivError> {
        let indices = transfer::read_buffer(&gpu.device, &gpu.queue, &level.indices)?;
        Ok(Refined {
            positions: read_vec3(gpu, &level.positions, level.vertex_count)?,
            normals: read_vec3(gpu, &level.normals, level.vertex_count)?,
            indices: bytemuck::pod_collect_to_vec::<u8, u32>(&indices)
                [..level.index_count as usize]
                .to_vec(),
        })
    }
}

fn read_vec3(gpu: &Gpu, buffer: &wgpu::Buffer, count: u32) -> Result<Vec<Vec3>, SubdivError> {
    let bytes = transfer::read_buffer(&gpu.device, &gpu.queue, buffer)?;
    let v: Vec<[f32; 4]> = bytemuck::pod_collect_to_vec(&bytes);
    Ok(v[..count as usize]
        .iter()
        .map(|p| Vec3::new(p[0], p[1], p[2]))
        .collect())
}

/// Uploads, runs both steps at `level` and reads the mesh back.
pub fn run(
    gpu: &Gpu,
    sub: &Subdivider,
    bft: &BftSet,
    m0_positions: &[Vec3],
    level: u32,
) -> Result<Refined, SubdivError> {
    let g = GpuSubdivider::new(&gpu.device, sub, bft)?;
    let out = g.level(&gpu.device, sub, level)?;
    g.set_positions(&gpu.queue, m0_positions)?;
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    g.encode(&mut encoder, &out, None);
    gpu.queue.submit([encoder.finish()]);
    g.read_level(gpu, &out)
}

/// Uploads, computes screen-space factors for `view` on the GPU, runs the adaptive
/// tessellation up to `max_level` and reads back the mesh (the whole vertex layout, triangles
/// in append order) and the factors.
pub fn run_adaptive(
    gpu: &Gpu,
    sub: &Subdivider,
    bft: &BftSet,
    m0_positions: &[Vec3],
    max_level: u32,
    view: &crate::adaptive::ScreenView,
) -> Result<(Refined, Vec<f32>), SubdivError> {
    let g = GpuSubdivider::new(&gpu.device, sub, bft)?;
    let a = g.adaptive(&gpu.device, sub, max_level)?;
    g.set_positions(&gpu.queue, m0_positions)?;
    a.set_view(&gpu.queue, view)?;
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    g.encode_initial(&mut encoder, None);
    g.encode_screen_factors(&mut encoder, &a, None);
    g.encode_adaptive(&mut encoder, &a, None);
    gpu.queue.submit([encoder.finish()]);
    Ok((g.read_adaptive(gpu, &a)?, g.read_factors(gpu, &a)?))
}
