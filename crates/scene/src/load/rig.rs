//! The animated part of a glTF file ([`crate::animation`]): clips, skins, the vertices' joints
//! and weights, morph targets — read through the checked accessors and validated, so a
//! hostile file is an error that names the part at fault.

use std::collections::HashSet;

use glam::{Mat4, Vec3};

use super::accessor;
use crate::SceneErrorKind;
use crate::animation::{Channel, Clip, Interpolation, MorphTarget, Property, Skin};

fn invalid(problem: String) -> SceneErrorKind {
    SceneErrorKind::Gltf(problem)
}

/// Whether the file moves anything: animations, skins or morph targets.
pub fn has_rig(doc: &gltf::Document) -> bool {
    doc.animations().next().is_some()
        || doc.skins().next().is_some()
        || doc
            .meshes()
            .any(|m| m.primitives().any(|p| p.morph_targets().next().is_some()))
}

/// The glTF nodes some channel moves (translation, rotation or scale).
pub fn moved_nodes(doc: &gltf::Document) -> HashSet<usize> {
    doc.animations()
        .flat_map(|a| a.channels().collect::<Vec<_>>())
        .filter(|c| c.target().property() != gltf::animation::Property::MorphTargetWeights)
        .map(|c| c.target().node().index())
        .collect()
}

/// Every animation of the file; `targets(node)` is the morph-target count of the mesh on
/// `node` (0 without), which a weights channel's width must equal.
pub fn clips(
    doc: &gltf::Document,
    buffers: &[Vec<u8>],
    targets: &dyn Fn(usize) -> usize,
) -> Result<Vec<Clip>, SceneErrorKind> {
    doc.animations()
        .map(|a| {
            let name = a
                .name()
                .map_or_else(|| format!("animation {}", a.index()), str::to_owned);
            let channels = a
                .channels()
                .map(|c| channel(&c, buffers, &name, targets))
                .collect::<Result<Vec<_>, _>>()?;
            let duration = channels
                .iter()
                .filter_map(|c| c.times.last().copied())
                .fold(0.0f32, f32::max);
            Ok(Clip {
                name,
                duration,
                channels,
            })
        })
        .collect()
}

fn channel(
    c: &gltf::animation::Channel,
    buffers: &[Vec<u8>],
    clip: &str,
    targets: &dyn Fn(usize) -> usize,
) -> Result<Channel, SceneErrorKind> {
    use gltf::animation::{Interpolation as I, Property as P};
    let node = c.target().node().index();
    let what = format!("{clip:?} channel {} (node {node})", c.index());
    let sampler = c.sampler();
    let times: Vec<f32> = accessor::read(
        &sampler.input(),
        buffers,
        &format!("key times of {what}"),
        &accessor::SCALAR_F32,
    )?
    .into_iter()
    .map(|t| t as f32)
    .collect();
    if times.is_empty() {
        return Err(invalid(format!("{what} has no keys")));
    }
    if times.iter().any(|t| !t.is_finite() || *t < 0.0) || times.windows(2).any(|w| w[1] <= w[0]) {
        return Err(invalid(format!(
            "{what}: key times must be finite, non-negative and strictly increasing"
        )));
    }
    let (property, allowed) = match c.target().property() {
        P::Translation => (Property::Translation, &accessor::VEC3_F32),
        P::Rotation => (Property::Rotation, &accessor::ROTATION),
        P::Scale => (Property::Scale, &accessor::VEC3_F32),
        P::MorphTargetWeights => (Property::Weights, &accessor::SCALAR_F32),
    };
    let interpolation = match sampler.interpolation() {
        I::Step => Interpolation::Step,
        I::Linear => Interpolation::Linear,
        I::CubicSpline => Interpolation::CubicSpline,
    };
    let values: Vec<f32> = accessor::read(
        &sampler.output(),
        buffers,
        &format!("values of {what}"),
        allowed,
    )?
    .into_iter()
    .map(|v| v as f32)
    .collect();
    if values.iter().any(|v| !v.is_finite()) {
        return Err(invalid(format!("{what}: values must be finite")));
    }
    let parts = if interpolation == Interpolation::CubicSpline {
        3
    } else {
        1
    };
    let width = match property {
        Property::Translation | Property::Scale => 3,
        Property::Rotation => 4,
        Property::Weights => targets(node),
    };
    if width == 0 || values.len() != times.len() * parts * width {
        return Err(invalid(format!(
            "{what}: {} values for {} keys of {width} components{}",
            values.len(),
            times.len(),
            if parts == 3 {
                " (×3 for a cubic spline)"
            } else {
                ""
            }
        )));
    }
    Ok(Channel {
        node: node as u32,
        property,
        interpolation,
        times,
        values,
        width,
    })
}

/// Skin `skin` with its joints' node instances (`instance(node)`: the first placement of a
/// glTF node in the scene).
pub fn skin(
    skin: &gltf::Skin,
    buffers: &[Vec<u8>],
    instance: &dyn Fn(usize) -> Option<u32>,
) -> Result<Skin, SceneErrorKind> {
    let what = format!("skin {}", skin.index());
    let joints = skin
        .joints()
        .map(|j| {
            instance(j.index()).ok_or_else(|| {
                invalid(format!(
                    "{what}: joint node {} is not in the scene",
                    j.index()
                ))
            })
        })
        .collect::<Result<Vec<u32>, _>>()?;
    let inverse_bind = match skin.inverse_bind_matrices() {
        Some(a) => {
            let v = accessor::read(
                &a,
                buffers,
                &format!("inverse bind matrices of {what}"),
                &accessor::MAT4_F32,
            )?;
            let m: Vec<Mat4> = v
                .chunks_exact(16)
                .map(|c| Mat4::from_cols_array(&std::array::from_fn(|k| c[k] as f32)))
                .collect();
            if m.len() != joints.len() || !m.iter().all(|m| m.is_finite()) {
                return Err(invalid(format!(
                    "{what}: {} finite inverse bind matrices are needed, one per joint",
                    joints.len()
                )));
            }
            m
        }
        None => vec![Mat4::IDENTITY; joints.len()],
    };
    Ok(Skin {
        joints,
        inverse_bind,
    })
}

/// Four joint indices and four weights per vertex.
type JointsAndWeights = (Vec<[u32; 4]>, Vec<[f32; 4]>);

/// `JOINTS_0` and `WEIGHTS_0` of a skinned primitive of `n` vertices: joint indices below
/// `joint_count`, weights made to sum to 1 (all on the first joint where they sum to 0).
pub fn joints_and_weights(
    prim: &gltf::Primitive,
    buffers: &[Vec<u8>],
    name: &str,
    n: usize,
    joint_count: usize,
) -> Result<JointsAndWeights, SceneErrorKind> {
    use gltf::Semantic;
    let bad = |problem: String| SceneErrorKind::InvalidMesh {
        mesh: name.into(),
        problem,
    };
    let (Some(j), Some(w)) = (
        prim.get(&Semantic::Joints(0)),
        prim.get(&Semantic::Weights(0)),
    ) else {
        return Err(bad("it is skinned but has no JOINTS_0 and WEIGHTS_0".into()));
    };
    let j = accessor::read(
        &j,
        buffers,
        &format!("JOINTS_0 of {name:?}"),
        &accessor::JOINTS,
    )?;
    let w = accessor::read(
        &w,
        buffers,
        &format!("WEIGHTS_0 of {name:?}"),
        &accessor::WEIGHTS,
    )?;
    if j.len() != 4 * n || w.len() != 4 * n {
        return Err(bad(format!(
            "{} joints and {} weights for {n} positions",
            j.len() / 4,
            w.len() / 4
        )));
    }
    let joints: Vec<[u32; 4]> = j
        .chunks_exact(4)
        .map(|c| std::array::from_fn(|k| c[k] as u32))
        .collect();
    if let Some(v) = joints
        .iter()
        .position(|js| js.iter().any(|&i| i as usize >= joint_count))
    {
        return Err(bad(format!(
            "vertex {v} names joint {:?}, but the skin has {joint_count}",
            joints[v]
        )));
    }
    let weights = w
        .chunks_exact(4)
        .map(|c| {
            let c: [f32; 4] = std::array::from_fn(|k| (c[k] as f32).max(0.0));
            let sum: f32 = c.iter().sum();
            if sum > 0.0 && sum.is_finite() {
                c.map(|x| x / sum)
            } else {
                [1.0, 0.0, 0.0, 0.0]
            }
        })
        .collect();
    Ok((joints, weights))
}

/// The morph targets of a primitive of `n` vertices (VEC3 float displacements).
pub fn morph_targets(
    prim: &gltf::Primitive,
    buffers: &[Vec<u8>],
    name: &str,
    n: usize,
) -> Result<Vec<MorphTarget>, SceneErrorKind> {
    let read = |a: Option<gltf::Accessor>, what: &str, k: usize| -> Result<Vec<Vec3>, _> {
        let Some(a) = a else {
            return Ok(Vec::new());
        };
        let v = accessor::read(
            &a,
            buffers,
            &format!("morph target {k} {what} of {name:?}"),
            &accessor::VEC3_F32,
        )?;
        if v.len() != 3 * n || v.iter().any(|x| !x.is_finite()) {
            return Err(SceneErrorKind::InvalidMesh {
                mesh: name.into(),
                problem: format!(
                    "morph target {k} has {} finite {what} for {n} positions",
                    v.len() / 3
                ),
            });
        }
        Ok(v.chunks_exact(3)
            .map(|c| Vec3::new(c[0] as f32, c[1] as f32, c[2] as f32))
            .collect())
    };
    prim.morph_targets()
        .enumerate()
        .map(|(k, t)| {
            Ok(MorphTarget {
                positions: read(t.positions(), "positions", k)?,
                normals: read(t.normals(), "normals", k)?,
                tangents: read(t.tangents(), "tangents", k)?,
            })
        })
        .collect()
}
