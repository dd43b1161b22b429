//! The GPU pipeline of Figure 2.5: `initial.wgsl` (`refine_m1`, `normals_m1`: computational
//! entries M⁰ → M¹) then `evaluate.wgsl` (`evaluate`: every patch with the tables, or
//! `evaluate_adaptive` with per-edge factors, given or computed by `factors.wgsl`). Static
//! data (entries, patches, tables) is uploaded once; an animated M⁰ only rewrites its position
//! buffer ([`GpuSubdivider::set_positions`]). Nothing is read back between passes. One
//! module per stage: `initial` (M⁰ → M¹), `evaluate` (uniform level, into buffers the
//! caller may own: [`GpuSubdivider::bind_level`]), `adaptive` (`factors.wgsl` and
//! `evaluate_adaptive`); test helpers in [`run`].

mod adaptive;
mod evaluate;
mod initial;
pub mod run;

pub use adaptive::{GpuAdaptive, MAX_SEGMENTS};
pub use run::{run, run_adaptive};

use ::gpu::kernel::{self, Binding, Layout, Passes, Workgroups};
use ::gpu::shader::Specialisation;
use ::gpu::{PassTimer, transfer};
use bytemuck::{Pod, Zeroable};
use glam::Vec3;

use crate::patch::padded_weights;
use crate::{BftSet, SubdivError, Subdivider};

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

/// Patches per workgroup of the uniform main step at low levels.
const SMALL_GRID_SLOTS: u32 = 4;

/// Patches a 64-thread workgroup of the uniform main step holds at once for `s` segments
/// (`SLOTS` of `evaluate.wgsl`): 4 while each still has a thread per grid vertex (s ≤ 4, up to
/// 15 grid vertices; one patch would leave most of the workgroup idle), else 1.
pub fn patch_slots(s: u32) -> u32 {
    if crate::bft::grid_count(s) as u32 <= WORKGROUP / SMALL_GRID_SLOTS {
        SMALL_GRID_SLOTS
    } else {
        1
    }
}

const WORKGROUP: u32 = 64;

fn storage(device: &wgpu::Device, label: &str, bytes: &[u8]) -> Result<wgpu::Buffer, SubdivError> {
    Ok(transfer::buffer_init(
        device,
        label,
        bytes,
        wgpu::BufferUsages::STORAGE,
    )?)
}

/// Bindings 0–8 of `evaluate.wgsl`, shared by the uniform and the adaptive kernel: params,
/// patches, rings, tables, M¹ positions and normals, grid walk; fine positions and normals.
const EVALUATE_BINDINGS: [Binding; 9] = [
    Binding::Uniform,
    Binding::StorageRead,
    Binding::StorageRead,
    Binding::StorageRead,
    Binding::StorageRead,
    Binding::StorageRead,
    Binding::StorageRead,
    Binding::Storage,
    Binding::Storage,
];

/// `evaluate.wgsl` specialised: `slots` patches per workgroup of the uniform main step (1 for
/// grids larger than 16 vertices and the adaptive kernel's module, [`SMALL_GRID_SLOTS`] for
/// smaller grids) and the adaptive kernel's [`ADAPTIVE_CHUNK`].
fn evaluate_specialisation(slots: u32) -> Specialisation {
    let (vertices, triangles) = ADAPTIVE_CHUNK;
    Specialisation::default()
        .set("SLOTS", format!("{slots}u"))
        .set("CHUNK_VERTICES", format!("{vertices}u"))
        .set("CHUNK_TRIANGLES", format!("{triangles}u"))
}

/// Grid vertices and triangles of one patch that one workgroup of the adaptive main step
/// (`evaluate_adaptive`) takes: a fine patch spreads over several workgroups, so patches of
/// different levels no longer leave one workgroup each busy for very different times.
const ADAPTIVE_CHUNK: (u32, u32) = (128, 256);

/// Chunks of a patch with `s` segments (`chunk_count` in `evaluate.wgsl`).
fn adaptive_chunks(s: u32) -> u32 {
    let (vertices, triangles) = ADAPTIVE_CHUNK;
    (crate::bft::grid_count(s) as u32)
        .div_ceil(vertices)
        .max((s * s).div_ceil(triangles))
}

/// The variants of this crate's shaders its kernels build (for the shader validation test).
pub fn shader_variants() -> Vec<(&'static str, Specialisation)> {
    [1, SMALL_GRID_SLOTS]
        .map(|slots| ("evaluate.wgsl", evaluate_specialisation(slots)))
        .into()
}

/// Storage buffers the adaptive kernel binds (`evaluate_adaptive`: 8 + factors, indices, draw
/// arguments, triangle walk), above `wgpu::Limits::default()`'s 8.
pub const ADAPTIVE_STORAGE_BUFFERS: u32 = 12;

/// A compute pipeline of `entry` in `module` over one explicit layout per bind group.
fn kernel(
    device: &wgpu::Device,
    module: &wgpu::ShaderModule,
    entry: &str,
    groups: &[&[Binding]],
) -> (wgpu::ComputePipeline, Vec<Layout>) {
    let layouts: Vec<Layout> = groups
        .iter()
        .map(|b| Layout::compute(device, entry, b))
        .collect();
    let refs: Vec<&Layout> = layouts.iter().collect();
    (kernel::pipeline(device, module, entry, &refs, &[]), layouts)
}

/// One pass of one dispatch.
fn pass(
    name: &str,
    pipeline: &wgpu::ComputePipeline,
    groups: &[&wgpu::BindGroup],
    workgroups: Workgroups,
) -> Passes {
    Passes::one(
        name,
        pipeline,
        groups.iter().map(|&g| g.clone()).collect(),
        workgroups,
    )
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
    groups: Workgroups,
}

/// The GPU subdivision of one control mesh: pipelines, static buffers, M¹ buffers.
pub struct GpuSubdivider {
    refine: wgpu::ComputePipeline,
    normals: wgpu::ComputePipeline,
    /// The uniform main step with one patch per workgroup, and its layout.
    evaluate: (wgpu::ComputePipeline, Layout),
    /// The same with [`SMALL_GRID_SLOTS`] patches per workgroup (same layout).
    evaluate_slots: wgpu::ComputePipeline,
    /// The adaptive kernels (`evaluate_adaptive`, `edge_factors`), where the device binds
    /// [`ADAPTIVE_STORAGE_BUFFERS`] storage buffers.
    adaptive: Option<[(wgpu::ComputePipeline, Layout); 2]>,
    /// End vertices of each M¹ edge (`factors.wgsl`).
    edge_ends: wgpu::Buffer,
    /// M⁰ positions (`vec4<f32>`, `COPY_DST`): rewrite them to animate.
    pub m0_positions: wgpu::Buffer,
    /// M¹ positions.
    pub m1_positions: wgpu::Buffer,
    /// M¹ normals.
    pub m1_normals: wgpu::Buffer,
    refine_bind: wgpu::BindGroup,
    normals_bind: [wgpu::BindGroup; 2],
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
        let initial = crate::SHADERS.module(device, "initial.wgsl")?;
        let evaluate_module =
            crate::SHADERS.module_with(device, "evaluate.wgsl", &evaluate_specialisation(1))?;
        let slots_module = crate::SHADERS.module_with(
            device,
            "evaluate.wgsl",
            &evaluate_specialisation(SMALL_GRID_SLOTS),
        )?;
        let read = Binding::StorageRead;
        let refine = kernel(
            device,
            &initial,
            "refine_m1",
            &[&[Binding::Uniform, read, read, read, Binding::Storage]],
        );
        let normals = kernel(
            device,
            &initial,
            "normals_m1",
            &[&[Binding::Uniform], &[read, read, read, Binding::Storage]],
        );
        let (evaluate, mut evaluate_layout) =
            kernel(device, &evaluate_module, "evaluate", &[&EVALUATE_BINDINGS]);
        let evaluate = (evaluate, evaluate_layout.remove(0));
        let evaluate_slots =
            kernel::pipeline(device, &slots_module, "evaluate", &[&evaluate.1], &[]);
        let adaptive = (device.limits().max_storage_buffers_per_shader_stage
            >= ADAPTIVE_STORAGE_BUFFERS)
            .then(|| -> Result<_, SubdivError> {
                let extra = [read, Binding::Storage, Binding::Storage, read];
                let bindings = [&EVALUATE_BINDINGS[..], &extra].concat();
                let (p, mut l) =
                    kernel(device, &evaluate_module, "evaluate_adaptive", &[&bindings]);
                let factors_module = crate::SHADERS.module(device, "factors.wgsl")?;
                let factor_bindings = [Binding::Uniform, read, read, Binding::Storage];
                let (f, mut fl) =
                    kernel(device, &factors_module, "edge_factors", &[&factor_bindings]);
                Ok([(p, l.remove(0)), (f, fl.remove(0))])
            })
            .transpose()?;
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
        let m0_positions = transfer::buffer(
            device,
            "M0 positions",
            u64::from(m0_count) * 16,
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
        )?;
        let m1_positions = transfer::buffer(device, "M1 positions", u64::from(m1_count) * 16, rw)?;
        let m1_normals = transfer::buffer(device, "M1 normals", u64::from(m1_count) * 16, rw)?;
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
        let refine_bind = refine.1[0].bind_buffers(
            device,
            &[
                &counts,
                &m0_positions,
                &entry_offsets,
                &entries,
                &m1_positions,
            ],
        );
        let normals_bind = [
            normals.1[0].bind_buffers(device, &[&counts]),
            normals.1[1].bind_buffers(device, &[&m1_positions, &ring_offsets, &ring, &m1_normals]),
        ];
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
            refine: refine.0,
            normals: normals.0,
            evaluate,
            evaluate_slots,
            adaptive,
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

    /// Workgroups of the uniform main step for `s` segments.
    fn main_step_groups(&self, s: u32) -> Workgroups {
        Workgroups::linear(self.patch_count.div_ceil(patch_slots(s)), 1)
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
}

fn read_vec3(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    buffer: &wgpu::Buffer,
    count: u32,
) -> Result<Vec<Vec3>, SubdivError> {
    let v: Vec<[f32; 4]> = transfer::read_pod(device, queue, buffer)?;
    Ok(v.iter()
        .take(count as usize)
        .map(|p| Vec3::new(p[0], p[1], p[2]))
        .collect())
}

/// A mesh read back: `vertex_count` vertices of `positions` and `normals` (vec4 f32 each)
/// and the first `index_count` indices of `indices`.
fn read_mesh(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    [positions, normals, indices]: [&wgpu::Buffer; 3],
    vertex_count: u32,
    index_count: u32,
) -> Result<crate::Refined, SubdivError> {
    let mut indices: Vec<u32> = transfer::read_pod(device, queue, indices)?;
    indices.truncate(index_count as usize);
    Ok(crate::Refined {
        positions: read_vec3(device, queue, positions, vertex_count)?,
        normals: read_vec3(device, queue, normals, vertex_count)?,
        indices,
    })
}
