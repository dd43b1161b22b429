//! The initial step of Figure 2.5 (`shaders/subdiv-bft/initial.wgsl`): M⁰ → M¹ by the
//! computational entries and normal entries of [`crate::Subdivider`] (CPU twin: the entries
//! applied by [`crate::Subdivider::evaluate_cpu`], built by [`crate::cpu::loop_step`]).

use ::gpu::{PassTimer, kernel::Workgroups};
use glam::Vec3;

use super::{GpuSubdivider, WORKGROUP, pass, read_vec3};
use crate::SubdivError;

impl GpuSubdivider {
    /// Records the initial step (M⁰ → M¹ positions, then normals).
    pub fn encode_initial(&self, encoder: &mut wgpu::CommandEncoder, timer: Option<&PassTimer>) {
        let groups = Workgroups::linear(self.m1_count, WORKGROUP);
        let [counts, normals] = &self.normals_bind;
        pass(
            "initial step: positions",
            &self.refine,
            &[&self.refine_bind],
            groups.clone(),
        )
        .then(pass(
            "initial step: normals",
            &self.normals,
            &[counts, normals],
            groups,
        ))
        .encode(encoder, timer);
    }

    /// Reads back M¹ positions and normals (tests).
    pub fn read_m1(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
    ) -> Result<(Vec<Vec3>, Vec<Vec3>), SubdivError> {
        Ok((
            read_vec3(device, queue, &self.m1_positions, self.m1_count)?,
            read_vec3(device, queue, &self.m1_normals, self.m1_count)?,
        ))
    }
}
