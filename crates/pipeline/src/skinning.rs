//! Skinning and morphing on the GPU, the frame's first stage (`skinning.wgsl`): the rest
//! vertices of every mesh a [`Rig`] moves, their joints, weights and morph displacements are
//! uploaded once ([`Skinning::bind`]); each frame writes only the pose's joint matrices and
//! morph weights ([`BoundSkinning::set_pose`]) and one dispatch rewrites the moved vertices in
//! the scene's vertex buffers ([`GpuScene::vertex_buffers`]). The CPU twin is
//! [`Rig::deform`].

use ::gpu::kernel::{Binding, Kernel, Passes, Workgroups};
use ::gpu::{PassTimer, transfer};
use gbuffer::gpu::GpuScene;
use scene::animation::{Pose, Rig};

use crate::RenderError;

/// A moved vertex as `skinning.wgsl`'s `SkinVertex` reads it.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuSkinVertex {
    /// Rest position (object space).
    pub position: [f32; 3],
    /// Its vertex in the scene's buffers.
    pub vertex: u32,
    /// Rest normal.
    pub normal: [f32; 3],
    /// Its deformer.
    pub deformer: u32,
    /// Rest tangent (zero where the mesh has none).
    pub tangent: [f32; 4],
    /// Joint indices into its deformer's joints.
    pub joints: [u32; 4],
    /// Joint weights.
    pub weights: [f32; 4],
}

/// A moved mesh as `skinning.wgsl`'s `Deformer` reads it.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuDeformer {
    /// First joint matrix.
    pub first_joint: u32,
    /// Joint matrices.
    pub joint_count: u32,
    /// First displacement (three a vertex and target).
    pub first_delta: u32,
    /// Morph targets.
    pub targets: u32,
    /// First morph weight.
    pub first_weight: u32,
    /// First vertex in the skinning's vertex list.
    pub first_vertex: u32,
    /// 1 when tangents move.
    pub tangents: u32,
    /// Padding.
    pub _pad: u32,
}

/// `skinning.wgsl`: vertices, deformers, displacements, joint matrices, morph weights (read);
/// scene positions and attributes (written).
const BINDINGS: [Binding; 7] = [
    Binding::StorageRead,
    Binding::StorageRead,
    Binding::StorageRead,
    Binding::StorageRead,
    Binding::StorageRead,
    Binding::Storage,
    Binding::Storage,
];

/// Threads of a workgroup (`WORKGROUP` in the shader).
const WORKGROUP: u32 = 64;

/// The skinning kernel.
pub struct Skinning {
    kernel: Kernel,
}

/// Where one deformer's pose goes in the per-frame buffers.
struct Slots {
    first_joint: usize,
    first_weight: usize,
    targets: usize,
}

/// The skinning bound to one rig and one uploaded scene.
pub struct BoundSkinning {
    passes: Passes,
    joints: wgpu::Buffer,
    weights: wgpu::Buffer,
    slots: Vec<Slots>,
}

impl Skinning {
    /// Builds the pipeline.
    pub fn new(device: &wgpu::Device) -> Result<Self, RenderError> {
        let module = crate::SHADERS.module(device, "skinning.wgsl")?;
        Ok(Self {
            kernel: Kernel::new(device, &module, "skin", &BINDINGS, &[]),
        })
    }

    /// Uploads `rig`'s rest vertices for `scene` (uploaded from the scene that holds `rig`) and
    /// binds them.
    pub fn bind(
        &self,
        device: &wgpu::Device,
        rig: &Rig,
        scene: &GpuScene,
    ) -> Result<BoundSkinning, RenderError> {
        let [positions, attributes] = scene.vertex_buffers();
        let mut vertices = Vec::new();
        let mut deformers = Vec::new();
        let mut deltas: Vec<[f32; 4]> = Vec::new();
        let mut slots = Vec::new();
        let (mut joints, mut weights) = (0usize, 0usize);
        let too_many = || RenderError::Animation("more than 2^32 moved vertices".into());
        for (i, d) in rig.deformers.iter().enumerate() {
            let base = scene.base_vertex(d.mesh as usize).ok_or_else(|| {
                RenderError::Animation(format!(
                    "the rig moves mesh {}, which the upload lacks",
                    d.mesh
                ))
            })?;
            let joint_count = match d.joints {
                scene::animation::Joints::Skin(s) => rig.skins[s as usize].joints.len(),
                scene::animation::Joints::Node(_) => 1,
            };
            let u = |x: usize| u32::try_from(x).map_err(|_| too_many());
            deformers.push(GpuDeformer {
                first_joint: u(joints)?,
                joint_count: u(joint_count)?,
                first_delta: u(deltas.len())?,
                targets: u(d.targets.len())?,
                first_weight: u(weights)?,
                first_vertex: u(vertices.len())?,
                tangents: u32::from(!d.tangents.is_empty()),
                _pad: 0,
            });
            slots.push(Slots {
                first_joint: joints,
                first_weight: weights,
                targets: d.targets.len(),
            });
            joints += joint_count;
            weights += d.targets.len();
            for v in 0..d.positions.len() {
                vertices.push(GpuSkinVertex {
                    position: d.positions[v].to_array(),
                    vertex: base + u(v)?,
                    normal: d.normals[v].to_array(),
                    deformer: u(i)?,
                    tangent: d.tangents.get(v).map_or([0.0; 4], |t| t.to_array()),
                    joints: d.joint_indices[v],
                    weights: d.weights[v],
                });
                for t in &d.targets {
                    for part in [&t.positions, &t.normals, &t.tangents] {
                        deltas.push(part.get(v).map_or([0.0; 4], |x| x.extend(0.0).to_array()));
                    }
                }
            }
        }
        let read = wgpu::BufferUsages::STORAGE;
        let write = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST;
        let init = |label, bytes: &[u8]| transfer::buffer_init(device, label, bytes, read);
        let vertex_buffer = init("skin vertices", bytemuck::cast_slice(&vertices))?;
        let deformer_buffer = init("deformers", bytemuck::cast_slice(&deformers))?;
        // Runtime-sized arrays bind at least one element.
        deltas.resize(deltas.len().max(1), [0.0; 4]);
        let delta_buffer = init("morph displacements", bytemuck::cast_slice(&deltas))?;
        let joint_buffer =
            transfer::buffer(device, "joint matrices", 64 * joints.max(1) as u64, write)?;
        let weight_buffer =
            transfer::buffer(device, "morph weights", 4 * weights.max(1) as u64, write)?;
        let group = self.kernel.bind_buffers(
            device,
            &[
                &vertex_buffer,
                &deformer_buffer,
                &delta_buffer,
                &joint_buffer,
                &weight_buffer,
                positions,
                attributes,
            ],
        );
        let n = u32::try_from(vertices.len()).map_err(|_| too_many())?;
        Ok(BoundSkinning {
            passes: Passes::one(
                "skinning",
                &self.kernel.pipeline,
                vec![group],
                Workgroups::linear(n, WORKGROUP),
            ),
            joints: joint_buffer,
            weights: weight_buffer,
            slots,
        })
    }
}

impl BoundSkinning {
    /// Writes `pose`'s joint matrices and morph weights for the next [`BoundSkinning::encode`]
    /// (`rig` is the one bound).
    pub fn set_pose(&self, queue: &wgpu::Queue, rig: &Rig, pose: &Pose) {
        for (d, slot) in rig.deformers.iter().zip(&self.slots) {
            let matrices: Vec<[f32; 16]> = rig
                .joint_matrices(d, pose)
                .iter()
                .map(|m| m.to_cols_array())
                .collect();
            queue.write_buffer(
                &self.joints,
                64 * slot.first_joint as u64,
                bytemuck::cast_slice(&matrices),
            );
            if slot.targets > 0 {
                let node = &pose.weights[d.node as usize];
                let w: Vec<f32> = (0..slot.targets)
                    .map(|k| node.get(k).copied().unwrap_or(0.0))
                    .collect();
                queue.write_buffer(
                    &self.weights,
                    4 * slot.first_weight as u64,
                    bytemuck::cast_slice(&w),
                );
            }
        }
    }

    /// Records the skinning pass (timed as `skinning`).
    pub fn encode(&self, encoder: &mut wgpu::CommandEncoder, timer: Option<&PassTimer>) {
        self.passes.encode(encoder, timer);
    }
}
