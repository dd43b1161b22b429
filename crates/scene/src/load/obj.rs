//! Wavefront OBJ + MTL through `tobj`.

use std::path::Path;

use glam::{Vec2, Vec3, Vec4};

use super::folder::{SceneFolder, UNDECLARED_LIMIT};
use crate::{AlphaMode, Material, Mesh, Scene, SceneErrorKind, TextureRef};

pub fn load(path: &Path, progress: &mut dyn FnMut(usize, usize)) -> Result<Scene, SceneErrorKind> {
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ..Default::default()
    };
    let folder = SceneFolder::of(path)?;
    let bytes = super::read_scene_file(path)?;
    check_obj(&bytes)?;
    let mut reader = &bytes[..];
    // Material libraries are read through the scene's folder, and checked before tobj parses
    // them (tobj panics on colour lines with fewer than three numbers).
    let mtl_problem = std::cell::RefCell::new(None);
    let (models, mtl) = tobj::load_obj_buf(&mut reader, &options, |mtl_path| {
        let read = mtl_path
            .to_str()
            .ok_or_else(|| SceneErrorKind::Reference {
                reference: mtl_path.display().to_string(),
                problem: "not UTF-8".into(),
            })
            .and_then(|p| folder.read_path(p, UNDECLARED_LIMIT))
            .and_then(|bytes| check_mtl(&mtl_path.display().to_string(), &bytes).map(|()| bytes));
        match read {
            Ok(bytes) => tobj::load_mtl_buf(&mut &bytes[..]),
            // A missing library costs the materials (a warning below), anything else fails.
            Err(SceneErrorKind::MissingFile(_)) => Err(tobj::LoadError::OpenFileFailed),
            Err(e) => {
                *mtl_problem.borrow_mut() = Some(e);
                Err(tobj::LoadError::OpenFileFailed)
            }
        }
    })
    .map_err(|e| SceneErrorKind::Obj(e.to_string()))?;
    if let Some(e) = mtl_problem.into_inner() {
        return Err(e);
    }
    let mtl = mtl.unwrap_or_else(|e| {
        log::warn!(
            "{}: materials not loaded ({e}); using the default material",
            path.display()
        );
        Vec::new()
    });

    let mut scene = Scene::default();
    // A texture file is decoded once however many materials and roles use it.
    let mut loaded: std::collections::HashMap<String, u32> = Default::default();
    let mut texture = |scene: &mut Scene, file: &str| -> Result<TextureRef, SceneErrorKind> {
        if let Some(&i) = loaded.get(file) {
            return Ok(TextureRef::new(i));
        }
        let bytes = folder.read_path(file, UNDECLARED_LIMIT)?;
        let i = scene.textures.len() as u32;
        scene
            .textures
            .push(super::decode_texture(file.to_owned(), i as usize, &bytes)?);
        loaded.insert(file.to_owned(), i);
        Ok(TextureRef::new(i))
    };
    for m in &mtl {
        let base_color_texture = m
            .diffuse_texture
            .as_deref()
            .map(|f| texture(&mut scene, f))
            .transpose()?;
        // `norm` (a tangent-space normal map) or `map_Bump`/`bump` taken as one, with its
        // `-bm` scale.
        let normal = m
            .unknown_param
            .get("norm")
            .or(m.normal_texture.as_ref())
            .map(|line| map_options(line));
        let normal_texture = normal
            .as_ref()
            .map(|(f, _)| texture(&mut scene, f))
            .transpose()?;
        let emissive_texture = m
            .unknown_param
            .get("map_Ke")
            .map(|line| texture(&mut scene, &map_options(line).0))
            .transpose()?;
        let alpha = m.dissolve.unwrap_or(1.0).clamp(0.0, 1.0);
        let shininess = m.shininess.unwrap_or(10.0).max(0.0);
        scene.materials.push(Material {
            name: m.name.clone(),
            base_color: Vec3::from(m.diffuse.unwrap_or([0.8; 3])).extend(alpha),
            base_color_texture,
            normal_texture,
            normal_scale: normal.map_or(1.0, |(_, scale)| scale),
            emissive_texture,
            alpha_mode: if alpha < 1.0 {
                AlphaMode::Blend
            } else {
                AlphaMode::Opaque
            },
            // Blinn-Phong exponent to GGX roughness: alpha = sqrt(2 / (Ns + 2)), roughness = sqrt(alpha).
            roughness: (2.0 / (shininess + 2.0)).sqrt().sqrt().clamp(0.0, 1.0),
            metallic: 0.0,
            // `map_Ke` scales `Ke`; without `Ke` a texture alone emits as it is.
            emissive: Vec3::from(m.emissive.unwrap_or(if emissive_texture.is_some() {
                [1.0; 3]
            } else {
                [0.0; 3]
            })),
            // An explicit black `Ks` says the material has no specular reflection.
            specular: if m.specular == Some([0.0; 3]) {
                0.0
            } else {
                1.0
            },
            ..Default::default()
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
            ..Default::default()
        };
        scene.meshes.push(super::complete(mesh));
        progress(i + 1, total);
    }
    Ok(scene)
}

/// A texture line of an MTL statement (`[-option value…] file`): the file and the `-bm` scale
/// (1 without it). Options other than `-bm` are skipped with their one value.
fn map_options(line: &str) -> (String, f32) {
    let words: Vec<&str> = line.split_whitespace().collect();
    let (mut i, mut scale) = (0, 1.0);
    while i + 1 < words.len() && words[i].starts_with('-') {
        if words[i] == "-bm" {
            scale = words[i + 1].parse().unwrap_or(1.0);
        }
        i += 2;
    }
    (words[i..].join(" "), scale)
}

/// Checks what tobj would misread or reject without a line number: `v`/`vn` need three finite
/// numbers and `vt` one, a face at least three vertices whose references (`v`, `v/vt`,
/// `v//vn`, `v/vt/vn`, negative = relative) name elements defined before it.
fn check_obj(bytes: &[u8]) -> Result<(), SceneErrorKind> {
    let text = std::str::from_utf8(bytes)
        .map_err(|e| SceneErrorKind::Obj(format!("not UTF-8 text (byte {})", e.valid_up_to())))?;
    // Defined positions, texture coordinates and normals so far.
    let mut counts = [0i64; 3];
    for (n, line) in text.lines().enumerate() {
        let bad = |problem: String| SceneErrorKind::Obj(format!("line {}: {problem}", n + 1));
        let line = line.split('#').next().unwrap_or("");
        let mut words = line.split_whitespace();
        let Some(key) = words.next() else { continue };
        let values: Vec<&str> = words.collect();
        let numbers = |need: usize, what: &str| -> Result<(), SceneErrorKind> {
            let finite = values
                .iter()
                .take_while(|v| v.parse::<f32>().is_ok_and(f32::is_finite))
                .count();
            if finite < need || (key != "v" && finite < values.len()) {
                return Err(bad(format!(
                    "{what} needs {need} finite numbers, got {:?}",
                    values.join(" ")
                )));
            }
            Ok(())
        };
        match key {
            "v" => {
                numbers(3, "a vertex position")?;
                counts[0] += 1;
            }
            "vt" => {
                numbers(1, "a texture coordinate")?;
                counts[1] += 1;
            }
            "vn" => {
                numbers(3, "a normal")?;
                counts[2] += 1;
            }
            "f" => {
                if values.len() < 3 {
                    return Err(bad(format!(
                        "a face needs at least three vertices, got {}",
                        values.len()
                    )));
                }
                for v in &values {
                    let parts: Vec<&str> = v.split('/').collect();
                    if parts.len() > 3 || parts[0].is_empty() {
                        return Err(bad(format!(
                            "face vertex {v:?} is not v, v/vt, v//vn or v/vt/vn"
                        )));
                    }
                    for (k, part) in parts.iter().enumerate() {
                        if part.is_empty() {
                            continue;
                        }
                        let count = counts[k];
                        let i: i64 = part.parse().map_err(|_| {
                            bad(format!("face vertex {v:?}: {part:?} is not an index"))
                        })?;
                        let resolved = if i < 0 { count + i + 1 } else { i };
                        if resolved < 1 || resolved > count {
                            return Err(bad(format!(
                                "face vertex {v:?}: {} index {i} outside 1..={count}",
                                ["position", "texture coordinate", "normal"][k]
                            )));
                        }
                    }
                }
            }
            _ => {}
        }
    }
    Ok(())
}

/// Refuses MTL colour statements (`Ka`, `Kd`, `Ks`, `Ke`, `Tf`) without three finite numbers
/// (tobj would panic on too few) and scalars (`Ns`, `d`, `Tr`, `Ni`) that are not a finite
/// number, naming the file and line; `Tf`/`K*` spectral and XYZ forms are left to tobj.
fn check_mtl(name: &str, bytes: &[u8]) -> Result<(), SceneErrorKind> {
    for (n, line) in String::from_utf8_lossy(bytes).lines().enumerate() {
        let mut words = line.split_whitespace();
        if let Some(key @ ("Ka" | "Kd" | "Ks" | "Ke" | "Tf")) = words.next() {
            let values: Vec<&str> = words.collect();
            if matches!(values.first(), Some(&("spectral" | "xyz"))) {
                continue;
            }
            let numbers = values
                .iter()
                .filter(|v| v.parse::<f32>().is_ok_and(f32::is_finite));
            if values.len() < 3 || numbers.count() < 3 {
                return Err(SceneErrorKind::Obj(format!(
                    "{name} line {}: {key} needs three finite numbers, got {:?}",
                    n + 1,
                    values.join(" ")
                )));
            }
        } else if let Some(key @ ("Ns" | "d" | "Tr" | "Ni")) = line.split_whitespace().next() {
            let value = line.split_whitespace().nth(1);
            if !value.is_some_and(|v| v.parse::<f32>().is_ok_and(f32::is_finite)) {
                return Err(SceneErrorKind::Obj(format!(
                    "{name} line {}: {key} needs a finite number, got {:?}",
                    n + 1,
                    value.unwrap_or("")
                )));
            }
        }
    }
    Ok(())
}
