//! Animation (glTF 2.0 §3.7 skins, §3.7.2.3 morph targets, §3.11 animations): a [`Rig`] of
//! node instances with their rest transforms, the file's clips, skins and the meshes they move;
//! [`Rig::pose`] samples a clip at a time, [`Rig::deform`] moves a mesh's rest vertices by a
//! pose — the CPU twin of the renderer's GPU skinning (`shaders/pipeline/skinning.wgsl`),
//! operation for operation in `f32`.
//!
//! Every moved mesh is deformed the same way: morph targets first (object space, weights in
//! target order), then a blend of joint matrices. A rigidly animated mesh is a skin of one
//! joint — its node, with an identity inverse bind matrix — so skinned, morphed and rigidly
//! animated meshes share one kernel.
//!
//! ```no_run
//! let scene = scene::Scene::load("CesiumMan.glb")?;
//! let rig = scene.rig.as_ref().expect("an animated file");
//! let pose = rig.pose(Some(0), 0.5);
//! for d in &rig.deformers {
//!     let posed = rig.deform(d, &pose);
//!     println!("mesh {}: first vertex at {}", d.mesh, posed.positions[0]);
//! }
//! # Ok::<(), scene::SceneError>(())
//! ```

use glam::{Mat3, Mat4, Quat, Vec3, Vec4};

use crate::{Camera, Light, SceneErrorKind};

/// The channel target of the root node instances [`Rig::insert`] adds (no channel moves them).
pub const PLACEMENT_NODE: u32 = u32::MAX;

/// A node's local transform as translation, rotation and scale (glTF `TRS`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Trs {
    /// Translation.
    pub translation: Vec3,
    /// Unit rotation.
    pub rotation: Quat,
    /// Scale.
    pub scale: Vec3,
}

impl Trs {
    /// `T · R · S`.
    pub fn matrix(&self) -> Mat4 {
        Mat4::from_scale_rotation_translation(self.scale, self.rotation, self.translation)
    }
}

/// One placement of a glTF node (a node reached through several parents has one instance per
/// path; glTF 2.0 forbids that, but files do it).
#[derive(Clone, Debug, PartialEq)]
pub struct NodeInstance {
    /// The glTF node index.
    pub node: u32,
    /// The parent instance (always an earlier one), `None` for a scene root.
    pub parent: Option<u32>,
    /// The file's local transform as TRS (what channels replace).
    pub rest: Trs,
    /// The file's local matrix when it gave one (glTF forbids animating such nodes): used
    /// as is, so shears survive.
    pub matrix: Option<Mat4>,
    /// The node's morph weights at rest (node `weights`, else its mesh's, else zeros).
    pub weights: Vec<f32>,
}

/// What a channel animates.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Property {
    /// `translation` (3 values a key).
    Translation,
    /// `rotation` (a quaternion xyzw a key).
    Rotation,
    /// `scale` (3 values a key).
    Scale,
    /// `weights` (one per morph target a key).
    Weights,
}

/// How a channel interpolates between keys (glTF 2.0 Appendix C).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Interpolation {
    /// The earlier key's value.
    Step,
    /// Linear; spherical linear for rotations.
    Linear,
    /// Cubic Hermite spline: each key holds in-tangent, value, out-tangent.
    CubicSpline,
}

/// One animated property of one node.
#[derive(Clone, Debug, PartialEq)]
pub struct Channel {
    /// The glTF node it moves (every instance of it).
    pub node: u32,
    /// The property.
    pub property: Property,
    /// Interpolation.
    pub interpolation: Interpolation,
    /// Key times in seconds, strictly increasing.
    pub times: Vec<f32>,
    /// Key values, `width` per key (three times that for cubic splines: in-tangent, value,
    /// out-tangent).
    pub values: Vec<f32>,
    /// Components of one value (3, 4, or the morph-target count).
    pub width: usize,
}

/// A glTF animation: channels sampled together.
#[derive(Clone, Debug, PartialEq)]
pub struct Clip {
    /// Name from the file, or `animation N`.
    pub name: String,
    /// The last key time of every channel, in seconds.
    pub duration: f32,
    /// The channels.
    pub channels: Vec<Channel>,
}

/// A glTF skin: its joints' node instances and inverse bind matrices.
#[derive(Clone, Debug, PartialEq)]
pub struct Skin {
    /// Node instance of each joint.
    pub joints: Vec<u32>,
    /// Inverse bind matrix of each joint.
    pub inverse_bind: Vec<Mat4>,
}

/// A morph target's displacements (glTF 2.0 §3.7.2.2), one per vertex (empty where the target
/// has no such attribute).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MorphTarget {
    /// Position displacements.
    pub positions: Vec<Vec3>,
    /// Normal displacements.
    pub normals: Vec<Vec3>,
    /// Tangent (xyz) displacements.
    pub tangents: Vec<Vec3>,
}

/// The joints that move a deformed mesh: a skin of the file, or its own node (rigid motion).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Joints {
    /// Skin `n` of [`Rig::skins`], with the mesh's `JOINTS_0`/`WEIGHTS_0`.
    Skin(u32),
    /// The node instance that places the mesh: every vertex follows it with weight 1.
    Node(u32),
}

/// A scene mesh that moves: its rest vertices in object space and what moves them.
#[derive(Clone, Debug, PartialEq)]
pub struct Deformer {
    /// Index of the mesh in [`crate::Scene::meshes`].
    pub mesh: u32,
    /// The node instance that places it (its morph weights are this node's).
    pub node: u32,
    /// The joints.
    pub joints: Joints,
    /// Rest positions in object space.
    pub positions: Vec<Vec3>,
    /// Rest unit normals in object space.
    pub normals: Vec<Vec3>,
    /// Rest tangents in object space (xyz unit, w the bitangent sign), or empty.
    pub tangents: Vec<Vec4>,
    /// Four joint indices per vertex (into the skin's joints; zeros for rigid motion).
    pub joint_indices: Vec<[u32; 4]>,
    /// Four weights per vertex summing to 1 (`[1, 0, 0, 0]` for rigid motion).
    pub weights: Vec<[f32; 4]>,
    /// Morph targets.
    pub targets: Vec<MorphTarget>,
}

/// A deformed mesh's vertices in world space.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Posed {
    /// Positions.
    pub positions: Vec<Vec3>,
    /// Unit normals.
    pub normals: Vec<Vec3>,
    /// Tangents (empty when the rest mesh has none).
    pub tangents: Vec<Vec4>,
}

/// Every node instance's world matrix and morph weights at one time of one clip.
#[derive(Clone, Debug, PartialEq)]
pub struct Pose {
    /// World matrix of each node instance.
    pub world: Vec<Mat4>,
    /// Morph weights of each node instance.
    pub weights: Vec<Vec<f32>>,
}

/// A camera or light on a node that moves: the node instance and the thing in its node's
/// space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Attached<T> {
    /// The node instance.
    pub node: u32,
    /// In the node's space (a camera at the origin looking down −Z, a light as the file
    /// places it on its node).
    pub local: T,
}

/// The animated part of a scene (loaded from glTF skins, morph targets and animations).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Rig {
    /// Node instances, parents before children.
    pub nodes: Vec<NodeInstance>,
    /// The file's animations.
    pub clips: Vec<Clip>,
    /// The file's skins.
    pub skins: Vec<Skin>,
    /// The meshes that move, in mesh order.
    pub deformers: Vec<Deformer>,
    /// The scene's camera, when its node moves.
    pub camera: Option<Attached<Camera>>,
    /// Lights whose nodes move: their index in [`crate::Scene::lights`].
    pub lights: Vec<(u32, Attached<Light>)>,
}

impl Channel {
    /// The channel's value at `t` seconds (held before the first and after the last key).
    pub fn sample(&self, t: f32) -> Vec<f32> {
        let w = self.width;
        let n = self.times.len();
        let cubic = self.interpolation == Interpolation::CubicSpline;
        // Key k's value (the middle of its three parts for cubic splines).
        let value = |k: usize| -> &[f32] {
            let start = if cubic { (3 * k + 1) * w } else { k * w };
            &self.values[start..start + w]
        };
        let next = self.times.partition_point(|&key| key <= t);
        if next == 0 {
            return value(0).to_vec();
        }
        if next == n {
            return value(n - 1).to_vec();
        }
        let k = next - 1;
        let (t0, t1) = (self.times[k], self.times[k + 1]);
        let dt = t1 - t0;
        let s = (t - t0) / dt;
        let rotation = self.property == Property::Rotation;
        match self.interpolation {
            Interpolation::Step => value(k).to_vec(),
            Interpolation::Linear if rotation => {
                let q = |v: &[f32]| Quat::from_xyzw(v[0], v[1], v[2], v[3]);
                let r = q(value(k)).slerp(q(value(k + 1)), s);
                r.to_array().to_vec()
            }
            Interpolation::Linear => value(k)
                .iter()
                .zip(value(k + 1))
                .map(|(a, b)| a + (b - a) * s)
                .collect(),
            Interpolation::CubicSpline => {
                let part = |key: usize, p: usize, c: usize| self.values[(3 * key + p) * w + c];
                let (s2, s3) = (s * s, s * s * s);
                let out: Vec<f32> = (0..w)
                    .map(|c| {
                        (2.0 * s3 - 3.0 * s2 + 1.0) * part(k, 1, c)
                            + (s3 - 2.0 * s2 + s) * dt * part(k, 2, c)
                            + (-2.0 * s3 + 3.0 * s2) * part(k + 1, 1, c)
                            + (s3 - s2) * dt * part(k + 1, 0, c)
                    })
                    .collect();
                if rotation {
                    let q = Quat::from_xyzw(out[0], out[1], out[2], out[3]).normalize();
                    q.to_array().to_vec()
                } else {
                    out
                }
            }
        }
    }
}

impl Rig {
    /// The pose at `t` seconds of clip `clip` (held at its ends; the caller loops), or the
    /// rest pose for `None`.
    ///
    /// # Panics
    ///
    /// If `clip` is not an index of [`Rig::clips`].
    pub fn pose(&self, clip: Option<usize>, t: f32) -> Pose {
        let mut local: Vec<Trs> = self.nodes.iter().map(|n| n.rest).collect();
        let mut animated = vec![false; self.nodes.len()];
        let mut weights: Vec<Vec<f32>> = self.nodes.iter().map(|n| n.weights.clone()).collect();
        if let Some(c) = clip {
            // The instances of each channel target, found once per pose.
            let mut instances: std::collections::HashMap<u32, Vec<usize>> = Default::default();
            for (i, n) in self.nodes.iter().enumerate() {
                instances.entry(n.node).or_default().push(i);
            }
            for ch in &self.clips[c].channels {
                let v = ch.sample(t);
                for &i in instances.get(&ch.node).map_or(&[][..], Vec::as_slice) {
                    let l = &mut local[i];
                    match ch.property {
                        Property::Translation => l.translation = Vec3::from_slice(&v),
                        Property::Rotation => l.rotation = Quat::from_slice(&v).normalize(),
                        Property::Scale => l.scale = Vec3::from_slice(&v),
                        Property::Weights => weights[i] = v.clone(),
                    }
                    animated[i] = animated[i] || ch.property != Property::Weights;
                }
            }
        }
        let mut world: Vec<Mat4> = Vec::with_capacity(self.nodes.len());
        for (i, n) in self.nodes.iter().enumerate() {
            let m = match n.matrix {
                Some(m) if !animated[i] => m,
                _ => local[i].matrix(),
            };
            let parent = n.parent.map_or(Mat4::IDENTITY, |p| world[p as usize]);
            world.push(parent * m);
        }
        Pose { world, weights }
    }

    /// The joint matrices of `deformer` in `pose`: joint world × inverse bind for a skin,
    /// the node's world matrix for rigid motion.
    pub fn joint_matrices(&self, deformer: &Deformer, pose: &Pose) -> Vec<Mat4> {
        match deformer.joints {
            Joints::Skin(s) => {
                let skin = &self.skins[s as usize];
                skin.joints
                    .iter()
                    .zip(&skin.inverse_bind)
                    .map(|(&j, ibm)| pose.world[j as usize] * *ibm)
                    .collect()
            }
            Joints::Node(n) => vec![pose.world[n as usize]],
        }
    }

    /// `deformer`'s vertices in `pose`, in world space (CPU twin of `skinning.wgsl`).
    pub fn deform(&self, deformer: &Deformer, pose: &Pose) -> Posed {
        let joints = self.joint_matrices(deformer, pose);
        let weights = &pose.weights[deformer.node as usize];
        let mut out = Posed {
            positions: Vec::with_capacity(deformer.positions.len()),
            normals: Vec::with_capacity(deformer.positions.len()),
            tangents: Vec::with_capacity(deformer.tangents.len()),
        };
        for v in 0..deformer.positions.len() {
            let (p, n, t) = morphed(deformer, weights, v);
            let m = blend(&joints, deformer.joint_indices[v], deformer.weights[v]);
            let (p, n, t) = skin_vertex(m, p, n, t);
            out.positions.push(p);
            out.normals.push(n);
            if !deformer.tangents.is_empty() {
                out.tangents.push(t);
            }
        }
        out
    }

    /// Adds `model` (the rig of a scene whose meshes and lights were appended after
    /// `mesh_offset` and `light_offset` of this rig's scene; its camera is dropped) under a new
    /// root node instance placed by `placement`. The model's
    /// channel targets are renumbered past this rig's, so each clip moves only its own file's
    /// nodes; its clips are appended.
    pub fn insert(&mut self, model: Rig, placement: Mat4, (mesh_offset, light_offset): (u32, u32)) {
        let target_offset = self
            .nodes
            .iter()
            .map(|n| n.node)
            .chain(
                self.clips
                    .iter()
                    .flat_map(|c| c.channels.iter().map(|ch| ch.node)),
            )
            .filter(|&n| n != PLACEMENT_NODE)
            .max()
            .map_or(0, |n| n + 1);
        let root = self.nodes.len() as u32;
        let (scale, rotation, translation) = placement.to_scale_rotation_translation();
        self.nodes.push(NodeInstance {
            node: PLACEMENT_NODE,
            parent: None,
            rest: Trs {
                translation,
                rotation,
                scale,
            },
            matrix: Some(placement),
            weights: Vec::new(),
        });
        let offset = self.nodes.len() as u32;
        self.nodes.extend(model.nodes.into_iter().map(|mut n| {
            n.node += target_offset;
            n.parent = Some(n.parent.map_or(root, |p| p + offset));
            n
        }));
        let skin_offset = self.skins.len() as u32;
        self.skins.extend(model.skins.into_iter().map(|mut s| {
            for j in &mut s.joints {
                *j += offset;
            }
            s
        }));
        self.deformers
            .extend(model.deformers.into_iter().map(|mut d| {
                d.mesh += mesh_offset;
                d.node += offset;
                d.joints = match d.joints {
                    Joints::Skin(s) => Joints::Skin(s + skin_offset),
                    Joints::Node(n) => Joints::Node(n + offset),
                };
                d
            }));
        self.lights
            .extend(model.lights.into_iter().map(|(index, mut a)| {
                a.node += offset;
                (index + light_offset, a)
            }));
        self.clips.extend(model.clips.into_iter().map(|mut c| {
            for ch in &mut c.channels {
                ch.node += target_offset;
            }
            c
        }));
    }

    /// The scene's camera in `pose`, if its node moves.
    pub fn camera(&self, pose: &Pose) -> Option<Camera> {
        let a = self.camera.as_ref()?;
        let world = pose.world[a.node as usize];
        let c = &a.local;
        Some(Camera {
            eye: world.transform_point3(c.eye),
            target: world.transform_point3(c.target),
            up: world.transform_vector3(c.up).normalize_or(Vec3::Y),
            ..*c
        })
    }

    /// Writes the lights whose nodes move, as `pose` places them, into `lights` (the scene's
    /// lights, or a list that starts with them).
    pub fn place_lights(&self, pose: &Pose, lights: &mut [Light]) {
        for (index, a) in &self.lights {
            if let Some(light) = lights.get_mut(*index as usize) {
                *light = a.local.transformed(pose.world[a.node as usize]);
            }
        }
    }

    /// Writes `pose` into the moved meshes of `meshes` (the scene's, which this rig moves):
    /// positions, normals and tangents in world space ([`Rig::deform`]).
    pub fn apply(&self, pose: &Pose, meshes: &mut [crate::Mesh]) {
        for d in &self.deformers {
            let posed = self.deform(d, pose);
            if let Some(mesh) = meshes.get_mut(d.mesh as usize) {
                mesh.positions = posed.positions;
                mesh.normals = posed.normals;
                mesh.tangents = posed.tangents;
            }
        }
    }

    /// Checks that every reference holds: parents before children, skins and joints inside
    /// the rig, one rest vertex (with joints, weights and displacements) per vertex of its
    /// mesh in `meshes`.
    pub fn validate(&self, meshes: &[crate::Mesh], lights: usize) -> Result<(), SceneErrorKind> {
        let bad = |problem: String| SceneErrorKind::Gltf(format!("animation: {problem}"));
        let nodes = self.nodes.len() as u32;
        let attached = self.camera.iter().map(|c| c.node);
        if attached
            .chain(self.lights.iter().map(|(_, l)| l.node))
            .any(|n| n >= nodes)
            || self.lights.iter().any(|(i, _)| *i as usize >= lights)
        {
            return Err(bad(
                "a moving camera or light names a node or light that does not exist".into(),
            ));
        }
        if let Some(i) = self
            .nodes
            .iter()
            .enumerate()
            .position(|(i, n)| n.parent.is_some_and(|p| p >= i as u32))
        {
            return Err(bad(format!("node instance {i} comes before its parent")));
        }
        for (s, skin) in self.skins.iter().enumerate() {
            if skin.joints.len() != skin.inverse_bind.len()
                || skin.joints.iter().any(|&j| j >= nodes)
            {
                return Err(bad(format!("skin {s} has joints outside the rig")));
            }
        }
        for d in &self.deformers {
            let Some(mesh) = meshes.get(d.mesh as usize) else {
                return Err(bad(format!(
                    "a deformer moves mesh {}, which does not exist",
                    d.mesh
                )));
            };
            let n = mesh.positions.len();
            let joints = match d.joints {
                Joints::Skin(s) => self.skins.get(s as usize).map(|s| s.joints.len()),
                Joints::Node(node) => (node < nodes).then_some(1),
            };
            let lengths_match = [
                d.positions.len(),
                d.normals.len(),
                d.joint_indices.len(),
                d.weights.len(),
            ]
            .iter()
            .all(|&l| l == n)
                && (d.tangents.is_empty() || d.tangents.len() == n)
                && d.targets.iter().all(|t| {
                    [&t.positions, &t.normals, &t.tangents]
                        .iter()
                        .all(|v| v.is_empty() || v.len() == n)
                });
            let in_range = joints.is_some_and(|count| {
                d.joint_indices
                    .iter()
                    .flatten()
                    .all(|&j| (j as usize) < count)
            });
            if d.node >= nodes || !lengths_match || !in_range {
                return Err(SceneErrorKind::InvalidMesh {
                    mesh: mesh.name.clone(),
                    problem: format!(
                        "its animation data does not fit it ({n} vertices; node, skin and joints \
                         must exist)"
                    ),
                });
            }
        }
        Ok(())
    }

    /// Whether any clip moves anything.
    pub fn is_animated(&self) -> bool {
        self.clips.iter().any(|c| !c.channels.is_empty())
    }
}

/// Vertex `v` of `d` after its morph targets with `weights` (targets in order; a weight the
/// node lacks counts 0), in object space.
fn morphed(d: &Deformer, weights: &[f32], v: usize) -> (Vec3, Vec3, Vec4) {
    let mut p = d.positions[v];
    let mut n = d.normals[v];
    let mut t = d.tangents.get(v).copied().unwrap_or(Vec4::ZERO);
    for (k, target) in d.targets.iter().enumerate() {
        let w = weights.get(k).copied().unwrap_or(0.0);
        if let Some(dp) = target.positions.get(v) {
            p += w * *dp;
        }
        if let Some(dn) = target.normals.get(v) {
            n += w * *dn;
        }
        if let Some(dt) = target.tangents.get(v) {
            t += (w * *dt).extend(0.0);
        }
    }
    (p, n, t)
}

/// `Σ wᵢ · joints[jᵢ]` (a joint index past the end counts as none).
fn blend(joints: &[Mat4], indices: [u32; 4], weights: [f32; 4]) -> Mat4 {
    let mut m = Mat4::ZERO;
    for (j, w) in indices.into_iter().zip(weights) {
        if let Some(joint) = joints.get(j as usize) {
            m += *joint * w;
        }
    }
    m
}

/// A vertex through the blended matrix `m`: the position by `m`, the normal by its cofactor
/// matrix (the inverse transpose times the determinant; the determinant's sign keeps it
/// outward under mirroring), the tangent by its linear part with `w` flipped under mirroring.
fn skin_vertex(m: Mat4, p: Vec3, n: Vec3, t: Vec4) -> (Vec3, Vec3, Vec4) {
    let l = Mat3::from_mat4(m);
    let cofactor = Mat3::from_cols(
        l.y_axis.cross(l.z_axis),
        l.z_axis.cross(l.x_axis),
        l.x_axis.cross(l.y_axis),
    );
    let sign = if l.determinant() < 0.0 { -1.0 } else { 1.0 };
    let position = m.transform_point3(p);
    let normal = (sign * (cofactor * n)).normalize_or(Vec3::Y);
    let tangent = (l * t.truncate()).normalize_or(Vec3::X).extend(t.w * sign);
    (position, normal, tangent)
}
