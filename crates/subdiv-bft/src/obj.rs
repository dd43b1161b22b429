//! A small OBJ reader for control meshes: `v` positions and `f` faces (polygons fan-split into
//! triangles; `v/vt/vn` references and negative indices accepted), and OpenSubdiv's `t` tags
//! (`interpolateboundary`, `crease`, `corner`), which plain OBJ readers drop.

use glam::DVec3;

use crate::{SubdivError, TriMesh};

/// An OBJ control mesh.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ObjMesh {
    /// Vertex positions.
    pub positions: Vec<DVec3>,
    /// Triangles (polygons fan-split from their first vertex).
    pub triangles: Vec<[u32; 3]>,
    /// OpenSubdiv's `t interpolateboundary` value if present (0 none, 1 edge and corner,
    /// 2 edge only — the rule this crate implements).
    pub interpolate_boundary: Option<u32>,
    /// Number of `crease` and `corner` tags (sharpness this crate does not implement).
    pub sharpness_tags: usize,
}

/// The largest coordinate magnitude a control mesh may use: subdivision takes affine
/// combinations of positions, which stay finite in `f32` well below its 3.4e38.
pub const MAX_COORDINATE: f64 = 1e30;

impl ObjMesh {
    /// Parses OBJ text.
    pub fn parse(text: &str) -> Result<Self, SubdivError> {
        let mut m = Self::default();
        for (n, line) in text.lines().enumerate() {
            let bad = |problem: String| SubdivError::Obj {
                line: n + 1,
                problem,
            };
            let mut words = line.split_whitespace();
            match words.next() {
                Some("v") => {
                    let c: Vec<f64> = words
                        .take(3)
                        .map(|w| {
                            w.parse::<f64>()
                                .map_err(|e| bad(format!("coordinate {w:?}: {e}")))
                        })
                        .collect::<Result<_, _>>()?;
                    if c.len() != 3 {
                        return Err(bad("a vertex needs three coordinates".into()));
                    }
                    if let Some(x) = c.iter().find(|x| !(x.abs() <= MAX_COORDINATE)) {
                        return Err(bad(format!(
                            "coordinate {x:e} is not a finite number of magnitude at most \
                             {MAX_COORDINATE:e} (the refined and limit positions are f32)"
                        )));
                    }
                    m.positions.push(DVec3::new(c[0], c[1], c[2]));
                }
                Some("f") => {
                    let count = m.positions.len() as i64;
                    let face: Vec<u32> = words
                        .map(|w| {
                            let first = w.split('/').next().unwrap_or("");
                            let i: i64 = first
                                .parse()
                                .map_err(|e| bad(format!("face index {w:?}: {e}")))?;
                            let i = if i < 0 { count + i } else { i - 1 };
                            if i < 0 || i >= count {
                                return Err(bad(format!("face index {w} outside 1..={count}")));
                            }
                            Ok(i as u32)
                        })
                        .collect::<Result<_, _>>()?;
                    if face.len() < 3 {
                        return Err(bad("a face needs at least three vertices".into()));
                    }
                    for k in 1..face.len() - 1 {
                        m.triangles.push([face[0], face[k], face[k + 1]]);
                    }
                }
                Some("t") => match words.next() {
                    Some("interpolateboundary") => {
                        let value = words.nth(1).and_then(|w| w.parse().ok());
                        m.interpolate_boundary = Some(
                            value.ok_or_else(|| bad("interpolateboundary needs a value".into()))?,
                        );
                    }
                    Some("crease" | "corner") => m.sharpness_tags += 1,
                    _ => {}
                },
                _ => {}
            }
        }
        Ok(m)
    }

    /// Reads and parses a file.
    pub fn read(path: &std::path::Path) -> Result<Self, SubdivError> {
        let text = std::fs::read_to_string(path).map_err(|e| SubdivError::Obj {
            line: 0,
            problem: format!("{}: {e}", path.display()),
        })?;
        Self::parse(&text)
    }

    /// The validated mesh, refusing tags this crate does not implement (creases, corners,
    /// boundary rules other than "edge only") rather than subdividing them wrongly.
    pub fn into_mesh(self) -> Result<TriMesh, SubdivError> {
        let bad = |problem: String| SubdivError::Obj { line: 0, problem };
        if self.sharpness_tags > 0 {
            return Err(bad(format!(
                "{} crease/corner tags: sharp features are not implemented",
                self.sharpness_tags
            )));
        }
        if let Some(b) = self.interpolate_boundary.filter(|&b| b != 2) {
            return Err(bad(format!(
                "interpolateboundary {b}: only 2 (edge only) is implemented"
            )));
        }
        if self.triangles.is_empty() {
            return Err(bad("no faces: nothing to subdivide".into()));
        }
        TriMesh::new(self.positions, self.triangles)
    }

    /// OBJ text of a mesh (positions, optional normals, triangles).
    pub fn write(
        positions: &[glam::Vec3],
        normals: Option<&[glam::Vec3]>,
        indices: &[u32],
    ) -> String {
        use std::fmt::Write;
        let mut s = String::with_capacity(positions.len() * 40 + indices.len() * 8);
        for p in positions {
            let _ = writeln!(s, "v {} {} {}", p.x, p.y, p.z);
        }
        if let Some(ns) = normals {
            for n in ns {
                let _ = writeln!(s, "vn {} {} {}", n.x, n.y, n.z);
            }
        }
        for t in indices.chunks_exact(3) {
            let [a, b, c] = [t[0] + 1, t[1] + 1, t[2] + 1];
            if normals.is_some() {
                let _ = writeln!(s, "f {a}//{a} {b}//{b} {c}//{c}");
            } else {
                let _ = writeln!(s, "f {a} {b} {c}");
            }
        }
        s
    }
}
