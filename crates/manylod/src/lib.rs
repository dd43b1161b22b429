//! Many-view level-of-detail cuts (ManyLoDs; Holländer 2013 §3.5–3.7).
//!
//! The scene is sampled into `2^d` [surfels](surfels) stored as `(s, t, triangle)` so that mesh
//! deformation moves them; a [bounding-sphere hierarchy](bsh) — a perfect complete binary tree
//! with a bounding sphere and a normal cone per node — is built once and refit after
//! deformation. For many [views](view) at once, a [cut](cut) through the tree is found for
//! every view: the node-views `(N, V)` whose criterion `c(N, V)` (projected size in pixels, 0
//! when culled) is below `ε` while their parent's is not. Basic (from the roots), incremental
//! (from last frame's cut: split / merge / draw / cull, Listing 3.1) and lazy (q iterations).
//!
//! The cut is [splatted](splat) into an atlas of per-view depth tiles. The CPU reference is
//! the specification; the [GPU kernels](gpu) mirror it.

pub mod bsh;
pub mod cut;
pub mod gpu;
pub mod hybrid;
pub mod lookup;
pub mod splat;
pub mod surfels;
pub mod view;

pub use bsh::{Bsh, Node};
pub use cut::{Cut, CutProblem, NodeView};
pub use splat::AtlasLayout;
pub use surfels::Surfel;
pub use view::View;

/// This crate's WGSL (`shaders/manylod/`, carried into the package by the `shaders` link).
pub static SHADERS: ::gpu::shader::Library = ::gpu::shader_library!(
    "manylod",
    imports: [],
    files: [
        "common.wgsl",
        "cut.wgsl",
        "hybrid.wgsl",
        "inplace.wgsl",
        "inplace_atomic.wgsl",
        "inplace_ballot.wgsl",
        "lookup.wgsl",
        "nearest.wgsl",
        "refit.wgsl",
        "splat.wgsl",
    ],
);

/// What this crate's kernels need of a device: wgpu's default limits suffice; the ballot compaction of the in-place variant is used only where the device has `SUBGROUP`.
pub fn device_needs() -> ::gpu::DeviceNeeds {
    ::gpu::DeviceNeeds::default()
}

/// Everything that can go wrong.
#[derive(Debug, thiserror::Error)]
pub enum ManyLodError {
    /// The mesh cannot be sampled.
    #[error("mesh: {0}")]
    Mesh(String),
    /// A hierarchy needs a power-of-two number of points.
    #[error("{0} points: a perfect binary tree needs a power of two (at least 1, at most 2^26)")]
    PointCount(usize),
    /// NaN or infinite input.
    #[error("{what} {index} is not finite")]
    NonFinite {
        /// What.
        what: &'static str,
        /// Which.
        index: usize,
    },
    /// A view that cannot be used.
    #[error("view {index}: {problem}")]
    View {
        /// View index.
        index: usize,
        /// What is wrong.
        problem: String,
    },
    /// Sizes that do not fit together.
    #[error("{0}")]
    Mismatch(String),
    /// A GPU list ran out of room.
    #[error("{what}: {needed} node-views do not fit the capacity of {capacity}; raise it")]
    Capacity {
        /// Which list.
        what: &'static str,
        /// Node-views appended.
        needed: u64,
        /// Capacity.
        capacity: u64,
    },
    /// The device lacks a feature the request needs.
    #[error("{0}")]
    Unsupported(&'static str),
    /// The GPU failed.
    #[error(transparent)]
    Gpu(#[from] ::gpu::GpuError),
}
