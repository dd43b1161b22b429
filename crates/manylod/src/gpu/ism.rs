//! The imperfect-shadow-map baseline on the GPU, splatted by `splat.wgsl`.

use ::gpu::kernel::{Passes, Workgroups};
use ::gpu::{PassTimer, transfer};

use super::{AtlasParams, CUT_SLOTS, GpuManyLod, STORAGE, WORKGROUP, uniform};
use crate::{ManyLodError, Node, NodeView};

/// The imperfect-shadow-map baseline on the GPU ([`crate::splat::ism`]): a fixed list of
/// random points per view splatted into [`GpuManyLod::atlas`] by the same splat kernel.
pub struct GpuIsm {
    bind: wgpu::BindGroup,
    count: u32,
    /// The points (nodes) the list indexes.
    pub points: wgpu::Buffer,
}

impl GpuIsm {
    /// Uploads the ISM points `nodes` and their node-views `list` for the views of `m`.
    pub fn new(
        device: &wgpu::Device,
        m: &GpuManyLod,
        nodes: &[Node],
        list: &[NodeView],
    ) -> Result<Self, ManyLodError> {
        if let Some(bad) = list
            .iter()
            .find(|nv| nv.node as usize >= nodes.len() || nv.view >= m.view_count)
        {
            return Err(ManyLodError::Mismatch(format!(
                "ISM node-view {bad:?} outside {} points × {} views",
                nodes.len(),
                m.view_count
            )));
        }
        let storage = |label, bytes: &[u8]| {
            transfer::buffer_init(device, label, bytes, STORAGE).map_err(ManyLodError::from)
        };
        let node_buffer = storage("ism points", bytemuck::cast_slice(nodes))?;
        let raw: Vec<[u32; 2]> = list.iter().map(|nv| [nv.node, nv.view]).collect();
        let list_buffer = storage("ism list", bytemuck::cast_slice(&raw))?;
        let mut counts = [0u32; 16];
        counts[CUT_SLOTS[0] as usize] = list.len() as u32;
        let counters = storage("ism counters", bytemuck::cast_slice(&counts))?;
        let params = uniform(
            device,
            "ism atlas",
            bytemuck::bytes_of(&AtlasParams::new(&m.layout, CUT_SLOTS[0])),
        )?;
        let bind = m.splat.bind_buffers(
            device,
            &[
                &node_buffer,
                &m.views,
                &params,
                &counters,
                &list_buffer,
                &m.atlas,
            ],
        );
        Ok(Self {
            bind,
            count: list.len() as u32,
            points: node_buffer,
        })
    }

    /// Records clearing `m`'s atlas and splatting the ISM points into it (one pass, `ism`).
    pub fn encode(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        m: &GpuManyLod,
        timer: Option<&PassTimer>,
    ) {
        let groups = Workgroups::linear(self.count, WORKGROUP);
        let dispatches: Vec<_> = m
            .clear_dispatch()
            .into_iter()
            .chain([m.splat.dispatch(&self.bind, groups)])
            .collect();
        Passes::new().pass("ism", dispatches).encode(encoder, timer);
    }
}
