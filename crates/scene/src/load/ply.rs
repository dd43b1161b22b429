//! Stanford PLY (ASCII and binary) through `ply-rs`.

use std::path::Path;

use glam::{Vec2, Vec3};
use ply_rs::{
    parser::Parser,
    ply::{DefaultElement, Property},
};

use crate::{Material, Mesh, Scene, SceneErrorKind};

fn scalar(p: Option<&Property>) -> Option<f32> {
    Some(match p? {
        Property::Float(v) => *v,
        Property::Double(v) => *v as f32,
        Property::Int(v) => *v as f32,
        Property::UInt(v) => *v as f32,
        Property::Short(v) => f32::from(*v),
        Property::UShort(v) => f32::from(*v),
        Property::Char(v) => f32::from(*v),
        Property::UChar(v) => f32::from(*v),
        _ => return None,
    })
}

fn list(p: Option<&Property>) -> Option<Vec<i64>> {
    Some(match p? {
        Property::ListInt(v) => v.iter().map(|&i| i64::from(i)).collect(),
        Property::ListUInt(v) => v.iter().map(|&i| i64::from(i)).collect(),
        Property::ListShort(v) => v.iter().map(|&i| i64::from(i)).collect(),
        Property::ListUShort(v) => v.iter().map(|&i| i64::from(i)).collect(),
        Property::ListChar(v) => v.iter().map(|&i| i64::from(i)).collect(),
        Property::ListUChar(v) => v.iter().map(|&i| i64::from(i)).collect(),
        _ => return None,
    })
}

pub fn load(path: &Path, progress: &mut dyn FnMut(usize, usize)) -> Result<Scene, SceneErrorKind> {
    let file = std::fs::File::open(path)?;
    let mut reader = std::io::BufReader::new(file);
    let ply = Parser::<DefaultElement>::new()
        .read_ply(&mut reader)
        .map_err(|e| SceneErrorKind::Ply(e.to_string()))?;
    let bad = |s: &str| SceneErrorKind::Ply(s.to_owned());
    let vertices = ply
        .payload
        .get("vertex")
        .ok_or_else(|| bad("no vertex element"))?;
    let faces = ply
        .payload
        .get("face")
        .ok_or_else(|| bad("no face element"))?;

    let mut mesh = Mesh {
        name: path
            .file_stem()
            .map_or("ply".into(), |s| s.to_string_lossy().into_owned()),
        ..Default::default()
    };
    let has_normals = vertices.first().is_some_and(|v| v.contains_key("nx"));
    for v in vertices {
        let get = |k: &str| {
            scalar(v.get(k))
                .ok_or_else(|| bad(&format!("vertex property {k} missing or not a number")))
        };
        mesh.positions
            .push(Vec3::new(get("x")?, get("y")?, get("z")?));
        if has_normals {
            mesh.normals
                .push(Vec3::new(get("nx")?, get("ny")?, get("nz")?).normalize_or(Vec3::Y));
        }
        if let (Some(u), Some(t)) = (
            scalar(v.get("u").or(v.get("s"))),
            scalar(v.get("v").or(v.get("t"))),
        ) {
            mesh.uvs.push(Vec2::new(u, 1.0 - t));
        }
    }
    progress(1, 2);
    let n = mesh.positions.len() as i64;
    for f in faces {
        let idx = list(f.get("vertex_indices").or(f.get("vertex_index")))
            .ok_or_else(|| bad("face without vertex_indices list"))?;
        if let Some(i) = idx.iter().find(|&&i| i < 0 || i >= n) {
            return Err(bad(&format!(
                "face index {i} out of range for {n} vertices"
            )));
        }
        for k in 1..idx.len().saturating_sub(1) {
            mesh.indices
                .extend([idx[0] as u32, idx[k] as u32, idx[k + 1] as u32]);
        }
    }
    progress(2, 2);
    Ok(Scene {
        meshes: vec![super::complete(mesh)],
        materials: vec![Material::default()],
        ..Default::default()
    })
}
