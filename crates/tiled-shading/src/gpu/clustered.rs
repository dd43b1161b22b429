//! Clustered deferred shading on the GPU ([`Method::Clustered`](crate::Method::Clustered),
//! Olsson et al. 2012 as thesis §2.5 summarises it): `clustered.wgsl`'s four dispatches in
//! one compute pass — cluster keys and explicit cluster bounds from the depth buffer with the
//! occupied clusters compacted, the indirect dispatch of the next step, light assignment per
//! cluster through the light hierarchy, and shading of every pixel from its cluster's list.
//!
//! The grid holds `tiles × CLUSTER_SLICES` cells; the lists go into one buffer of
//! [`entry_capacity`] light indices. A cluster whose lights do not fit (more than 1024, or
//! past the buffer's end) is shaded by testing every light at its pixels instead: the same
//! image, slower — there is no limit on the number of lights.

use ::gpu::kernel::{self, Binding, Dispatch, Kernel, Layout, Workgroups};
use ::gpu::shader::Specialisation;
use ::gpu::{GpuError, transfer};

use super::{ACCUMULATION_FORMAT, storage};
use crate::{CLUSTER_SLICES, ShadingConfig, ShadingError};

/// A record of `clustered.wgsl` whose list did not fit (`OVERFLOW`).
const OVERFLOW: u32 = u32::MAX;
/// Light indices the entry buffer holds per screen tile (before the device's limit).
const ENTRIES_PER_TILE: u64 = 1024;

/// Invocations of `assign_lights` per cluster, and the hierarchy's groups it tests per round:
/// 256 rather than 64 made clustered shading 1.10× (16 384 lights) to 1.35× (1 M lights)
/// faster on the H200 (`docs/bench/logs-2026-12-05/h200-focused`).
const ASSIGN_THREADS: u32 = 256;

/// The compile-time constants of `clustered.wgsl` for `config`.
pub fn specialisation(config: &ShadingConfig) -> Specialisation {
    Specialisation::default()
        .set("TILE", format!("{}u", config.tile_size))
        .set("WG", format!("{}u", config.tile_size.min(16)))
        .set("THREADS", format!("{ASSIGN_THREADS}u"))
        .set("ROUND", format!("{ASSIGN_THREADS}u"))
        .set("LIGHT_TREE", config.search == crate::LightSearch::Tree)
}

/// Light indices the list buffer holds for `tiles` screen tiles on `device`:
/// `tiles × 1024`, at most what one storage binding holds.
pub fn entry_capacity(device: &wgpu::Device, tiles: u64) -> u64 {
    let limits = device.limits();
    let bytes = limits
        .max_storage_buffer_binding_size
        .min(limits.max_buffer_size);
    (tiles * ENTRIES_PER_TILE).min(bytes / 4)
}

/// The bindings of `shade_clusters` at group 0: frame, params, lights, the G-buffer, the two
/// outputs, records and entries (the shadow lookup is group 1).
pub(super) fn shade_bindings() -> Vec<(u32, Binding)> {
    let mut bindings = vec![
        (0, Binding::Uniform),
        (1, Binding::Uniform),
        (2, Binding::StorageRead),
    ];
    bindings.extend((3..).zip(gbuffer::gpu::GBUFFER_BINDINGS));
    bindings.extend([
        (7, Binding::StorageTexture(ACCUMULATION_FORMAT)),
        (8, Binding::StorageTexture(ACCUMULATION_FORMAT)),
        (12, Binding::Storage),
        (13, Binding::Storage),
    ]);
    bindings
}

/// The kernels before the shading: keys and compaction, the assignment's indirect dispatch,
/// assignment.
pub(super) struct ClusterKernels {
    keys: Kernel,
    dispatch: Kernel,
    assign: Kernel,
}

/// The grid, lists and bind groups of one [`super::BoundShading`] of the clustered method.
pub(super) struct BoundClusters {
    groups: [wgpu::BindGroup; 3],
    clusters: wgpu::Buffer,
    records: wgpu::Buffer,
    entries: wgpu::Buffer,
    state: wgpu::Buffer,
    assign_groups: wgpu::Buffer,
    /// Screen tiles across and down.
    tiles: (u32, u32),
}

/// What the clustered kernels read besides their own buffers.
pub(super) struct ClusterInputs<'a> {
    pub frame: &'a wgpu::Buffer,
    pub params: &'a wgpu::Buffer,
    pub lights: &'a wgpu::Buffer,
    pub light_tree: &'a wgpu::Buffer,
    pub linear_depth: &'a wgpu::TextureView,
}

impl ClusterKernels {
    /// The kernels of `module` (`clustered.wgsl` specialised for the configuration).
    pub(super) fn new(device: &wgpu::Device, module: &wgpu::ShaderModule) -> Self {
        let depth = (3, Binding::TextureUnfilterable);
        let state = (14, Binding::Storage);
        let params = (1, Binding::Uniform);
        Self {
            keys: Kernel::numbered(
                device,
                module,
                "cluster_keys",
                &[params, depth, (10, Binding::Storage), state],
            ),
            dispatch: Kernel::numbered(
                device,
                module,
                "cluster_dispatch",
                &[state, (15, Binding::Storage)],
            ),
            assign: Kernel::numbered(
                device,
                module,
                "assign_lights",
                &[
                    (0, Binding::Uniform),
                    params,
                    (2, Binding::StorageRead),
                    depth,
                    (10, Binding::Storage),
                    (11, Binding::StorageRead),
                    (12, Binding::Storage),
                    (13, Binding::Storage),
                    state,
                ],
            ),
        }
    }

    /// The grid and lists for `tiles` screen tiles (across, down) and their bind groups;
    /// `records` and `entries` are also bound by the shading group the caller makes
    /// ([`BoundClusters::lists`]).
    pub(super) fn bind(
        &self,
        device: &wgpu::Device,
        tiles: (u32, u32),
        inputs: ClusterInputs<'_>,
    ) -> Result<BoundClusters, ShadingError> {
        let tile_count = u64::from(tiles.0) * u64::from(tiles.1);
        let cells = tile_count * u64::from(CLUSTER_SLICES);
        if cells > u64::from(u32::MAX) {
            return Err(GpuError::TooLarge {
                what: "cluster grid".into(),
                needed: cells,
                limit: u64::from(u32::MAX),
            }
            .into());
        }
        let clusters = storage(device, "unique clusters", cells * 16)?;
        let records = storage(device, "cluster records", cells * 8)?;
        let entries = storage(
            device,
            "cluster light lists",
            entry_capacity(device, tile_count) * 4,
        )?;
        let state = transfer::buffer(
            device,
            "cluster state",
            12,
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        )?;
        let assign_groups = transfer::buffer(
            device,
            "cluster assignment dispatch",
            12,
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::INDIRECT,
        )?;
        let depth = wgpu::BindingResource::TextureView(inputs.linear_depth);
        let b = wgpu::Buffer::as_entire_binding;
        let groups = [
            self.keys.bind(
                device,
                &[b(inputs.params), depth.clone(), b(&clusters), b(&state)],
            ),
            self.dispatch.bind(device, &[b(&state), b(&assign_groups)]),
            self.assign.bind(
                device,
                &[
                    b(inputs.frame),
                    b(inputs.params),
                    b(inputs.lights),
                    depth,
                    b(&clusters),
                    b(inputs.light_tree),
                    b(&records),
                    b(&entries),
                    b(&state),
                ],
            ),
        ];
        Ok(BoundClusters {
            groups,
            clusters,
            records,
            entries,
            state,
            assign_groups,
            tiles,
        })
    }

    /// The dispatches before the shading.
    pub(super) fn dispatches(&self, bound: &BoundClusters) -> Vec<Dispatch> {
        let [keys, dispatch, assign] = &bound.groups;
        vec![
            self.keys
                .dispatch(keys, Workgroups::Direct([bound.tiles.0, bound.tiles.1, 1])),
            self.dispatch
                .dispatch(dispatch, Workgroups::Direct([1, 1, 1])),
            self.assign
                .dispatch(assign, Workgroups::Indirect(bound.assign_groups.clone(), 0)),
        ]
    }
}

impl BoundClusters {
    /// The records and entries buffers (bindings 12 and 13 of the shading group).
    pub(super) fn lists(&self) -> [&wgpu::Buffer; 2] {
        [&self.records, &self.entries]
    }

    /// Reads back every tile's lights as (light index, mask of the tile's clusters whose list
    /// holds it), sorted by light index — [`crate::cpu::shade`]'s lists. An overflowed
    /// cluster (shaded by testing every light) counts every one of the `light_count` lights.
    pub(super) fn read_lists(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        tiles: usize,
        light_count: u32,
    ) -> Result<Vec<Vec<(u32, u32)>>, ShadingError> {
        let state: Vec<u32> = transfer::read_pod(device, queue, &self.state)?;
        let clusters: Vec<[u32; 4]> = transfer::read_pod(device, queue, &self.clusters)?;
        let records: Vec<[u32; 2]> = transfer::read_pod(device, queue, &self.records)?;
        let entries: Vec<u32> = transfer::read_pod(device, queue, &self.entries)?;
        let mut masks = vec![std::collections::BTreeMap::<u32, u32>::new(); tiles];
        for &[cell, ..] in &clusters[..state[1] as usize] {
            let (tile, slice) = ((cell / CLUSTER_SLICES) as usize, cell % CLUSTER_SLICES);
            let [offset, count] = records[cell as usize];
            let lights: Box<dyn Iterator<Item = u32>> = if offset == OVERFLOW {
                Box::new(0..light_count)
            } else {
                let list = &entries[offset as usize..(offset + count) as usize];
                Box::new(list.iter().copied())
            };
            for light in lights {
                *masks[tile].entry(light).or_default() |= 1 << slice;
            }
        }
        Ok(masks.into_iter().map(|m| m.into_iter().collect()).collect())
    }
}

/// `shade_clusters`' pipeline on its group-0 layout and the shadow lookup's.
pub(super) fn shade_pipeline(
    device: &wgpu::Device,
    module: &wgpu::ShaderModule,
    layout: &Layout,
    shadow_layout: &Layout,
) -> wgpu::ComputePipeline {
    kernel::pipeline(
        device,
        module,
        "shade_clusters",
        &[layout, shadow_layout],
        &[],
    )
}
