//! The light hierarchy built on the GPU (`light_tree.wgsl`; CPU twin [`crate::LightGroups`]):
//! the lights' bounds, a counting sort of the lights by the top 15 bits of their Morton codes,
//! and the groups' bounding spheres — five dispatches at the start of the first light
//! accumulation pass after the lights change, for every method that searches through the
//! hierarchy ([`crate::LightSearch::Tree`]); the CPU sorts nothing.

use ::gpu::kernel::{Binding, Dispatch, Kernel, Workgroups};
use ::gpu::{GpuError, transfer};

use super::storage;

/// Buckets of the counting sort: directional lights, then 2¹⁵ Morton prefixes.
const BUCKETS: u64 = 1 + (1 << 15);
/// Invocations per workgroup of the per-light kernels.
const THREADS: u32 = 256;

/// The five kernels of `light_tree.wgsl`.
pub(super) struct TreeKernels {
    bounds: Kernel,
    histogram: Kernel,
    scan: Kernel,
    scatter: Kernel,
    spheres: Kernel,
}

/// The build's own buffers and bind groups for one [`super::BoundShading`].
pub(super) struct BoundTree {
    groups: [wgpu::BindGroup; 5],
    tree: wgpu::Buffer,
}

impl BoundTree {
    /// The hierarchy's buffer (`LightGroups::words`' layout).
    pub(super) fn buffer(&self) -> &wgpu::Buffer {
        &self.tree
    }
}

impl TreeKernels {
    pub(super) fn new(device: &wgpu::Device) -> Result<Self, GpuError> {
        let module = crate::SHADERS.module(device, "light_tree.wgsl")?;
        let (params, lights) = ((1, Binding::Uniform), (2, Binding::StorageRead));
        let tree = (11, Binding::Storage);
        let (bounds, counts, cursor) = (
            (16, Binding::Storage),
            (17, Binding::Storage),
            (18, Binding::Storage),
        );
        let kernel =
            |entry, bindings: &[(u32, Binding)]| Kernel::numbered(device, &module, entry, bindings);
        Ok(Self {
            bounds: kernel("tree_bounds", &[params, lights, bounds]),
            histogram: kernel("tree_histogram", &[params, lights, bounds, counts]),
            scan: kernel("tree_scan", &[counts, cursor]),
            scatter: kernel("tree_scatter", &[params, lights, tree, bounds, cursor]),
            spheres: kernel("tree_spheres", &[params, lights, tree, bounds]),
        })
    }

    /// Binds the build to the shading's parameters, lights and hierarchy buffer.
    pub(super) fn bind(
        &self,
        device: &wgpu::Device,
        params: &wgpu::Buffer,
        lights: &wgpu::Buffer,
        tree: &wgpu::Buffer,
    ) -> Result<BoundTree, GpuError> {
        // The bounds start empty (least = all ones, greatest = 0); each build leaves them so.
        let empty: [u32; 6] = [u32::MAX, u32::MAX, u32::MAX, 0, 0, 0];
        let bounds = transfer::buffer_init(
            device,
            "light hierarchy bounds",
            bytemuck::cast_slice(&empty),
            wgpu::BufferUsages::STORAGE,
        )?;
        let counts = storage(device, "light hierarchy bucket counts", BUCKETS * 4)?;
        let cursor = storage(device, "light hierarchy bucket slots", BUCKETS * 4)?;
        let b = wgpu::Buffer::as_entire_binding;
        Ok(BoundTree {
            groups: [
                self.bounds
                    .bind(device, &[b(params), b(lights), b(&bounds)]),
                self.histogram
                    .bind(device, &[b(params), b(lights), b(&bounds), b(&counts)]),
                self.scan.bind(device, &[b(&counts), b(&cursor)]),
                self.scatter.bind(
                    device,
                    &[b(params), b(lights), b(tree), b(&bounds), b(&cursor)],
                ),
                self.spheres
                    .bind(device, &[b(params), b(lights), b(tree), b(&bounds)]),
            ],
            tree: tree.clone(),
        })
    }

    /// The build's dispatches for `light_count` lights in `group_count` groups.
    pub(super) fn dispatches(
        &self,
        bound: &BoundTree,
        light_count: u32,
        group_count: u32,
    ) -> Vec<Dispatch> {
        let [bounds, histogram, scan, scatter, spheres] = &bound.groups;
        let per_light = Workgroups::linear(light_count, THREADS);
        vec![
            self.bounds.dispatch(bounds, per_light.clone()),
            self.histogram.dispatch(histogram, per_light.clone()),
            self.scan.dispatch(scan, Workgroups::Direct([1, 1, 1])),
            self.scatter.dispatch(scatter, per_light),
            self.spheres
                .dispatch(spheres, Workgroups::linear(group_count, 64)),
        ]
    }
}
