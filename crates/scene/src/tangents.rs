//! Tangents for normal maps where the file has none: MikkTSpace (Mikkelsen 2008, the
//! `mikktspace` crate), as glTF 2.0 §3.7.2.1 asks — from the positions, normals and the
//! texture coordinates the normal map reads. MikkTSpace gives each triangle corner its own
//! tangent; a vertex whose corners disagree is split, one copy per distinct tangent. Tangents
//! are made perpendicular to the vertex normal; corners without one (UVs of no area) get a
//! unit tangent in the surface.

use std::collections::HashMap;

use glam::{Vec2, Vec4};

use crate::Mesh;

/// The mesh as MikkTSpace reads it, with one tangent per triangle corner written back.
struct Corners<'m> {
    mesh: &'m Mesh,
    uvs: &'m [Vec2],
    tangents: Vec<Vec4>,
}

impl mikktspace::Geometry for Corners<'_> {
    fn num_faces(&self) -> usize {
        self.mesh.indices.len() / 3
    }

    fn num_vertices_of_face(&self, _face: usize) -> usize {
        3
    }

    fn position(&self, face: usize, vert: usize) -> [f32; 3] {
        self.mesh.positions[self.mesh.indices[face * 3 + vert] as usize].into()
    }

    fn normal(&self, face: usize, vert: usize) -> [f32; 3] {
        self.mesh.normals[self.mesh.indices[face * 3 + vert] as usize].into()
    }

    fn tex_coord(&self, face: usize, vert: usize) -> [f32; 2] {
        self.uvs[self.mesh.indices[face * 3 + vert] as usize].into()
    }

    fn set_tangent_encoded(&mut self, tangent: [f32; 4], face: usize, vert: usize) {
        self.tangents[face * 3 + vert] = Vec4::from(tangent);
    }
}

impl Mesh {
    /// Fills [`Mesh::tangents`] by MikkTSpace from texture-coordinate set `uv_set` (0 or 1),
    /// splitting vertices whose corners get different tangents. A mesh without those
    /// coordinates, or one MikkTSpace cannot handle (no triangles), keeps no tangents.
    pub fn generate_tangents(&mut self, uv_set: u32) {
        let uvs = if uv_set == 1 { &self.uvs1 } else { &self.uvs };
        if uvs.len() != self.positions.len() || self.indices.is_empty() {
            return;
        }
        let mut corners = Corners {
            mesh: self,
            uvs,
            tangents: vec![Vec4::ZERO; self.indices.len()],
        };
        if !mikktspace::generate_tangents(&mut corners) {
            return;
        }
        // A corner whose UVs have no area gets no tangent: any unit one in the surface
        // stands in (its normal map then tilts along an arbitrary direction, as in any
        // renderer; the file's UVs say nothing better).
        let tangents: Vec<Vec4> = corners
            .tangents
            .iter()
            .zip(&self.indices)
            .map(|(t, &v)| {
                // Perpendicular to the vertex normal (MikkTSpace's tangent of a corner with a
                // degenerate UV direction is not).
                let n = self.normals[v as usize];
                let xyz = t.truncate();
                match (xyz - n * n.dot(xyz)).try_normalize() {
                    Some(u) if xyz.length_squared() > 0.25 => u.extend(t.w),
                    _ => crate::orthonormal_basis(n).0.extend(1.0),
                }
            })
            .collect();
        // One vertex per (original vertex, tangent bits).
        let mut welded: HashMap<(u32, [u32; 4]), u32> = HashMap::new();
        let mut from = Vec::new();
        let mut vertex_tangents = Vec::new();
        let indices: Vec<u32> = self
            .indices
            .iter()
            .zip(&tangents)
            .map(|(&v, t)| {
                let key = (v, t.to_array().map(f32::to_bits));
                *welded.entry(key).or_insert_with(|| {
                    from.push(v as usize);
                    vertex_tangents.push(*t);
                    (from.len() - 1) as u32
                })
            })
            .collect();
        let pick = |values: &[Vec2]| -> Vec<Vec2> {
            if values.is_empty() {
                Vec::new()
            } else {
                from.iter().map(|&i| values[i]).collect()
            }
        };
        self.uvs1 = pick(&self.uvs1);
        self.uvs = pick(&self.uvs);
        self.positions = from.iter().map(|&i| self.positions[i]).collect();
        self.normals = from.iter().map(|&i| self.normals[i]).collect();
        if !self.colors.is_empty() {
            self.colors = from.iter().map(|&i| self.colors[i]).collect();
        }
        self.tangents = vertex_tangents;
        self.indices = indices;
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;

    /// A quad in the xy plane facing +z with glTF's texture coordinates (u right, v down):
    /// the tangent is +x (increasing u) and w = −1 (the bitangent, increasing v, is −y =
    /// −(n × t)); no vertex splits.
    #[test]
    fn a_flat_quad_gets_the_u_direction_and_the_v_handedness() {
        let mut quad = Mesh::quad(
            "q",
            [
                Vec3::new(0.0, 0.0, 0.0),
                Vec3::new(1.0, 0.0, 0.0),
                Vec3::new(1.0, 1.0, 0.0),
                Vec3::new(0.0, 1.0, 0.0),
            ],
            0,
        );
        quad.uvs = quad
            .positions
            .iter()
            .map(|p| Vec2::new(p.x, 1.0 - p.y))
            .collect();
        quad.generate_tangents(0);
        assert_eq!(quad.positions.len(), 4);
        for t in &quad.tangents {
            assert!(
                (t.truncate() - Vec3::X).length() < 1e-5 && t.w == -1.0,
                "{t}"
            );
        }
    }

    /// A UV seam mirrored across a shared edge: the two triangles' tangents point opposite
    /// ways, so the edge's two vertices are split and every corner keeps its own.
    #[test]
    fn mirrored_uvs_split_the_shared_vertices() {
        let mut m = Mesh {
            positions: vec![
                Vec3::new(0.0, 0.0, 0.0),
                Vec3::new(1.0, 0.0, 0.0),
                Vec3::new(0.0, 1.0, 0.0),
                Vec3::new(-1.0, 0.0, 0.0),
            ],
            normals: vec![Vec3::Z; 4],
            // Right triangle: u grows with +x; left one mirrored: u grows with −x.
            uvs: vec![
                Vec2::new(0.0, 1.0),
                Vec2::new(1.0, 1.0),
                Vec2::new(0.0, 0.0),
                Vec2::new(1.0, 1.0),
            ],
            indices: vec![0, 1, 2, 0, 2, 3],
            ..Default::default()
        };
        m.generate_tangents(0);
        assert_eq!(m.positions.len(), 6, "vertices 0 and 2 split");
        let t = |corner: usize| m.tangents[m.indices[corner] as usize].truncate();
        assert!((t(0) - Vec3::X).length() < 1e-4, "{}", t(0));
        assert!((t(3) + Vec3::X).length() < 1e-4, "{}", t(3));
    }
}
