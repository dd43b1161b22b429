//! Loop subdivision per frame from the (animated) control mesh (Holländer 2013 ch. 2, the
//! basis-function tables of [`subdiv_bft`]): [`prepare`] keeps each control mesh in the scene
//! and appends its uniform tessellation at one level as another mesh, texture coordinates and
//! vertex colours evaluated through the same stencils as the positions; the renderer
//! ([`crate::gpu::GpuRenderer::set_subdivision`]) hides the control meshes and, every frame
//! after the skinning, gathers their vertices into M⁰ (`shaders/pipeline/subdivision.wgsl`),
//! runs the initial and main steps on the GPU and writes the limit surface's positions and
//! normals into the refined meshes (adaptive tessellation, §2.4: the screen-space factors for
//! the frame's camera first, and the triangles too, the slots past them degenerate).
//! [`SubdivisionPlan::refine_cpu`] is the CPU twin (the posed scene's refined meshes, for what
//! the CPU builds from the scene: VPLs, BVHs, surfels).
//!
//! A mesh is welded by bit-identical positions first (its texture seams joined), so a vertex
//! on a seam takes the texture coordinates of one side: textures across seams are stretched
//! over the seam's triangles. Tangents are not subdivided (a normal map on a subdivided mesh
//! is not applied).

use ::gpu::kernel::{self, Binding, Layout, Passes, Workgroups};
use ::gpu::{PassTimer, transfer};
use glam::{Vec2, Vec3};
use scene::Camera;
use scene::{Mesh, Scene};
use subdiv_bft::adaptive::ScreenView;
use subdiv_bft::gpu::{GpuAdaptive, GpuLevel, GpuSubdivider};
use subdiv_bft::{BftSet, Subdivider, TriMesh};

use crate::RenderError;

/// One subdivided mesh: its control and refined meshes in the prepared scene, the render
/// vertex each welded M⁰ vertex is gathered from, and its subdivider.
#[derive(Clone, Debug)]
struct Subdivided {
    control: usize,
    refined: usize,
    vertices: usize,
    /// Index slots of the refined mesh (the uniform tessellation's count).
    index_slots: usize,
    welded_from: Vec<u32>,
    sub: Subdivider,
}

/// How the refined meshes are tessellated.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Tessellation {
    /// Every patch at the plan's level.
    Uniform,
    /// Each M¹ edge split so its fine edges are about `target_pixels` long on screen for the
    /// frame's camera, up to the plan's level (Holländer 2013 §2.4; `subdiv_bft::adaptive`).
    /// Needs [`subdiv_bft::adaptive_device_needs`].
    Adaptive {
        /// Wanted fine-edge length in pixels.
        target_pixels: f32,
    },
}

/// Which meshes are subdivided to which level and how ([`prepare`]), with the tables.
#[derive(Clone, Debug)]
pub struct SubdivisionPlan {
    level: u32,
    tessellation: Tessellation,
    bft: BftSet,
    meshes: Vec<Subdivided>,
}

fn subdiv_error(mesh: &Mesh, e: subdiv_bft::SubdivError) -> RenderError {
    RenderError::Subdivision(format!("mesh {:?}: {e}", mesh.name))
}

/// The scene with `meshes` (indices into `scene.meshes`) subdivided to surface `level`
/// (1 = M¹; at most the tables' level + 1; adaptive: the finest level) as `tessellation` says:
/// each control mesh stays where it is (its index, the rig's deformers) and its refined mesh
/// is appended, evaluated uniformly at `level` at the control mesh's current positions (for
/// adaptive tessellation: the vertex layout every adaptive frame writes into, and as many
/// triangle slots). Render the returned scene with
/// [`crate::gpu::GpuRenderer::set_subdivision`]; give what the CPU builds from the scene
/// [`SubdivisionPlan::drawn`] after [`SubdivisionPlan::refine_cpu`].
pub fn prepare(
    scene: &Scene,
    meshes: &[usize],
    (level, tessellation): (u32, Tessellation),
    bft: BftSet,
) -> Result<(Scene, SubdivisionPlan), RenderError> {
    if let Tessellation::Adaptive { target_pixels } = tessellation
        && !(target_pixels.is_finite() && target_pixels > 0.0)
    {
        return Err(RenderError::Subdivision(format!(
            "adaptive target of {target_pixels} pixels: give a positive length"
        )));
    }
    let mut prepared = scene.clone();
    let mut plan = SubdivisionPlan {
        level,
        tessellation,
        bft,
        meshes: Vec::new(),
    };
    for &k in meshes {
        let mesh = scene.meshes.get(k).ok_or_else(|| {
            RenderError::Subdivision(format!(
                "mesh {k}: the scene has {} meshes",
                scene.meshes.len()
            ))
        })?;
        if plan.meshes.iter().any(|m| m.control == k) {
            return Err(RenderError::Subdivision(format!("mesh {k} given twice")));
        }
        let (control, welded_from) =
            TriMesh::welding(&mesh.positions, &mesh.indices).map_err(|e| subdiv_error(mesh, e))?;
        let sub =
            Subdivider::new(&control.topology, &plan.bft).map_err(|e| subdiv_error(mesh, e))?;
        let mut subdivided = Subdivided {
            control: k,
            refined: prepared.meshes.len(),
            vertices: 0,
            index_slots: 0,
            welded_from,
            sub,
        };
        let refined = plan.uniform(&subdivided, mesh)?;
        subdivided.vertices = refined.positions.len();
        subdivided.index_slots = refined.indices.len();
        let gathered = |values: &dyn Fn(usize) -> Vec3| -> Vec<Vec3> {
            subdivided
                .welded_from
                .iter()
                .map(|&v| values(v as usize))
                .collect()
        };
        let through_stencils = |values: Vec<Vec3>| {
            subdivided
                .sub
                .evaluate_cpu(&plan.bft, &values, level)
                .map(|r| r.positions)
                .map_err(|e| subdiv_error(mesh, e))
        };
        let uvs = through_stencils(gathered(&|v| mesh.uvs[v].extend(0.0)))?;
        let uvs1 = if mesh.uvs1.is_empty() {
            Vec::new()
        } else {
            through_stencils(gathered(&|v| mesh.uvs1[v].extend(0.0)))?
        };
        let colors = if mesh.colors.is_empty() {
            Vec::new()
        } else {
            let rgb = through_stencils(gathered(&|v| mesh.colors[v].truncate()))?;
            rgb.into_iter().map(|c| c.extend(1.0)).collect()
        };
        prepared.meshes.push(Mesh {
            name: format!("{} (Loop level {level})", mesh.name),
            positions: refined.positions,
            normals: refined.normals,
            uvs: uvs.into_iter().map(|p| Vec2::new(p.x, p.y)).collect(),
            uvs1: uvs1.into_iter().map(|p| Vec2::new(p.x, p.y)).collect(),
            colors,
            indices: refined.indices,
            material: mesh.material,
            ..Default::default()
        });
        plan.meshes.push(subdivided);
    }
    prepared
        .validate()
        .map_err(|e| RenderError::Subdivision(e.to_string()))?;
    Ok((prepared, plan))
}

impl SubdivisionPlan {
    /// The surface level.
    pub fn level(&self) -> u32 {
        self.level
    }

    /// The control meshes (indices into the prepared scene's meshes).
    pub fn controls(&self) -> impl Iterator<Item = usize> + '_ {
        self.meshes.iter().map(|m| m.control)
    }

    /// How the refined meshes are tessellated.
    pub fn tessellation(&self) -> Tessellation {
        self.tessellation
    }

    /// M⁰ of `m`: `control`'s current positions at the welded vertices.
    fn m0(m: &Subdivided, control: &Mesh) -> Vec<Vec3> {
        m.welded_from
            .iter()
            .map(|&v| control.positions[v as usize])
            .collect()
    }

    /// The uniform tessellation of `m` at the plan's level from `control` (CPU).
    fn uniform(&self, m: &Subdivided, control: &Mesh) -> Result<subdiv_bft::Refined, RenderError> {
        m.sub
            .evaluate_cpu(&self.bft, &Self::m0(m, control), self.level)
            .map_err(|e| subdiv_error(control, e))
    }

    /// The CPU twin of the frame's subdivision: every refined mesh of `prepared` (the scene
    /// [`prepare`] returned, its control meshes posed as the frame poses them) evaluated again
    /// from its control mesh — adaptively for `camera` over a `size` image (the frame's), its
    /// triangles those the factors keep.
    pub fn refine_cpu(
        &self,
        prepared: &mut Scene,
        camera: &Camera,
        size: (u32, u32),
    ) -> Result<(), RenderError> {
        for m in &self.meshes {
            let control = &prepared.meshes[m.control];
            let refined = match self.tessellation {
                Tessellation::Uniform => self.uniform(m, control)?,
                Tessellation::Adaptive { target_pixels } => {
                    let error = |e| subdiv_error(control, e);
                    let m0 = Self::m0(m, control);
                    let s_max = m.sub.segments(self.level).map_err(error)?;
                    let (p1, _) = m.sub.initial_step_f32(&m0).map_err(error)?;
                    let view = screen_view(camera, size, target_pixels);
                    let factors =
                        subdiv_bft::adaptive::screen_factors(&m.sub.m1, &p1, &view, s_max);
                    let mut r = m
                        .sub
                        .evaluate_adaptive_cpu(&self.bft, &m0, &factors, self.level)
                        .map_err(error)?;
                    // The kept triangles first, the other slots degenerate, as the GPU fills
                    // them (the upload keeps every slot; `drawn` drops the degenerate ones).
                    r.indices = r
                        .indices
                        .chunks_exact(3)
                        .filter(|t| !degenerate(t))
                        .flatten()
                        .copied()
                        .collect();
                    r.indices.resize(m.index_slots, 0);
                    r
                }
            };
            let adaptive = matches!(self.tessellation, Tessellation::Adaptive { .. });
            let mesh = &mut prepared.meshes[m.refined];
            mesh.positions = refined.positions;
            mesh.normals = refined.normals;
            if adaptive {
                mesh.indices = refined.indices;
            }
        }
        Ok(())
    }

    /// The control meshes as a proxy of the limit surface: `prepared` without the refined
    /// meshes (and without the rig). Cheap to pose every frame — no subdivision, few triangles
    /// for a BVH — for what the CPU rebuilds per frame (VPLs traced against it, ManyLoD surfels
    /// sampled on it and refit to its posed triangles); the limit surface lies within the
    /// control mesh's hull, a subdivision step or so away, so surfel visibility of points on it
    /// may be off by that much.
    pub fn proxy(&self, prepared: &Scene) -> Scene {
        without(prepared.clone(), self.meshes.iter().map(|m| m.refined))
    }

    /// What is drawn of `prepared`: the scene without the control meshes (and without the rig,
    /// whose mesh indices are `prepared`'s), for what the CPU builds from the scene — VPLs,
    /// BVHs, surfels, shadows.
    pub fn drawn(&self, prepared: &Scene) -> Scene {
        let mut drawn = prepared.clone();
        for m in &self.meshes {
            let mesh = &mut drawn.meshes[m.refined];
            mesh.indices = mesh
                .indices
                .chunks_exact(3)
                .filter(|t| !degenerate(t))
                .flatten()
                .copied()
                .collect();
        }
        without(drawn, self.meshes.iter().map(|m| m.control))
    }
}

/// `scene` without the meshes `removed` and without its rig (whose mesh indices they change).
fn without(mut scene: Scene, removed: impl Iterator<Item = usize>) -> Scene {
    scene.rig = None;
    let mut removed: Vec<usize> = removed.collect();
    removed.sort_unstable();
    for k in removed.into_iter().rev() {
        scene.meshes.remove(k);
    }
    scene
}

/// A triangle with a repeated vertex (an adaptive tessellation's collapsed or unused slot).
fn degenerate(t: &[u32]) -> bool {
    t[0] == t[1] || t[1] == t[2] || t[2] == t[0]
}

/// The screen-space view of the adaptive factors: `camera` over a `size` image.
fn screen_view(camera: &Camera, size: (u32, u32), target_pixels: f32) -> ScreenView {
    ScreenView {
        view_proj: camera.view_projection(size.0 as f32 / size.1.max(1) as f32),
        viewport: size,
        target_pixels,
    }
}

/// `subdivision.wgsl`'s `Params`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct Params {
    count: u32,
    base: u32,
    _pad: [u32; 2],
}

const WORKGROUP: u32 = 64;

/// A mesh's tessellation on the GPU: a uniform level's buffers, or the adaptive buffers with
/// where the refined mesh's triangles are in the scene's index buffer (byte offset).
enum Output {
    Uniform(GpuLevel),
    Adaptive(GpuAdaptive, u64, IndirectDraw),
}

/// The refined mesh's indirect draw of its appended triangles: the mesh and its arguments
/// (the count copied in each frame).
struct IndirectDraw {
    mesh: usize,
    args: wgpu::Buffer,
}

/// One mesh's subdivision on the GPU: the subdivider, its output and the gather and scatter
/// dispatches.
struct GpuMesh {
    subdivider: GpuSubdivider,
    output: Output,
    gather: Passes,
    scatter: Passes,
}

/// The frame's subdivision stage: every mesh of a plan, bound to the uploaded scene.
pub(crate) struct SubdivisionStage {
    meshes: Vec<GpuMesh>,
    tessellation: Tessellation,
    scene_indices: wgpu::Buffer,
}

impl SubdivisionStage {
    /// Builds the subdivision of `plan`'s meshes into `scene` (uploaded from the scene
    /// [`prepare`] returned); the caller hides the control meshes.
    pub(crate) fn new(
        device: &wgpu::Device,
        plan: &SubdivisionPlan,
        scene: &gbuffer::gpu::GpuScene,
    ) -> Result<Self, RenderError> {
        let module = crate::SHADERS.module(device, "subdivision.wgsl")?;
        let gather_layout = Layout::compute_numbered(
            device,
            "subdivision gather",
            &[
                (0, Binding::Uniform),
                (1, Binding::StorageRead),
                (2, Binding::Storage),
                (5, Binding::Storage),
            ],
        );
        let scatter_layout = Layout::compute_numbered(
            device,
            "subdivision scatter",
            &[
                (0, Binding::Uniform),
                (3, Binding::StorageRead),
                (4, Binding::StorageRead),
                (5, Binding::Storage),
                (6, Binding::Storage),
            ],
        );
        let gather = kernel::pipeline(device, &module, "gather", &[&gather_layout], &[]);
        let scatter = kernel::pipeline(device, &module, "scatter", &[&scatter_layout], &[]);
        let [positions, attributes] = scene.vertex_buffers();
        let base = |mesh: usize| {
            scene.base_vertex(mesh).ok_or_else(|| {
                RenderError::Subdivision(format!("mesh {mesh} is not in the uploaded scene"))
            })
        };
        let params = |count: u32, base: u32| {
            transfer::buffer_init(
                device,
                "subdivision params",
                bytemuck::bytes_of(&Params {
                    count,
                    base,
                    _pad: [0; 2],
                }),
                wgpu::BufferUsages::UNIFORM,
            )
        };
        let mut meshes = Vec::new();
        for m in &plan.meshes {
            let error = |e: subdiv_bft::SubdivError| RenderError::Subdivision(e.to_string());
            let subdivider = GpuSubdivider::new(device, &m.sub, &plan.bft).map_err(error)?;
            let (output, vertex_count, [fine_positions, fine_normals]) = match plan.tessellation {
                Tessellation::Uniform => {
                    let level = subdivider
                        .level(device, &m.sub, plan.level)
                        .map_err(error)?;
                    let (n, buffers) = (level.vertex_count, [&level.positions, &level.normals]);
                    let buffers = buffers.map(Clone::clone);
                    (Output::Uniform(level), n, buffers)
                }
                Tessellation::Adaptive { .. } => {
                    let a = subdivider
                        .adaptive(device, &m.sub, plan.level)
                        .map_err(error)?;
                    let (_, first, count) = scene.indices(m.refined).ok_or_else(|| {
                        RenderError::Subdivision(format!("mesh {} is not uploaded", m.refined))
                    })?;
                    if u64::from(count) * 4 != a.indices.size() {
                        return Err(RenderError::Subdivision(format!(
                            "mesh {}: {count} index slots for {} adaptive indices",
                            m.refined,
                            a.indices.size() / 4
                        )));
                    }
                    let (n, buffers) = (a.vertex_capacity, [&a.positions, &a.normals]);
                    let buffers = buffers.map(Clone::clone);
                    let args = transfer::buffer_init(
                        device,
                        "adaptive mesh draw arguments",
                        bytemuck::cast_slice(&[0, 1, first, base(m.refined)?, 0]),
                        wgpu::BufferUsages::INDIRECT | wgpu::BufferUsages::COPY_DST,
                    )?;
                    let draw = IndirectDraw {
                        mesh: m.refined,
                        args,
                    };
                    (Output::Adaptive(a, u64::from(first) * 4, draw), n, buffers)
                }
            };
            if vertex_count as usize != m.vertices {
                return Err(RenderError::Subdivision(format!(
                    "level {}: {vertex_count} vertices on the GPU, {} in the refined mesh",
                    plan.level, m.vertices
                )));
            }
            let welded = m.welded_from.len() as u32;
            let welded_from = transfer::buffer_init(
                device,
                "welded from",
                bytemuck::cast_slice(&m.welded_from),
                wgpu::BufferUsages::STORAGE,
            )?;
            let gather_params = params(welded, base(m.control)?)?;
            let gather_group = gather_layout.bind_buffers(
                device,
                &[
                    &gather_params,
                    &welded_from,
                    &subdivider.m0_positions,
                    positions,
                ],
            );
            let scatter_params = params(vertex_count, base(m.refined)?)?;
            let scatter_group = scatter_layout.bind_buffers(
                device,
                &[
                    &scatter_params,
                    &fine_positions,
                    &fine_normals,
                    positions,
                    attributes,
                ],
            );
            meshes.push(GpuMesh {
                gather: Passes::one(
                    "subdivision gather",
                    &gather,
                    vec![gather_group],
                    Workgroups::linear(welded, WORKGROUP),
                ),
                scatter: Passes::one(
                    "subdivision scatter",
                    &scatter,
                    vec![scatter_group],
                    Workgroups::linear(vertex_count, WORKGROUP),
                ),
                subdivider,
                output,
            });
        }
        let scene_indices = match scene.indices(0) {
            Some((buffer, _, _)) => buffer.clone(),
            None => return Err(RenderError::Subdivision("the scene has no meshes".into())),
        };
        Ok(Self {
            meshes,
            tessellation: plan.tessellation,
            scene_indices,
        })
    }

    /// The refined meshes drawn indirectly (adaptive) and their draw arguments, for
    /// [`gbuffer::gpu::GpuScene::draw_indirect`].
    pub(crate) fn indirect_draws(&self) -> impl Iterator<Item = (usize, &wgpu::Buffer)> {
        self.meshes.iter().filter_map(|m| match &m.output {
            Output::Adaptive(_, _, draw) => Some((draw.mesh, &draw.args)),
            Output::Uniform(_) => None,
        })
    }

    /// Sets the view of the adaptive factors: `camera` over a `size` frame.
    pub(crate) fn set_camera(
        &self,
        queue: &wgpu::Queue,
        camera: &Camera,
        size: (u32, u32),
    ) -> Result<(), RenderError> {
        let Tessellation::Adaptive { target_pixels } = self.tessellation else {
            return Ok(());
        };
        let view = screen_view(camera, size, target_pixels);
        for m in &self.meshes {
            if let Output::Adaptive(a, _, _) = &m.output {
                a.set_view(queue, &view)
                    .map_err(|e| RenderError::Subdivision(e.to_string()))?;
            }
        }
        Ok(())
    }

    /// Records every mesh's gather, initial and main steps (adaptive: the factors first, and
    /// the triangles copied into the scene's index buffer) and scatter.
    pub(crate) fn encode(&self, encoder: &mut wgpu::CommandEncoder, timer: &PassTimer) {
        for m in &self.meshes {
            m.gather.encode(encoder, Some(timer));
            match &m.output {
                Output::Uniform(level) => m.subdivider.encode(encoder, level, Some(timer)),
                Output::Adaptive(a, offset, draw) => {
                    m.subdivider.encode_initial(encoder, Some(timer));
                    m.subdivider.encode_screen_factors(encoder, a, Some(timer));
                    // The slots past the appended triangles stay (0, 0, 0): degenerate.
                    encoder.clear_buffer(&a.indices, 0, None);
                    m.subdivider.encode_adaptive(encoder, a, Some(timer));
                    let bytes = a.indices.size();
                    encoder.copy_buffer_to_buffer(
                        &a.indices,
                        0,
                        &self.scene_indices,
                        *offset,
                        bytes,
                    );
                    encoder.copy_buffer_to_buffer(&a.draw_args, 0, &draw.args, 0, 4);
                }
            }
            m.scatter.encode(encoder, Some(timer));
        }
    }
}
