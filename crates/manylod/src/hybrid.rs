//! The hybrid CPU/GPU basic cut (§3.7.3, Table 3.4). The cut's iteration is split into two
//! kernels — *event generation* (each active node-view is CUT: valid, into the cut; or SPLIT:
//! its two children become active) and *compaction* (a prefix scan of the events gives every
//! node-view its slots in the next active list and the cut) — and each may run on the CPU
//! (rayon) or the GPU; the events may also be shared, a fraction of the list on the GPU while
//! the CPU classifies the rest. The CPU drives the iterations, so every iteration's list
//! passes through host memory, as the tasks of the paper's StarPU version did.
//!
//! [`events`] and [`compact`] are the CPU halves and the specification; [`GpuHybridCut`] runs
//! a [`Split`]. Every split finds [`crate::cut::basic`]'s cut (as a set: GPU compaction appends
//! with atomics, so its order differs).

use std::time::Instant;

use ::gpu::kernel::{Binding, Kernel, Passes, Workgroups};
use ::gpu::transfer;
use bytemuck::{Pod, Zeroable};
use rayon::prelude::*;

use crate::{Bsh, Cut, CutProblem, ManyLodError, NodeView, View, bsh::first_child, cut::roots};

/// Event of a node-view that joins the cut (`hybrid.wgsl`'s `CUT`).
pub const CUT: u32 = 0;
/// Event of a node-view whose children become active (`hybrid.wgsl`'s `SPLIT`).
pub const SPLIT: u32 = 1;

/// The CPU's event generation for `list` (of a basic cut: no parent is valid).
pub fn events(problem: &CutProblem, list: &[NodeView]) -> Vec<u32> {
    list.par_iter()
        .map(|&nv| if problem.is_valid(nv) { CUT } else { SPLIT })
        .collect()
}

/// Node-views per task of the CPU's prefix scan.
const CHUNK: usize = 1 << 14;

/// The CPU's compaction: an exclusive prefix scan of the events (per chunk in parallel, then
/// over the chunks' totals) and the scatter it places: the next active list (two children per
/// SPLIT, in list order) and the node-views that join the cut.
pub fn compact(list: &[NodeView], events: &[u32]) -> (Vec<NodeView>, Vec<NodeView>) {
    let totals: Vec<(usize, usize)> = events
        .par_chunks(CHUNK)
        .map(|c| {
            let splits = c.iter().filter(|&&e| e == SPLIT).count();
            (2 * splits, c.len() - splits)
        })
        .collect();
    let next_len = totals.iter().map(|t| t.0).sum();
    let cut_len = totals.iter().map(|t| t.1).sum();
    let mut next = vec![NodeView::default(); next_len];
    let mut cut = vec![NodeView::default(); cut_len];
    // The scan: each chunk writes its own consecutive ranges of both outputs.
    let mut next_parts = split_at_lengths(&mut next, totals.iter().map(|t| t.0));
    let mut cut_parts = split_at_lengths(&mut cut, totals.iter().map(|t| t.1));
    list.par_chunks(CHUNK)
        .zip(events.par_chunks(CHUNK))
        .zip(next_parts.par_iter_mut().zip(cut_parts.par_iter_mut()))
        .for_each(|((l, e), (n, c))| {
            let (mut i, mut j) = (0, 0);
            for (&nv, &ev) in l.iter().zip(e) {
                if ev == CUT {
                    c[j] = nv;
                    j += 1;
                } else {
                    let child = first_child(nv.node);
                    n[i] = NodeView { node: child, ..nv };
                    n[i + 1] = NodeView {
                        node: child + 1,
                        ..nv
                    };
                    i += 2;
                }
            }
        });
    drop((next_parts, cut_parts));
    (next, cut)
}

/// `v` cut into consecutive slices of the given lengths.
fn split_at_lengths<T>(mut v: &mut [T], lengths: impl Iterator<Item = usize>) -> Vec<&mut [T]> {
    let mut parts = Vec::new();
    for n in lengths {
        let (a, b) = v.split_at_mut(n);
        parts.push(a);
        v = b;
    }
    parts
}

/// Where a kernel runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Unit {
    /// rayon on the host's cores.
    Cpu,
    /// The GPU.
    Gpu,
}

/// How a [`GpuHybridCut`] shares an iteration: the fraction of the active list whose events
/// the GPU generates (the CPU classifies the rest at the same time), and where the
/// compaction runs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Split {
    /// Share of the events on the GPU, `0..=1`.
    pub gpu_events: f32,
    /// Where the compaction runs.
    pub compaction: Unit,
}

impl Split {
    /// A short name: `events GPU 50 % / compaction CPU`.
    pub fn name(&self) -> String {
        let events = match self.gpu_events {
            1.0 => "GPU".to_string(),
            0.0 => "CPU".to_string(),
            s => format!("GPU {:.0} % + CPU", s * 100.0),
        };
        let compaction = match self.compaction {
            Unit::Cpu => "CPU",
            Unit::Gpu => "GPU",
        };
        format!("events {events} / compaction {compaction}")
    }
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct Params {
    count: u32,
    leaf_start: u32,
    epsilon: f32,
    _pad: u32,
}

const STORAGE: wgpu::BufferUsages = wgpu::BufferUsages::STORAGE
    .union(wgpu::BufferUsages::COPY_SRC)
    .union(wgpu::BufferUsages::COPY_DST);
const WORKGROUP: u32 = 256;

/// A hybrid cut's timing: wall-clock milliseconds of the whole cut and of its parts.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct HybridTiming {
    /// The whole cut, host-driven, transfers included.
    pub total_ms: f64,
    /// Waiting for the GPU's events (upload, kernel, readback), beyond the CPU's share.
    pub gpu_events_ms: f64,
    /// The CPU's event share.
    pub cpu_events_ms: f64,
    /// The compaction (CPU scan + scatter, or GPU kernel + readback of the next list).
    pub compaction_ms: f64,
    /// Writing each iteration's active list into the GPU's (where a GPU kernel reads it).
    pub upload_ms: f64,
}

/// The GPU half of a hybrid cut: the tree, the views, the lists and `hybrid.wgsl`'s kernels.
pub struct GpuHybridCut {
    classify: Kernel,
    compact: Kernel,
    bind: wgpu::BindGroup,
    params: wgpu::Buffer,
    list: wgpu::Buffer,
    events: wgpu::Buffer,
    counters: wgpu::Buffer,
    next: wgpu::Buffer,
    cut: wgpu::Buffer,
    leaf_start: u32,
    epsilon: f32,
    capacity: usize,
}

impl GpuHybridCut {
    /// Uploads `bsh` and `views` (threshold `epsilon`) with room for `capacity` node-views in
    /// the active list and in the cut.
    pub fn new(
        device: &wgpu::Device,
        bsh: &Bsh,
        views: &[View],
        epsilon: f32,
        capacity: usize,
    ) -> Result<Self, ManyLodError> {
        CutProblem {
            bsh,
            views,
            epsilon,
        }
        .check()?;
        if views.is_empty() || capacity < views.len() {
            return Err(ManyLodError::Mismatch(format!(
                "{} views with a list capacity of {capacity}",
                views.len()
            )));
        }
        let module = crate::SHADERS.module(device, "hybrid.wgsl")?;
        use Binding::{Storage as Rw, StorageRead as R, Uniform as U};
        let bindings = [R, R, U, R, Rw, Rw, Rw, Rw];
        let classify = Kernel::new(device, &module, "classify", &bindings, &[]);
        let compact = Kernel::new(device, &module, "compact", &bindings, &[]);
        let buffer = |label, bytes: u64| transfer::buffer(device, label, bytes, STORAGE);
        let gpu_views: Vec<_> = views.iter().map(View::gpu).collect();
        let nodes = transfer::buffer_init(
            device,
            "hybrid nodes",
            bytemuck::cast_slice(&bsh.nodes),
            STORAGE,
        )?;
        let views = transfer::buffer_init(
            device,
            "hybrid views",
            bytemuck::cast_slice(&gpu_views),
            STORAGE,
        )?;
        let params = transfer::buffer(
            device,
            "hybrid params",
            size_of::<Params>() as u64,
            wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        )?;
        let n = capacity as u64;
        let list = buffer("hybrid active", 8 * n)?;
        let events = buffer("hybrid events", 4 * n)?;
        let counters = buffer("hybrid counters", 8)?;
        let next = buffer("hybrid next", 8 * n)?;
        let cut = buffer("hybrid cut", 8 * n)?;
        let bind = classify.bind_buffers(
            device,
            &[
                &nodes, &views, &params, &list, &events, &counters, &next, &cut,
            ],
        );
        Ok(Self {
            classify,
            compact,
            bind,
            params,
            list,
            events,
            counters,
            next,
            cut,
            leaf_start: bsh.leaf_count() as u32 - 1,
            epsilon,
            capacity,
        })
    }

    /// One dispatch of `kernel` over `count` node-views.
    fn encode(
        &self,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
        kernel: &Kernel,
        count: usize,
    ) {
        let params = Params {
            count: count as u32,
            leaf_start: self.leaf_start,
            epsilon: self.epsilon,
            _pad: 0,
        };
        queue.write_buffer(&self.params, 0, bytemuck::bytes_of(&params));
        let groups = Workgroups::linear(count as u32, WORKGROUP);
        Passes::new()
            .pass("hybrid", vec![kernel.dispatch(&self.bind, groups)])
            .encode(encoder, None);
    }

    /// The basic cut of `problem` (the tree and views this was made with) shared as `split`
    /// says, with its wall-clock timing. Errors when a list outgrows the capacity.
    pub fn cut(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        problem: &CutProblem,
        split: Split,
    ) -> Result<(Cut, HybridTiming), ManyLodError> {
        if !(0.0..=1.0).contains(&split.gpu_events) {
            return Err(ManyLodError::Mismatch(format!(
                "a GPU share of {} of the events",
                split.gpu_events
            )));
        }
        let start = Instant::now();
        let mut timing = HybridTiming::default();
        let mut cut = Cut::default();
        let mut active = roots(problem.views.len());
        let on_gpu = split.compaction == Unit::Gpu;
        if on_gpu {
            queue.write_buffer(&self.counters, 0, bytemuck::cast_slice(&[0u32, 0]));
        }
        let mut gpu_cut_len = 0usize;
        while !active.is_empty() {
            if active.len() > self.capacity {
                return Err(ManyLodError::Capacity {
                    what: "hybrid active list",
                    needed: active.len() as u64,
                    capacity: self.capacity as u64,
                });
            }
            cut.iterations += 1;
            cut.processed += active.len() as u64;
            let n = active.len();
            let k = ((n as f64 * f64::from(split.gpu_events)).round() as usize).min(n);
            // The GPU's share of the events, recorded before the CPU classifies the rest.
            let needs_list = k > 0 || on_gpu;
            if needs_list {
                let upload = Instant::now();
                queue.write_buffer(&self.list, 0, bytemuck::cast_slice(&as_pairs(&active)));
                timing.upload_ms += ms(upload);
            }
            if k > 0 {
                let mut encoder = device.create_command_encoder(&Default::default());
                self.encode(queue, &mut encoder, &self.classify, k);
                queue.submit([encoder.finish()]);
            }
            // The CPU classifies the rest while the GPU runs.
            let cpu_start = Instant::now();
            let cpu_part = events(problem, &active[k..]);
            timing.cpu_events_ms += ms(cpu_start);
            let wait = Instant::now();
            let mut ev = Vec::new();
            if k > 0 && !on_gpu {
                let encoder = device.create_command_encoder(&Default::default());
                let range = 0..4 * k as u64;
                let bytes = transfer::read_after(device, queue, encoder, &self.events, range)?;
                ev = bytemuck::pod_collect_to_vec(&bytes);
            }
            timing.gpu_events_ms += ms(wait);
            let c = Instant::now();
            if on_gpu {
                if k < n {
                    queue.write_buffer(&self.events, 4 * k as u64, bytemuck::cast_slice(&cpu_part));
                }
                queue.write_buffer(&self.counters, 0, bytemuck::cast_slice(&[0u32]));
                let mut encoder = device.create_command_encoder(&Default::default());
                self.encode(queue, &mut encoder, &self.compact, n);
                let counts: Vec<u32> = bytemuck::pod_collect_to_vec(&transfer::read_after(
                    device,
                    queue,
                    encoder,
                    &self.counters,
                    0..8,
                )?);
                let (next_len, cut_len) = (counts[0] as usize, counts[1] as usize);
                if next_len > self.capacity || cut_len > self.capacity {
                    return Err(ManyLodError::Capacity {
                        what: "hybrid next list or cut",
                        needed: next_len.max(cut_len) as u64,
                        capacity: self.capacity as u64,
                    });
                }
                // The next list becomes the active one: back to the host, which schedules it.
                let encoder = device.create_command_encoder(&Default::default());
                let bytes = transfer::read_after(
                    device,
                    queue,
                    encoder,
                    &self.next,
                    0..8 * next_len as u64,
                )?;
                active = from_pairs(&bytemuck::pod_collect_to_vec(&bytes));
                gpu_cut_len = cut_len;
            } else {
                ev.extend(cpu_part);
                let (next, joined) = compact(&active, &ev);
                cut.node_views.extend(joined);
                active = next;
            }
            timing.compaction_ms += ms(c);
        }
        if on_gpu {
            let encoder = device.create_command_encoder(&Default::default());
            let bytes =
                transfer::read_after(device, queue, encoder, &self.cut, 0..8 * gpu_cut_len as u64)?;
            cut.node_views = from_pairs(&bytemuck::pod_collect_to_vec(&bytes));
        }
        cut.converged = true;
        timing.total_ms = ms(start);
        cut.culled = cut
            .node_views
            .par_iter()
            .filter(|&&nv| problem.criterion(nv) == 0.0)
            .count() as u64;
        Ok((cut, timing))
    }
}

fn ms(since: Instant) -> f64 {
    since.elapsed().as_secs_f64() * 1e3
}

fn as_pairs(list: &[NodeView]) -> Vec<[u32; 2]> {
    list.iter().map(|nv| [nv.node, nv.view]).collect()
}

fn from_pairs(pairs: &[[u32; 2]]) -> Vec<NodeView> {
    pairs
        .iter()
        .map(|&[node, view]| NodeView { node, view })
        .collect()
}
