//! Half-edge topology of a triangle mesh with validation (§2.1.1: Loop subdivision needs a
//! manifold triangle mesh; boundaries are allowed).
//!
//! Half-edge `h = 3·f + i` runs from corner `i` to corner `i + 1` of triangle `f`.

use crate::SubdivError;

/// Marks a half-edge without a twin (a boundary edge).
pub const NONE: u32 = u32::MAX;

/// A validated manifold, consistently oriented triangle mesh.
#[derive(Clone, Debug, PartialEq)]
pub struct Topology {
    /// Three vertex indices per triangle, counter-clockwise seen from outside.
    pub triangles: Vec<[u32; 3]>,
    /// Opposite half-edge of each half-edge, or [`NONE`] on a boundary.
    pub twin: Vec<u32>,
    /// One outgoing half-edge per vertex (the first of its fan, on a boundary the one whose
    /// twin is [`NONE`]), or [`NONE`] for a vertex no triangle uses.
    pub outgoing: Vec<u32>,
    /// Undirected edge of each half-edge.
    pub edge_of: Vec<u32>,
    /// One half-edge per undirected edge (the one with a twin of higher index, or the only one).
    pub edges: Vec<u32>,
}

/// One vertex's fan of triangles in counter-clockwise order.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Fan {
    /// Neighbours in counter-clockwise order; triangle `j` of the fan is `(v, ring[j], ring[j + 1])`
    /// (indices modulo the ring length when the fan is closed).
    pub ring: Vec<u32>,
    /// Whether the vertex lies on the boundary (open fan: `ring.len()` = faces + 1).
    pub boundary: bool,
}

impl Fan {
    /// Number of edges at the vertex (its valence).
    pub fn valence(&self) -> usize {
        self.ring.len()
    }
}

/// Next half-edge in the same triangle.
pub fn next(h: u32) -> u32 {
    if h % 3 == 2 { h - 2 } else { h + 1 }
}

/// Previous half-edge in the same triangle.
pub fn prev(h: u32) -> u32 {
    if h.is_multiple_of(3) { h + 2 } else { h - 1 }
}

impl Topology {
    /// Builds and validates the topology of `triangles` over `vertex_count` vertices.
    ///
    /// Errors: an index out of range, a triangle using a vertex twice, an edge shared by more
    /// than two triangles or twice in the same direction (non-manifold or inconsistently
    /// oriented), a vertex whose triangles do not form one fan (non-manifold vertex).
    pub fn new(vertex_count: usize, triangles: Vec<[u32; 3]>) -> Result<Self, SubdivError> {
        for (f, t) in triangles.iter().enumerate() {
            if let Some(&i) = t.iter().find(|&&i| i as usize >= vertex_count) {
                return Err(SubdivError::IndexOutOfRange {
                    triangle: f,
                    index: i,
                    vertices: vertex_count,
                });
            }
            if t[0] == t[1] || t[1] == t[2] || t[2] == t[0] {
                return Err(SubdivError::Degenerate { triangle: f });
            }
        }
        if triangles.len() * 3 >= NONE as usize {
            return Err(SubdivError::TooLarge(format!(
                "{} triangles exceed 32-bit half-edge indices",
                triangles.len()
            )));
        }
        let origin = |h: u32| triangles[h as usize / 3][h as usize % 3];
        let dest = |h: u32| origin(next(h));
        // Directed edges sorted by (from, to): twins are found by binary search.
        let mut directed: Vec<(u32, u32, u32)> = (0..triangles.len() as u32 * 3)
            .map(|h| (origin(h), dest(h), h))
            .collect();
        directed.sort_unstable();
        for w in directed.windows(2) {
            if w[0].0 == w[1].0 && w[0].1 == w[1].1 {
                return Err(SubdivError::NonManifoldEdge {
                    a: w[0].0,
                    b: w[0].1,
                    problem: "two triangles use it in the same direction (non-manifold or inconsistently oriented)",
                });
            }
        }
        let find = |a: u32, b: u32| {
            directed
                .binary_search_by(|&(x, y, _)| (x, y).cmp(&(a, b)))
                .ok()
                .map(|i| directed[i].2)
        };
        let mut twin = vec![NONE; triangles.len() * 3];
        for &(a, b, h) in &directed {
            if let Some(t) = find(b, a) {
                twin[h as usize] = t;
            }
        }
        let mut edge_of = vec![NONE; twin.len()];
        let mut edges = Vec::new();
        for h in 0..twin.len() as u32 {
            let t = twin[h as usize];
            if t == NONE || h < t {
                edge_of[h as usize] = edges.len() as u32;
                if t != NONE {
                    edge_of[t as usize] = edges.len() as u32;
                }
                edges.push(h);
            }
        }
        // Fans: every vertex's triangles must be reachable by rotating around it.
        let mut outgoing = vec![NONE; vertex_count];
        let mut incident = vec![0u32; vertex_count];
        for h in 0..twin.len() as u32 {
            let v = origin(h) as usize;
            incident[v] += 1;
            if outgoing[v] == NONE || twin[h as usize] == NONE {
                if twin[h as usize] == NONE
                    && outgoing[v] != NONE
                    && twin[outgoing[v] as usize] == NONE
                {
                    return Err(SubdivError::NonManifoldVertex { vertex: v as u32 });
                }
                outgoing[v] = h;
            }
        }
        let topology = Self {
            triangles,
            twin,
            outgoing,
            edge_of,
            edges,
        };
        for v in 0..vertex_count {
            if topology.outgoing[v] != NONE
                && topology.fan(v as u32).ring.len() - usize::from(topology.fan(v as u32).boundary)
                    != incident[v] as usize
            {
                return Err(SubdivError::NonManifoldVertex { vertex: v as u32 });
            }
        }
        Ok(topology)
    }

    /// Number of vertices (including any no triangle uses).
    pub fn vertex_count(&self) -> usize {
        self.outgoing.len()
    }

    /// Vertex a half-edge starts from.
    pub fn origin(&self, h: u32) -> u32 {
        self.triangles[h as usize / 3][h as usize % 3]
    }

    /// Vertex a half-edge points to.
    pub fn dest(&self, h: u32) -> u32 {
        self.origin(next(h))
    }

    /// The next outgoing half-edge counter-clockwise around its origin, or [`NONE`] at a boundary.
    pub fn rotate_ccw(&self, h: u32) -> u32 {
        self.twin[prev(h) as usize]
    }

    /// The next outgoing half-edge clockwise around its origin, or [`NONE`] at a boundary.
    pub fn rotate_cw(&self, h: u32) -> u32 {
        match self.twin[h as usize] {
            NONE => NONE,
            t => next(t),
        }
    }

    /// Whether the edge of half-edge `h` lies on the boundary.
    pub fn is_boundary_edge(&self, h: u32) -> bool {
        self.twin[h as usize] == NONE
    }

    /// The fan of `v` (empty ring for an unused vertex).
    pub fn fan(&self, v: u32) -> Fan {
        let start = self.outgoing[v as usize];
        let mut ring = Vec::new();
        if start == NONE {
            return Fan {
                ring,
                boundary: false,
            };
        }
        let boundary = self.twin[start as usize] == NONE;
        let mut h = start;
        loop {
            ring.push(self.dest(h));
            let r = self.rotate_ccw(h);
            if r == NONE {
                ring.push(self.origin(prev(h)));
                break;
            }
            if r == start || ring.len() > self.twin.len() {
                break;
            }
            h = r;
        }
        Fan { ring, boundary }
    }
}
