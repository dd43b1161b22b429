//! Views and the cut criterion (§3.5.2): `c(N, V)` = the projected size of node N's bounding
//! sphere in view V's pixels, or 0 when V cannot see any of it (outside the view, or every
//! normal of its cone faces away from every direction under which V sees the sphere).
//!
//! The size is measured by the sphere's angular diameter `2·asin(r / dist)` times the view's
//! pixels per radian, so a sphere inside another never measures more, and `c` decreases down
//! the tree (children lie inside their parent, their cones inside its cone): the property the
//! cut definition needs.

use glam::{Mat4, Vec2, Vec3, Vec4};

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

    /// Pixels per radian the criterion scales angular sizes by: a perspective view's at its
    /// centre, its smallest; a paraboloid's at its rim, its largest (see [`View::criterion`]).
    pub fn pixels_per_radian(&self) -> f32 {
        match *self {
            // The paraboloid maps the hemisphere (π/2 from the axis) to the tile's half side,
            // r = tan(γ/2): dr/dγ = 1 / (1 + cos γ) half sides per radian, 1 at the rim.
            View::Paraboloid { size, .. } => size as f32 * 0.5,
            View::Perspective { fov_y, size, .. } => size.1 as f32 * 0.5 / (fov_y * 0.5).tan(),
        }
    }

    /// `c(N, V)`: projected diameter in pixels, 0 when culled, [`INSIDE`] when the eye is in
    /// the sphere. Mirrored by the GPU kernels.
    ///
    /// Neither projection has one scale: the paraboloid is conformal with scale
    /// `1 / (1 + cos γ)` at angle γ from its axis, growing towards the rim; a pinhole image
    /// stretches radially by `1 / cos² γ` (1.6× in the corners of a 1080p frame at 60°
    /// vertical field of view). The sphere is measured at the largest scale it reaches, at
    /// γ + β (β its angular radius) capped at [`View::rim`]. A child's sphere lies inside its
    /// parent's, so it reaches no further from the axis and `c` still decreases down the tree.
    pub fn criterion(&self, node: &Node) -> f32 {
        let to = node.center - self.eye();
        let dist = to.length();
        if dist <= node.radius {
            return INSIDE;
        }
        // Angular radius of the sphere seen from the eye.
        let beta = (node.radius / dist).asin();
        let dir = to / dist;
        let visible = self
            .planes()
            .iter()
            .all(|p| p.truncate().dot(node.center) + p.w >= -node.radius);
        // Back-facing: every normal makes more than 90° with every direction towards the eye.
        let facing_angle = angle_between(-dir, node.axis);
        let back_facing = facing_angle - node.angle - beta > std::f32::consts::FRAC_PI_2;
        if !visible || back_facing {
            return 0.0;
        }
        2.0 * beta * self.pixels_per_radian() * self.scale(dir, beta)
    }

    /// The projection's scale (relative to [`View::pixels_per_radian`]) where a sphere seen in
    /// direction `dir` under angular radius `beta` reaches furthest from the axis.
    fn scale(&self, dir: Vec3, beta: f32) -> f32 {
        let reach = (angle_between(dir, self.axis()) + beta).min(self.rim());
        match *self {
            View::Paraboloid { .. } => 1.0 / (1.0 + reach.cos()),
            View::Perspective { .. } => 1.0 / (reach.cos() * reach.cos()),
        }
    }

    /// The view's axis: the paraboloid's normal, the pinhole's forward direction (its near
    /// plane's normal).
    pub fn axis(&self) -> Vec3 {
        match *self {
            View::Paraboloid { normal, .. } => normal,
            View::Perspective { .. } => self.planes()[4].truncate(),
        }
    }

    /// The largest angle from [`View::axis`] the view sees: π/2 for the paraboloid, the
    /// frustum's corner for a pinhole (whose `view_proj` has the aspect of its size).
    pub fn rim(&self) -> f32 {
        match *self {
            View::Paraboloid { .. } => std::f32::consts::FRAC_PI_2,
            View::Perspective { fov_y, size, .. } => {
                let aspect = size.0 as f32 / size.1 as f32;
                ((fov_y * 0.5).tan() * (1.0 + aspect * aspect).sqrt()).atan()
            }
        }
    }
}

impl View {
    /// The unit planes a visible sphere must not lie entirely behind: the paraboloid's base
    /// plane, or the frustum's six (depth 0..1); unused planes are zero.
    pub fn planes(&self) -> [Vec4; 6] {
        match *self {
            View::Paraboloid {
                position, normal, ..
            } => {
                let mut p = [Vec4::ZERO; 6];
                p[0] = normal.extend(-normal.dot(position));
                p
            }
            View::Perspective { view_proj: m, .. } => {
                let r = [m.row(0), m.row(1), m.row(2), m.row(3)];
                [
                    r[3] + r[0],
                    r[3] - r[0],
                    r[3] + r[1],
                    r[3] - r[1],
                    r[2],
                    r[3] - r[2],
                ]
                .map(|p| {
                    let len = p.truncate().length();
                    if len > 0.0 { p / len } else { Vec4::ZERO }
                })
            }
        }
    }

    /// World → view: the perspective `view_proj`, or for a paraboloid the rigid transform to
    /// its frame (tangent, bitangent, normal; origin at the position).
    pub fn transform(&self) -> Mat4 {
        match *self {
            View::Paraboloid {
                position, normal, ..
            } => {
                let (t, b) = paraboloid_frame(normal);
                Mat4::from_cols(
                    Vec4::new(t.x, b.x, normal.x, 0.0),
                    Vec4::new(t.y, b.y, normal.y, 0.0),
                    Vec4::new(t.z, b.z, normal.z, 0.0),
                    Vec4::new(
                        -t.dot(position),
                        -b.dot(position),
                        -normal.dot(position),
                        1.0,
                    ),
                )
            }
            View::Perspective { view_proj, .. } => view_proj,
        }
    }

    /// Tile size in pixels.
    pub fn size(&self) -> (u32, u32) {
        match *self {
            View::Paraboloid { size, .. } => (size, size),
            View::Perspective { size, .. } => size,
        }
    }

    /// The view as the GPU kernels read it.
    pub fn gpu(&self) -> GpuView {
        let (w, h) = self.size();
        GpuView {
            planes: self.planes().map(|p| p.to_array()),
            transform: self.transform().to_cols_array_2d(),
            eye: self.eye().to_array(),
            kind: match self {
                View::Paraboloid { .. } => PARABOLOID,
                View::Perspective { .. } => PERSPECTIVE,
            },
            size: [w as f32, h as f32],
            pixels_per_radian: self.pixels_per_radian(),
            rim: self.rim(),
        }
    }

    /// Where a node's disc lands in the view's tile: centre in pixels, radius in pixels (at
    /// least [`MIN_SPLAT_RADIUS`], at most [`MAX_SPLAT_RADIUS`]) and depth in `[0, 1]`
    /// (paraboloid: distance / `far`; perspective: NDC depth). A perspective disc's radius is
    /// half the criterion's size, at the scale the sphere reaches ([`View::criterion`]), so
    /// it covers the sphere's stretched image off the axis. `None` when the centre is not in
    /// front of the view or the eye is inside the sphere. Mirrored by `splat.wgsl`.
    pub fn splat(&self, node: &Node, far: f32) -> Option<Splat> {
        let (w, h) = self.size();
        let (center, radius, depth) = match *self {
            View::Paraboloid { .. } => {
                let local = self.transform().transform_point3(node.center);
                let dist = local.length();
                if dist <= node.radius || local.z <= 0.0 {
                    return None;
                }
                let d = local / dist;
                let uv = Vec2::new(d.x, d.y) / (1.0 + d.z);
                let beta = (node.radius / dist).asin();
                (
                    (uv * 0.5 + 0.5) * w as f32,
                    beta * (w as f32 * 0.5) / (1.0 + d.z),
                    dist / far,
                )
            }
            View::Perspective { view_proj, .. } => {
                let clip = view_proj * node.center.extend(1.0);
                let dist = node.center.distance(self.eye());
                if clip.w <= 0.0 || dist <= node.radius {
                    return None;
                }
                let ndc = clip.truncate() / clip.w;
                let beta = (node.radius / dist).asin();
                let dir = (node.center - self.eye()) / dist;
                (
                    Vec2::new(
                        (ndc.x * 0.5 + 0.5) * w as f32,
                        (0.5 - ndc.y * 0.5) * h as f32,
                    ),
                    beta * self.pixels_per_radian() * self.scale(dir, beta),
                    ndc.z,
                )
            }
        };
        Some(Splat {
            center,
            radius: radius.clamp(MIN_SPLAT_RADIUS, MAX_SPLAT_RADIUS),
            depth: depth.clamp(0.0, 1.0),
        })
    }
}

/// The tangent and bitangent of a paraboloid view with unit `normal` (a fixed choice the GPU
/// shares through [`View::transform`]).
pub fn paraboloid_frame(normal: Vec3) -> (Vec3, Vec3) {
    let helper = if normal.z.abs() < 0.9 {
        Vec3::Z
    } else {
        Vec3::X
    };
    let t = helper.cross(normal).normalize();
    (t, normal.cross(t))
}

/// A disc in a view's tile (pixels) with its depth.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Splat {
    /// Centre in tile pixels (x right, y down).
    pub center: Vec2,
    /// Radius in pixels.
    pub radius: f32,
    /// Depth in `[0, 1]`.
    pub depth: f32,
}

/// Smallest splat radius: a disc of √½ px covers at least the pixel centre nearest to it.
pub const MIN_SPLAT_RADIUS: f32 = std::f32::consts::FRAC_1_SQRT_2;
/// Largest splat radius in pixels (nodes near a view are leaves bigger than ε).
pub const MAX_SPLAT_RADIUS: f32 = 16.0;

/// [`View::gpu`]'s kind tag of a paraboloid view.
pub const PARABOLOID: u32 = 0;
/// [`View::gpu`]'s kind tag of a perspective view.
pub const PERSPECTIVE: u32 = 1;

/// A view in the layout of `common.wgsl` (`View`, 192 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuView {
    /// [`View::planes`].
    pub planes: [[f32; 4]; 6],
    /// [`View::transform`] (columns).
    pub transform: [[f32; 4]; 4],
    /// Centre of projection.
    pub eye: [f32; 3],
    /// [`PARABOLOID`] or [`PERSPECTIVE`].
    pub kind: u32,
    /// Tile size in pixels.
    pub size: [f32; 2],
    /// [`View::pixels_per_radian`].
    pub pixels_per_radian: f32,
    /// [`View::rim`].
    pub rim: f32,
}
