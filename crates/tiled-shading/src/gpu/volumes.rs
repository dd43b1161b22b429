//! Light volumes of [`Method::LightVolumes`](crate::Method::LightVolumes) (thesis §4.1,
//! `volumes.wgsl`): the unit meshes every light is drawn as an instance of, and the order the
//! lights are drawn in.

use std::ops::Range;

use glam::Vec3;

use crate::{GpuLight, LIGHT_DIRECTIONAL};

/// `GpuLight::kind` of a spot light.
const LIGHT_SPOT: u32 = 1;

/// Spots whose outer cone is at most 60° (cosine ≥ ½) are drawn as cones, wider ones as
/// spheres (a cone that wide covers more of the screen than the sphere around it).
const CONE_MIN_COS_OUTER: f32 = 0.5;

/// Sides of the cone's base polygon.
const CONE_SIDES: u32 = 16;

/// The unit volumes' corners (`volumes.wgsl`'s `corners`) and the vertex range of each mesh.
pub struct VolumeMeshes {
    /// Triangle corners, outward faces counter-clockwise; w: 0 sphere, 1 cone, 2 screen.
    pub corners: Vec<[f32; 4]>,
    /// The sphere's vertices: a twice subdivided icosahedron (320 faces) whose faces are all
    /// at least 1 from the centre, so it holds the unit sphere.
    pub sphere: Range<u32>,
    /// The cone's: apex at the origin, axis +z, height 1, a base polygon of 16
    /// sides around the unit circle.
    pub cone: Range<u32>,
    /// The full-screen triangle's (clip space, clockwise: a back face).
    pub screen: Range<u32>,
}

impl VolumeMeshes {
    /// Builds the three meshes.
    pub fn new() -> Self {
        let mut corners = Vec::new();
        let mut push = |triangles: &[[Vec3; 3]], tag: f32| {
            let start = corners.len() as u32;
            corners.extend(triangles.iter().flatten().map(|p| p.extend(tag).to_array()));
            start..corners.len() as u32
        };
        let sphere = push(&enclosing_sphere(), 0.0);
        let cone = push(&enclosing_cone(), 1.0);
        let screen = push(
            &[[
                Vec3::new(-1.0, -1.0, 0.0),
                Vec3::new(-1.0, 3.0, 0.0),
                Vec3::new(3.0, -1.0, 0.0),
            ]],
            2.0,
        );
        Self {
            corners,
            sphere,
            cone,
            screen,
        }
    }
}

impl Default for VolumeMeshes {
    fn default() -> Self {
        Self::new()
    }
}

/// A twice subdivided icosahedron scaled so that its closest face plane is at distance 1.
fn enclosing_sphere() -> Vec<[Vec3; 3]> {
    let t = (1.0 + 5f32.sqrt()) / 2.0;
    let v = [
        (-1.0, t, 0.0),
        (1.0, t, 0.0),
        (-1.0, -t, 0.0),
        (1.0, -t, 0.0),
        (0.0, -1.0, t),
        (0.0, 1.0, t),
        (0.0, -1.0, -t),
        (0.0, 1.0, -t),
        (t, 0.0, -1.0),
        (t, 0.0, 1.0),
        (-t, 0.0, -1.0),
        (-t, 0.0, 1.0),
    ]
    .map(|(x, y, z)| Vec3::new(x, y, z).normalize());
    let faces = [
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    let mut triangles: Vec<[Vec3; 3]> = faces.iter().map(|f| f.map(|i| v[i])).collect();
    for _ in 0..2 {
        triangles = triangles
            .iter()
            .flat_map(|&[a, b, c]| {
                let [ab, bc, ca] = [a + b, b + c, c + a].map(Vec3::normalize);
                [[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]
            })
            .collect();
    }
    let inradius = triangles
        .iter()
        .map(|&[a, b, c]| (b - a).cross(c - a).normalize().dot(a))
        .fold(f32::INFINITY, f32::min);
    triangles
        .into_iter()
        .map(|t| t.map(|p| p / inradius))
        .collect()
}

/// The cone: its sides and its base, the base polygon around the unit circle at z = 1.
fn enclosing_cone() -> Vec<[Vec3; 3]> {
    let step = std::f32::consts::TAU / CONE_SIDES as f32;
    let reach = 1.0 / (step / 2.0).cos();
    let rim = |i: u32| {
        let a = i as f32 * step;
        Vec3::new(a.cos() * reach, a.sin() * reach, 1.0)
    };
    let centre = Vec3::Z;
    (0..CONE_SIDES)
        .flat_map(|i| {
            let (p, q) = (rim(i), rim(i + 1));
            [[Vec3::ZERO, q, p], [centre, p, q]]
        })
        .collect()
}

/// Whether `light` is drawn as a cone.
fn is_cone(light: &GpuLight) -> bool {
    light.kind == LIGHT_SPOT && light.cos_outer >= CONE_MIN_COS_OUTER
}

/// The light indices in draw order (spheres, cones, directional lights) and the instance
/// range of each.
pub fn draw_order(lights: &[GpuLight]) -> (Vec<u32>, [Range<u32>; 3]) {
    let class = |l: &GpuLight| match l {
        l if l.kind == LIGHT_DIRECTIONAL => 2,
        l if is_cone(l) => 1,
        _ => 0,
    };
    let mut order: Vec<u32> = (0..lights.len() as u32).collect();
    order.sort_by_key(|&i| class(&lights[i as usize]));
    let count = |c| lights.iter().filter(|l| class(l) == c).count() as u32;
    let (spheres, cones) = (count(0), count(1));
    let all = lights.len() as u32;
    (
        order,
        [0..spheres, spheres..spheres + cones, spheres + cones..all],
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every face's plane at distance ≥ 1 from the centre with its normal pointing out.
    fn encloses_unit_ball(triangles: &[[f32; 4]], apex_ok: bool) {
        for t in triangles.chunks_exact(3) {
            let [a, b, c] = [t[0], t[1], t[2]].map(|p| Vec3::new(p[0], p[1], p[2]));
            let n = (b - a).cross(c - a).normalize();
            let d = n.dot(a);
            assert!(d >= 1.0 - 1e-5 || apex_ok, "face at {d}");
        }
    }

    #[test]
    fn the_sphere_holds_the_unit_ball_with_outward_faces() {
        let meshes = VolumeMeshes::new();
        let sphere = &meshes.corners[meshes.sphere.start as usize..meshes.sphere.end as usize];
        assert_eq!(sphere.len(), 320 * 3);
        encloses_unit_ball(sphere, false);
        // Not much more than needed: every corner within 1.1 of the centre.
        assert!(
            sphere
                .iter()
                .all(|p| Vec3::new(p[0], p[1], p[2]).length() < 1.1)
        );
    }

    #[test]
    fn the_cone_holds_the_unit_cone_with_outward_faces() {
        let meshes = VolumeMeshes::new();
        let cone = &meshes.corners[meshes.cone.start as usize..meshes.cone.end as usize];
        // Points of the circular cone (apex 0, axis z, height 1, radius 1 at z = 1) lie
        // behind every face plane.
        for t in cone.chunks_exact(3) {
            let [a, b, c] = [t[0], t[1], t[2]].map(|p| Vec3::new(p[0], p[1], p[2]));
            let n = (b - a).cross(c - a);
            for k in 0..64 {
                let phi = k as f32 / 64.0 * std::f32::consts::TAU;
                for z in [0.25, 0.5, 1.0] {
                    let p = Vec3::new(phi.cos() * z, phi.sin() * z, z);
                    assert!(n.dot(p - a) <= 1e-5, "{p} outside a face");
                }
            }
            // Outward: the cone's inner point (0, 0, 0.5) is behind the face.
            assert!(n.dot(Vec3::new(0.0, 0.0, 0.5) - a) < 0.0);
        }
    }

    #[test]
    fn lights_are_drawn_spheres_then_cones_then_directional() {
        let light = |kind, cos_outer| GpuLight {
            kind,
            cos_outer,
            radius: 1.0,
            ..bytemuck::Zeroable::zeroed()
        };
        let lights = [
            light(LIGHT_DIRECTIONAL, 0.0),
            light(LIGHT_SPOT, 0.9),
            light(0, 0.0),
            light(LIGHT_SPOT, 0.1),
            light(3, 0.0),
        ];
        let (order, ranges) = draw_order(&lights);
        assert_eq!(order, vec![2, 3, 4, 1, 0]);
        assert_eq!(ranges, [0..3, 3..4, 4..5]);
    }
}
