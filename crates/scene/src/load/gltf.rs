//! glTF 2.0 (`.gltf` + `.bin` + images, and `.glb`): the document parsed by the `gltf` crate,
//! buffers, images and accessors read and checked by the toolkit.

use std::path::Path;

use glam::{Mat3, Mat4, Quat, Vec2, Vec3, Vec4};

use super::folder::{SceneFolder, UNDECLARED_LIMIT};
use super::{accessor, rig};
use crate::animation::{Attached, Deformer, Joints, NodeInstance, Rig, Trs};
use crate::{
    AlphaMode, Camera, Light, Material, Mesh, Sampler, Scene, SceneErrorKind, TextureRef,
    UvTransform, Wrap, light::default_radius,
};

/// The most node instances a scene may place (a node reached through several parents counts
/// once per path): 2^20.
const MAX_NODE_INSTANCES: usize = 1 << 20;

pub fn load(path: &Path, progress: &mut dyn FnMut(usize, usize)) -> Result<Scene, SceneErrorKind> {
    let folder = SceneFolder::of(path)?;
    let bytes = super::read_scene_file(path)?;
    let invalid = |e: gltf::Error| SceneErrorKind::Gltf(e.to_string());
    let gltf::Gltf { document, blob } =
        gltf::Gltf::from_slice_without_validation(&bytes).map_err(invalid)?;
    let json = document.into_json();
    // gltf-json's validation indexes the accessors with POSITION unchecked: check it first.
    for (m, mesh) in json.meshes.iter().enumerate() {
        for (p, prim) in mesh.primitives.iter().enumerate() {
            let position = gltf::json::validation::Checked::Valid(gltf::Semantic::Positions);
            if let Some(a) = prim.attributes.get(&position)
                && a.value() >= json.accessors.len()
            {
                return Err(SceneErrorKind::Gltf(format!(
                    "mesh {m} primitive {p}: POSITION names accessor {}, of {}",
                    a.value(),
                    json.accessors.len()
                )));
            }
        }
    }
    // gltf-json does not validate animation channels' targets, which the `gltf` crate's
    // accessors unwrap: check them first.
    for (a, animation) in json.animations.iter().enumerate() {
        for (c, channel) in animation.channels.iter().enumerate() {
            let target = &channel.target;
            let node = target.node.value();
            let valid_path = matches!(target.path, gltf::json::validation::Checked::Valid(_));
            if node >= json.nodes.len() || !valid_path {
                return Err(SceneErrorKind::Gltf(format!(
                    "animation {a} channel {c}: its target (node {node} of {}, path {}) is not \
                     a node's translation, rotation, scale or weights",
                    json.nodes.len(),
                    if valid_path { "valid" } else { "unknown" }
                )));
            }
        }
    }
    let doc = gltf::Document::from_json(json).map_err(invalid)?;
    let buffers = doc
        .buffers()
        .map(|b| buffer_data(&folder, &b, blob.as_deref()))
        .collect::<Result<Vec<_>, _>>()?;

    let textures = doc
        .textures()
        .map(|t| {
            let image = t.source();
            let index = image.index();
            let name = t.name().or(image.name()).unwrap_or("texture").to_owned();
            let bytes = image_bytes(&folder, &image, &buffers).map_err(|e| match e {
                SceneErrorKind::Reference { .. } => e,
                other => SceneErrorKind::Texture {
                    index,
                    problem: other.to_string(),
                },
            })?;
            let mut texture = super::decode_texture(name, index, &bytes)?;
            texture.sampler = sampler(&t.sampler());
            Ok::<_, SceneErrorKind>(texture)
        })
        .collect::<Result<Vec<_>, _>>()?;

    let materials = doc
        .materials()
        .enumerate()
        .map(|(i, m)| material(i, &m))
        .collect::<Result<Vec<_>, _>>()?;
    let mut materials: Vec<Material> = materials;
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
    // Each stack entry carries its ancestors, so a node that is its own ancestor (a cycle,
    // which glTF forbids) is an error instead of an endless walk; instances are counted, so a
    // node reused on many levels cannot multiply the scene without bound. With a rig, each
    // entry also carries its parent's node instance and whether a channel moves it or an
    // ancestor.
    let rigged = rig::has_rig(&doc);
    let moved = rig::moved_nodes(&doc);
    let mut nodes: Vec<NodeInstance> = Vec::new();
    let mut pending: Vec<Deformer> = Vec::new();
    let mut camera = None;
    let mut lights = Vec::new();
    let mut stack: Vec<Visit> = gscene
        .nodes()
        .map(|node| Visit {
            node,
            parent: Mat4::IDENTITY,
            ancestors: Vec::new(),
            parent_instance: None,
            moving: false,
        })
        .collect();
    let total = doc
        .meshes()
        .map(|m| m.primitives().len())
        .sum::<usize>()
        .max(1);
    let mut instances = 0usize;
    while let Some(Visit {
        node,
        parent,
        mut ancestors,
        parent_instance,
        moving,
    }) = stack.pop()
    {
        if ancestors.contains(&node.index()) {
            return Err(SceneErrorKind::Gltf(format!(
                "node {} is its own ancestor (the node hierarchy has a cycle)",
                node.index()
            )));
        }
        instances += 1;
        if instances > MAX_NODE_INSTANCES {
            return Err(SceneErrorKind::Gltf(format!(
                "the node hierarchy places more than {MAX_NODE_INSTANCES} node instances"
            )));
        }
        let world = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
        let moving = rigged && (moving || moved.contains(&node.index()));
        let instance = rigged.then(|| {
            nodes.push(node_instance(&node, parent_instance));
            nodes.len() as u32 - 1
        });
        ancestors.push(node.index());
        stack.extend(node.children().map(|c| Visit {
            node: c,
            parent: world,
            ancestors: ancestors.clone(),
            parent_instance: instance,
            moving,
        }));
        if let Some(mesh) = node.mesh() {
            for prim in mesh.primitives() {
                if prim.mode() != gltf::mesh::Mode::Triangles {
                    log::warn!("skipping non-triangle primitive of mesh {:?}", mesh.name());
                    continue;
                }
                let name = mesh.name().unwrap_or("mesh");
                let skin = node.skin();
                let morphed = prim.morph_targets().next().is_some();
                match instance.filter(|_| moving || morphed || skin.is_some()) {
                    Some(instance) => {
                        let mut object = super::complete(primitive(
                            &prim,
                            &buffers,
                            Mat4::IDENTITY,
                            name,
                            default_material,
                        )?);
                        // Tangents of normal maps are made in object space, so they move too.
                        object.complete_tangents(&scene.materials);
                        pending.push(deformer(
                            &prim,
                            &buffers,
                            &object,
                            scene.meshes.len() as u32,
                            instance,
                            skin.as_ref(),
                        )?);
                        scene.meshes.push(object);
                    }
                    None => {
                        let m = primitive(&prim, &buffers, world, name, default_material)?;
                        scene.meshes.push(super::complete(m));
                    }
                }
                progress(scene.meshes.len(), total);
            }
        }
        // On a moving node a camera or light is kept in its node's space too.
        let attach = instance.filter(|_| moving);
        if let Some(cam) = node.camera()
            && scene.camera.is_none()
            && let gltf::camera::Projection::Perspective(p) = cam.projection()
        {
            let local = Camera {
                eye: Vec3::ZERO,
                target: Vec3::NEG_Z,
                up: Vec3::Y,
                fov_y: p.yfov(),
                near: p.znear(),
                far: p.zfar().unwrap_or(p.znear() * 1e4),
            };
            scene.camera = Some(Camera {
                eye: world.transform_point3(local.eye),
                target: world.transform_point3(local.target),
                up: world.transform_vector3(local.up),
                ..local
            });
            camera = attach.map(|node| Attached { node, local });
        }
        if let Some(light) = node.light() {
            if let Some(node) = attach {
                let local = convert_light(&light, Mat4::IDENTITY);
                lights.push((scene.lights.len() as u32, Attached { node, local }));
            }
            scene.lights.push(convert_light(&light, world));
        }
    }
    if rigged {
        let mut rig = finish_rig(&doc, &buffers, nodes, pending, &mut scene.meshes)?;
        rig.camera = camera;
        rig.lights = lights;
        scene.rig = Some(rig);
    }
    if let Some(cam) = &mut scene.camera
        && cam.far <= cam.near
    {
        cam.far = cam.near * 1e4;
    }
    Ok(scene)
}

/// A node to visit: its parent's world matrix, its ancestors' glTF indices, its parent's
/// node instance (with a rig) and whether a channel moves an ancestor.
struct Visit<'a> {
    node: gltf::Node<'a>,
    parent: Mat4,
    ancestors: Vec<usize>,
    parent_instance: Option<u32>,
    moving: bool,
}

/// `node` placed under `parent`: its rest TRS (and matrix, when the file gave one) and morph
/// weights (the node's, else its mesh's, else zeros for its targets).
fn node_instance(node: &gltf::Node, parent: Option<u32>) -> NodeInstance {
    let (t, r, s) = node.transform().decomposed();
    let targets = node
        .mesh()
        .and_then(|m| m.primitives().next())
        .map_or(0, |p| p.morph_targets().count());
    let weights = node
        .weights()
        .or_else(|| node.mesh().and_then(|m| m.weights()))
        .map_or_else(|| vec![0.0; targets], <[f32]>::to_vec);
    NodeInstance {
        node: node.index() as u32,
        parent,
        rest: Trs {
            translation: Vec3::from(t),
            rotation: Quat::from_array(r).normalize(),
            scale: Vec3::from(s),
        },
        matrix: match node.transform() {
            gltf::scene::Transform::Matrix { matrix } => Some(Mat4::from_cols_array_2d(&matrix)),
            gltf::scene::Transform::Decomposed { .. } => None,
        },
        weights,
    }
}

/// What moves `object` (primitive `prim` as mesh `mesh`, placed by node instance `instance`):
/// `skin`'s joints with the vertices' `JOINTS_0`/`WEIGHTS_0`, else the node itself; and the
/// primitive's morph targets.
fn deformer(
    prim: &gltf::Primitive,
    buffers: &[Vec<u8>],
    object: &Mesh,
    mesh: u32,
    instance: u32,
    skin: Option<&gltf::Skin>,
) -> Result<Deformer, SceneErrorKind> {
    let n = object.positions.len();
    let (joints, joint_indices, weights) = match skin {
        Some(s) => {
            let count = s.joints().count();
            let (j, w) = rig::joints_and_weights(prim, buffers, &object.name, n, count)?;
            (Joints::Skin(s.index() as u32), j, w)
        }
        None => (
            Joints::Node(instance),
            vec![[0; 4]; n],
            vec![[1.0, 0.0, 0.0, 0.0]; n],
        ),
    };
    Ok(Deformer {
        mesh,
        node: instance,
        joints,
        positions: object.positions.clone(),
        normals: object.normals.clone(),
        tangents: object.tangents.clone(),
        joint_indices,
        weights,
        targets: rig::morph_targets(prim, buffers, &object.name, n)?,
    })
}

/// The rig of the file's node instances and `deformers`, with its skins and clips; each
/// deformed mesh is set to the rest pose (no clip: the nodes' own transforms and weights).
fn finish_rig(
    doc: &gltf::Document,
    buffers: &[Vec<u8>],
    nodes: Vec<NodeInstance>,
    deformers: Vec<Deformer>,
    meshes: &mut [Mesh],
) -> Result<Rig, SceneErrorKind> {
    let first_instance = |node: usize| {
        nodes
            .iter()
            .position(|n| n.node as usize == node)
            .map(|i| i as u32)
    };
    let skins = doc
        .skins()
        .map(|s| rig::skin(&s, buffers, &first_instance))
        .collect::<Result<Vec<_>, _>>()?;
    let targets = |node: usize| {
        doc.nodes()
            .nth(node)
            .and_then(|n| n.mesh())
            .and_then(|m| m.primitives().next())
            .map_or(0, |p| p.morph_targets().count())
    };
    let clips = rig::clips(doc, buffers, &targets)?;
    let rig = Rig {
        nodes,
        clips,
        skins,
        deformers,
        ..Default::default()
    };
    let rest = rig.pose(None, 0.0);
    rig.apply(&rest, meshes);
    for d in &rig.deformers {
        if let Joints::Node(n) = d.joints
            && rest.world[n as usize].determinant() < 0.0
        {
            for t in meshes[d.mesh as usize].indices.chunks_exact_mut(3) {
                t.swap(1, 2);
            }
        }
    }
    Ok(rig)
}

fn primitive(
    prim: &gltf::Primitive,
    buffers: &[Vec<u8>],
    world: Mat4,
    name: &str,
    default_material: u32,
) -> Result<Mesh, SceneErrorKind> {
    use gltf::Semantic;
    let bad = |problem: String| SceneErrorKind::InvalidMesh {
        mesh: name.into(),
        problem,
    };
    let attribute = |semantic: Semantic, allowed: &accessor::Allowed| {
        prim.get(&semantic)
            .map(|a| {
                accessor::read(
                    &a,
                    buffers,
                    &format!("{semantic:?} of mesh {name:?}"),
                    allowed,
                )
            })
            .transpose()
    };
    let positions: Vec<Vec3> = attribute(Semantic::Positions, &accessor::VEC3_F32)?
        .ok_or_else(|| bad("no POSITION attribute".into()))?
        .chunks_exact(3)
        .map(|p| world.transform_point3(Vec3::new(p[0] as f32, p[1] as f32, p[2] as f32)))
        .collect();
    let n = positions.len();
    let same_count = |what: &str, len: usize| {
        if len == n {
            Ok(())
        } else {
            Err(bad(format!("{len} {what} for {n} positions")))
        }
    };
    let normal_matrix = Mat3::from_mat4(world).inverse().transpose();
    let normals: Vec<Vec3> = attribute(Semantic::Normals, &accessor::VEC3_F32)?
        .map(|v| {
            v.chunks_exact(3)
                .map(|c| {
                    (normal_matrix * Vec3::new(c[0] as f32, c[1] as f32, c[2] as f32))
                        .normalize_or(Vec3::Y)
                })
                .collect()
        })
        .unwrap_or_default();
    if !normals.is_empty() {
        same_count("normals", normals.len())?;
    }
    // TEXCOORD_n, checked against the positions when present.
    let texcoords = |set: u32, what: &str| -> Result<Vec<Vec2>, SceneErrorKind> {
        let uvs: Vec<Vec2> = attribute(Semantic::TexCoords(set), &accessor::TEXCOORD)?
            .map(|v| {
                v.chunks_exact(2)
                    .map(|c| Vec2::new(c[0] as f32, c[1] as f32))
                    .collect()
            })
            .unwrap_or_default();
        if !uvs.is_empty() {
            same_count(what, uvs.len())?;
        }
        Ok(uvs)
    };
    let uvs = texcoords(0, "texture coordinates")?;
    let uvs1 = texcoords(1, "second texture coordinates")?;
    let mut indices: Vec<u32> = match prim.indices() {
        Some(a) => accessor::read(
            &a,
            buffers,
            &format!("indices of mesh {name:?}"),
            &accessor::INDICES,
        )?
        .into_iter()
        .map(|i| i as u32)
        .collect(),
        None => (0..n as u32).collect(),
    };
    if !indices.len().is_multiple_of(3) {
        return Err(bad(format!(
            "{} indices (or vertices) is not a multiple of 3 for a triangle list",
            indices.len()
        )));
    }
    if world.determinant() < 0.0 {
        for t in indices.chunks_exact_mut(3) {
            t.swap(1, 2);
        }
    }
    // Tangents turn with the normals' frame: the xyz by the world matrix's linear part (a
    // direction in the surface), w flipped where the matrix mirrors.
    let linear = Mat3::from_mat4(world);
    let mirror = if world.determinant() < 0.0 { -1.0 } else { 1.0 };
    let tangents: Vec<Vec4> = attribute(Semantic::Tangents, &accessor::VEC4_F32)?
        .map(|v| {
            v.chunks_exact(4)
                .map(|c| {
                    let t = (linear * Vec3::new(c[0] as f32, c[1] as f32, c[2] as f32))
                        .normalize_or(Vec3::X);
                    t.extend(if c[3] < 0.0 { -mirror } else { mirror })
                })
                .collect()
        })
        .unwrap_or_default();
    if !tangents.is_empty() {
        same_count("tangents", tangents.len())?;
    }
    let colors: Vec<Vec4> = match prim.get(&Semantic::Colors(0)) {
        Some(a) => {
            let (width, allowed) = if a.dimensions() == gltf::accessor::Dimensions::Vec3 {
                (3, &accessor::COLOR_RGB)
            } else {
                (4, &accessor::COLOR_RGBA)
            };
            let values =
                accessor::read(&a, buffers, &format!("COLOR_0 of mesh {name:?}"), allowed)?;
            values
                .chunks_exact(width)
                .map(|c| {
                    Vec4::new(
                        c[0] as f32,
                        c[1] as f32,
                        c[2] as f32,
                        if width == 4 { c[3] as f32 } else { 1.0 },
                    )
                })
                .collect()
        }
        None => Vec::new(),
    };
    if !colors.is_empty() {
        same_count("colours", colors.len())?;
    }
    Ok(Mesh {
        name: name.to_owned(),
        positions,
        normals,
        uvs,
        uvs1,
        tangents,
        colors,
        indices,
        material: prim
            .material()
            .index()
            .map_or(default_material, |i| i as u32),
    })
}

/// Material `index` of the file: factors, the five texture roles, alpha and sidedness.
fn material(index: usize, m: &gltf::Material) -> Result<Material, SceneErrorKind> {
    let pbr = m.pbr_metallic_roughness();
    let name = m.name().unwrap_or("material").to_owned();
    let slot = |role: &str, texture: usize, tex_coord: u32, transform: Option<UvTransform>| {
        if tex_coord > 1 {
            return Err(SceneErrorKind::Gltf(format!(
                "material {index} ({name:?}): its {role} texture reads TEXCOORD_{tex_coord}; \
                 sets 0 and 1 are supported"
            )));
        }
        Ok(TextureRef {
            texture: texture as u32,
            uv_set: tex_coord,
            transform: transform.unwrap_or(UvTransform::IDENTITY),
        })
    };
    // `textureInfo` with its KHR_texture_transform (whose texCoord overrides the info's).
    let info = |role: &str, t: Option<gltf::texture::Info>| {
        t.map(|t| {
            let transform = t.texture_transform();
            let tex_coord = transform
                .as_ref()
                .and_then(|x| x.tex_coord())
                .unwrap_or(t.tex_coord());
            let transform = transform.map(|x| UvTransform {
                offset: Vec2::from(x.offset()),
                rotation: x.rotation(),
                scale: Vec2::from(x.scale()),
            });
            slot(role, t.texture().index(), tex_coord, transform)
        })
        .transpose()
    };
    let normal = m.normal_texture();
    let occlusion = m.occlusion_texture();
    Ok(Material {
        base_color: Vec4::from(pbr.base_color_factor()),
        base_color_texture: info("base colour", pbr.base_color_texture())?,
        metallic_roughness_texture: info("metallic-roughness", pbr.metallic_roughness_texture())?,
        normal_texture: normal
            .as_ref()
            .map(|t| slot("normal", t.texture().index(), t.tex_coord(), None))
            .transpose()?,
        normal_scale: normal.as_ref().map_or(1.0, |t| t.scale()),
        occlusion_texture: occlusion
            .as_ref()
            .map(|t| slot("occlusion", t.texture().index(), t.tex_coord(), None))
            .transpose()?,
        occlusion_strength: occlusion
            .as_ref()
            .map_or(1.0, |t| t.strength().clamp(0.0, 1.0)),
        emissive_texture: info("emissive", m.emissive_texture())?,
        alpha_mode: match m.alpha_mode() {
            gltf::material::AlphaMode::Opaque => AlphaMode::Opaque,
            gltf::material::AlphaMode::Mask => AlphaMode::Mask {
                cutoff: m.alpha_cutoff().unwrap_or(0.5),
            },
            gltf::material::AlphaMode::Blend => AlphaMode::Blend,
        },
        double_sided: m.double_sided(),
        roughness: pbr.roughness_factor().clamp(0.0, 1.0),
        metallic: pbr.metallic_factor().clamp(0.0, 1.0),
        emissive: Vec3::from(m.emissive_factor()) * m.emissive_strength().unwrap_or(1.0),
        specular: m
            .specular()
            .map_or(1.0, |s| s.specular_factor().clamp(0.0, 1.0)),
        transmission: m
            .transmission()
            .map_or(0.0, |t| t.transmission_factor().clamp(0.0, 1.0)),
        ior: m.ior().unwrap_or(1.5).max(1.0),
        name,
    })
}

/// A texture's glTF sampler (defaults: repeat, linear, linear between mip levels).
fn sampler(s: &gltf::texture::Sampler) -> Sampler {
    use gltf::texture::{MagFilter, MinFilter, WrappingMode};
    let wrap = |w| match w {
        WrappingMode::Repeat => Wrap::Repeat,
        WrappingMode::MirroredRepeat => Wrap::MirroredRepeat,
        WrappingMode::ClampToEdge => Wrap::ClampToEdge,
    };
    let (min_linear, mipmaps) = match s.min_filter() {
        None | Some(MinFilter::LinearMipmapLinear) => (true, Some(true)),
        Some(MinFilter::Nearest) => (false, None),
        Some(MinFilter::Linear) => (true, None),
        Some(MinFilter::NearestMipmapNearest) => (false, Some(false)),
        Some(MinFilter::LinearMipmapNearest) => (true, Some(false)),
        Some(MinFilter::NearestMipmapLinear) => (false, Some(true)),
    };
    Sampler {
        wrap_u: wrap(s.wrap_s()),
        wrap_v: wrap(s.wrap_t()),
        mag_linear: s.mag_filter() != Some(MagFilter::Nearest),
        min_linear,
        mipmaps,
    }
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

/// The bytes of glTF buffer `b`: the GLB's binary chunk or its URI read through `folder`,
/// holding at least the declared `byteLength` (only those bytes are kept).
fn buffer_data(
    folder: &SceneFolder,
    b: &gltf::Buffer,
    blob: Option<&[u8]>,
) -> Result<Vec<u8>, SceneErrorKind> {
    let declared = b.length();
    let mut data = match b.source() {
        gltf::buffer::Source::Bin => blob
            .ok_or_else(|| {
                SceneErrorKind::Gltf(format!(
                    "buffer {} names the GLB binary chunk, which is missing",
                    b.index()
                ))
            })?
            .to_vec(),
        gltf::buffer::Source::Uri(uri) => folder.read_uri(uri, declared as u64 + 3)?,
    };
    if data.len() < declared {
        return Err(SceneErrorKind::Gltf(format!(
            "buffer {} declares {declared} bytes but holds {}",
            b.index(),
            data.len()
        )));
    }
    data.truncate(declared);
    Ok(data)
}

/// The encoded bytes (PNG, JPEG) of `image`: a buffer view of `buffers` or a URI read
/// through `folder`.
fn image_bytes(
    folder: &SceneFolder,
    image: &gltf::Image,
    buffers: &[Vec<u8>],
) -> Result<Vec<u8>, SceneErrorKind> {
    match image.source() {
        gltf::image::Source::View { view, .. } => {
            let buffer = &buffers[view.buffer().index()];
            let range = view.offset()..view.offset().saturating_add(view.length());
            buffer.get(range).map(<[u8]>::to_vec).ok_or_else(|| {
                SceneErrorKind::Gltf(format!(
                    "image {} reads past the end of buffer {}",
                    image.index(),
                    view.buffer().index()
                ))
            })
        }
        gltf::image::Source::Uri { uri, .. } => folder.read_uri(uri, UNDECLARED_LIMIT),
    }
}
