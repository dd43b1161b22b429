//! File loaders. Each returns a scene or the problem, without the path (the caller adds it).

mod accessor;
mod folder;
pub mod gltf;
pub mod obj;
pub mod ply;
mod rig;

use std::path::Path;

use glam::Vec2;

use crate::{Mesh, SceneErrorKind, Texture};

/// The most bytes a scene file itself may hold: 4 GiB (GLB's own 32-bit length field).
const FILE_LIMIT: u64 = u32::MAX as u64;

/// The bytes of the scene file at `path`: a regular file (not a device or pipe, which could
/// be read without end) of at most [`FILE_LIMIT`] bytes.
pub(crate) fn read_scene_file(path: &Path) -> Result<Vec<u8>, SceneErrorKind> {
    let refuse = |problem: String| SceneErrorKind::Reference {
        reference: path.display().to_string(),
        problem,
    };
    let file = std::fs::File::open(path)?;
    let meta = file.metadata()?;
    if !meta.is_file() {
        return Err(refuse("not a regular file".into()));
    }
    if meta.len() > FILE_LIMIT {
        return Err(refuse(format!(
            "holds {} bytes, more than the {FILE_LIMIT} allowed",
            meta.len()
        )));
    }
    let mut bytes = Vec::with_capacity(meta.len() as usize);
    std::io::Read::read_to_end(&mut std::io::Read::take(file, FILE_LIMIT), &mut bytes)?;
    Ok(bytes)
}

/// Fills missing normals (smooth, from the triangles) and texture coordinates (zero).
pub(crate) fn complete(mut mesh: Mesh) -> Mesh {
    if mesh.normals.len() != mesh.positions.len() {
        mesh.compute_normals();
    }
    if mesh.uvs.len() != mesh.positions.len() {
        mesh.uvs = vec![Vec2::ZERO; mesh.positions.len()];
    }
    mesh
}

/// Decodes an image file's bytes into an RGBA8 texture.
pub(crate) fn decode_texture(
    name: String,
    index: usize,
    bytes: &[u8],
) -> Result<Texture, SceneErrorKind> {
    let img = image::load_from_memory(bytes)
        .map_err(|e| SceneErrorKind::Texture {
            index,
            problem: format!("{name}: {e}"),
        })?
        .to_rgba8();
    Ok(Texture {
        name,
        width: img.width(),
        height: img.height(),
        rgba8: img.into_raw(),
        sampler: Default::default(),
    })
}
