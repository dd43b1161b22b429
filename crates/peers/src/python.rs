//! Loop subdivision by MeshLab (`pymeshlab`) and Open3D (`open3d`) on the CPU, run by the
//! Python interpreter (`$PYTHON`, else `python3`) where the module imports; where it does not,
//! [`Outcome::Unavailable`] says why, and the benchmark reports that instead of a time.

use std::path::Path;
use std::process::Command;

use anyhow::{Context, Result, bail};
use glam::DVec3;

/// A Python library with a Loop subdivision.
#[derive(Clone, Copy, Debug)]
pub struct Peer {
    /// What the reports call it.
    pub name: &'static str,
    /// The Python module.
    pub module: &'static str,
}

/// MeshLab's Loop filter (`meshing_surface_subdivision_loop`, Loop's weights, every edge split)
/// and Open3D's `TriangleMesh.subdivide_loop`.
pub const PEERS: [Peer; 2] = [
    Peer {
        name: "MeshLab",
        module: "pymeshlab",
    },
    Peer {
        name: "Open3D",
        module: "open3d",
    },
];

/// Loads the OBJ, then times `level` Loop steps `runs` times (the mesh loaded again before
/// each), prints `{"version", "ms": [...]}` as JSON and writes the positions of the last
/// result's vertices that a triangle uses as little-endian f64 triples; prints `{"unavailable": why}` if the module does not
/// import.
const SCRIPT: &str = r#"
import json, sys, time
module, obj, level, runs, out = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4]), sys.argv[5]
try:
    import numpy
    if module == "pymeshlab":
        import pymeshlab as lib
    else:
        import open3d as lib
except Exception as e:
    print(json.dumps({"unavailable": f"{type(e).__name__}: {e}"}))
    sys.exit(0)
times = []
for _ in range(runs):
    if module == "pymeshlab":
        ms = lib.MeshSet()
        ms.load_new_mesh(obj)
        start = time.perf_counter()
        ms.meshing_surface_subdivision_loop(loopweight=0, iterations=level, threshold=lib.PercentageValue(0.0))
        times.append((time.perf_counter() - start) * 1e3)
        vertices = ms.current_mesh().vertex_matrix()
        faces = ms.current_mesh().face_matrix()
    else:
        mesh = lib.io.read_triangle_mesh(obj)
        start = time.perf_counter()
        fine = mesh.subdivide_loop(number_of_iterations=level)
        times.append((time.perf_counter() - start) * 1e3)
        vertices = numpy.asarray(fine.vertices)
        faces = numpy.asarray(fine.triangles)
numpy.asarray(vertices[numpy.unique(faces)], dtype="<f8").tofile(out)
from importlib.metadata import version
print(json.dumps({"version": version(module), "ms": times}))
"#;

/// What running a peer gave.
#[derive(Debug)]
pub enum Outcome {
    /// It ran: its version, the wall-clock ms of each run, the refined positions.
    Ran {
        /// The module's version.
        version: String,
        /// Wall-clock ms of each run's subdivision (not the loading).
        ms: Vec<f64>,
        /// The refined positions of the last run's vertices that a triangle uses.
        positions: Vec<DVec3>,
    },
    /// It could not run here, and why (the module does not import, no Python).
    Unavailable(String),
}

/// `level` Loop steps of the mesh in `obj` by `peer`, `runs` times; `scratch` is a folder for
/// the positions it writes.
pub fn loop_subdivide(
    peer: Peer,
    obj: &Path,
    level: u32,
    runs: u32,
    scratch: &Path,
) -> Result<Outcome> {
    let python = std::env::var("PYTHON").unwrap_or_else(|_| "python3".into());
    let out = scratch.join(format!("{}-positions.f64", peer.module));
    let output = match Command::new(&python)
        .args(["-c", SCRIPT, peer.module])
        .arg(obj)
        .args([level.to_string(), runs.to_string()])
        .arg(&out)
        .output()
    {
        Ok(o) => o,
        Err(e) => return Ok(Outcome::Unavailable(format!("{python}: {e}"))),
    };
    if !output.status.success() {
        bail!(
            "{} ({python}) failed on {}: {}",
            peer.name,
            obj.display(),
            String::from_utf8_lossy(&output.stderr).trim()
        );
    }
    let stdout = String::from_utf8_lossy(&output.stdout);
    let last = stdout.lines().last().unwrap_or_default();
    let report: serde_json::Value = serde_json::from_str(last)
        .with_context(|| format!("{}: unexpected output {stdout:?}", peer.name))?;
    if let Some(why) = report.get("unavailable").and_then(|v| v.as_str()) {
        return Ok(Outcome::Unavailable(why.to_owned()));
    }
    let ms = report
        .get("ms")
        .and_then(|v| v.as_array())
        .map(|a| a.iter().filter_map(|v| v.as_f64()).collect())
        .context("no times")?;
    let version = report
        .get("version")
        .and_then(|v| v.as_str())
        .unwrap_or("?")
        .to_owned();
    let bytes = std::fs::read(&out).with_context(|| format!("{}", out.display()))?;
    let values: Vec<f64> = bytemuck::pod_collect_to_vec(&bytes);
    let positions = values
        .chunks_exact(3)
        .map(|p| DVec3::new(p[0], p[1], p[2]))
        .collect();
    Ok(Outcome::Ran {
        version,
        ms,
        positions,
    })
}
