//! Exact visibility by rays, for the lights' shadows ([`crate::shadows::RAY_SHADOW`]) and the
//! VPLs' (`instant_radiosity::shadows::VplShadows::Rays`), beyond shadow maps, which are exact
//! only up to their resolution (docs/ground-truth.md): a BVH2 of the scene's triangles (obvhs'
//! PLOC builder), flattened for the GPU and traversed per (receiver, light) pair by
//! `rays.wgsl`. [`RayBvh::occluded`] (any hit) and [`RayBvh::nearest`] (the closest hit, for
//! the VPLs' near field, `instant_radiosity::near_field`) are the CPU twins of its traversals,
//! node for node; `scene::Bvh` is the independent reference.

use glam::Vec3;
use obvhs::{BvhBuildParams, triangle::Triangle};

use scene::Scene;

use crate::ShadingError;

/// The traversal stack of `rays.wgsl`: trees deeper than this are refused.
pub const STACK: usize = 64;

/// A node of the flattened BVH (`RayNode` of `rays.wgsl`): an inner node's children are nodes
/// `first` and `first + 1`; a leaf (`count > 0`) holds triangles `first .. first + count`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct RayNode {
    /// Box minimum.
    pub min: [f32; 3],
    /// Triangles of a leaf; 0 for an inner node.
    pub count: u32,
    /// Box maximum.
    pub max: [f32; 3],
    /// First child or first triangle.
    pub first: u32,
}

/// A triangle as the traversal tests it (`RayTriangle` of `rays.wgsl`): a vertex, its index in
/// the mesh the BVH was built from, and the two edges from the vertex (w unused).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct RayTriangle {
    /// Vertex 0.
    pub v0: [f32; 3],
    /// The triangle's index in the mesh (`indices[3·index ..]`).
    pub index: u32,
    /// v1 − v0.
    pub e1: [f32; 4],
    /// v2 − v0.
    pub e2: [f32; 4],
}

/// The scene's triangles in a flattened BVH2, leaves in triangle order.
#[derive(Clone, Debug)]
pub struct RayBvh {
    /// Nodes, the root first.
    pub nodes: Vec<RayNode>,
    /// Triangles in leaf order.
    pub triangles: Vec<RayTriangle>,
}

impl RayBvh {
    /// The BVH of the triangle `mesh` ([`scene_mesh`]); a mesh without
    /// triangles, or a tree deeper than [`STACK`], is an error.
    pub fn new((positions, indices): (&[Vec3], &[u32])) -> Result<Self, ShadingError> {
        let triangles: Vec<Triangle> = indices
            .chunks_exact(3)
            .map(|t| {
                let [v0, v1, v2] = [t[0], t[1], t[2]].map(|i| positions[i as usize].into());
                Triangle { v0, v1, v2 }
            })
            .collect();
        if triangles.is_empty() {
            return Err(ShadingError::Rays("the scene has no triangles".into()));
        }
        let bvh = obvhs::bvh2::builder::build_bvh2_from_tris(
            &triangles,
            BvhBuildParams::medium_build(),
            &mut std::time::Duration::default(),
        );
        let nodes: Vec<RayNode> = bvh
            .nodes
            .iter()
            .map(|n| RayNode {
                min: n.aabb.min.into(),
                count: n.prim_count,
                max: n.aabb.max.into(),
                first: n.first_index,
            })
            .collect();
        let four = |v: Vec3| [v.x, v.y, v.z, 0.0];
        let triangles = bvh
            .primitive_indices
            .iter()
            .map(|&i| {
                let t = &triangles[i as usize];
                let (v0, v1, v2) = (Vec3::from(t.v0), Vec3::from(t.v1), Vec3::from(t.v2));
                RayTriangle {
                    v0: v0.into(),
                    index: i,
                    e1: four(v1 - v0),
                    e2: four(v2 - v0),
                }
            })
            .collect();
        let depth = depth(&nodes);
        if depth + 1 >= STACK {
            return Err(ShadingError::Rays(format!(
                "the scene's BVH is {depth} levels deep; the traversal's stack holds {STACK}"
            )));
        }
        Ok(Self { nodes, triangles })
    }

    /// Whether a triangle meets the open segment from `origin` to `origin + to` (`occluded`
    /// of `rays.wgsl`).
    pub fn occluded(&self, origin: Vec3, to: Vec3) -> bool {
        self.traverse(origin, to, true).is_some()
    }

    /// The first triangle the segment from `origin` to `origin + to` meets: its parameter
    /// `t` in (0, 1) and its slot in [`RayBvh::triangles`] (`nearest` of `rays.wgsl`).
    pub fn nearest(&self, origin: Vec3, to: Vec3) -> Option<(f32, usize)> {
        self.traverse(origin, to, false)
    }

    /// The first triangle on the segment, or with `any` the first one found
    /// (`ray_traverse`).
    fn traverse(&self, origin: Vec3, to: Vec3, any: bool) -> Option<(f32, usize)> {
        let inv = to.map(|c| 1.0 / if c == 0.0 { 1e-30 } else { c });
        let mut stack = [0u32; STACK];
        let mut top = 1;
        let (mut best, mut hit) = (1.0, None);
        while top > 0 {
            top -= 1;
            let node = self.nodes[stack[top] as usize];
            if !slab(&node, origin, inv, best) {
                continue;
            }
            if node.count == 0 {
                stack[top] = node.first;
                stack[top + 1] = node.first + 1;
                top += 2;
                continue;
            }
            for slot in node.first as usize..(node.first + node.count) as usize {
                let t = hit_t(&self.triangles[slot], origin, to);
                if t < best {
                    (best, hit) = (t, Some((t, slot)));
                    if any {
                        return hit;
                    }
                }
            }
        }
        hit
    }
}

/// Levels of the tree below its root.
fn depth(nodes: &[RayNode]) -> usize {
    let mut deepest = 0;
    let mut stack = vec![(0u32, 0usize)];
    while let Some((i, d)) = stack.pop() {
        deepest = deepest.max(d);
        let n = nodes[i as usize];
        if n.count == 0 {
            stack.extend([(n.first, d + 1), (n.first + 1, d + 1)]);
        }
    }
    deepest
}

/// Whether the segment's parameter range [0, `end`] meets the node's box.
fn slab(node: &RayNode, origin: Vec3, inv: Vec3, end: f32) -> bool {
    let t0 = (Vec3::from(node.min) - origin) * inv;
    let t1 = (Vec3::from(node.max) - origin) * inv;
    let near = t0.min(t1).max_element().max(0.0);
    let far = t0.max(t1).min_element().min(end);
    near <= far
}

/// Möller–Trumbore: the segment's parameter t where it meets the triangle, if 0 < t < 1;
/// else 2 (`ray_t` of `rays.wgsl`).
fn hit_t(t: &RayTriangle, origin: Vec3, to: Vec3) -> f32 {
    let (v0, e1, e2) = (
        Vec3::from(t.v0),
        Vec3::from_slice(&t.e1),
        Vec3::from_slice(&t.e2),
    );
    let p = to.cross(e2);
    let det = e1.dot(p);
    if det.abs() < 1e-30 {
        return MISS;
    }
    let inv_det = 1.0 / det;
    let s = origin - v0;
    let u = s.dot(p) * inv_det;
    let q = s.cross(e1);
    let v = to.dot(q) * inv_det;
    let t = e2.dot(q) * inv_det;
    if u >= 0.0 && v >= 0.0 && u + v <= 1.0 && t > 0.0 && t < 1.0 {
        t
    } else {
        MISS
    }
}

/// [`hit_t`] of a segment that misses.
const MISS: f32 = 2.0;

/// All meshes of `scene` as one triangle list (world-space positions, indices).
pub fn scene_mesh(scene: &Scene) -> (Vec<Vec3>, Vec<u32>) {
    let mut positions = Vec::new();
    let mut indices = Vec::new();
    for m in &scene.meshes {
        let base = positions.len() as u32;
        positions.extend_from_slice(&m.positions);
        indices.extend(m.indices.iter().map(|i| base + i));
    }
    (positions, indices)
}

/// Uniform `RayParams` of `shadows.wgsl`: how the lights' shadow rays leave their receiver
/// and how far a directional light's reaches.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct RayParams {
    /// 1 to move the ray's origin off the receiver along its normal by [`ray_lift`] (the
    /// path tracer's rule), 0 not at all.
    pub offset: f32,
    /// Length of a directional light's ray (towards the light).
    pub reach: f32,
    /// Unused.
    pub _pad: [f32; 2],
}

/// Exact shadows of the direct lights (a light whose `shadow_count` is
/// [`crate::shadows::RAY_SHADOW`]): a ray from the receiver to the light, or towards a
/// directional light for twice the scene's diagonal, through the scene's BVH — the hard
/// shadows of the path tracer (`scene::reference`), with no map, bias or filter.
#[derive(Clone, Debug)]
pub struct RayShadows {
    /// The scene's triangles.
    pub bvh: RayBvh,
    /// Offset and reach.
    pub params: RayParams,
}

/// How far a ray leaves a surface (`ray_lift` in `rays.wgsl`): the path tracer's rule. A lift
/// in proportion to the scene's size instead (10⁻⁴ of Sponza's diagonal, 4 mm) carried the
/// sun's rays past ledges that stand a few millimetres off Sponza's walls: lit pixels the
/// path tracer has in shadow.
pub use scene::reference::ray_lift;

impl RayShadows {
    /// The BVH of `scene` ([`RayBvh::new`]), rays lifted by [`ray_lift`].
    pub fn new(scene: &Scene) -> Result<Self, ShadingError> {
        let (positions, indices) = scene_mesh(scene);
        let diagonal = scene.bounds().diagonal().max(1e-6);
        Ok(Self {
            bvh: RayBvh::new((&positions, &indices))?,
            params: RayParams {
                offset: 1.0,
                reach: 2.0 * diagonal,
                _pad: [0.0; 2],
            },
        })
    }

    /// Whether `p` (unit normal `n`) sees `light`: 1 or 0 (`ray_shadow` in `shadows.wgsl`).
    pub fn visibility(&self, light: &crate::GpuLight, p: Vec3, n: Vec3) -> f32 {
        let origin = p + n * (self.params.offset * ray_lift(p));
        let to = if light.kind == crate::LIGHT_DIRECTIONAL {
            -Vec3::from(light.direction) * self.params.reach
        } else {
            Vec3::from(light.position) - origin
        };
        f32::from(u8::from(!self.bvh.occluded(origin, to)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `RayNode`, `RayTriangle` (`rays.wgsl`) and `RayParams` (`shadows.wgsl`) as WGSL lays
    /// them out: vec3 + u32 pairs of 16 bytes, vec4s, four f32.
    #[test]
    fn ray_structs_match_wgsl_layout() {
        assert_eq!(size_of::<RayNode>(), 32);
        assert_eq!(std::mem::offset_of!(RayNode, count), 12);
        assert_eq!(std::mem::offset_of!(RayNode, max), 16);
        assert_eq!(std::mem::offset_of!(RayNode, first), 28);
        assert_eq!(size_of::<RayTriangle>(), 48);
        assert_eq!(std::mem::offset_of!(RayTriangle, index), 12);
        assert_eq!(std::mem::offset_of!(RayTriangle, e2), 32);
        assert_eq!(size_of::<RayParams>(), 16);
        assert_eq!(std::mem::offset_of!(RayParams, reach), 4);
    }
}
