//! The GPU refit (`refit.wgsl`, §3.5.3).

use ::gpu::kernel::{Binding, Kernel, Passes, Workgroups};
use ::gpu::{PassTimer, transfer};
use bytemuck::{Pod, Zeroable};
use glam::Vec3;

use super::{GpuManyLod, STORAGE, WORKGROUP, uniform};
use crate::{Bsh, ManyLodError, Node, Surfel, surfels::check_mesh};

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct RefitParams {
    first: u32,
    count: u32,
    leaves: u32,
    leaf_radius: f32,
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct GpuSurfel {
    s: f32,
    t: f32,
    triangle: u32,
}

/// The GPU refit (§3.5.3): surfels evaluated on the deformed mesh into the leaves, then one
/// `merge` dispatch per level, bottom-up, into [`GpuManyLod::nodes`].
pub struct GpuRefit {
    leaves: Kernel,
    merge: Kernel,
    /// Mesh positions (`vec4<f32>`, `COPY_DST`): rewrite them after deformation.
    pub positions: wgpu::Buffer,
    leaves_bind: wgpu::BindGroup,
    /// One bind group per level `l = depth − 1 … 0` with its node count.
    levels: Vec<(wgpu::BindGroup, u32)>,
    /// The surfels, their leaf order and the mesh indices, for [`GpuRefit::follow_points`].
    inputs: [wgpu::Buffer; 3],
    /// Point sets that follow the leaves ([`GpuRefit::follow_points`]).
    points: Vec<wgpu::BindGroup>,
    leaf_count: u32,
    vertex_count: usize,
}

impl GpuRefit {
    /// Sets up the refit of `m`'s nodes for `bsh` built over `surfels` of the mesh
    /// `positions`/`indices`.
    pub fn new(
        device: &wgpu::Device,
        m: &GpuManyLod,
        bsh: &Bsh,
        surfels: &[Surfel],
        positions: &[Vec3],
        indices: &[u32],
    ) -> Result<Self, ManyLodError> {
        check_mesh(positions, indices)?;
        if surfels.len() != bsh.leaf_count() || m.depth != bsh.depth {
            return Err(ManyLodError::Mismatch(format!(
                "{} surfels for a tree of {} leaves",
                surfels.len(),
                bsh.leaf_count()
            )));
        }
        let triangles = (indices.len() / 3) as u32;
        if let Some(k) = surfels.iter().position(|s| s.triangle >= triangles) {
            return Err(ManyLodError::Mismatch(format!(
                "surfel {k}: triangle out of range"
            )));
        }
        let module = crate::SHADERS.module(device, "refit.wgsl")?;
        use Binding::{Storage as Rw, StorageRead as R, Uniform as U};
        // refit.wgsl: nodes, refit parameters, surfels, order, positions, indices.
        let leaves = Kernel::new(device, &module, "leaves", &[Rw, U, R, R, R, R], &[]);
        let merge = Kernel::new(device, &module, "merge", &[Rw, U], &[]);
        let gpu_surfels: Vec<GpuSurfel> = surfels
            .iter()
            .map(|s| GpuSurfel {
                s: s.s,
                t: s.t,
                triangle: s.triangle,
            })
            .collect();
        let storage = |label, bytes: &[u8]| {
            transfer::buffer_init(device, label, bytes, STORAGE).map_err(ManyLodError::from)
        };
        let surfel_buffer = storage("manylod surfels", bytemuck::cast_slice(&gpu_surfels))?;
        let order = storage("manylod order", bytemuck::cast_slice(&bsh.order))?;
        let position_buffer = storage(
            "manylod positions",
            bytemuck::cast_slice(&transfer::vec4s(positions, 1.0)),
        )?;
        let index_buffer = storage("manylod indices", bytemuck::cast_slice(indices))?;
        let n = bsh.leaf_count() as u32;
        let params = |first: u32, count: u32| {
            uniform(
                device,
                "manylod refit",
                bytemuck::bytes_of(&RefitParams {
                    first,
                    count,
                    leaves: n,
                    leaf_radius: bsh.leaf_radius,
                }),
            )
        };
        let leaf_params = params(n - 1, n)?;
        let leaves_bind = leaves.bind_buffers(
            device,
            &[
                &m.nodes,
                &leaf_params,
                &surfel_buffer,
                &order,
                &position_buffer,
                &index_buffer,
            ],
        );
        let levels = (0..bsh.depth)
            .rev()
            .map(|l| {
                let p = params((1 << l) - 1, 1 << l)?;
                Ok((merge.bind_buffers(device, &[&m.nodes, &p]), 1u32 << l))
            })
            .collect::<Result<Vec<_>, ManyLodError>>()?;
        Ok(Self {
            leaves,
            merge,
            positions: position_buffer,
            leaves_bind,
            levels,
            inputs: [surfel_buffer, order, index_buffer],
            points: Vec::new(),
            leaf_count: n,
            vertex_count: positions.len(),
        })
    }

    /// Also rewrites `points` (one node per leaf in leaf order, e.g. the ISM baseline's points,
    /// [`crate::splat::ism`]) with the refit leaves at `radius` each refit.
    pub fn follow_points(
        &mut self,
        device: &wgpu::Device,
        points: &wgpu::Buffer,
        radius: f32,
    ) -> Result<(), ManyLodError> {
        let size = u64::from(self.leaf_count) * size_of::<Node>() as u64;
        if points.size() < size {
            return Err(ManyLodError::Mismatch(format!(
                "{} bytes of points for {} leaves",
                points.size(),
                self.leaf_count
            )));
        }
        let params = uniform(
            device,
            "manylod points",
            bytemuck::bytes_of(&RefitParams {
                first: 0,
                count: self.leaf_count,
                leaves: self.leaf_count,
                leaf_radius: radius,
            }),
        )?;
        let [surfels, order, indices] = &self.inputs;
        self.points.push(self.leaves.bind_buffers(
            device,
            &[points, &params, surfels, order, &self.positions, indices],
        ));
        Ok(())
    }

    /// Uploads deformed mesh positions (same vertex count).
    pub fn set_positions(
        &self,
        queue: &wgpu::Queue,
        positions: &[Vec3],
    ) -> Result<(), ManyLodError> {
        if positions.len() != self.vertex_count {
            return Err(ManyLodError::Mismatch(format!(
                "{} positions for a mesh of {}",
                positions.len(),
                self.vertex_count
            )));
        }
        if let Some(index) = positions.iter().position(|p| !p.is_finite()) {
            return Err(ManyLodError::NonFinite {
                what: "position",
                index,
            });
        }
        queue.write_buffer(
            &self.positions,
            0,
            bytemuck::cast_slice(&transfer::vec4s(positions, 1.0)),
        );
        Ok(())
    }

    /// Records the refit (one pass, timed as `refit`).
    pub fn encode(&self, encoder: &mut wgpu::CommandEncoder, timer: Option<&PassTimer>) {
        let leaves = Workgroups::linear(self.leaf_count, WORKGROUP);
        let mut dispatches = vec![self.leaves.dispatch(&self.leaves_bind, leaves.clone())];
        dispatches.extend(self.levels.iter().map(|(bind, count)| {
            self.merge
                .dispatch(bind, Workgroups::linear(*count, WORKGROUP))
        }));
        dispatches.extend(
            self.points
                .iter()
                .map(|bind| self.leaves.dispatch(bind, leaves.clone())),
        );
        Passes::new()
            .pass("refit", dispatches)
            .encode(encoder, timer);
    }
}
