//! Wavefront OBJ + MTL through `tobj`.

use std::path::Path;

use glam::{Vec2, Vec3, Vec4};

use crate::{Material, Mesh, Scene, SceneErrorKind};

pub fn load(path: &Path, progress: &mut dyn FnMut(usize, usize)) -> Result<Scene, SceneErrorKind> {
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ..Default::default()
    };
    let (models, mtl) =
        tobj::load_obj(path, &options).map_err(|e| SceneErrorKind::Obj(e.to_string()))?;
    let dir = path.parent().unwrap_or(Path::new("."));
    let mtl = mtl.unwrap_or_else(|e| {
        log::warn!(
            "{}: materials not loaded ({e}); using the default material",
            path.display()
        );
        Vec::new()
    });

    let mut scene = Scene::default();
    for m in &mtl {
        let base_color_texture = match &m.diffuse_texture {
            Some(file) => {
                let bytes = std::fs::read(dir.join(file)).map_err(|e| SceneErrorKind::Texture {
                    index: scene.textures.len(),
                    problem: format!("{file}: {e}"),
                })?;
                scene.textures.push(super::decode_texture(
                    file.clone(),
                    scene.textures.len(),
                    &bytes,
                )?);
                Some(scene.textures.len() as u32 - 1)
            }
            None => None,
        };
        let shininess = m.shininess.unwrap_or(10.0).max(0.0);
        scene.materials.push(Material {
            name: m.name.clone(),
            base_color: Vec3::from(m.diffuse.unwrap_or([0.8; 3])).extend(m.dissolve.unwrap_or(1.0)),
            base_color_texture,
            // Blinn-Phong exponent to GGX roughness: alpha = sqrt(2 / (Ns + 2)), roughness = sqrt(alpha).
            roughness: (2.0 / (shininess + 2.0)).sqrt().sqrt().clamp(0.0, 1.0),
            metallic: 0.0,
            emissive: Vec3::from(m.emissive.unwrap_or([0.0; 3])),
        });
    }
    let default_material = scene.materials.len() as u32;
    scene.materials.push(Material {
        base_color: Vec4::new(0.8, 0.8, 0.8, 1.0),
        ..Default::default()
    });

    let total = models.len();
    for (i, model) in models.into_iter().enumerate() {
        let m = model.mesh;
        let mesh = Mesh {
            name: model.name,
            positions: m
                .positions
                .chunks_exact(3)
                .map(|p| Vec3::new(p[0], p[1], p[2]))
                .collect(),
            normals: m
                .normals
                .chunks_exact(3)
                .map(|n| Vec3::new(n[0], n[1], n[2]).normalize_or(Vec3::Y))
                .collect(),
            uvs: m
                .texcoords
                .chunks_exact(2)
                .map(|t| Vec2::new(t[0], 1.0 - t[1]))
                .collect(),
            indices: m.indices,
            material: m.material_id.map_or(default_material, |i| i as u32),
        };
        scene.meshes.push(super::complete(mesh));
        progress(i + 1, total);
    }
    Ok(scene)
}
