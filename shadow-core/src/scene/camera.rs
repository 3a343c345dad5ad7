//! The perspective camera with an infinite far plane (DESIGN 4).

use glam::{Mat4, Vec3};

use super::SceneError;

/// A perspective camera with an infinite far plane (DESIGN 4).
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
    /// Near plane distance.
    pub near: f32,
}

impl Camera {
    /// A camera at `eye` looking at `target` with a vertical field of view in degrees.
    #[must_use]
    pub fn look_at(eye: Vec3, target: Vec3, fov_y_deg: f32) -> Self {
        Self { eye, target, up: Vec3::Y, fov_y: fov_y_deg.to_radians(), near: 0.05 }
    }

    /// The camera moved by the affine transform `m`: its eye, target and up are, its field of view and
    /// near plane are not.
    #[must_use]
    pub fn transformed(&self, m: Mat4) -> Self {
        let up = m.transform_vector3(self.up).normalize_or(self.up);
        Self { eye: m.transform_point3(self.eye), target: m.transform_point3(self.target), up, ..*self }
    }

    /// World to view (right-handed, looking down -Z).
    #[must_use]
    pub fn view_from_world(&self) -> Mat4 {
        let dir = (self.target - self.eye).normalize_or(Vec3::NEG_Z);
        let up = if dir.cross(self.up).length_squared() < 1e-8 { Vec3::Z } else { self.up };
        glam::camera::rh::view::look_to_mat4(self.eye, dir, up)
    }

    /// View to clip: an infinite right-handed perspective (NDC y up), depth 0 at the near plane and 1 at infinity.
    #[must_use]
    pub fn clip_from_view(&self, aspect: f32) -> Mat4 {
        glam::camera::rh::proj::directx::perspective_infinite(self.fov_y, aspect, self.near)
    }

    /// World to clip for a view of the given aspect ratio (width / height).
    #[must_use]
    pub fn clip_from_world(&self, aspect: f32) -> Mat4 {
        self.clip_from_view(aspect) * self.view_from_world()
    }

    /// Checks the camera can be used.
    ///
    /// # Errors
    /// [`SceneError::Invalid`] naming the bad parameter.
    pub fn validate(&self) -> Result<(), SceneError> {
        if !(self.eye.is_finite() && self.target.is_finite() && self.up.is_finite()) {
            return Err(SceneError::Invalid("camera eye, target or up is not finite".into()));
        }
        if (self.target - self.eye).length_squared() < 1e-12 {
            return Err(SceneError::Invalid("camera eye and target coincide".into()));
        }
        if !(self.fov_y > 0.0 && self.fov_y < std::f32::consts::PI) {
            return Err(SceneError::Invalid("camera field of view must be between 0 and 180 degrees".into()));
        }
        if !(self.near > 0.0 && self.near.is_finite()) {
            return Err(SceneError::Invalid("camera near plane must be positive".into()));
        }
        Ok(())
    }
}
