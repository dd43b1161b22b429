//! Views and the cut criterion (§3.5.2): `c(N, V)` = the projected size of node N's bounding
//! sphere in view V's pixels, or 0 when V cannot see any of it (outside the view, or every
//! normal of its cone faces away from every direction under which V sees the sphere).
//!
//! The size is measured by the sphere's angular diameter `2·asin(r / dist)` times the view's
//! pixels per radian, so a sphere inside another never measures more, and `c` decreases down
//! the tree (children lie inside their parent, their cones inside its cone): the property the
//! cut definition needs.

use glam::{Mat4, Vec3};

use crate::{
    ManyLodError,
    bsh::{Node, angle_between},
};

/// A view nodes are cut and splatted for.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum View {
    /// A hemispherical view (a VPL): paraboloid projection around `normal`, `size`×`size`
    /// pixels.
    Paraboloid {
        /// Centre of projection.
        position: Vec3,
        /// Hemisphere axis (unit).
        normal: Vec3,
        /// Tile side in pixels.
        size: u32,
    },
    /// A pinhole camera.
    Perspective {
        /// Eye position.
        eye: Vec3,
        /// World → clip (depth 0..1).
        view_proj: Mat4,
        /// Vertical field of view in radians.
        fov_y: f32,
        /// Tile size in pixels (width, height).
        size: (u32, u32),
    },
}

/// Criterion value of a node the view cannot resolve (the eye is inside its sphere): always
/// split.
pub const INSIDE: f32 = f32::INFINITY;

impl View {
    /// Checks the view: finite, unit normal, non-empty tile.
    pub fn check(&self, index: usize) -> Result<(), ManyLodError> {
        let bad = |problem: &str| {
            Err(ManyLodError::View {
                index,
                problem: problem.into(),
            })
        };
        match *self {
            View::Paraboloid {
                position,
                normal,
                size,
            } => {
                if !position.is_finite() || !normal.is_finite() {
                    return bad("not finite");
                }
                if (normal.length() - 1.0).abs() > 1e-3 {
                    return bad("the normal is not unit length");
                }
                if size == 0 {
                    return bad("empty tile");
                }
            }
            View::Perspective {
                eye,
                view_proj,
                fov_y,
                size,
            } => {
                if !eye.is_finite() || !view_proj.is_finite() || !fov_y.is_finite() {
                    return bad("not finite");
                }
                if !(fov_y > 0.0 && fov_y < std::f32::consts::PI) {
                    return bad("field of view outside (0, π)");
                }
                if size.0 == 0 || size.1 == 0 {
                    return bad("empty tile");
                }
            }
        }
        Ok(())
    }

    /// Centre of projection.
    pub fn eye(&self) -> Vec3 {
        match *self {
            View::Paraboloid { position, .. } => position,
            View::Perspective { eye, .. } => eye,
        }
    }

    /// Pixels per radian at the centre of the view.
    pub fn pixels_per_radian(&self) -> f32 {
        match *self {
            // The paraboloid maps the hemisphere (π/2 from the axis) to the tile's half side,
            // r = tan(γ/2): dr/dγ is largest at the rim (1 per radian, in units of half sides).
            View::Paraboloid { size, .. } => size as f32 * 0.5,
            View::Perspective { fov_y, size, .. } => size.1 as f32 * 0.5 / (fov_y * 0.5).tan(),
        }
    }

    /// `c(N, V)`: projected diameter in pixels, 0 when culled, [`INSIDE`] when the eye is in
    /// the sphere. Mirrored by the GPU kernels.
    pub fn criterion(&self, node: &Node) -> f32 {
        let to = node.center - self.eye();
        let dist = to.length();
        if dist <= node.radius {
            return INSIDE;
        }
        // Angular radius of the sphere seen from the eye.
        let beta = (node.radius / dist).asin();
        let dir = to / dist;
        let visible = match *self {
            View::Paraboloid { normal, .. } => {
                // Any part of the sphere above the plane through the view's position.
                normal.dot(node.center - self.eye()) > -node.radius
            }
            View::Perspective { view_proj, .. } => sphere_in_frustum(view_proj, node),
        };
        // Back-facing: every normal makes more than 90° with every direction towards the eye.
        let facing_angle = angle_between(-dir, node.axis);
        let back_facing = facing_angle - node.angle - beta > std::f32::consts::FRAC_PI_2;
        if !visible || back_facing {
            return 0.0;
        }
        2.0 * beta * self.pixels_per_radian()
    }
}

/// Whether the sphere meets the frustum of `view_proj` (depth 0..1), by its six planes.
fn sphere_in_frustum(m: Mat4, node: &Node) -> bool {
    let rows = [m.row(0), m.row(1), m.row(2), m.row(3)];
    let planes = [
        rows[3] + rows[0],
        rows[3] - rows[0],
        rows[3] + rows[1],
        rows[3] - rows[1],
        rows[2],
        rows[3] - rows[2],
    ];
    planes.iter().all(|p| {
        let n = p.truncate();
        let len = n.length();
        len == 0.0 || (n.dot(node.center) + p.w) / len >= -node.radius
    })
}
