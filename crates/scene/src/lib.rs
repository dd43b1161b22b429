//! Scenes for the deferred-rendering toolkit: meshes, materials, cameras and lights, loaders
//! for glTF 2.0, OBJ and PLY, built-in test scenes, a triangle BVH for ray queries, and the
//! path-traced ground truth ([`reference`]).
//!
//! Conventions (DESIGN.md): right-handed, +Y up, a camera looks down its local −Z; radiance
//! and colours are linear; meshes are stored in world space (node transforms are applied when
//! loading).
//!
//! ```no_run
//! let scene = scene::Scene::load("scene.gltf")?;
//! println!("{} triangles, {} lights", scene.triangle_count(), scene.lights.len());
//! # Ok::<(), scene::SceneError>(())
//! ```

pub mod animation;
mod builtin;
mod bvh;
mod camera;
mod light;
mod load;
mod material;
pub mod reference;
mod tangents;
mod texture;

use std::path::{Path, PathBuf};

pub use builtin::{
    THESIS_HIDDEN_LIGHTS, THESIS_LIGHT_RADIUS, THESIS_VISIBLE_LIGHTS, checker_texture,
    checkerboard, cornell_box, dress_procedurally, material_gallery, mirror_spheres,
    spheres_on_plane, thesis_walls, wall,
};
pub use bvh::{Bvh, Hit};
pub use camera::Camera;
pub use glam;
pub use light::{Light, luminance, scatter_point_lights};
pub use material::{
    AlphaMode, MaterialSample, Sampler, SceneTextures, SurfaceAttributes, TextureRef, UvTransform,
    Wrap, dither_threshold, role_space, texture_spaces,
};
pub use texture::{
    ColorSpace, LinearTexture, MAX_ANISOTROPY, anisotropic_footprint, linear_to_srgb,
    srgb_to_linear,
};

use glam::{Vec2, Vec3, Vec4};

/// |cos| between a shading normal and its triangle's plane normal under which the shading
/// normal is taken for an asset's error ([`facing_shading_normal`]).
pub const BENT_NORMAL_COS: f32 = 0.01;

/// The shading normal `n` (unit) turned to the side of its triangle that the viewer sees
/// (`facing`: the unit plane normal on that side) — or, where `n` lies within
/// [`BENT_NORMAL_COS`] of the plane (normals that no side owns: Sponza's `object5_1`, or a
/// wall's normals on its neighbour at a corner), `facing` itself. The path tracer and the
/// G-buffer (CPU and `facing_normal` of `gbuffer.wgsl`) share this rule, so both shade such
/// points alike.
pub fn facing_shading_normal(n: Vec3, facing: Vec3) -> Vec3 {
    let c = n.dot(facing);
    if c.abs() < BENT_NORMAL_COS {
        facing
    } else if c < 0.0 {
        -n
    } else {
        n
    }
}

/// Two unit vectors completing unit `n` to a right-handed orthonormal basis, continuous in `n`
/// (Duff et al. 2017, "Building an orthonormal basis, revisited").
pub fn orthonormal_basis(n: Vec3) -> (Vec3, Vec3) {
    let sign = 1f32.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    (
        Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
        Vec3::new(b, sign + n.y * n.y * a, -n.y),
    )
}

/// The largest coordinate magnitude a scene may have: 10^15 (squared distances, which
/// shading and framing compute, stay finite in `f32`).
pub const MAX_COORDINATE: f32 = 1e15;

/// A triangle mesh in world space with one material.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    /// Name from the file, or a generated one.
    pub name: String,
    /// Vertex positions.
    pub positions: Vec<Vec3>,
    /// Unit vertex normals, one per position.
    pub normals: Vec<Vec3>,
    /// Texture coordinates, one per position (zero when the file has none).
    pub uvs: Vec<Vec2>,
    /// The second texture-coordinate set (glTF `TEXCOORD_1`), one per position, or empty.
    pub uvs1: Vec<Vec2>,
    /// Tangents (xyz unit, w = ±1 the bitangent's sign; glTF `TANGENT`), one per position, or
    /// empty.
    pub tangents: Vec<Vec4>,
    /// Linear vertex colours (glTF `COLOR_0`, RGB with alpha 1 or RGBA), one per position, or
    /// empty.
    pub colors: Vec<Vec4>,
    /// Three indices per triangle.
    pub indices: Vec<u32>,
    /// Index into [`Scene::materials`].
    pub material: u32,
}

impl Mesh {
    /// The quad `a b c d` as two triangles with `material`: normals from its winding (counter-
    /// clockwise seen from the side they point to), zero texture coordinates.
    pub fn quad(name: &str, corners: [Vec3; 4], material: u32) -> Self {
        let mut mesh = Self {
            name: name.into(),
            positions: corners.to_vec(),
            uvs: vec![Vec2::ZERO; 4],
            indices: vec![0, 1, 2, 0, 2, 3],
            material,
            ..Default::default()
        };
        mesh.compute_normals();
        mesh
    }

    /// Generates MikkTSpace tangents ([`Mesh::generate_tangents`]) when its material (in
    /// `materials`) has a normal map and the mesh has none.
    pub fn complete_tangents(&mut self, materials: &[Material]) {
        if let Some(normal) = materials
            .get(self.material as usize)
            .and_then(|m| m.normal_texture)
            && self.tangents.is_empty()
        {
            self.generate_tangents(normal.uv_set);
        }
    }

    /// Number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }

    /// Area-weighted smooth vertex normals from the triangles.
    pub fn compute_normals(&mut self) {
        let mut normals = vec![Vec3::ZERO; self.positions.len()];
        let n = self.positions.len();
        // Triangles with an index out of range add nothing here; `validate` reports them.
        for t in self.indices.chunks_exact(3) {
            if t.iter().any(|&i| i as usize >= n) {
                continue;
            }
            let [a, b, c] = [t[0], t[1], t[2]].map(|i| self.positions[i as usize]);
            let n = (b - a).cross(c - a);
            for &i in t {
                normals[i as usize] += n;
            }
        }
        self.normals = normals
            .into_iter()
            .map(|n| n.try_normalize().unwrap_or(Vec3::Y))
            .collect();
    }

    /// Checks the invariants every consumer relies on: finite data, matching lengths, indices
    /// in range, a multiple of three indices.
    fn validate(&self) -> Result<(), SceneErrorKind> {
        let n = self.positions.len();
        let bad = |what: String| {
            Err(SceneErrorKind::InvalidMesh {
                mesh: self.name.clone(),
                problem: what,
            })
        };
        if self.normals.len() != n || self.uvs.len() != n {
            return bad(format!(
                "{n} positions but {} normals and {} uvs",
                self.normals.len(),
                self.uvs.len()
            ));
        }
        if !self.indices.len().is_multiple_of(3) {
            return bad(format!(
                "{} indices is not a multiple of 3",
                self.indices.len()
            ));
        }
        if let Some(i) = self.indices.iter().find(|&&i| i as usize >= n) {
            return bad(format!("index {i} out of range for {n} vertices"));
        }
        if let Some(i) = self.positions.iter().position(|p| !p.is_finite()) {
            return bad(format!(
                "vertex {i} has a non-finite position {:?}",
                self.positions[i]
            ));
        }
        if self.normals.iter().any(|v| !v.is_finite()) || self.uvs.iter().any(|u| !u.is_finite()) {
            return bad("non-finite normal or texture coordinate".into());
        }
        for (what, len) in [
            ("second texture coordinates", self.uvs1.len()),
            ("tangents", self.tangents.len()),
            ("colours", self.colors.len()),
        ] {
            if len != 0 && len != n {
                return bad(format!("{n} positions but {len} {what}"));
            }
        }
        if self.uvs1.iter().any(|u| !u.is_finite())
            || self.tangents.iter().any(|t| !t.is_finite())
            || self.colors.iter().any(|c| !c.is_finite())
        {
            return bad("non-finite second texture coordinate, tangent or colour".into());
        }
        Ok(())
    }
}

/// An RGBA8 texture as its file stores it. Whether its colour channels are sRGB depends on the
/// role that reads it (glTF 2.0 §3.9): base colour and emissive are sRGB; metallic-roughness,
/// normal and occlusion linear.
#[derive(Clone, Debug, PartialEq)]
pub struct Texture {
    /// Name or file it came from.
    pub name: String,
    /// Width in texels.
    pub width: u32,
    /// Height in texels.
    pub height: u32,
    /// `width × height` texels, row-major from the top-left, 4 bytes each.
    pub rgba8: Vec<u8>,
    /// How it is sampled.
    pub sampler: Sampler,
}

/// A metallic-roughness material: the glTF 2.0 core model with `KHR_materials_emissive_strength`
/// (folded into `emissive`) and `KHR_materials_specular`'s factor.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    /// Name from the file.
    pub name: String,
    /// Linear base colour and alpha factor.
    pub base_color: Vec4,
    /// The base colour texture (sRGB; RGB × `base_color.rgb`, A × `base_color.a`).
    pub base_color_texture: Option<TextureRef>,
    /// The metallic-roughness texture (linear; B × `metallic`, G × `roughness`).
    pub metallic_roughness_texture: Option<TextureRef>,
    /// The tangent-space normal map (linear, `2·rgb − 1`).
    pub normal_texture: Option<TextureRef>,
    /// Scale of the normal map's x and y.
    pub normal_scale: f32,
    /// The ambient occlusion texture (linear, R).
    pub occlusion_texture: Option<TextureRef>,
    /// `1 + strength · (R − 1)` multiplies the ambient and indirect light.
    pub occlusion_strength: f32,
    /// The emissive texture (sRGB; RGB × `emissive`).
    pub emissive_texture: Option<TextureRef>,
    /// How alpha is used.
    pub alpha_mode: AlphaMode,
    /// Whether back faces are lit with the flipped normal (glTF `doubleSided`); a one-sided
    /// material's back faces are culled where the camera sees them (the G-buffer, the path
    /// tracer's camera rays). True by default: OBJ and built-in materials are two-sided.
    pub double_sided: bool,
    /// Perceptual roughness in \[0, 1\].
    pub roughness: f32,
    /// Metalness in \[0, 1\].
    pub metallic: f32,
    /// Emitted radiance (linear).
    pub emissive: Vec3,
    /// Scale of the dielectric specular reflectance F0 = 0.04 (glTF
    /// `KHR_materials_specular`'s `specularFactor`; an OBJ material whose `Ks` is black has
    /// 0: Lambert only). 1 by default.
    pub specular: f32,
    /// The share of light that passes through the surface instead of its diffuse lobe (glTF
    /// `KHR_materials_transmission`'s factor, in \[0, 1\]): [`Material::evaluate`] scales the
    /// albedo by 1 − it; the deferred renderer draws the transmitted light through refraction
    /// maps (`instant_radiosity::reflections`), while the VPLs, the surfels and the path
    /// tracer see only the scaled diffuse lobe (no light passes through). 0 by default.
    pub transmission: f32,
    /// Index of refraction (glTF `KHR_materials_ior`, at least 1); 1.5 by default. The
    /// reflection maps' Fresnel takes its F0 from it; the direct lighting keeps 0.04.
    pub ior: f32,
}

impl Material {
    /// Its five texture roles in the order the G-buffer binds them (base colour,
    /// metallic-roughness, normal, occlusion, emissive), each with its name and texture.
    pub fn roles(&self) -> [(&'static str, Option<TextureRef>); 5] {
        [
            ("base colour", self.base_color_texture),
            ("metallic-roughness", self.metallic_roughness_texture),
            ("normal", self.normal_texture),
            ("occlusion", self.occlusion_texture),
            ("emissive", self.emissive_texture),
        ]
    }

    /// Whether the renderers treat its surfaces as area lights: a uniform emitter (finite,
    /// non-zero emissive factor, no emissive texture — a lamp). Textured emission (glowing
    /// panels, decals) is seen where a ray or the camera meets it, but not sampled as a light:
    /// the deferred renderer's stand-in lights and VPL photons leave it out, the path tracer
    /// reaches it by its BRDF samples only.
    pub fn is_light(&self) -> bool {
        self.emissive.max_element() > 0.0
            && self.emissive.is_finite()
            && self.emissive_texture.is_none()
    }

    /// Rejects factors and texture transforms that are not finite, and negative emission.
    pub fn validate(&self) -> Result<(), SceneErrorKind> {
        let cutoff = match self.alpha_mode {
            AlphaMode::Mask { cutoff } => cutoff,
            _ => 0.0,
        };
        let scalars = [
            ("roughness", self.roughness),
            ("metallic", self.metallic),
            ("specular", self.specular),
            ("normal scale", self.normal_scale),
            ("occlusion strength", self.occlusion_strength),
            ("alpha cutoff", cutoff),
            ("transmission", self.transmission),
        ];
        let problem = if !self.base_color.is_finite() {
            Some(format!("base colour {} is not finite", self.base_color))
        } else if !self.emissive.is_finite() || self.emissive.min_element() < 0.0 {
            Some(format!(
                "emission {} is not finite and non-negative",
                self.emissive
            ))
        } else if let Some((what, v)) = scalars.iter().find(|(_, v)| !v.is_finite()) {
            Some(format!("{what} {v} is not finite"))
        } else if !(0.0..=1.0).contains(&self.transmission) {
            Some(format!(
                "transmission {} is outside [0, 1]",
                self.transmission
            ))
        } else if !(self.ior >= 1.0 && self.ior.is_finite()) {
            Some(format!(
                "index of refraction {} is not a finite value ≥ 1",
                self.ior
            ))
        } else {
            self.textures()
                .find(|(_, t)| {
                    let u = t.transform;
                    !(u.offset.is_finite() && u.scale.is_finite() && u.rotation.is_finite())
                })
                .map(|(role, t)| {
                    format!(
                        "the {role} texture's transform {:?} is not finite",
                        t.transform
                    )
                })
        };
        match problem {
            Some(problem) => Err(SceneErrorKind::Material {
                name: self.name.clone(),
                problem,
            }),
            None => Ok(()),
        }
    }

    /// The textures it reads, each with its role's name.
    pub fn textures(&self) -> impl Iterator<Item = (&'static str, TextureRef)> + '_ {
        self.roles()
            .into_iter()
            .filter_map(|(role, t)| t.map(|t| (role, t)))
    }
}

impl Default for Material {
    fn default() -> Self {
        Self {
            name: "default".into(),
            base_color: Vec4::new(0.8, 0.8, 0.8, 1.0),
            base_color_texture: None,
            metallic_roughness_texture: None,
            normal_texture: None,
            normal_scale: 1.0,
            occlusion_texture: None,
            occlusion_strength: 1.0,
            emissive_texture: None,
            alpha_mode: AlphaMode::Opaque,
            double_sided: true,
            roughness: 0.8,
            metallic: 0.0,
            emissive: Vec3::ZERO,
            specular: 1.0,
            transmission: 0.0,
            ior: 1.5,
        }
    }
}

/// An axis-aligned bounding box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    /// Minimum corner.
    pub min: Vec3,
    /// Maximum corner.
    pub max: Vec3,
}

impl Aabb {
    /// The empty box (grows from nothing).
    pub const EMPTY: Self = Self {
        min: Vec3::INFINITY,
        max: Vec3::NEG_INFINITY,
    };

    /// The box grown to contain `p`.
    pub fn grow(self, p: Vec3) -> Self {
        Self {
            min: self.min.min(p),
            max: self.max.max(p),
        }
    }

    /// Centre point.
    pub fn center(&self) -> Vec3 {
        (self.min + self.max) * 0.5
    }

    /// Length of the diagonal.
    pub fn diagonal(&self) -> f32 {
        (self.max - self.min).length()
    }
}

/// Meshes, materials, textures, an optional camera and lights.
#[derive(Clone, Debug, Default)]
pub struct Scene {
    /// Meshes in world space.
    pub meshes: Vec<Mesh>,
    /// Materials; every mesh indexes one.
    pub materials: Vec<Material>,
    /// Textures; materials index them.
    pub textures: Vec<Texture>,
    /// The scene's own camera (glTF camera or a built-in scene's), if any.
    pub camera: Option<Camera>,
    /// Lights from the file or the built-in scene.
    pub lights: Vec<Light>,
    /// What moves: glTF skins, morph targets and animations (`None` for a still scene). Its
    /// meshes are [`Scene::meshes`] at the rest pose.
    pub rig: Option<animation::Rig>,
}

impl Scene {
    /// Loads a scene, choosing the loader by extension: `.gltf`, `.glb`, `.obj`, `.ply`.
    pub fn load(path: impl AsRef<Path>) -> Result<Self, SceneError> {
        Self::load_with_progress(path, &mut |_, _| {})
    }

    /// Like [`Scene::load`], calling `progress(done, total)` as meshes are converted.
    pub fn load_with_progress(
        path: impl AsRef<Path>,
        progress: &mut dyn FnMut(usize, usize),
    ) -> Result<Self, SceneError> {
        let path = path.as_ref();
        let err = |kind| SceneError {
            path: path.to_owned(),
            kind,
        };
        match std::fs::metadata(path) {
            Err(_) => {
                return Err(err(SceneErrorKind::Io(std::io::Error::new(
                    std::io::ErrorKind::NotFound,
                    "no such file",
                ))));
            }
            Ok(meta) if !meta.is_file() => {
                return Err(err(SceneErrorKind::Reference {
                    reference: path.display().to_string(),
                    problem: "not a regular file".into(),
                }));
            }
            Ok(_) => {}
        }
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .unwrap_or("")
            .to_ascii_lowercase();
        let scene = match ext.as_str() {
            "gltf" | "glb" => load::gltf::load(path, progress),
            "obj" => load::obj::load(path, progress),
            "ply" => load::ply::load(path, progress),
            _ => Err(SceneErrorKind::UnsupportedFormat(ext)),
        }
        .map_err(err)?;
        let mut scene = scene;
        scene.complete_tangents();
        scene.validate().map_err(err)?;
        Ok(scene)
    }

    /// Adds `model` (another scene: its meshes, materials, textures, lights and animation)
    /// placed by `placement`; its camera is dropped. Its rig hangs under a new root node that
    /// holds `placement`, its clips follow this scene's, and its channels keep moving only its
    /// own nodes.
    pub fn insert(&mut self, model: Scene, placement: glam::Mat4) -> Result<(), SceneErrorKind> {
        if !placement.is_finite() || placement.determinant().abs() < 1e-12 {
            return Err(SceneErrorKind::Extent(format!(
                "a model's placement must be finite and invertible, not {placement}"
            )));
        }
        let Scene {
            meshes,
            materials,
            textures,
            lights,
            rig,
            ..
        } = model;
        let (mesh_offset, material_offset) =
            (self.meshes.len() as u32, self.materials.len() as u32);
        let light_offset = self.lights.len() as u32;
        let texture_offset = self.textures.len() as u32;
        self.textures.extend(textures);
        self.materials.extend(materials.into_iter().map(|mut m| {
            for t in [
                &mut m.base_color_texture,
                &mut m.metallic_roughness_texture,
                &mut m.normal_texture,
                &mut m.occlusion_texture,
                &mut m.emissive_texture,
            ]
            .into_iter()
            .flatten()
            {
                t.texture += texture_offset;
            }
            m
        }));
        let normals = glam::Mat3::from_mat4(placement).inverse().transpose();
        let linear = glam::Mat3::from_mat4(placement);
        let mirror = placement.determinant() < 0.0;
        for mut m in meshes {
            m.material += material_offset;
            for p in &mut m.positions {
                *p = placement.transform_point3(*p);
            }
            for n in &mut m.normals {
                *n = (normals * *n).normalize_or(Vec3::Y);
            }
            for t in &mut m.tangents {
                let w = if mirror { -t.w } else { t.w };
                *t = (linear * t.truncate()).normalize_or(Vec3::X).extend(w);
            }
            if mirror {
                for t in m.indices.chunks_exact_mut(3) {
                    t.swap(1, 2);
                }
            }
            self.meshes.push(m);
        }
        self.lights
            .extend(lights.iter().map(|l| l.transformed(placement)));
        if let Some(model_rig) = rig {
            let own = self.rig.get_or_insert_with(Default::default);
            own.insert(model_rig, placement, (mesh_offset, light_offset));
            let rest = own.pose(None, 0.0);
            own.apply(&rest, &mut self.meshes);
        }
        self.validate()
    }

    /// Generates MikkTSpace tangents ([`Mesh::generate_tangents`]) for every mesh whose
    /// material has a normal map and whose file gave none.
    pub fn complete_tangents(&mut self) {
        for mesh in &mut self.meshes {
            mesh.complete_tangents(&self.materials);
        }
    }

    /// Checks every mesh and reference; loaders and built-ins call it, so a `Scene` from
    /// [`Scene::load`] is always consistent. Call it after editing a scene by hand.
    pub fn validate(&self) -> Result<(), SceneErrorKind> {
        if self.meshes.iter().all(|m| m.indices.is_empty()) {
            return Err(SceneErrorKind::NoMeshes);
        }
        for m in &self.meshes {
            m.validate()?;
            if m.material as usize >= self.materials.len() {
                return Err(SceneErrorKind::InvalidMesh {
                    mesh: m.name.clone(),
                    problem: format!("material {} does not exist", m.material),
                });
            }
        }
        if let Some(rig) = &self.rig {
            rig.validate(&self.meshes, self.lights.len())?;
        }
        let b = self.bounds();
        let reach = b.min.abs().max(b.max.abs()).max_element();
        if !(reach <= MAX_COORDINATE) {
            return Err(SceneErrorKind::Extent(format!(
                "coordinates reach {reach:e}, beyond the ±{MAX_COORDINATE:e} a frame can hold \
                 (squared distances overflow f32 near 1.8e19)"
            )));
        }
        if (b.max - b.min).max_element() <= 0.0 {
            return Err(SceneErrorKind::Extent(format!(
                "every vertex is at {}: the scene has no extent to frame",
                b.min
            )));
        }
        for (i, mat) in self.materials.iter().enumerate() {
            mat.validate()?;
            for (role, t) in mat.textures() {
                if t.texture as usize >= self.textures.len() {
                    return Err(SceneErrorKind::Texture {
                        index: i,
                        problem: format!(
                            "material {:?}'s {role} texture is {}, of {}",
                            mat.name,
                            t.texture,
                            self.textures.len()
                        ),
                    });
                }
            }
        }
        for mesh in &self.meshes {
            let Some(mat) = self.materials.get(mesh.material as usize) else {
                continue;
            };
            if let Some((role, _)) = mat.textures().find(|(_, t)| t.uv_set == 1)
                && mesh.uvs1.is_empty()
            {
                return Err(SceneErrorKind::InvalidMesh {
                    mesh: mesh.name.clone(),
                    problem: format!(
                        "its material {:?} reads the {role} texture through TEXCOORD_1, which \
                         the mesh does not have",
                        mat.name
                    ),
                });
            }
        }
        for (index, t) in self.textures.iter().enumerate() {
            if t.rgba8.len() != t.width as usize * t.height as usize * 4
                || t.width == 0
                || t.height == 0
            {
                return Err(SceneErrorKind::Texture {
                    index,
                    problem: format!("texture {:?} has inconsistent size", t.name),
                });
            }
        }
        Ok(())
    }

    /// Total number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.meshes.iter().map(Mesh::triangle_count).sum()
    }

    /// Bounds of all vertices.
    pub fn bounds(&self) -> Aabb {
        self.meshes
            .iter()
            .flat_map(|m| &m.positions)
            .fold(Aabb::EMPTY, |b, &p| b.grow(p))
    }

    /// The scene's camera, or one framing the scene's bounds.
    pub fn camera_or_framed(&self) -> Camera {
        self.camera
            .unwrap_or_else(|| Camera::framing(self.bounds()))
    }
}

/// A loading or validation error, naming the file.
#[derive(Debug, thiserror::Error)]
#[error("{}: {kind}", path.display())]
pub struct SceneError {
    /// The file that failed.
    pub path: PathBuf,
    /// What went wrong.
    pub kind: SceneErrorKind,
}

/// What went wrong with a scene.
#[derive(Debug, thiserror::Error)]
pub enum SceneErrorKind {
    /// The file could not be read.
    #[error("{0}")]
    Io(#[from] std::io::Error),
    /// The extension names no supported format.
    #[error("unsupported scene format {0:?} (expected .gltf, .glb, .obj or .ply)")]
    UnsupportedFormat(String),
    /// The glTF parser or importer refused the file (truncated buffer, bad JSON, ...).
    #[error("invalid glTF: {0}")]
    Gltf(String),
    /// The OBJ/MTL parser refused the file.
    #[error("invalid OBJ: {0}")]
    Obj(String),
    /// The PLY parser refused the file.
    #[error("invalid PLY: {0}")]
    Ply(String),
    /// The file holds no triangles.
    #[error("the scene has no triangle meshes")]
    NoMeshes,
    /// A mesh breaks an invariant (NaN positions, bad indices, ...).
    #[error("mesh {mesh:?}: {problem}")]
    InvalidMesh {
        /// Mesh name.
        mesh: String,
        /// The problem.
        problem: String,
    },
    /// A file the scene names may not or cannot be read: outside the scene's folder, absolute,
    /// a URI scheme, not a regular file, larger than declared or allowed.
    #[error("{reference:?}: {problem}")]
    Reference {
        /// The path or URI as the scene writes it.
        reference: String,
        /// Why it is not read.
        problem: String,
    },
    /// A file the scene names does not exist (inside the scene's folder).
    #[error("{0:?}: no such file in the scene's folder")]
    MissingFile(String),
    /// The scene's coordinates are too large for `f32` rendering, or it has no extent.
    #[error("{0}")]
    Extent(String),
    /// A material's factor or texture transform is not a finite number, or its emission is
    /// negative.
    #[error("material {name:?}: {problem}")]
    Material {
        /// The material's name.
        name: String,
        /// Which value, and what it is.
        problem: String,
    },
    /// A texture could not be decoded or is inconsistent.
    #[error("texture {index}: {problem}")]
    Texture {
        /// Texture or material index.
        index: usize,
        /// The problem.
        problem: String,
    },
}

/// The folder of third-party test assets: `$DEFERRED_FIXTURES` if set, else `../shared/fixtures`
/// beside the workspace (see its `SOURCES.md`). `None` when neither exists.
pub fn shared_fixtures() -> Option<PathBuf> {
    let dir = match std::env::var_os("DEFERRED_FIXTURES") {
        Some(d) => PathBuf::from(d),
        None => Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/fixtures"),
    };
    dir.is_dir().then(|| dir.canonicalize().unwrap_or(dir))
}

/// The view `views.json` (shipped with this crate) gives for a scene file without a camera, by
/// file name: e.g. inside the Sponza atrium rather than the framing view from outside.
pub fn preset_view(path: &Path, scene: &Scene) -> Option<Camera> {
    #[derive(serde::Deserialize)]
    struct View {
        eye: [f32; 3],
        target: [f32; 3],
        fov_deg: f32,
    }
    let views: std::collections::HashMap<String, serde_json::Value> =
        serde_json::from_str(include_str!("views.json")).ok()?;
    let view: View =
        serde_json::from_value(views.get(path.file_name()?.to_str()?)?.clone()).ok()?;
    let mut camera = Camera::look_at(Vec3::from(view.eye), Vec3::from(view.target));
    camera.fov_y = view.fov_deg.to_radians();
    camera.fit_planes(scene.bounds());
    Some(camera)
}
