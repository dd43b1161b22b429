//! File loaders. Each returns a scene or the problem, without the path (the caller adds it).

mod accessor;
mod folder;
pub mod gltf;
pub mod obj;
pub mod ply;

use glam::Vec2;

use crate::{Mesh, SceneErrorKind, Texture};

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
    })
}
