//! The viewer's two rigs: a camera orbiting a point (turned by dragging, zoomed by the wheel, flown with
//! the keys) and the first light on a sphere around the scene's centre (dragged, moved with the keys, or
//! turning on its own).

use shadow_core::glam::Vec3;
use shadow_core::scene::{Camera, Light, LightKind};

/// How far from the poles either rig may turn: at a pole the view's up and its direction coincide.
const PITCH_LIMIT: f32 = 89f32 * std::f32::consts::PI / 180.0;

/// A direction from its angles: yaw about +y from +z, pitch up from the ground plane.
fn direction(yaw: f32, pitch: f32) -> Vec3 {
    Vec3::new(pitch.cos() * yaw.sin(), pitch.sin(), pitch.cos() * yaw.cos())
}

/// The angles of a unit direction (inverse of [`direction`]).
fn angles(d: Vec3) -> (f32, f32) {
    (d.x.atan2(d.z), d.y.clamp(-1.0, 1.0).asin())
}

/// A camera at `distance` from `target`, in the direction of its yaw and pitch.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Orbit {
    /// The point looked at.
    pub target: Vec3,
    /// The eye's distance from it.
    pub distance: f32,
    /// The eye's direction from the target: yaw about +y (radians).
    pub yaw: f32,
    /// Its pitch above the ground plane (radians).
    pub pitch: f32,
    fov_y: f32,
    near: f32,
}

impl Orbit {
    /// The orbit that gives `camera` (its up taken as +y).
    #[must_use]
    pub fn around(camera: &Camera) -> Self {
        let offset = camera.eye - camera.target;
        let distance = offset.length().max(1e-4);
        let (yaw, pitch) = angles(offset / distance);
        Self { target: camera.target, distance, yaw, pitch, fov_y: camera.fov_y, near: camera.near }
    }

    /// The camera.
    #[must_use]
    pub fn camera(&self) -> Camera {
        let eye = self.target + self.distance * direction(self.yaw, self.pitch);
        Camera { eye, target: self.target, up: Vec3::Y, fov_y: self.fov_y, near: self.near }
    }

    /// Turns the eye around the target by these angles (radians), short of the poles.
    pub fn turn(&mut self, yaw: f32, pitch: f32) {
        self.yaw += yaw;
        self.pitch = (self.pitch + pitch).clamp(-PITCH_LIMIT, PITCH_LIMIT);
    }

    /// Scales the distance by `factor`, staying beyond the near plane.
    pub fn zoom(&mut self, factor: f32) {
        self.distance = (self.distance * factor).max(4.0 * self.near);
    }

    /// Moves eye and target together: `forward` along the view, `right` across it, `up` along +y.
    pub fn fly(&mut self, forward: f32, right: f32, up: f32) {
        let ahead = -direction(self.yaw, self.pitch);
        let across = ahead.cross(Vec3::Y).normalize_or(Vec3::X);
        self.target += forward * ahead + right * across + up * Vec3::Y;
    }
}

/// The first light of a scene on a sphere around a centre: a spot or point light at `distance` in the
/// direction of its yaw and pitch, a spot aimed at the centre; a directional light shining from there.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightRig {
    /// The centre the light turns around and aims at.
    pub center: Vec3,
    /// A positioned light's distance from it.
    pub distance: f32,
    /// The light's direction from the centre: yaw about +y (radians).
    pub yaw: f32,
    /// Its pitch above the ground plane (radians).
    pub pitch: f32,
    /// The light as the scene gave it (colour, cone, radius).
    pub base: Light,
}

impl LightRig {
    /// The rig that gives `light` around `center` (a spot aimed elsewhere is aimed at the centre).
    #[must_use]
    pub fn around(light: &Light, center: Vec3, scene_radius: f32) -> Self {
        let (offset, distance) = match light.kind {
            LightKind::Spot { position, .. } | LightKind::Point { position } => {
                let offset = position - center;
                (offset, offset.length())
            }
            LightKind::Directional { direction } => (-direction, 2.0 * scene_radius),
        };
        let (yaw, pitch) = angles(offset.normalize_or(Vec3::Y));
        Self { center, distance: distance.max(1e-3), yaw, pitch, base: *light }
    }

    /// Turns the light around the centre by these angles (radians), short of the poles.
    pub fn turn(&mut self, yaw: f32, pitch: f32) {
        self.yaw += yaw;
        self.pitch = (self.pitch + pitch).clamp(-PITCH_LIMIT, PITCH_LIMIT);
    }

    /// The light.
    #[must_use]
    pub fn light(&self) -> Light {
        let out = direction(self.yaw, self.pitch);
        let position = self.center + self.distance * out;
        let kind = match self.base.kind {
            LightKind::Spot { cone_angle, .. } => LightKind::Spot { position, direction: -out, cone_angle },
            LightKind::Point { .. } => LightKind::Point { position },
            LightKind::Directional { .. } => LightKind::Directional { direction: -out },
        };
        Light { kind, ..self.base }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: Vec3, b: Vec3) -> bool {
        (a - b).length() < 1e-4
    }

    #[test]
    fn an_orbit_gives_back_its_camera_and_turns_about_the_target() {
        let camera = Camera::look_at(Vec3::new(3.0, 4.0, 5.0), Vec3::new(0.0, 0.5, 0.0), 40.0);
        let mut orbit = Orbit::around(&camera);
        let again = orbit.camera();
        assert!(close(again.eye, camera.eye) && close(again.target, camera.target), "{again:?}");
        assert_eq!((again.fov_y, again.near), (camera.fov_y, camera.near));
        orbit.turn(std::f32::consts::PI, 0.0);
        let turned = orbit.camera();
        let mirrored = Vec3::new(-3.0, 4.0, -5.0);
        assert!(close(turned.eye, mirrored), "half a turn about +y: {:?}", turned.eye);
        orbit.turn(0.0, 10.0);
        assert!((orbit.pitch - PITCH_LIMIT).abs() < 1e-6, "the pitch stops short of the pole");
    }

    #[test]
    fn flying_moves_eye_and_target_together_and_zoom_keeps_the_target() {
        let camera = Camera::look_at(Vec3::new(0.0, 0.0, 10.0), Vec3::ZERO, 40.0);
        let mut orbit = Orbit::around(&camera);
        orbit.fly(2.0, 1.0, 0.5);
        let flown = orbit.camera();
        assert!(close(flown.target, Vec3::new(1.0, 0.5, -2.0)), "{:?}", flown.target);
        assert!(close(flown.eye - flown.target, camera.eye - camera.target));
        orbit.zoom(0.5);
        assert!((orbit.camera().eye - orbit.camera().target).length() - 5.0 < 1e-4);
        orbit.zoom(0.0);
        assert!(orbit.distance > 0.0, "the eye stays off the target");
    }

    #[test]
    fn the_light_rig_keeps_the_light_and_aims_a_spot_at_the_centre() {
        let spot = Light::spot(Vec3::new(2.0, 4.0, 1.5), Vec3::ZERO, 60.0);
        let mut rig = LightRig::around(&spot, Vec3::ZERO, 5.0);
        let LightKind::Spot { position, direction, cone_angle } = rig.light().kind else { panic!("a spot") };
        assert!(close(position, Vec3::new(2.0, 4.0, 1.5)));
        assert!(close(direction, -position.normalize()));
        assert!((cone_angle - 60f32.to_radians()).abs() < 1e-6);
        rig.turn(std::f32::consts::FRAC_PI_2, 0.0);
        let LightKind::Spot { position: moved, .. } = rig.light().kind else { panic!("a spot") };
        assert!((moved.length() - position.length()).abs() < 1e-4, "it stays on its sphere");
        assert!((moved.y - 4.0).abs() < 1e-4 && !close(moved, position));
        let sun = Light { kind: LightKind::Directional { direction: Vec3::new(0.0, -1.0, -1.0).normalize() }, ..spot };
        let LightKind::Directional { direction } = LightRig::around(&sun, Vec3::ZERO, 5.0).light().kind else {
            panic!("directional")
        };
        assert!(close(direction, Vec3::new(0.0, -1.0, -1.0).normalize()));
    }
}
