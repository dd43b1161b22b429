//! A triangle BVH (obvhs' compressed wide BVH) with closest-hit and any-hit ray queries.

use glam::{Vec2, Vec3, Vec3A};
use obvhs::{
    BvhBuildParams,
    cwbvh::CwBvh,
    ray::{Ray, RayHit},
    triangle::Triangle,
};

use crate::Scene;

/// The closest intersection of a ray with the scene.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Distance along the ray, in units of the direction's length.
    pub t: f32,
    /// Index of the mesh in [`Scene::meshes`].
    pub mesh: u32,
    /// Triangle index within the mesh.
    pub triangle: u32,
    /// Barycentric coordinates (u, v) of the hit: weights of vertices 1 and 2.
    pub barycentrics: Vec2,
    /// World-space hit point.
    pub position: Vec3,
}

/// A BVH over all triangles of a scene.
pub struct Bvh {
    bvh: CwBvh,
    triangles: Vec<Triangle>,
    /// (mesh, triangle) of each entry of `triangles`.
    origin: Vec<(u32, u32)>,
}

/// The barycentric coordinates (weights of `v1` and `v2`) where the ray meets the plane of
/// `tri` (Möller–Trumbore). obvhs 0.4's `Triangle::compute_barycentric` divides by the
/// *normalised* normal's cosine, so its coordinates are off by the triangle's doubled area.
fn barycentrics(tri: &Triangle, origin: Vec3, direction: Vec3) -> Vec2 {
    let (v0, v1, v2) = (Vec3::from(tri.v0), Vec3::from(tri.v1), Vec3::from(tri.v2));
    let (e1, e2) = (v1 - v0, v2 - v0);
    let p = direction.cross(e2);
    let det = e1.dot(p);
    if det == 0.0 {
        return Vec2::ZERO;
    }
    let s = origin - v0;
    Vec2::new(s.dot(p), direction.dot(s.cross(e1))) / det
}

impl Bvh {
    /// Builds the BVH (PLOC with reinsertion, obvhs' "medium" preset).
    pub fn build(scene: &Scene) -> Self {
        let mut triangles = Vec::with_capacity(scene.triangle_count());
        let mut origin = Vec::with_capacity(scene.triangle_count());
        for (mi, m) in scene.meshes.iter().enumerate() {
            for (ti, t) in m.indices.chunks_exact(3).enumerate() {
                let [v0, v1, v2] = [t[0], t[1], t[2]].map(|i| Vec3A::from(m.positions[i as usize]));
                triangles.push(Triangle { v0, v1, v2 });
                origin.push((mi as u32, ti as u32));
            }
        }
        let bvh = obvhs::cwbvh::builder::build_cwbvh_from_tris(
            &triangles,
            BvhBuildParams::medium_build(),
            &mut std::time::Duration::default(),
        );
        Self {
            bvh,
            triangles,
            origin,
        }
    }

    fn ray(origin: Vec3, direction: Vec3, t_max: f32) -> Option<Ray> {
        (origin.is_finite() && direction.is_finite() && direction != Vec3::ZERO && t_max > 0.0)
            .then(|| Ray::new(origin.into(), direction.into(), 0.0, t_max))
    }

    /// The closest hit with `0 <= t <= t_max`, or `None`. Invalid rays (non-finite or zero
    /// direction) hit nothing.
    pub fn closest_hit(&self, origin: Vec3, direction: Vec3, t_max: f32) -> Option<Hit> {
        let ray = Self::ray(origin, direction, t_max)?;
        let mut hit = RayHit::none();
        if !self.bvh.ray_traverse(ray, &mut hit, |r, id| {
            self.triangles[self.bvh.primitive_indices[id] as usize].intersect(r)
        }) {
            return None;
        }
        let index = self.bvh.primitive_indices[hit.primitive_id as usize] as usize;
        let tri = &self.triangles[index];
        let (mesh, triangle) = self.origin[index];
        Some(Hit {
            t: hit.t,
            mesh,
            triangle,
            barycentrics: barycentrics(tri, origin, direction),
            position: origin + direction * hit.t,
        })
    }

    /// Whether anything is hit with `0 <= t <= t_max` (a shadow-ray query).
    pub fn any_hit(&self, origin: Vec3, direction: Vec3, t_max: f32) -> bool {
        let Some(ray) = Self::ray(origin, direction, t_max) else {
            return false;
        };
        !self.bvh.ray_traverse_miss(ray, |r, id| {
            self.triangles[self.bvh.primitive_indices[id] as usize].intersect(r)
        })
    }
}
