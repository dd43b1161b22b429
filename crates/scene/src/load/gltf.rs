//! glTF 2.0 (`.gltf` + `.bin` + images, and `.glb`) through the `gltf` crate.

use std::path::Path;

use glam::{Mat3, Mat4, Vec2, Vec3, Vec4};

use crate::{Camera, Light, Material, Mesh, Scene, SceneErrorKind, Texture, light::default_radius};

pub fn load(path: &Path, progress: &mut dyn FnMut(usize, usize)) -> Result<Scene, SceneErrorKind> {
    let (doc, buffers, images) =
        gltf::import(path).map_err(|e| SceneErrorKind::Gltf(e.to_string()))?;

    let textures = doc
        .textures()
        .map(|t| {
            let index = t.source().index();
            let data = images.get(index).ok_or_else(|| SceneErrorKind::Texture {
                index,
                problem: "image missing".into(),
            })?;
            to_rgba8(t.name().unwrap_or("texture").to_owned(), index, data)
        })
        .collect::<Result<Vec<_>, _>>()?;

    let mut materials: Vec<Material> = doc
        .materials()
        .map(|m| {
            let pbr = m.pbr_metallic_roughness();
            let emissive = Vec3::from(m.emissive_factor()) * m.emissive_strength().unwrap_or(1.0);
            Material {
                name: m.name().unwrap_or("material").to_owned(),
                base_color: Vec4::from(pbr.base_color_factor()),
                base_color_texture: pbr.base_color_texture().map(|t| t.texture().index() as u32),
                roughness: pbr.roughness_factor().clamp(0.0, 1.0),
                metallic: pbr.metallic_factor().clamp(0.0, 1.0),
                emissive,
            }
        })
        .collect();
    let default_material = materials.len() as u32;
    materials.push(Material::default());

    let mut scene = Scene {
        materials,
        textures,
        ..Default::default()
    };
    let Some(gscene) = doc.default_scene().or_else(|| doc.scenes().next()) else {
        return Err(SceneErrorKind::NoMeshes);
    };
    let mut stack: Vec<(gltf::Node, Mat4)> = gscene.nodes().map(|n| (n, Mat4::IDENTITY)).collect();
    let total = doc
        .meshes()
        .map(|m| m.primitives().len())
        .sum::<usize>()
        .max(1);
    while let Some((node, parent)) = stack.pop() {
        let world = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
        stack.extend(node.children().map(|c| (c, world)));
        if let Some(mesh) = node.mesh() {
            for prim in mesh.primitives() {
                if prim.mode() != gltf::mesh::Mode::Triangles {
                    log::warn!("skipping non-triangle primitive of mesh {:?}", mesh.name());
                    continue;
                }
                let m = primitive(
                    &prim,
                    &buffers,
                    world,
                    mesh.name().unwrap_or("mesh"),
                    default_material,
                )?;
                scene.meshes.push(super::complete(m));
                progress(scene.meshes.len(), total);
            }
        }
        if let Some(cam) = node.camera()
            && scene.camera.is_none()
            && let gltf::camera::Projection::Perspective(p) = cam.projection()
        {
            let eye = world.transform_point3(Vec3::ZERO);
            let forward = world.transform_vector3(Vec3::NEG_Z);
            let up = world.transform_vector3(Vec3::Y);
            scene.camera = Some(Camera {
                eye,
                target: eye + forward,
                up,
                fov_y: p.yfov(),
                near: p.znear(),
                far: p.zfar().unwrap_or(p.znear() * 1e4),
            });
        }
        if let Some(light) = node.light() {
            scene.lights.push(convert_light(&light, world));
        }
    }
    if let Some(cam) = &mut scene.camera
        && cam.far <= cam.near
    {
        cam.far = cam.near * 1e4;
    }
    Ok(scene)
}

fn primitive(
    prim: &gltf::Primitive,
    buffers: &[gltf::buffer::Data],
    world: Mat4,
    name: &str,
    default_material: u32,
) -> Result<Mesh, SceneErrorKind> {
    let reader = prim.reader(|b| buffers.get(b.index()).map(|d| &d.0[..]));
    let missing = |what: &str| SceneErrorKind::InvalidMesh {
        mesh: name.into(),
        problem: format!("{what} missing or unreadable"),
    };
    let normal_matrix = Mat3::from_mat4(world).inverse().transpose();
    let positions: Vec<Vec3> = reader
        .read_positions()
        .ok_or_else(|| missing("POSITION"))?
        .map(|p| world.transform_point3(Vec3::from(p)))
        .collect();
    let normals = reader
        .read_normals()
        .map(|n| {
            n.map(|n| (normal_matrix * Vec3::from(n)).normalize_or(Vec3::Y))
                .collect()
        })
        .unwrap_or_default();
    let uvs = reader
        .read_tex_coords(0)
        .map(|t| t.into_f32().map(Vec2::from).collect())
        .unwrap_or_default();
    let mut indices: Vec<u32> = match reader.read_indices() {
        Some(i) => i.into_u32().collect(),
        None => (0..positions.len() as u32).collect(),
    };
    indices.truncate(indices.len() / 3 * 3);
    if world.determinant() < 0.0 {
        for t in indices.chunks_exact_mut(3) {
            t.swap(1, 2);
        }
    }
    Ok(Mesh {
        name: name.to_owned(),
        positions,
        normals,
        uvs,
        indices,
        material: prim
            .material()
            .index()
            .map_or(default_material, |i| i as u32),
    })
}

fn convert_light(light: &gltf::khr_lights_punctual::Light, world: Mat4) -> Light {
    use gltf::khr_lights_punctual::Kind;
    let position = world.transform_point3(Vec3::ZERO);
    let direction = world
        .transform_vector3(Vec3::NEG_Z)
        .normalize_or(Vec3::NEG_Y);
    let color = Vec3::from(light.color());
    let intensity = light.intensity();
    let radius = light.range().unwrap_or_else(|| default_radius(intensity));
    match light.kind() {
        Kind::Directional => Light::Directional {
            direction,
            color,
            intensity,
        },
        Kind::Point => Light::Point {
            position,
            color,
            intensity,
            radius,
        },
        Kind::Spot {
            inner_cone_angle,
            outer_cone_angle,
        } => Light::Spot {
            position,
            direction,
            color,
            intensity,
            radius,
            inner_angle: inner_cone_angle,
            outer_angle: outer_cone_angle,
        },
    }
}

fn to_rgba8(
    name: String,
    index: usize,
    data: &gltf::image::Data,
) -> Result<Texture, SceneErrorKind> {
    use gltf::image::Format;
    let (w, h) = (data.width, data.height);
    let n = (w * h) as usize;
    let px = &data.pixels;
    let rgba8 = match data.format {
        Format::R8G8B8A8 => px.clone(),
        Format::R8G8B8 => px
            .chunks_exact(3)
            .flat_map(|c| [c[0], c[1], c[2], 255])
            .collect(),
        Format::R8G8 => px
            .chunks_exact(2)
            .flat_map(|c| [c[0], c[1], 0, 255])
            .collect(),
        Format::R8 => px.iter().flat_map(|&c| [c, c, c, 255]).collect(),
        other => {
            return Err(SceneErrorKind::Texture {
                index,
                problem: format!("{name}: unsupported pixel format {other:?}"),
            });
        }
    };
    if rgba8.len() != n * 4 {
        return Err(SceneErrorKind::Texture {
            index,
            problem: format!("{name}: truncated pixel data"),
        });
    }
    Ok(Texture {
        name,
        width: w,
        height: h,
        rgba8,
    })
}
