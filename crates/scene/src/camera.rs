//! Perspective camera.

use glam::{Mat4, Vec3};

use crate::Aabb;

/// A perspective pinhole camera (right-handed, looking from `eye` towards `target`).
///
/// Projection follows wgpu: clip-space depth in \[0, 1\] with `near` at 0 and `far` at 1.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Eye position.
    pub eye: Vec3,
    /// Point looked at.
    pub target: Vec3,
    /// Up direction (need not be orthogonal to the view direction).
    pub up: Vec3,
    /// Vertical field of view in radians.
    pub fov_y: f32,
    /// Near plane distance (> 0).
    pub near: f32,
    /// Far plane distance (> near).
    pub far: f32,
}

impl Camera {
    /// A camera at `eye` looking at `target`, +Y up, 45° vertical field of view, planes 0.1 and 100.
    pub fn look_at(eye: Vec3, target: Vec3) -> Self {
        Self {
            eye,
            target,
            up: Vec3::Y,
            fov_y: 45f32.to_radians(),
            near: 0.1,
            far: 100.0,
        }
    }

    /// World → view transform.
    pub fn view(&self) -> Mat4 {
        let forward = (self.target - self.eye).normalize_or(Vec3::NEG_Z);
        let up = if forward.cross(self.up).length_squared() < 1e-12 {
            Vec3::Z
        } else {
            self.up
        };
        glam::camera::rh::view::look_at_mat4(self.eye, self.eye + forward, up)
    }

    /// View → clip transform for an image of the given aspect ratio (width / height).
    pub fn projection(&self, aspect: f32) -> Mat4 {
        glam::camera::rh::proj::directx::perspective(self.fov_y, aspect, self.near, self.far)
    }

    /// World → clip transform.
    pub fn view_projection(&self, aspect: f32) -> Mat4 {
        self.projection(aspect) * self.view()
    }

    /// A camera in front of (+Z side of) and slightly above `bounds`, seeing all of it.
    pub fn framing(bounds: Aabb) -> Self {
        let center = bounds.center();
        let radius = (bounds.diagonal() * 0.5).max(1e-3);
        let fov_y = 45f32.to_radians();
        let distance = radius / (fov_y * 0.5).sin();
        let dir = Vec3::new(0.35, 0.3, 1.0).normalize();
        let mut camera = Self::look_at(center + dir * distance, center);
        camera.fov_y = fov_y;
        camera.fit_planes(bounds);
        camera
    }

    /// Sets `near` and `far` so the whole of `bounds` lies between them (with a margin).
    pub fn fit_planes(&mut self, bounds: Aabb) {
        let radius = (bounds.diagonal() * 0.5).max(1e-3);
        let distance = (bounds.center() - self.eye).length();
        self.far = (distance + radius) * 1.01;
        self.near = (distance - radius).max(self.far * 1e-4);
    }
}
