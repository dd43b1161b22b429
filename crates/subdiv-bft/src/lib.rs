//! Real-time Loop subdivision with basis-function tables (Holländer & Boubekeur 2010;
//! Holländer 2013, chapter 2).
//!
//! The pipeline of Figure 2.5:
//!
//! 1. **Initial step** (§2.2.2): M⁰ → M¹ with *computational entries* ([`cpu::Stencils`]:
//!    weights and indices per M¹ vertex) and one-ring *normal entries* per M¹ vertex. After
//!    it, every M¹ face has at most one extraordinary vertex.
//! 2. **Main step** (§2.2.3): every M¹ face is a patch ([`patch::GpuPatch`], Listing 2.1's
//!    `BFTPatch`) tessellated uniformly with `s = 2^(k−1)` segments for surface level `k`; each
//!    fine vertex is `Σ Bⁱ(u, v)·vᵢ¹` with the weights of its configuration's
//!    [basis-function table](bft) at level L (subsampled for `k ≤ L + 1`), its normal the same
//!    weights applied to the M¹ normals, normalised (Subdivision Shading).
//!
//! Levels count from M⁰: level `k` has `4^k` triangles per input triangle, like Table 2.1.
//! Every fine vertex lies on the limit surface. Loop's original weights are used
//! (β = (5/8 − (3/8 + ¼·cos(2π/n))²)/n, as OpenSubdiv, Hbr and trimesh), boundaries are
//! "edge only" (¾, ⅛, ⅛ on boundary vertices, midpoints on boundary edges).
//!
//! ```
//! use subdiv_bft::{BftSet, Subdivider, TriMesh};
//! // A tetrahedron.
//! let mesh = TriMesh::from_f32(
//!     &[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
//!     &[0, 2, 1, 0, 1, 3, 1, 2, 3, 0, 3, 2],
//! )?;
//! let bft = BftSet::build(3, 6)?; // level 3 tables, valences up to 6 (tests; default 5 / 18)
//! let sub = Subdivider::new(&mesh.topology, &bft)?;
//! let out = sub.evaluate_cpu(&bft, &mesh.positions_f32(), 3)?;
//! assert_eq!(out.indices.len() / 3, 4 * 64);
//! # Ok::<(), subdiv_bft::SubdivError>(())
//! ```

pub mod adaptive;
pub mod bft;
pub mod cpu;
pub mod gpu;
pub mod mesh;
pub mod obj;
pub mod patch;

use glam::{DVec3, Vec3};

pub use bft::{BftSet, Corner, DEFAULT_LEVEL, MAX_VALENCE};
pub use cpu::{Stencils, TriMesh};
pub use mesh::Topology;
pub use patch::Patches;

/// This crate's WGSL (`shaders/subdiv-bft/`, carried into the package by the `shaders` link).
pub static SHADERS: ::gpu::shader::Library = ::gpu::shader_library!(
    "subdiv-bft",
    imports: [],
    files: [
        "evaluate.wgsl",
        "factors.wgsl",
        "initial.wgsl",
    ],
);

/// What this crate's kernels need of a device: wgpu's default limits suffice for the uniform evaluation; see [`adaptive_device_needs`] for adaptive tessellation.
pub fn device_needs() -> ::gpu::DeviceNeeds {
    ::gpu::DeviceNeeds::default()
}

/// What adaptive tessellation needs ([`gpu::GpuSubdivider::adaptive`]): its kernel binds
/// [`gpu::ADAPTIVE_STORAGE_BUFFERS`] storage buffers. On a device with fewer, `GpuSubdivider`
/// builds only the uniform evaluation and `adaptive` is an error naming the limit.
pub fn adaptive_device_needs() -> ::gpu::DeviceNeeds {
    ::gpu::DeviceNeeds {
        features: ::gpu::wgpu::Features::empty(),
        limits: ::gpu::wgpu::Limits {
            max_storage_buffers_per_shader_stage: gpu::ADAPTIVE_STORAGE_BUFFERS,
            ..Default::default()
        },
    }
}

/// Everything that can go wrong.
#[derive(Debug, thiserror::Error)]
pub enum SubdivError {
    /// A triangle names a vertex that does not exist.
    #[error("triangle {triangle} uses vertex {index}, but the mesh has {vertices} vertices")]
    IndexOutOfRange {
        /// Triangle.
        triangle: usize,
        /// The bad index.
        index: u32,
        /// Vertex count.
        vertices: usize,
    },
    /// A triangle uses one vertex twice.
    #[error("triangle {triangle} is degenerate (uses a vertex twice)")]
    Degenerate {
        /// Triangle.
        triangle: usize,
    },
    /// An edge with more than two triangles, or two in the same direction.
    #[error("edge {a}–{b}: {problem}")]
    NonManifoldEdge {
        /// One end.
        a: u32,
        /// Other end.
        b: u32,
        /// What is wrong.
        problem: &'static str,
    },
    /// A vertex whose triangles do not form one fan.
    #[error("vertex {vertex} is non-manifold (its triangles form more than one fan)")]
    NonManifoldVertex {
        /// Vertex.
        vertex: u32,
    },
    /// NaN or infinite coordinates.
    #[error("vertex {vertex} has a non-finite position")]
    NonFinite {
        /// Vertex.
        vertex: usize,
    },
    /// A face configuration the tables do not cover.
    #[error(
        "M¹ face {face}: no basis-function table for a {} vertex of valence {valence}; build tables with a higher maximum valence",
        if *boundary { "boundary" } else { "interior" }
    )]
    NoTable {
        /// M¹ face.
        face: u32,
        /// Largest valence among its corners.
        valence: u32,
        /// Whether a corner is on the boundary.
        boundary: bool,
    },
    /// The one-ring of a face meets itself (a mesh too small for the table's configuration).
    #[error("M¹ face {face}: its one-ring meets itself; the mesh is too small or folded there")]
    RingFolds {
        /// M¹ face.
        face: u32,
    },
    /// A surface level the tables cannot give.
    #[error("level {level} is outside 1..={max} (tables of level {table_level} give up to {max})")]
    Level {
        /// Requested level.
        level: u32,
        /// Largest level.
        max: u32,
        /// Table level.
        table_level: u32,
    },
    /// Positions do not match the mesh.
    #[error("{given} positions given, the mesh has {expected} vertices")]
    PositionCount {
        /// Given.
        given: usize,
        /// Expected.
        expected: usize,
    },
    /// Table construction failed.
    #[error("basis-function table: {0}")]
    Table(String),
    /// A table file is malformed.
    #[error("basis-function table file: {0}")]
    TableFile(String),
    /// An OBJ file could not be used.
    #[error("OBJ line {line}: {problem}")]
    Obj {
        /// 1-based line.
        line: usize,
        /// What is wrong.
        problem: String,
    },
    /// Adaptive tessellation factors that do not fit the mesh.
    #[error("tessellation factors: {0}")]
    Factors(String),
    /// Too big for 32-bit indices or the device.
    #[error("too large: {0}")]
    TooLarge(String),
    /// A GPU error.
    #[error(transparent)]
    Gpu(#[from] ::gpu::GpuError),
}

impl TriMesh {
    /// A mesh from f32 positions and a triangle list (validated).
    pub fn from_f32(positions: &[[f32; 3]], indices: &[u32]) -> Result<Self, SubdivError> {
        if indices.len() % 3 != 0 {
            return Err(SubdivError::Obj {
                line: 0,
                problem: format!("{} indices is not a multiple of 3", indices.len()),
            });
        }
        Self::new(
            positions
                .iter()
                .map(|&p| Vec3::from(p).as_dvec3())
                .collect(),
            indices
                .chunks_exact(3)
                .map(|t| [t[0], t[1], t[2]])
                .collect(),
        )
    }

    /// A mesh from a render mesh whose vertices are split at texture seams: vertices with
    /// bit-identical positions are merged first, so the topology is the surface's.
    pub fn welded(positions: &[Vec3], indices: &[u32]) -> Result<Self, SubdivError> {
        Self::welding(positions, indices).map(|(mesh, _)| mesh)
    }

    /// [`TriMesh::welded`] and, for each merged vertex, the first render vertex merged into it
    /// (to gather moved render vertices into M⁰ each frame).
    pub fn welding(positions: &[Vec3], indices: &[u32]) -> Result<(Self, Vec<u32>), SubdivError> {
        let mut map = std::collections::HashMap::new();
        let mut first = Vec::new();
        let remap: Vec<u32> = positions
            .iter()
            .enumerate()
            .map(|(i, p)| {
                *map.entry(p.to_array().map(f32::to_bits))
                    .or_insert_with(|| {
                        first.push(i as u32);
                        first.len() as u32 - 1
                    })
            })
            .collect();
        let unique: Vec<[f32; 3]> = first
            .iter()
            .map(|&i| positions[i as usize].to_array())
            .collect();
        let indices: Vec<u32> = indices
            .iter()
            .map(|&i| remap.get(i as usize).copied().unwrap_or(u32::MAX))
            .collect();
        Ok((Self::from_f32(&unique, &indices)?, first))
    }

    /// Positions as f32 (what the GPU path takes).
    pub fn positions_f32(&self) -> Vec<Vec3> {
        self.positions.iter().map(|p| p.as_vec3()).collect()
    }
}

/// A refined mesh ready to draw: shared vertices with Subdivision Shading normals.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Refined {
    /// Fine vertex positions (on the limit surface).
    pub positions: Vec<Vec3>,
    /// Unit normals.
    pub normals: Vec<Vec3>,
    /// Three indices per triangle, counter-clockwise like the input.
    pub indices: Vec<u32>,
}

/// Everything derived from the connectivity of M⁰ once: computational entries, M¹ topology
/// and normal entries, patches. Positions of M⁰ may change every frame (animation) without
/// rebuilding any of it.
#[derive(Clone, Debug)]
pub struct Subdivider {
    /// M⁰ connectivity.
    pub m0: Topology,
    /// Computational entries M⁰ → M¹ (§2.2.2).
    pub entries: Stencils,
    /// M¹ connectivity.
    pub m1: Topology,
    /// Normal entries: the one-ring of each M¹ vertex (counter-clockwise) with its boundary flag.
    pub normal_entries: Vec<mesh::Fan>,
    /// Patch records of the M¹ faces.
    pub patches: Patches,
    /// Table level the patches were made for.
    pub table_level: u32,
}

impl Subdivider {
    /// Prepares the subdivision of meshes with connectivity `m0`.
    pub fn new(m0: &Topology, bft: &BftSet) -> Result<Self, SubdivError> {
        let (triangles, entries) = cpu::loop_step(m0);
        let m1 = Topology::new(entries.rows(), triangles)?;
        let normal_entries = (0..m1.vertex_count() as u32).map(|v| m1.fan(v)).collect();
        let patches = Patches::new(&m1, bft)?;
        Ok(Self {
            m0: m0.clone(),
            entries,
            m1,
            normal_entries,
            patches,
            table_level: bft.level,
        })
    }

    /// Segments per patch edge for surface level `level` (1..=L + 1).
    pub fn segments(&self, level: u32) -> Result<u32, SubdivError> {
        if level == 0 || level > self.table_level + 1 {
            return Err(SubdivError::Level {
                level,
                max: self.table_level + 1,
                table_level: self.table_level,
            });
        }
        Ok(1 << (level - 1))
    }

    /// M¹ positions and normals from M⁰ positions (the initial step, in f64).
    pub fn initial_step(
        &self,
        m0_positions: &[DVec3],
    ) -> Result<(Vec<DVec3>, Vec<DVec3>), SubdivError> {
        if m0_positions.len() != self.m0.vertex_count() {
            return Err(SubdivError::PositionCount {
                given: m0_positions.len(),
                expected: self.m0.vertex_count(),
            });
        }
        let p1 = self.entries.apply(m0_positions);
        let n1 = self
            .normal_entries
            .iter()
            .enumerate()
            .map(|(v, fan)| cpu::limit_normal(p1[v], fan, &p1))
            .collect();
        Ok((p1, n1))
    }

    /// [`Subdivider::initial_step`] from and to f32 (what the main step reads).
    pub fn initial_step_f32(
        &self,
        m0_positions: &[Vec3],
    ) -> Result<(Vec<Vec3>, Vec<Vec3>), SubdivError> {
        let p0: Vec<DVec3> = m0_positions.iter().map(|p| p.as_dvec3()).collect();
        let (p1, n1) = self.initial_step(&p0)?;
        let f32s = |v: Vec<DVec3>| v.iter().map(|p| p.as_vec3()).collect();
        Ok((f32s(p1), f32s(n1)))
    }

    /// The whole pipeline on the CPU: initial step, then every patch at surface level `level`.
    pub fn evaluate_cpu(
        &self,
        bft: &BftSet,
        m0_positions: &[Vec3],
        level: u32,
    ) -> Result<Refined, SubdivError> {
        let s = self.segments(level)?;
        let (p1, n1) = self.initial_step_f32(m0_positions)?;
        let (positions, normals) = self.patches.evaluate(bft, s, &p1, &n1);
        Ok(Refined {
            positions,
            normals,
            indices: self.patches.triangulate(s),
        })
    }
}
