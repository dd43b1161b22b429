//! Basis-function tables (§2.1.1, §2.2.1): for every face configuration of M¹ (at most one
//! extraordinary vertex), the limit-position weights over the face's one-ring at every vertex
//! of a uniform `2^L × 2^L` grid of the face.
//!
//! Tables are built from *configuration meshes* (the face and its one-ring): the unit basis
//! vector of every one-ring vertex is subdivided L times with the CPU reference and projected
//! to the limit, all basis functions at once.

use std::collections::HashMap;

use rayon::prelude::*;

use crate::{
    SubdivError,
    cpu::{limit_stencils, loop_step},
    mesh::{NONE, Topology, prev},
};

/// Largest valence the default tables cover (the paper's experiments: 18).
pub const MAX_VALENCE: u8 = 18;
/// Default table level: `2^5 = 32` segments per M¹ edge (32×32 per patch).
pub const DEFAULT_LEVEL: u32 = 5;
/// Largest one-ring a table may have (valence-18 interior vertex: 18 + 6).
pub const MAX_RING: usize = 24;

const MAGIC: &[u8; 8] = b"LOOPBFT\0";
/// Version of the binary table file written by [`BftSet::to_bytes`].
pub const FILE_VERSION: u32 = 1;

/// How one corner of a face sits in its vertex's fan.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Corner {
    /// An interior vertex of the given valence (6 is regular).
    Interior(u8),
    /// A boundary vertex: `before` triangles of its fan lie across the face's edge to the next
    /// corner, `after` across the edge to the previous corner (3 triangles in all is regular).
    Boundary {
        /// Triangles on the side of the edge (corner, next corner).
        before: u8,
        /// Triangles on the side of the edge (corner, previous corner).
        after: u8,
    },
}

impl Corner {
    /// Whether the vertex is regular (interior valence 6 or boundary valence 4).
    pub fn is_regular(self) -> bool {
        match self {
            Corner::Interior(n) => n == 6,
            Corner::Boundary { before, after } => before + after == 2,
        }
    }

    /// Number of edges at the vertex.
    pub fn valence(self) -> u32 {
        match self {
            Corner::Interior(n) => u32::from(n),
            Corner::Boundary { before, after } => u32::from(before) + u32::from(after) + 2,
        }
    }
}

/// A face configuration: its three corners, rotated to the smallest of the three rotations.
pub type Key = [Corner; 3];

/// Number of vertices of a triangle grid with `s` segments per edge.
pub fn grid_count(s: u32) -> usize {
    ((s + 1) * (s + 2) / 2) as usize
}

/// Linear index of grid vertex `(i, j)` (`i + j ≤ s`), rows of constant `j`.
pub fn grid_index(i: u32, j: u32, s: u32) -> usize {
    (j * (s + 1) - j * j.saturating_sub(1) / 2 + i) as usize
}

/// The corner of face-half-edge `h` (from the corner to the next one).
fn corner(top: &Topology, h: u32) -> Corner {
    let mut after = 0u32;
    let mut x = h;
    loop {
        let r = top.rotate_ccw(x);
        if r == h {
            return Corner::Interior((after + 1).min(255) as u8);
        }
        if r == NONE {
            break;
        }
        after += 1;
        x = r;
    }
    let mut before = 0u32;
    let mut x = h;
    loop {
        let r = top.rotate_cw(x);
        if r == NONE {
            break;
        }
        before += 1;
        x = r;
    }
    Corner::Boundary {
        before: before.min(255) as u8,
        after: after.min(255) as u8,
    }
}

/// The configuration of triangle `f` seen from rotation `r` (corner `r` first).
fn rotated_key(top: &Topology, f: u32, r: u32) -> Key {
    [0, 1, 2].map(|i| corner(top, 3 * f + (r + i) % 3))
}

/// Canonical key and rotation of triangle `f`: the smallest key over its three rotations.
pub fn face_key(top: &Topology, f: u32) -> (Key, u32) {
    (0..3)
        .map(|r| (rotated_key(top, f, r), r))
        .min()
        .unwrap_or(([Corner::Interior(6); 3], 0))
}

/// The one-ring of triangle `f` at rotation `r` in the order the tables use (structural
/// slots, the same for every face of one configuration): the three corners; the vertices
/// across edges (0, 1), (1, 2), (2, 0) where those triangles exist; then each corner's other
/// neighbours, counter-clockwise from the previous corner, then clockwise from the next one.
///
/// A vertex may fill two slots (the across-vertex of a valence-3 corner, or a small mesh
/// whose one-ring closes on itself); the tables put its weight in the first of a
/// configuration's repeated slots, and sums over repeated slots stay exact by linearity.
pub fn face_ring(top: &Topology, f: u32, r: u32) -> Vec<u32> {
    let hs = [0, 1, 2].map(|i| 3 * f + (r + i) % 3);
    let mut ring: Vec<u32> = hs.iter().map(|&h| top.origin(h)).collect();
    for &h in &hs {
        let t = top.twin[h as usize];
        if t != NONE {
            ring.push(top.origin(prev(t)));
        }
    }
    for &h in &hs {
        let mut forward = Vec::new();
        let mut x = h;
        loop {
            forward.push(top.origin(prev(x)));
            let r = top.rotate_ccw(x);
            if r == NONE || r == h {
                break;
            }
            x = r;
        }
        let closed = top.rotate_ccw(x) == h;
        // forward = [previous corner, across-vertex, others…, (closed: across-vertex of the
        // next edge, next corner)].
        let end = if closed {
            forward.len() - 2
        } else {
            forward.len()
        };
        ring.extend(forward.iter().take(end).skip(2));
        if !closed {
            let mut backward = Vec::new();
            let mut x = h;
            loop {
                let r = top.rotate_cw(x);
                if r == NONE {
                    break;
                }
                backward.push(top.dest(r));
                x = r;
            }
            ring.extend(backward.iter().skip(1));
        }
    }
    ring
}

/// The configuration mesh of `key`: the face `(0, 1, 2)` (triangle 0) and its one-ring, or
/// `None` when the corners cannot meet in a manifold mesh.
pub fn configuration_mesh(key: Key) -> Option<Topology> {
    let mut next_vertex = 3u32;
    let mut new = || {
        next_vertex += 1;
        next_vertex - 1
    };
    // across[i]: the vertex opposite the face across edge (i, i + 1).
    let mut across: [Option<u32>; 3] = [None; 3];
    let mut faces: Vec<[u32; 3]> = vec![[0, 1, 2]];
    for i in 0..3usize {
        let (v, n1, n2) = (i as u32, (i as u32 + 1) % 3, (i as u32 + 2) % 3);
        let (i1, i2) = (i, (i + 2) % 3);
        let mut ring = Vec::new();
        let closed;
        match key[i] {
            Corner::Interior(n) if n >= 3 => {
                closed = true;
                if n == 3 {
                    let y = across[i2].or(across[i1]).unwrap_or_else(&mut new);
                    if across[i1].is_some_and(|a| a != y) || across[i2].is_some_and(|a| a != y) {
                        return None;
                    }
                    across[i1] = Some(y);
                    across[i2] = Some(y);
                    ring.extend([n1, n2, y]);
                } else {
                    let x2 = *across[i2].get_or_insert_with(&mut new);
                    ring.extend([n1, n2, x2]);
                    for _ in 0..n - 4 {
                        ring.push(new());
                    }
                    ring.push(*across[i1].get_or_insert_with(&mut new));
                }
            }
            Corner::Interior(_) => return None,
            Corner::Boundary { before, after } => {
                closed = false;
                let mut pre = Vec::new();
                if before > 0 {
                    pre.push(*across[i1].get_or_insert_with(&mut new));
                    for _ in 1..before {
                        pre.push(new());
                    }
                }
                ring.extend(pre.into_iter().rev());
                ring.extend([n1, n2]);
                if after > 0 {
                    ring.push(*across[i2].get_or_insert_with(&mut new));
                    for _ in 1..after {
                        ring.push(new());
                    }
                }
            }
        }
        let pairs = ring.len() - usize::from(!closed);
        for j in 0..pairs {
            faces.push([v, ring[j], ring[(j + 1) % ring.len()]]);
        }
    }
    let canon = |t: [u32; 3]| {
        let m = (0..3).min_by_key(|&k| t[k]).unwrap_or(0);
        [t[m], t[(m + 1) % 3], t[(m + 2) % 3]]
    };
    let mut seen = Vec::new();
    faces.retain(|&t| {
        let c = canon(t);
        let fresh = !seen.contains(&c);
        seen.push(c);
        fresh
    });
    let top = Topology::new(next_vertex as usize, faces).ok()?;
    (rotated_key(&top, 0, 0) == key).then_some(top)
}

/// One table: the limit weights over the configuration's one-ring at every grid vertex.
#[derive(Clone, Debug, PartialEq)]
pub struct Table {
    /// The configuration.
    pub key: Key,
    /// One-ring size (weights per grid vertex).
    pub ring_size: u32,
    /// `grid_count(2^level) × ring_size` weights, grid vertex major.
    pub weights: Vec<f32>,
}

/// Builds the table of `key` at `level` from its configuration mesh.
pub fn build_table(key: Key, level: u32) -> Result<Table, SubdivError> {
    let bad = |why: &str| SubdivError::Table(format!("configuration {key:?}: {why}"));
    let mut top = configuration_mesh(key).ok_or_else(|| bad("corners cannot meet"))?;
    let ring = face_ring(&top, 0, 0);
    let n = top.vertex_count();
    // Unit basis vector per vertex, subdivided as a whole (stride n).
    let mut values = vec![0.0f64; n * n];
    for v in 0..n {
        values[v * n + v] = 1.0;
    }
    // Grid coordinates (scale 2^ℓ) of the vertices inside the face; `patch` = its triangles.
    let mut coords: HashMap<u32, (u32, u32)> =
        HashMap::from([(0, (0, 0)), (1, (1, 0)), (2, (0, 1))]);
    let mut patch = vec![0u32];
    for _ in 0..level {
        let (triangles, stencils) = loop_step(&top);
        let nv = top.vertex_count() as u32;
        let mut fine: HashMap<u32, (u32, u32)> = coords
            .iter()
            .map(|(&v, &(i, j))| (v, (2 * i, 2 * j)))
            .collect();
        let mut children = Vec::with_capacity(patch.len() * 4);
        for &f in &patch {
            for k in 0..3 {
                let h = 3 * f + k;
                let (a, b) = (coords[&top.origin(h)], coords[&top.dest(h)]);
                fine.insert(nv + top.edge_of[h as usize], (a.0 + b.0, a.1 + b.1));
            }
            children.extend(4 * f..4 * f + 4);
        }
        values = stencils.apply_strided(&values, n);
        top = Topology::new(stencils.rows(), triangles)?;
        coords = fine;
        patch = children;
    }
    let limit = limit_stencils(&top).apply_strided(&values, n);
    let s = 1u32 << level;
    let mut weights = vec![0.0f32; grid_count(s) * ring.len()];
    let mut found = 0;
    for (&v, &(i, j)) in &coords {
        let row = &limit[v as usize * n..(v as usize + 1) * n];
        let g = grid_index(i, j, s);
        for (r, &rv) in ring.iter().enumerate() {
            if !ring[..r].contains(&rv) {
                weights[g * ring.len() + r] = row[rv as usize] as f32;
            }
        }
        let outside: f64 = (0..n as u32)
            .filter(|c| !ring.contains(c))
            .map(|c| row[c as usize].abs())
            .sum();
        if outside > 1e-12 {
            return Err(bad("a limit weight falls outside the one-ring"));
        }
        found += 1;
    }
    if found != grid_count(s) {
        return Err(bad("grid incomplete"));
    }
    Ok(Table {
        key,
        ring_size: ring.len() as u32,
        weights,
    })
}

/// Every configuration a face of M¹ can have with vertices of valence ≤ `max_valence`.
///
/// After one step, a face is either a corner face `(a, ab, ca)` of a coarse vertex `a` (any
/// valence, interior or boundary; `ab` / `ca` are regular and on the boundary exactly when the
/// coarse edge is) or a middle face `(ab, bc, ca)` of three regular vertices.
pub fn m1_configurations(max_valence: u8) -> Vec<Key> {
    let mut corners: Vec<Corner> = (3..=max_valence).map(Corner::Interior).collect();
    for faces in 1..max_valence {
        for before in 0..faces {
            corners.push(Corner::Boundary {
                before,
                after: faces - 1 - before,
            });
        }
    }
    let mut keys: Vec<Key> = corners
        .into_iter()
        .map(|a| {
            let (before, after) = match a {
                Corner::Interior(_) => (1, 1),
                Corner::Boundary { before, after } => (before, after),
            };
            // The corners at the midpoints of the edges to the next and previous corner: on
            // the boundary where that edge is, else regular interior vertices.
            let midpoint = |on_boundary: bool, before, after| {
                if on_boundary {
                    Corner::Boundary { before, after }
                } else {
                    Corner::Interior(6)
                }
            };
            let ab = midpoint(before == 0, 2, 0);
            let ca = midpoint(after == 0, 0, 2);
            [a, ab, ca]
        })
        .collect();
    for mask in 0..8u32 {
        keys.push([0, 1, 2].map(|i| {
            if mask >> i & 1 == 1 {
                Corner::Boundary {
                    before: 1,
                    after: 1,
                }
            } else {
                Corner::Interior(6)
            }
        }));
    }
    let mut canonical: Vec<Key> = keys
        .into_iter()
        .filter_map(|k| {
            let top = configuration_mesh(k)?;
            Some(face_key(&top, 0).0)
        })
        .collect();
    canonical.sort();
    canonical.dedup();
    canonical
}

/// A set of tables at one level, looked up by configuration.
#[derive(Clone, Debug, PartialEq)]
pub struct BftSet {
    /// Table level L: `2^L` segments per M¹ edge.
    pub level: u32,
    /// The tables, sorted by key.
    pub tables: Vec<Table>,
    lookup: HashMap<Key, u32>,
}

impl BftSet {
    /// Builds the tables of every M¹ configuration up to `max_valence` at `level` (in parallel).
    pub fn build(level: u32, max_valence: u8) -> Result<Self, SubdivError> {
        if !(1..=7).contains(&level) {
            return Err(SubdivError::Table(format!(
                "table level {level} outside 1..=7"
            )));
        }
        if !(3..=(MAX_RING as u8 - 6)).contains(&max_valence) {
            return Err(SubdivError::Table(format!(
                "maximum valence {max_valence} outside 3..={}",
                MAX_RING - 6
            )));
        }
        let tables = m1_configurations(max_valence)
            .into_par_iter()
            .map(|k| build_table(k, level))
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Self::from_tables(level, tables))
    }

    /// Default cache file `loop-l{level}-v{max_valence}.bft` in `$SUBDIV_BFT_DIR`, else in the
    /// user's cache folder (`$XDG_CACHE_HOME/deferred`, `~/.cache/deferred`,
    /// `~/Library/Caches/deferred` on macOS, `%LOCALAPPDATA%\deferred` on Windows), else in the
    /// system's temporary folder: never a path of the machine the crate was built on.
    pub fn default_path(level: u32, max_valence: u8) -> std::path::PathBuf {
        let var = |name| {
            std::env::var_os(name)
                .filter(|v| !v.is_empty())
                .map(std::path::PathBuf::from)
        };
        let cache = var("XDG_CACHE_HOME")
            .or_else(|| var("LOCALAPPDATA"))
            .or_else(|| {
                let home = var("HOME")?;
                Some(if cfg!(target_os = "macos") {
                    home.join("Library/Caches")
                } else {
                    home.join(".cache")
                })
            })
            .unwrap_or_else(std::env::temp_dir);
        var("SUBDIV_BFT_DIR")
            .unwrap_or_else(|| cache.join("deferred"))
            .join(format!("loop-l{level}-v{max_valence}.bft"))
    }

    /// Reads the table file at `path` when it exists and holds this level and valence range;
    /// otherwise builds the tables and writes them there (a failed write is only reported).
    pub fn cached(
        path: &std::path::Path,
        level: u32,
        max_valence: u8,
    ) -> Result<Self, SubdivError> {
        if let Ok(bytes) = std::fs::read(path) {
            match Self::from_bytes(&bytes) {
                Ok(set) if set.level == level && set.max_valence() == max_valence => {
                    return Ok(set);
                }
                Ok(_) => {}
                Err(e) => eprintln!("{}: {e}; rebuilding", path.display()),
            }
        }
        let set = Self::build(level, max_valence)?;
        // Written beside the cache file and renamed into place: a reader never sees half a
        // table file; a cache that cannot be written only costs the next run the build time.
        let tmp = path.with_extension(format!("bft.{}.tmp", std::process::id()));
        let written = path
            .parent()
            .map_or(Ok(()), std::fs::create_dir_all)
            .and_then(|()| std::fs::write(&tmp, set.to_bytes()))
            .and_then(|()| std::fs::rename(&tmp, path));
        if let Err(e) = written {
            let _ = std::fs::remove_file(&tmp);
            eprintln!("could not cache the tables at {}: {e}", path.display());
        }
        Ok(set)
    }

    /// Largest interior valence with a table.
    pub fn max_valence(&self) -> u8 {
        self.tables
            .iter()
            .flat_map(|t| t.key)
            .filter_map(|c| match c {
                Corner::Interior(n) => Some(n),
                Corner::Boundary { .. } => None,
            })
            .max()
            .unwrap_or(0)
    }

    fn from_tables(level: u32, tables: Vec<Table>) -> Self {
        let lookup = tables
            .iter()
            .enumerate()
            .map(|(i, t)| (t.key, i as u32))
            .collect();
        Self {
            level,
            tables,
            lookup,
        }
    }

    /// Index of the table for `key`.
    pub fn find(&self, key: &Key) -> Option<u32> {
        self.lookup.get(key).copied()
    }

    /// Segments per M¹ edge of the tables' grid.
    pub fn segments(&self) -> u32 {
        1 << self.level
    }

    /// Bytes of weights (f32).
    pub fn weight_bytes(&self) -> usize {
        self.tables.iter().map(|t| t.weights.len() * 4).sum()
    }

    /// The versioned binary file: magic `LOOPBFT\0`, then little-endian u32 version (1), level,
    /// table count; per table three corners of 4 bytes (kind 0 interior / 1 boundary, valence
    /// or before, 0 or after, 0), u32 ring size, then `grid_count(2^level) × ring size` f32
    /// weights, grid vertex `grid_index(i, j)` major.
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut out = Vec::with_capacity(self.weight_bytes() + 64);
        out.extend_from_slice(MAGIC);
        for x in [FILE_VERSION, self.level, self.tables.len() as u32] {
            out.extend_from_slice(&x.to_le_bytes());
        }
        for t in &self.tables {
            for c in t.key {
                out.extend_from_slice(&match c {
                    Corner::Interior(n) => [0, n, 0, 0],
                    Corner::Boundary { before, after } => [1, before, after, 0],
                });
            }
            out.extend_from_slice(&t.ring_size.to_le_bytes());
            for w in &t.weights {
                out.extend_from_slice(&w.to_le_bytes());
            }
        }
        out
    }

    /// Reads a file written by [`BftSet::to_bytes`]; any mismatch is an error naming it.
    pub fn from_bytes(bytes: &[u8]) -> Result<Self, SubdivError> {
        let bad = |why: String| SubdivError::TableFile(why);
        let mut r = Reader { bytes, at: 0 };
        if r.take(8)? != MAGIC {
            return Err(bad("not a Loop BFT file (bad magic)".into()));
        }
        let version = r.u32()?;
        if version != FILE_VERSION {
            return Err(bad(format!(
                "file version {version}, this build reads version {FILE_VERSION}; regenerate with `cargo xtask bft`"
            )));
        }
        let level = r.u32()?;
        let count = r.u32()?;
        if !(1..=7).contains(&level) || count > 100_000 {
            return Err(bad(format!(
                "implausible level {level} or table count {count}"
            )));
        }
        let grid = grid_count(1 << level);
        let mut tables = Vec::new();
        for _ in 0..count {
            let mut key = [Corner::Interior(6); 3];
            for c in &mut key {
                let b = r.take(4)?;
                *c = match b[0] {
                    0 => Corner::Interior(b[1]),
                    1 => Corner::Boundary {
                        before: b[1],
                        after: b[2],
                    },
                    k => return Err(bad(format!("unknown corner kind {k}"))),
                };
            }
            let ring_size = r.u32()?;
            if ring_size as usize > MAX_RING {
                return Err(bad(format!("ring size {ring_size} above {MAX_RING}")));
            }
            let raw = r.take(grid * ring_size as usize * 4)?;
            let weights = raw
                .chunks_exact(4)
                .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
                .collect();
            tables.push(Table {
                key,
                ring_size,
                weights,
            });
        }
        if r.at != bytes.len() {
            return Err(bad(format!(
                "{} bytes after the last table",
                bytes.len() - r.at
            )));
        }
        Ok(Self::from_tables(level, tables))
    }
}

struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl<'a> Reader<'a> {
    fn take(&mut self, n: usize) -> Result<&'a [u8], SubdivError> {
        let s = self
            .bytes
            .get(self.at..self.at + n)
            .ok_or_else(|| SubdivError::TableFile(format!("truncated at byte {}", self.at)))?;
        self.at += n;
        Ok(s)
    }

    fn u32(&mut self) -> Result<u32, SubdivError> {
        self.take(4)
            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn regular_configuration_has_twelve_ring_vertices() {
        let key = [Corner::Interior(6); 3];
        let top = configuration_mesh(key).expect("regular configuration");
        assert_eq!(face_ring(&top, 0, 0).len(), 12);
        assert_eq!(top.triangles.len(), 13);
    }

    #[test]
    fn extraordinary_ring_sizes() {
        for n in 3..=18u8 {
            let key = [
                Corner::Interior(n),
                Corner::Interior(6),
                Corner::Interior(6),
            ];
            let top = configuration_mesh(key).expect("interior configuration");
            let mut ring = face_ring(&top, 0, 0);
            // A valence-3 corner's two across-vertices are one vertex in two slots.
            assert_eq!(ring.len(), n.max(4) as usize + 6, "valence {n}");
            ring.sort_unstable();
            ring.dedup();
            assert_eq!(ring.len(), n as usize + 6, "valence {n}");
        }
    }

    #[test]
    fn grid_index_is_a_bijection() {
        for s in [1u32, 2, 4, 8] {
            let mut seen = vec![false; grid_count(s)];
            for j in 0..=s {
                for i in 0..=s - j {
                    let g = grid_index(i, j, s);
                    assert!(!seen[g]);
                    seen[g] = true;
                }
            }
            assert!(seen.iter().all(|&b| b));
        }
    }
}
