//! Loop subdivision per frame from the (animated) control mesh (Holländer 2013 ch. 2, the
//! basis-function tables of [`subdiv_bft`]): [`prepare`] keeps each control mesh in the scene
//! and appends its uniform tessellation at one level as another mesh, texture coordinates and
//! vertex colours evaluated through the same stencils as the positions; the renderer
//! ([`crate::gpu::GpuRenderer::set_subdivision`]) hides the control meshes and, every frame
//! after the skinning, gathers their vertices into M⁰ (`shaders/pipeline/subdivision.wgsl`),
//! runs the initial and main steps on the GPU and writes the limit surface's positions and
//! normals into the refined meshes. [`SubdivisionPlan::refine_cpu`] is the CPU twin (the
//! posed scene's refined meshes, for what the CPU builds from the scene: VPLs, BVHs, surfels).
//!
//! A mesh is welded by bit-identical positions first (its texture seams joined), so a vertex
//! on a seam takes the texture coordinates of one side: textures across seams are stretched
//! over the seam's triangles. Tangents are not subdivided (a normal map on a subdivided mesh
//! is not applied).

use ::gpu::kernel::{self, Binding, Layout, Passes, Workgroups};
use ::gpu::{PassTimer, transfer};
use glam::{Vec2, Vec3};
use scene::{Mesh, Scene};
use subdiv_bft::gpu::{GpuLevel, GpuSubdivider};
use subdiv_bft::{BftSet, Subdivider, TriMesh};

use crate::RenderError;

/// One subdivided mesh: its control and refined meshes in the prepared scene, the render
/// vertex each welded M⁰ vertex is gathered from, and its subdivider.
#[derive(Clone, Debug)]
struct Subdivided {
    control: usize,
    refined: usize,
    vertices: usize,
    welded_from: Vec<u32>,
    sub: Subdivider,
}

/// Which meshes are subdivided to which level ([`prepare`]), with the tables.
#[derive(Clone, Debug)]
pub struct SubdivisionPlan {
    level: u32,
    bft: BftSet,
    meshes: Vec<Subdivided>,
}

fn subdiv_error(mesh: &Mesh, e: subdiv_bft::SubdivError) -> RenderError {
    RenderError::Subdivision(format!("mesh {:?}: {e}", mesh.name))
}

/// The scene with `meshes` (indices into `scene.meshes`) subdivided uniformly to surface
/// `level` (1 = M¹; at most the tables' level + 1): each control mesh stays where it is (its
/// index, the rig's deformers) and its refined mesh is appended, evaluated at the control
/// mesh's current positions. Render the returned scene with
/// [`crate::gpu::GpuRenderer::set_subdivision`]; give what the CPU builds from the scene
/// [`SubdivisionPlan::drawn`].
pub fn prepare(
    scene: &Scene,
    meshes: &[usize],
    level: u32,
    bft: BftSet,
) -> Result<(Scene, SubdivisionPlan), RenderError> {
    let mut prepared = scene.clone();
    let mut plan = SubdivisionPlan {
        level,
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
            welded_from,
            sub,
        };
        let refined = plan.refine(&subdivided, mesh)?;
        subdivided.vertices = refined.positions.len();
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

    /// The refined mesh of `m` from `control`'s current positions (CPU).
    fn refine(&self, m: &Subdivided, control: &Mesh) -> Result<subdiv_bft::Refined, RenderError> {
        let m0: Vec<Vec3> = m
            .welded_from
            .iter()
            .map(|&v| control.positions[v as usize])
            .collect();
        m.sub
            .evaluate_cpu(&self.bft, &m0, self.level)
            .map_err(|e| subdiv_error(control, e))
    }

    /// The CPU twin of the frame's subdivision: every refined mesh of `prepared` (the scene
    /// [`prepare`] returned, its control meshes posed as the frame poses them) evaluated again
    /// from its control mesh.
    pub fn refine_cpu(&self, prepared: &mut Scene) -> Result<(), RenderError> {
        for m in &self.meshes {
            let refined = self.refine(m, &prepared.meshes[m.control])?;
            let mesh = &mut prepared.meshes[m.refined];
            mesh.positions = refined.positions;
            mesh.normals = refined.normals;
        }
        Ok(())
    }

    /// What is drawn of `prepared`: the scene without the control meshes (and without the rig,
    /// whose mesh indices are `prepared`'s), for what the CPU builds from the scene — VPLs,
    /// BVHs, surfels, shadows.
    pub fn drawn(&self, prepared: &Scene) -> Scene {
        let mut drawn = prepared.clone();
        drawn.rig = None;
        let mut controls: Vec<usize> = self.meshes.iter().map(|m| m.control).collect();
        controls.sort_unstable();
        for k in controls.into_iter().rev() {
            drawn.meshes.remove(k);
        }
        drawn
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

/// One mesh's subdivision on the GPU: the subdivider, its level's buffers and the gather and
/// scatter dispatches.
struct GpuMesh {
    subdivider: GpuSubdivider,
    level: GpuLevel,
    gather: Passes,
    scatter: Passes,
}

/// The frame's subdivision stage: every mesh of a plan, bound to the uploaded scene.
pub(crate) struct SubdivisionStage {
    meshes: Vec<GpuMesh>,
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
            let level = subdivider
                .level(device, &m.sub, plan.level)
                .map_err(error)?;
            if level.vertex_count as usize != m.vertices {
                return Err(RenderError::Subdivision(format!(
                    "level {}: {} vertices on the GPU, {} in the refined mesh",
                    plan.level, level.vertex_count, m.vertices
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
            let scatter_params = params(level.vertex_count, base(m.refined)?)?;
            let scatter_group = scatter_layout.bind_buffers(
                device,
                &[
                    &scatter_params,
                    &level.positions,
                    &level.normals,
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
                    Workgroups::linear(level.vertex_count, WORKGROUP),
                ),
                subdivider,
                level,
            });
        }
        Ok(Self { meshes })
    }

    /// Records every mesh's gather, initial and main steps and scatter.
    pub(crate) fn encode(&self, encoder: &mut wgpu::CommandEncoder, timer: &PassTimer) {
        for m in &self.meshes {
            m.gather.encode(encoder, Some(timer));
            m.subdivider.encode(encoder, &m.level, Some(timer));
            m.scatter.encode(encoder, Some(timer));
        }
    }
}
