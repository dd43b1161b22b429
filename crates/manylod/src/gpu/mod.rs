//! The GPU kernels (§3.7): refit (`refit.wgsl`), many-view cuts with ping-pong active lists
//! and indirect dispatch (`cut.wgsl`), splatting into the atlas (`splat.wgsl`) and the in-place
//! variant (`inplace_atomic.wgsl`, and `inplace_ballot.wgsl` where the device has subgroups).
//! Everything for one frame is recorded into the caller's encoder; counts never come back to
//! the CPU between iterations — each pass's size is written on the GPU by a one-thread
//! `prepare` dispatch and used as the next pass's indirect dispatch.
//!
//! A frame's cut lands in one of two cut lists; the next incremental or lazy frame starts from
//! it and writes the other one.
//!
//! ```no_run
//! use manylod::{AtlasLayout, Bsh, View, gpu::{CutKind, GpuManyLod}};
//! # let gpu = gpu::Gpu::from_env()?;
//! # let (points, normals) = (vec![glam::Vec3::ZERO; 1024], vec![glam::Vec3::Y; 1024]);
//! let bsh = Bsh::build(&points, &normals, 0.01)?;
//! let views = vec![View::Paraboloid { position: glam::Vec3::Y, normal: -glam::Vec3::Y, size: 32 }];
//! let layout = AtlasLayout::new(views.len(), 32, 10.0);
//! let mut m = GpuManyLod::new(&gpu.device, &bsh, &views, 1.0, layout, 1 << 16, None)?;
//! let mut encoder = gpu.device.create_command_encoder(&Default::default());
//! m.encode_cut(&mut encoder, CutKind::Basic, None);
//! m.encode_splat(&mut encoder, None);
//! gpu.queue.submit([encoder.finish()]);
//! let cut = m.read_cut(&gpu.device, &gpu.queue)?;
//! let atlas = m.read_atlas(&gpu.device, &gpu.queue)?;
//! # Ok::<(), manylod::ManyLodError>(())
//! ```
//!
//! Modules follow the WGSL files: the refit in `gpu/refit.rs`, the ISM baseline in `gpu/ism.rs`; the
//! cut, splat and in-place kernels share [`GpuManyLod`]'s buffers and live here.

use crate::{
    AtlasLayout, Bsh, Cut, ManyLodError, Node, NodeView, View,
    cut::{CULLED, CutProblem},
};
use ::gpu::kernel::{Binding, Dispatch, Kernel, Passes, Workgroups};
use ::gpu::{PassTimer, transfer};
use bytemuck::{Pod, Zeroable};

mod ism;
mod refit;

pub use ism::GpuIsm;
pub use refit::GpuRefit;

/// Which cut a frame computes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CutKind {
    /// From the roots, to convergence.
    Basic,
    /// From the previous frame's cut, to convergence.
    Incremental,
    /// From the previous frame's cut, `q` iterations; leftover node-views join the cut.
    Lazy(u32),
}

/// How the in-place variant's cutfinders find the stack slots of the children they push
/// (§3.7.2, Listing 3.4).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Compaction {
    /// A workgroup atomic per splitting cutfinder (every adapter).
    Atomic,
    /// The paper's ballot scan: each lane counts the splitting lanes below it in its
    /// subgroup's ballot, and one workgroup atomic per subgroup reserves their slots (devices
    /// with `wgpu::Features::SUBGROUP`).
    Ballot,
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct Problem {
    epsilon: f32,
    view_count: u32,
    leaf_start: u32,
    levels: u32,
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct PassParams {
    in_slot: u32,
    out_slot: u32,
    cut_slot: u32,
    mode: u32,
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct AtlasParams {
    width: u32,
    tile: u32,
    columns: u32,
    cut_slot: u32,
    far: f32,
    first_view: u32,
    _pad: [u32; 2],
}

impl AtlasParams {
    /// `splat.wgsl`'s `Atlas` for `layout`, the cut length in counter `cut_slot`.
    fn new(layout: &AtlasLayout, cut_slot: u32) -> Self {
        Self {
            width: layout.size().0,
            tile: layout.tile,
            columns: layout.columns,
            cut_slot,
            far: layout.far,
            first_view: layout.first_view,
            _pad: [0; 2],
        }
    }
}

// `cut.wgsl` modes and counter slots.
const LIST: u32 = 0;
const ROOTS: u32 = 1;
const FLUSH: u32 = 2;
const COUNT: u32 = 3;
const BEGIN: u32 = 0x100;
const LIST_SLOTS: [u32; 2] = [0, 1];
const CUT_SLOTS: [u32; 2] = [2, 3];
const SCRATCH: u32 = 4;
const OVERFLOW: usize = 8;
const PROCESSED: usize = 9;
const ITERATIONS: usize = 10;
const COUNTERS: u64 = 16 * 4;
const WORKGROUP: u32 = 256;
const NODE_VIEW: u64 = 8;

const STORAGE: wgpu::BufferUsages = wgpu::BufferUsages::STORAGE
    .union(wgpu::BufferUsages::COPY_SRC)
    .union(wgpu::BufferUsages::COPY_DST);

/// A pass of `cut.wgsl`: its parameters and bind groups for `step` and `prepare`.
struct CutPass {
    step: wgpu::BindGroup,
    prepare: wgpu::BindGroup,
}

fn uniform(device: &wgpu::Device, label: &str, bytes: &[u8]) -> Result<wgpu::Buffer, ManyLodError> {
    Ok(transfer::buffer_init(
        device,
        label,
        bytes,
        wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
    )?)
}

/// The most node-views one list can hold on `device` (its largest storage binding of 8-byte
/// node-views).
pub fn largest_capacity(device: &wgpu::Device) -> usize {
    let limits = device.limits();
    (limits
        .max_storage_buffer_binding_size
        .min(limits.max_buffer_size)
        / NODE_VIEW) as usize
}

/// The GPU side of one hierarchy and one set of views: nodes, views, active and cut lists,
/// the atlas, and the pipelines.
pub struct GpuManyLod {
    prepare: Kernel,
    step: Kernel,
    clear: Kernel,
    splat: Kernel,
    /// The in-place variant per available compaction, with its bind group.
    inplace: Vec<(Compaction, Kernel, wgpu::BindGroup)>,
    /// Node bounds in heap order (`Node`, 32 bytes); the refit writes them.
    pub nodes: wgpu::Buffer,
    views: wgpu::Buffer,
    /// `common.wgsl`'s `Problem` and its values.
    problem: wgpu::Buffer,
    problem_values: Problem,
    counters: wgpu::Buffer,
    dispatch: wgpu::Buffer,
    cuts: [wgpu::Buffer; 2],
    /// Packed depths of the atlas, row-major `u32` (`STORAGE`): the VPL shadow maps.
    pub atlas: wgpu::Buffer,
    roots: [CutPass; 2],
    start: [CutPass; 2],
    steps: [[CutPass; 2]; 2],
    flush: [[CutPass; 2]; 2],
    count: [wgpu::BindGroup; 2],
    splats: [wgpu::BindGroup; 2],
    clear_bind: wgpu::BindGroup,
    depth: u32,
    view_count: u32,
    capacity: u64,
    layout: AtlasLayout,
    atlas_pixels: u32,
    /// Cut list of the last frame (0 or 1) and the list slot its leftovers are in.
    current: usize,
    leftover: u32,
    /// The atlas parameters of `splat.wgsl` for each cut list.
    splat_params: [wgpu::Buffer; 2],
    /// The nearest-node pass, once [`GpuManyLod::enable_nearest_nodes`] made it.
    nearest: Option<NearestNodes>,
}

/// The nearest node per atlas pixel (`nearest.wgsl` after `splat`): its kernels,
/// buffer and bind groups.
struct NearestNodes {
    clear: Kernel,
    resolve: Kernel,
    clear_bind: wgpu::BindGroup,
    binds: [wgpu::BindGroup; 2],
    ids: wgpu::Buffer,
}

impl GpuManyLod {
    /// Uploads `bsh` and `views` (threshold `epsilon`, atlas `layout`) with room for `capacity`
    /// node-views in each active and cut list. The splat writes into the caller's `atlas` when
    /// given (at least 4 bytes per atlas pixel of `layout`, `STORAGE`; packed depths, row-major:
    /// e.g. a buffer the application's shadow lookup already binds; a buffer too small or
    /// without `STORAGE` is an `Err`), else into one allocated here.
    pub fn new(
        device: &wgpu::Device,
        bsh: &Bsh,
        views: &[View],
        epsilon: f32,
        layout: AtlasLayout,
        capacity: usize,
        atlas: Option<&wgpu::Buffer>,
    ) -> Result<Self, ManyLodError> {
        let (w, h) = layout.size();
        let atlas_pixels = w * h;
        let atlas = match atlas {
            Some(atlas) => {
                ::gpu::kernel::check_buffer(
                    "ManyLoD atlas",
                    atlas,
                    u64::from(atlas_pixels) * 4,
                    wgpu::BufferUsages::STORAGE,
                )?;
                atlas.clone()
            }
            None => transfer::buffer(
                device,
                "manylod atlas",
                u64::from(atlas_pixels) * 4,
                STORAGE,
            )?,
        };
        CutProblem {
            bsh,
            views,
            epsilon,
        }
        .check()?;
        layout.check(views)?;
        if views.is_empty() || capacity < views.len().max(2) {
            return Err(ManyLodError::Mismatch(format!(
                "{} views with a list capacity of {capacity}",
                views.len()
            )));
        }
        let cut_module = crate::SHADERS.module(device, "cut.wgsl")?;
        let splat_module = crate::SHADERS.module(device, "splat.wgsl")?;
        use Binding::{Storage as Rw, StorageRead as R, Uniform as U};
        // cut.wgsl: nodes, views, problem, pass, counters, list in, list out, cut, dispatch.
        let prepare = Kernel::numbered(
            device,
            &cut_module,
            "prepare",
            &[(2, U), (3, U), (4, Rw), (8, Rw)],
        );
        let step = Kernel::new(
            device,
            &cut_module,
            "step",
            &[R, R, U, U, Rw, R, Rw, Rw],
            &[],
        );
        // splat.wgsl: nodes, views, atlas parameters, counters, cut, atlas.
        let clear = Kernel::numbered(device, &splat_module, "clear", &[(5, Rw)]);
        let splat = Kernel::new(device, &splat_module, "splat", &[R, R, U, Rw, R, Rw], &[]);
        let mut compactions = vec![(Compaction::Atomic, "inplace_atomic.wgsl")];
        if device.features().contains(wgpu::Features::SUBGROUP) {
            compactions.push((Compaction::Ballot, "inplace_ballot.wgsl"));
        }

        let nodes = transfer::buffer_init(
            device,
            "manylod nodes",
            bytemuck::cast_slice(&bsh.nodes),
            STORAGE,
        )?;
        let gpu_views: Vec<_> = views.iter().map(View::gpu).collect();
        let views_buffer = transfer::buffer_init(
            device,
            "manylod views",
            bytemuck::cast_slice(&gpu_views),
            STORAGE,
        )?;
        let problem_values = Problem {
            epsilon,
            view_count: views.len() as u32,
            leaf_start: bsh.leaf_count() as u32 - 1,
            levels: 1,
        };
        let problem = uniform(
            device,
            "manylod problem",
            bytemuck::bytes_of(&problem_values),
        )?;
        let counters = transfer::buffer(device, "manylod counters", COUNTERS, STORAGE)?;
        let dispatch = transfer::buffer(
            device,
            "manylod dispatch",
            12,
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::INDIRECT,
        )?;
        let bytes = capacity as u64 * NODE_VIEW;
        let list = |label| transfer::buffer(device, label, bytes, STORAGE);
        let lists = [list("manylod active 0")?, list("manylod active 1")?];
        let cuts = [list("manylod cut 0")?, list("manylod cut 1")?];
        let slot_buffer = |slot: u32| match slot {
            0 | 1 => &lists[slot as usize],
            _ => &cuts[slot as usize - 2],
        };
        let params = |in_slot: u32, out_slot: u32, cut_slot: u32, mode: u32| {
            uniform(
                device,
                "manylod pass",
                bytemuck::bytes_of(&PassParams {
                    in_slot,
                    out_slot,
                    cut_slot,
                    mode,
                }),
            )
        };
        let prepare_bind = |params: &wgpu::Buffer| {
            prepare.bind_buffers(device, &[&problem, &params, &counters, &dispatch])
        };
        let make_pass = |in_slot: u32, out_slot: u32, cut_slot: u32, mode: u32| {
            let params = params(in_slot, out_slot, cut_slot, mode)?;
            let input = if mode & 0xFF == ROOTS {
                &lists[1]
            } else {
                slot_buffer(in_slot)
            };
            Ok::<_, ManyLodError>(CutPass {
                step: step.bind_buffers(
                    device,
                    &[
                        &nodes,
                        &views_buffer,
                        &problem,
                        &params,
                        &counters,
                        input,
                        slot_buffer(out_slot),
                        slot_buffer(cut_slot),
                    ],
                ),
                prepare: prepare_bind(&params),
            })
        };
        let [l0, l1] = LIST_SLOTS;
        let roots = [0, 1].map(|c| make_pass(0, l0, CUT_SLOTS[c], ROOTS | BEGIN));
        let start = [0, 1].map(|c| make_pass(CUT_SLOTS[1 - c], l0, CUT_SLOTS[c], LIST | BEGIN));
        let steps = [l0, l1]
            .map(|p| [0, 1].map(|c| make_pass(p, LIST_SLOTS[1 - p as usize], CUT_SLOTS[c], LIST)));
        let flush = [l0, l1]
            .map(|p| [0, 1].map(|c| make_pass(p, LIST_SLOTS[1 - p as usize], CUT_SLOTS[c], FLUSH)));
        let count = [0, 1]
            .map(|c| params(CUT_SLOTS[c], SCRATCH, CUT_SLOTS[c], COUNT).map(|p| prepare_bind(&p)));
        let atlas_params = |cut_slot| {
            uniform(
                device,
                "manylod atlas",
                bytemuck::bytes_of(&AtlasParams::new(&layout, cut_slot)),
            )
        };
        let splat_params = [atlas_params(CUT_SLOTS[0])?, atlas_params(CUT_SLOTS[1])?];
        let splats = [0, 1].map(|c| {
            splat.bind_buffers(
                device,
                &[
                    &nodes,
                    &views_buffer,
                    &splat_params[c],
                    &counters,
                    &cuts[c],
                    &atlas,
                ],
            )
        });
        let inplace = compactions
            .into_iter()
            .map(|(compaction, file)| {
                let module = crate::SHADERS.module(device, file)?;
                // inplace.wgsl: splat.wgsl's bindings but the cut list, and the problem at 6.
                let bindings = [(0, R), (1, R), (2, U), (3, Rw), (5, Rw), (6, U)];
                let kernel = Kernel::numbered(device, &module, "inplace", &bindings);
                let bind = kernel.bind_buffers(
                    device,
                    &[
                        &nodes,
                        &views_buffer,
                        &splat_params[0],
                        &counters,
                        &atlas,
                        &problem,
                    ],
                );
                Ok::<_, ManyLodError>((compaction, kernel, bind))
            })
            .collect::<Result<Vec<_>, _>>()?;
        let clear_bind = clear.bind_buffers(device, &[&atlas]);
        let unwrap2 = |[a, b]: [Result<CutPass, ManyLodError>; 2]| Ok::<_, ManyLodError>([a?, b?]);
        let [s0, s1] = steps;
        let [f0, f1] = flush;
        let [c0, c1] = count;
        Ok(Self {
            prepare,
            step,
            clear,
            splat,
            inplace,
            nodes,
            views: views_buffer,
            problem,
            problem_values,
            counters,
            atlas,
            roots: unwrap2(roots)?,
            start: unwrap2(start)?,
            steps: [unwrap2(s0)?, unwrap2(s1)?],
            flush: [unwrap2(f0)?, unwrap2(f1)?],
            count: [c0?, c1?],
            splats,
            clear_bind,
            depth: bsh.depth,
            view_count: views.len() as u32,
            capacity: capacity as u64,
            layout,
            atlas_pixels,
            current: 1,
            leftover: l0,
            dispatch,
            cuts,
            splat_params,
            nearest: None,
        })
    }
}

impl GpuManyLod {
    /// Replaces the views (same count; for moving VPLs). The next incremental or lazy frame
    /// still starts from the last cut.
    pub fn set_views(&self, queue: &wgpu::Queue, views: &[View]) -> Result<(), ManyLodError> {
        if views.len() != self.view_count as usize {
            return Err(ManyLodError::Mismatch(format!(
                "{} views for a set-up of {}",
                views.len(),
                self.view_count
            )));
        }
        self.layout.check(views)?;
        let gpu_views: Vec<_> = views.iter().map(View::gpu).collect();
        queue.write_buffer(&self.views, 0, bytemuck::cast_slice(&gpu_views));
        Ok(())
    }

    /// The atlas layout.
    pub fn layout(&self) -> AtlasLayout {
        self.layout
    }

    /// Tree levels each pass of [`Self::encode_cut`] descends from now on (1, the default, is
    /// Listing 3.1; up to [`crate::cut::MAX_LEVELS_PER_ITERATION`]): the node-views below a split
    /// are decided by the thread that split it, so `levels` passes' work takes one pass — the
    /// same cut from fewer, larger dependent dispatches ([`crate::cut::refine_levels`]). A lazy
    /// frame's `q` passes then go `q · levels` levels deep.
    pub fn set_levels_per_pass(
        &mut self,
        queue: &wgpu::Queue,
        levels: u32,
    ) -> Result<(), ManyLodError> {
        if !(1..=crate::cut::MAX_LEVELS_PER_ITERATION).contains(&levels) {
            return Err(ManyLodError::Mismatch(format!(
                "{levels} tree levels per pass: must be 1 to {}",
                crate::cut::MAX_LEVELS_PER_ITERATION
            )));
        }
        self.problem_values.levels = levels;
        queue.write_buffer(&self.problem, 0, bytemuck::bytes_of(&self.problem_values));
        Ok(())
    }

    /// Records one frame's cut into the other cut list (one compute pass, timed as `cut`):
    /// ⌈(`depth` + 1) / levels per pass⌉ indirect iterations at most (each one `prepare` +
    /// `step`), then a flush.
    pub fn encode_cut(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        kind: CutKind,
        timer: Option<&PassTimer>,
    ) {
        let c = 1 - self.current;
        self.current = c;
        // Statistics and the overflow flag restart every frame.
        encoder.clear_buffer(&self.counters, 8 * 4, Some(8 * 4));
        let mut dispatches = Vec::new();
        let mut run = |p: &CutPass| {
            dispatches.push(
                self.prepare
                    .dispatch(&p.prepare, Workgroups::Direct([1, 1, 1])),
            );
            dispatches.push(self.step.dispatch(&p.step, self.indirect()));
        };
        // The tree's depth + 1 levels, `levels` per pass: ⌈(depth + 1) / levels⌉ passes.
        let full = self.depth / self.problem_values.levels;
        let (first, more) = match kind {
            CutKind::Basic => (&self.roots[c], full),
            CutKind::Incremental => (&self.start[c], full),
            CutKind::Lazy(q) => (&self.start[c], q.saturating_sub(1)),
        };
        run(first);
        let mut p = 0;
        for _ in 0..more {
            run(&self.steps[p][c]);
            p = 1 - p;
        }
        run(&self.flush[p][c]);
        Passes::new().pass("cut", dispatches).encode(encoder, timer);
        self.leftover = LIST_SLOTS[p];
    }

    /// Records the splat of the last cut into the cleared atlas (one pass, timed as `splat`),
    /// then, where enabled, the nearest nodes ([`Self::enable_nearest_nodes`]).
    pub fn encode_splat(&self, encoder: &mut wgpu::CommandEncoder, timer: Option<&PassTimer>) {
        let c = self.current;
        let first = self.layout.first_view == 0;
        let mut dispatches: Vec<Dispatch> = self
            .clear_dispatch()
            .into_iter()
            .chain(self.nearest.as_ref().filter(|_| first).map(|n| {
                n.clear.dispatch(
                    &n.clear_bind,
                    Workgroups::linear(self.atlas_pixels, WORKGROUP),
                )
            }))
            .chain([
                self.prepare
                    .dispatch(&self.count[c], Workgroups::Direct([1, 1, 1])),
                self.splat.dispatch(&self.splats[c], self.indirect()),
            ])
            .collect();
        if let Some(n) = &self.nearest {
            dispatches.push(n.resolve.dispatch(&n.binds[c], self.indirect()));
        }
        Passes::new()
            .pass("splat", dispatches)
            .encode(encoder, timer);
    }

    /// From now on every [`GpuManyLod::encode_splat`] also finds the nearest node of each
    /// atlas pixel (`u32` node index, [`crate::splat::NO_NODE`] where none; among discs of the
    /// same packed depth the smallest index, as [`crate::splat::nearest_nodes`]): a second
    /// pass over the cut that looks up what the winning node carries — point-based GI's
    /// radiance, a reflection map's colour (§3.6.1). Read it with
    /// [`GpuManyLod::nearest_nodes`] or [`GpuManyLod::read_nearest_nodes`].
    pub fn enable_nearest_nodes(&mut self, device: &wgpu::Device) -> Result<(), ManyLodError> {
        if self.nearest.is_some() {
            return Ok(());
        }
        let module = crate::SHADERS.module(device, "nearest.wgsl")?;
        use Binding::{Storage as Rw, StorageRead as R, Uniform as U};
        let clear = Kernel::numbered(device, &module, "clear_ids", &[(7, Rw)]);
        let resolve = Kernel::numbered(
            device,
            &module,
            "nearest",
            &[(0, R), (1, R), (2, U), (3, Rw), (4, R), (5, Rw), (7, Rw)],
        );
        let ids = transfer::buffer(
            device,
            "manylod nearest nodes",
            u64::from(self.atlas_pixels) * 4,
            STORAGE,
        )?;
        let binds = [0, 1].map(|c| {
            resolve.bind_buffers(
                device,
                &[
                    &self.nodes,
                    &self.views,
                    &self.splat_params[c],
                    &self.counters,
                    &self.cuts[c],
                    &self.atlas,
                    &ids,
                ],
            )
        });
        self.nearest = Some(NearestNodes {
            clear_bind: clear.bind_buffers(device, &[&ids]),
            clear,
            resolve,
            binds,
            ids,
        });
        Ok(())
    }

    /// The views (`common.wgsl`'s `View`, [`View::gpu`]; `STORAGE`): a kernel that makes
    /// views on the GPU writes them here (the count stays the set-up's).
    pub fn views_buffer(&self) -> &wgpu::Buffer {
        &self.views
    }

    /// The nearest node of every atlas pixel, row-major `u32` (`STORAGE`), once enabled.
    pub fn nearest_nodes(&self) -> Option<&wgpu::Buffer> {
        self.nearest.as_ref().map(|n| &n.ids)
    }

    /// Reads the nearest nodes back, after [`Self::check_lists`] (`None` when not enabled).
    pub fn read_nearest_nodes(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
    ) -> Result<Option<Vec<u32>>, ManyLodError> {
        self.check_lists(device, queue)?;
        match &self.nearest {
            Some(n) => Ok(Some(transfer::read_pod(device, queue, &n.ids)?)),
            None => Ok(None),
        }
    }

    /// The in-place variant's compactions this device runs: [`Compaction::Atomic`], and
    /// [`Compaction::Ballot`] where it has subgroups.
    pub fn compactions(&self) -> Vec<Compaction> {
        self.inplace.iter().map(|(c, _, _)| *c).collect()
    }

    /// Records the in-place variant (§3.7.2) with `compaction`: basic cuts found and rasterised
    /// by one workgroup per view, no cut list (one pass, timed as `in-place`). Overflow of the
    /// workgroup stack shows in [`GpuManyLod::read_atlas`]; a compaction the device cannot run
    /// (see [`GpuManyLod::compactions`]) is an error.
    pub fn encode_inplace(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        compaction: Compaction,
        timer: Option<&PassTimer>,
    ) -> Result<(), ManyLodError> {
        let (_, kernel, bind) = self
            .inplace
            .iter()
            .find(|(c, _, _)| *c == compaction)
            .ok_or(ManyLodError::Unsupported(
                "the in-place ballot compaction needs subgroups, which this device lacks",
            ))?;
        encoder.clear_buffer(&self.counters, 8 * 4, Some(8 * 4));
        let dispatches: Vec<Dispatch> = self
            .clear_dispatch()
            .into_iter()
            .chain([kernel.dispatch(bind, Workgroups::linear(self.view_count, 1))])
            .collect();
        Passes::new()
            .pass("in-place", dispatches)
            .encode(encoder, timer);
        Ok(())
    }

    /// The atlas clear, first dispatch of every splatting pass.
    /// Clearing the atlas, done by the set holding view 0 only: a later batch of views
    /// ([`AtlasLayout::batch`]) splats into the atlas that set cleared, so it is encoded first.
    fn clear_dispatch(&self) -> Option<Dispatch> {
        (self.layout.first_view == 0).then(|| {
            self.clear.dispatch(
                &self.clear_bind,
                Workgroups::linear(self.atlas_pixels, WORKGROUP),
            )
        })
    }

    /// Workgroups the last `prepare` wrote into the dispatch buffer.
    fn indirect(&self) -> Workgroups {
        Workgroups::Indirect(self.dispatch.clone(), 0)
    }

    fn read_counters(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
    ) -> Result<Vec<u32>, ManyLodError> {
        Ok(transfer::read_pod(device, queue, &self.counters)?)
    }

    fn check_overflow(&self, counters: &[u32], what: &'static str) -> Result<(), ManyLodError> {
        if counters[OVERFLOW] > 0 {
            return Err(ManyLodError::Capacity {
                what,
                needed: self.capacity + u64::from(counters[OVERFLOW]),
                capacity: self.capacity,
            });
        }
        Ok(())
    }

    /// Reads the last cut back (culled flags removed and counted; for tests and pictures),
    /// with its iterations and work. Errors when a list overflowed.
    pub fn read_cut(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
    ) -> Result<Cut, ManyLodError> {
        let counters = self.read_counters(device, queue)?;
        self.check_overflow(&counters, "active or cut list")?;
        let n = counters[CUT_SLOTS[self.current] as usize] as usize;
        let raw: Vec<[u32; 2]> = transfer::read_pod(device, queue, &self.cuts[self.current])?;
        Ok(Cut {
            node_views: raw[..n]
                .iter()
                .map(|&[node, view]| NodeView {
                    node: node & !CULLED,
                    view,
                })
                .collect(),
            iterations: counters[ITERATIONS],
            processed: u64::from(counters[PROCESSED]),
            converged: counters[self.leftover as usize] == 0,
            culled: raw[..n].iter().filter(|nv| nv[0] & CULLED != 0).count() as u64,
        })
    }

    /// Errors when the last cut's lists or the in-place stack overflowed (the atlas then misses
    /// splats).
    pub fn check_lists(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
    ) -> Result<(), ManyLodError> {
        self.check_overflow(
            &self.read_counters(device, queue)?,
            "a cut list or the in-place stack",
        )
    }

    /// Reads the atlas back (row-major packed depths), after [`Self::check_lists`].
    pub fn read_atlas(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
    ) -> Result<Vec<u32>, ManyLodError> {
        self.check_lists(device, queue)?;
        Ok(transfer::read_pod(device, queue, &self.atlas)?)
    }

    /// Reads the node bounds back.
    pub fn read_nodes(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
    ) -> Result<Vec<Node>, ManyLodError> {
        Ok(transfer::read_pod(device, queue, &self.nodes)?)
    }
}
