//! OpenSubdiv 3.7 through `opensubdiv-petite` 0.3.1: a triangle mesh refined uniformly by
//! Loop's scheme (boundaries "edge only", as the toolkit's CPU reference) into a stencil table
//! (`Far::StencilTableFactory`: one stencil of control-vertex weights per refined vertex of the
//! last level), evaluated by OpenSubdiv's CPU evaluator (`Osd::CpuEvaluator`, one thread) and by
//! opensubdiv-petite's WGSL port of OpenSubdiv's GLSL compute kernel on wgpu 29
//! ([`GpuEvaluator`], one invocation per stencil).

use std::time::Instant;

use anyhow::{Context, Result, bail};
use opensubdiv_petite::{far, osd};
use subdiv_bft::TriMesh;
use wgpu29 as wgpu;
use wgpu29::util::DeviceExt;

/// A mesh refined by OpenSubdiv to one uniform level, as a stencil table.
pub struct Refinement {
    refiner: far::TopologyRefiner,
    table: far::StencilTable,
    control_vertices: usize,
    /// The refinement level (4ˡ triangles per control triangle).
    pub level: u32,
    /// Wall-clock ms of the topology refiner: creation and uniform refinement.
    pub refine_ms: f64,
    /// Wall-clock ms of the stencil table's construction.
    pub stencil_ms: f64,
}

impl Refinement {
    /// Refines `mesh` to `level` with Loop's scheme and builds the last level's stencils.
    pub fn new(mesh: &TriMesh, level: u32) -> Result<Self> {
        let triangles = &mesh.topology.triangles;
        let arities = vec![3u32; triangles.len()];
        let indices: Vec<u32> = triangles.iter().flatten().copied().collect();
        let start = Instant::now();
        let mut refiner = far::TopologyRefiner::new(
            far::TopologyDescriptor::new(mesh.positions.len(), &arities, &indices)?,
            far::TopologyRefinerOptions {
                scheme: far::Scheme::Loop,
                boundary_interpolation: Some(far::BoundaryInterpolation::EdgeOnly),
                ..Default::default()
            },
        )?;
        refiner.refine_uniform(far::topology_refiner::UniformRefinementOptions {
            refinement_level: level as usize,
            ..Default::default()
        });
        let refine_ms = start.elapsed().as_secs_f64() * 1e3;
        let start = Instant::now();
        let table = far::StencilTable::new(
            &refiner,
            far::StencilTableOptions {
                generate_offsets: true,
                generate_intermediate_levels: false,
                ..Default::default()
            },
        )?;
        let stencil_ms = start.elapsed().as_secs_f64() * 1e3;
        Ok(Self {
            refiner,
            table,
            control_vertices: mesh.positions.len(),
            level,
            refine_ms,
            stencil_ms,
        })
    }

    /// Refined vertices of the last level (one stencil each).
    pub fn vertex_count(&self) -> usize {
        self.table.len()
    }

    /// Bytes of the stencil table: sizes, offsets, control indices and weights (4 bytes each).
    pub fn stencil_bytes(&self) -> usize {
        4 * (self.table.sizes().len()
            + self.table.offsets().len()
            + self.table.control_indices().len()
            + self.table.weights().len())
    }

    /// The last level's triangles (three vertex indices each, into the refined vertices).
    pub fn triangles(&self) -> Result<Vec<u32>> {
        let level = self
            .refiner
            .level(self.level as usize)
            .context("OpenSubdiv has no last level")?;
        let mut out = Vec::with_capacity(level.face_count() * 3);
        for face in level.face_vertices_iter() {
            if face.len() != 3 {
                bail!(
                    "OpenSubdiv's Loop level has a face of {} vertices",
                    face.len()
                );
            }
            out.extend(face.iter().map(|i| i.0));
        }
        Ok(out)
    }

    /// The refined positions from `control` positions by OpenSubdiv's CPU evaluator.
    pub fn evaluate_cpu(&self, control: &[[f32; 3]]) -> Result<Vec<[f32; 3]>> {
        if control.len() != self.control_vertices {
            bail!(
                "{} control positions for a mesh of {} vertices",
                control.len(),
                self.control_vertices
            );
        }
        let mut src = osd::CpuVertexBuffer::new(3, control.len())?;
        src.update_data(control.as_flattened(), 0, control.len())?;
        let mut dst = osd::CpuVertexBuffer::new(3, self.vertex_count())?;
        let desc = osd::BufferDescriptor::new(0, 3, 3)?;
        osd::cpu_evaluator::evaluate_stencils(&src, desc, &mut dst, desc, &self.table)?;
        Ok(dst
            .bind_cpu_buffer()?
            .chunks_exact(3)
            .map(|p| [p[0], p[1], p[2]])
            .collect())
    }
}

/// opensubdiv-petite's GPU stencil evaluator on its own wgpu 29 device, on the adapter the
/// toolkit measures on, with a timestamp bracket around its dispatch.
pub struct GpuEvaluator {
    device: wgpu::Device,
    queue: wgpu::Queue,
    pipeline: osd::wgpu::StencilEvalPipeline,
    queries: wgpu::QuerySet,
    resolved: wgpu::Buffer,
    /// The adapter's name, as wgpu 29 reports it.
    pub adapter: String,
}

/// The workgroup size of OpenSubdiv's stencil kernel (`StencilEvalConfig`'s default): stencils
/// per workgroup.
const STENCILS_PER_GROUP: u32 = 64;

/// A [`Refinement`]'s stencils and positions on the [`GpuEvaluator`]'s device.
pub struct GpuRefinement {
    table: osd::wgpu::StencilTableGpu,
    control: wgpu::Buffer,
    refined: wgpu::Buffer,
}

impl GpuEvaluator {
    /// The evaluator on the adapter named `adapter` (the toolkit's, through wgpu 30), which must
    /// offer timestamp queries.
    pub fn new(adapter: &str) -> Result<Self> {
        let instance = wgpu::Instance::new(wgpu::InstanceDescriptor {
            backends: wgpu::Backends::from_env().unwrap_or(wgpu::Backends::PRIMARY),
            ..wgpu::InstanceDescriptor::new_without_display_handle()
        });
        let adapters = pollster::block_on(instance.enumerate_adapters(wgpu::Backends::all()));
        let names: Vec<String> = adapters.iter().map(|a| a.get_info().name).collect();
        let chosen = adapters
            .into_iter()
            .find(|a| a.get_info().name == adapter)
            .with_context(|| format!("wgpu 29 sees no adapter {adapter:?} (it sees {names:?})"))?;
        if !chosen.features().contains(wgpu::Features::TIMESTAMP_QUERY) {
            bail!("{adapter} has no timestamp queries: OpenSubdiv's GPU time cannot be measured");
        }
        let (device, queue) = pollster::block_on(chosen.request_device(&wgpu::DeviceDescriptor {
            label: Some("opensubdiv"),
            required_features: wgpu::Features::TIMESTAMP_QUERY,
            required_limits: chosen.limits(),
            ..Default::default()
        }))?;
        let config = osd::wgpu::WgslModuleConfig {
            workgroup_size: std::num::NonZeroU32::new(STENCILS_PER_GROUP).context("workgroup")?,
        };
        let pipeline = osd::wgpu::StencilEvalPipeline::new(&device, config);
        let queries = device.create_query_set(&wgpu::QuerySetDescriptor {
            label: Some("opensubdiv bracket"),
            ty: wgpu::QueryType::Timestamp,
            count: 2,
        });
        let resolved = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("opensubdiv bracket"),
            size: 16,
            usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        Ok(Self {
            device,
            queue,
            pipeline,
            queries,
            resolved,
            adapter: adapter.to_owned(),
        })
    }

    /// Uploads `refinement`'s stencil table and the `control` positions; an `Err` where a table
    /// is larger than one storage binding of the device may be.
    pub fn bind(&self, refinement: &Refinement, control: &[[f32; 3]]) -> Result<GpuRefinement> {
        let limit = self.device.limits().max_storage_buffer_binding_size;
        let t = &refinement.table;
        for (what, count) in [
            ("indices", t.control_indices().len()),
            ("weights", t.weights().len()),
            ("refined positions", 3 * refinement.vertex_count()),
        ] {
            let bytes = 4 * count as u64;
            if bytes > limit {
                bail!(
                    "its stencil {what} take {bytes} bytes, more than one storage binding of {} ({limit})",
                    self.adapter
                );
            }
        }
        let table = osd::wgpu::StencilTableGpu::from_cpu(&self.device, &refinement.table)?;
        let control = self
            .device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("opensubdiv control"),
                contents: bytemuck::cast_slice(control.as_flattened()),
                usage: wgpu::BufferUsages::STORAGE,
            });
        let refined = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("opensubdiv refined"),
            size: (refinement.vertex_count() * 12).max(4) as u64,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        Ok(GpuRefinement {
            table,
            control,
            refined,
        })
    }

    /// One evaluation of every stencil; its GPU time in ms: from the end of an empty pass
    /// before OpenSubdiv's dispatch to the beginning of one after it. Its kernel runs one
    /// invocation per stencil in 64-wide workgroups along x alone: a dispatch holds at most the
    /// device's workgroups per dimension (65 535 by default, 4.2 M stencils), so larger tables
    /// go in batches of that many.
    pub fn evaluate(&self, g: &GpuRefinement) -> Result<f64> {
        let groups = self.device.limits().max_compute_workgroups_per_dimension;
        self.evaluate_in_batches(g, groups * STENCILS_PER_GROUP)
    }

    /// [`GpuEvaluator::evaluate`] in batches of `batch` stencils (its `batch_range`), one pass
    /// each.
    pub fn evaluate_in_batches(&self, g: &GpuRefinement, batch: u32) -> Result<f64> {
        if batch == 0 {
            bail!("a batch of OpenSubdiv's stencils must hold at least one");
        }
        // wgpu 29 panics on an error nobody captures: a refused dispatch becomes an `Err`.
        let scope = self.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let mut encoder = self.device.create_command_encoder(&Default::default());
        let bracket = |encoder: &mut wgpu::CommandEncoder, before: bool| {
            encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("opensubdiv bracket"),
                timestamp_writes: Some(wgpu::ComputePassTimestampWrites {
                    query_set: &self.queries,
                    beginning_of_pass_write_index: (!before).then_some(1),
                    end_of_pass_write_index: before.then_some(0),
                }),
            });
        };
        bracket(&mut encoder, true);
        let desc = osd::BufferDescriptor::new(0, 3, 3)?;
        for start in (0..g.table.stencil_count).step_by(batch as usize) {
            self.pipeline.encode(
                &self.device,
                &mut encoder,
                &g.table,
                &g.control,
                &g.refined,
                desc,
                desc,
                start..g.table.stencil_count.min(start + batch),
            )?;
        }
        bracket(&mut encoder, false);
        encoder.resolve_query_set(&self.queries, 0..2, &self.resolved, 0);
        let commands = encoder.finish();
        if let Some(e) = pollster::block_on(scope.pop()) {
            bail!("wgpu refused OpenSubdiv's evaluation: {e}");
        }
        self.queue.submit([commands]);
        let ticks: Vec<u64> = bytemuck::pod_collect_to_vec(&self.read_bytes(&self.resolved)?);
        let period = f64::from(self.queue.get_timestamp_period());
        Ok(ticks[1].wrapping_sub(ticks[0]) as f64 * period * 1e-6)
    }

    /// The refined positions of the last [`GpuEvaluator::evaluate`].
    pub fn read(&self, g: &GpuRefinement) -> Result<Vec<[f32; 3]>> {
        let values: Vec<f32> = bytemuck::pod_collect_to_vec(&self.read_bytes(&g.refined)?);
        Ok(values.chunks_exact(3).map(|p| [p[0], p[1], p[2]]).collect())
    }

    fn read_bytes(&self, buffer: &wgpu::Buffer) -> Result<Vec<u8>> {
        let staging = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("opensubdiv readback"),
            size: buffer.size(),
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut encoder = self.device.create_command_encoder(&Default::default());
        encoder.copy_buffer_to_buffer(buffer, 0, &staging, 0, buffer.size());
        self.queue.submit([encoder.finish()]);
        let (sender, receiver) = std::sync::mpsc::channel();
        staging
            .slice(..)
            .map_async(wgpu::MapMode::Read, move |r| drop(sender.send(r)));
        self.device.poll(wgpu::PollType::wait_indefinitely())?;
        receiver.recv()??;
        let bytes = staging.slice(..).get_mapped_range().to_vec();
        Ok(bytes)
    }
}
