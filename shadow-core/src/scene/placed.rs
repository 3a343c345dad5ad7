//! A scene's lights and cameras: each in world space, or in a node's space, following the node as it and
//! its parents move.

use glam::Mat4;

use super::{Camera, CameraKey, Light, LightKey, LightShadow, NodeKey, Scene, SceneError};

impl Scene {
    /// Adds a light placed in world space.
    pub fn add_light(&mut self, light: Light) -> LightKey {
        self.lights.insert(Placed { value: light, node: None })
    }

    /// Adds a light placed in `node`'s space: it follows the node, and moving a parent moves it.
    ///
    /// # Errors
    /// An unknown node key.
    pub fn add_light_to(&mut self, node: NodeKey, light: Light) -> Result<LightKey, SceneError> {
        self.nodes.get(node).ok_or(SceneError::UnknownKey("node"))?;
        Ok(self.lights.insert(Placed { value: light, node: Some(node) }))
    }

    /// A light as it was given: in world space, or in its node's ([`Scene::light_node`]).
    #[must_use]
    pub fn light(&self, key: LightKey) -> Option<&Light> {
        self.lights.get(key).map(|p| &p.value)
    }

    /// A light as it was given, to edit (lights hold no cached state; nothing depending on the light is
    /// cached).
    pub fn light_mut(&mut self, key: LightKey) -> Option<&mut Light> {
        self.lights.get_mut(key).map(|p| &mut p.value)
    }

    /// The node a light follows, if any.
    #[must_use]
    pub fn light_node(&self, key: LightKey) -> Option<NodeKey> {
        self.lights.get(key)?.node
    }

    /// A light placed in world space.
    #[must_use]
    pub fn world_light(&self, key: LightKey) -> Option<Light> {
        self.lights.get(key).map(|p| self.placed(p, Light::transformed))
    }

    /// Every light, placed in world space.
    pub fn lights(&self) -> impl Iterator<Item = (LightKey, Light)> + '_ {
        self.lights.iter().map(|(k, p)| (k, self.placed(p, Light::transformed)))
    }

    /// Removes every light.
    pub fn clear_lights(&mut self) {
        self.lights.clear();
        self.light_shadows.clear();
    }

    /// Removes a light and how it casts shadows; answers the light as it was given.
    pub fn remove_light(&mut self, key: LightKey) -> Option<Light> {
        self.light_shadows.remove(key);
        self.lights.remove(key).map(|p| p.value)
    }

    /// Gives the scene `count` lights, to measure how a frame grows with them: its first `count` lights,
    /// or all of them and copies, the n-th round of copies turned about the vertical through the centre
    /// of the scene's bounds by n golden angles (so copies spread out rather than pile up), each casting
    /// as the light it copies. A copy stands in world space where its light stands now.
    ///
    /// # Errors
    /// [`SceneError::Invalid`] for a count of zero, or for more lights than none where the scene has none.
    pub fn set_light_count(&mut self, count: usize) -> Result<(), SceneError> {
        if count == 0 {
            return Err(SceneError::Invalid("a light count must be at least 1".into()));
        }
        let have: Vec<(LightKey, Light)> = self.lights().collect();
        if have.is_empty() {
            return Err(SceneError::Invalid(format!("the scene has no light to make {count} of")));
        }
        for &(key, _) in have.iter().skip(count) {
            self.remove_light(key);
        }
        let centre = self.bounds().center();
        let golden_angle = std::f32::consts::PI * (3.0 - 5f32.sqrt());
        for k in have.len()..count {
            let (key, light) = have[k % have.len()];
            let round = (k / have.len()) as f32;
            let turn = Mat4::from_translation(centre)
                * Mat4::from_rotation_y(round * golden_angle)
                * Mat4::from_translation(-centre);
            let shadow = self.light_shadow(key);
            let copy = self.add_light(light.transformed(turn));
            self.light_shadows.insert(copy, shadow);
        }
        Ok(())
    }

    /// Sets how a light casts shadows: whether it does, and with which technique and settings.
    ///
    /// # Errors
    /// An unknown light key.
    pub fn set_light_shadow(&mut self, key: LightKey, shadow: LightShadow) -> Result<(), SceneError> {
        self.lights.get(key).ok_or(SceneError::UnknownKey("light"))?;
        self.light_shadows.insert(key, shadow);
        Ok(())
    }

    /// How a light casts shadows (by default: it does, with the frame's technique).
    #[must_use]
    pub fn light_shadow(&self, key: LightKey) -> LightShadow {
        self.light_shadows.get(key).cloned().unwrap_or_default()
    }

    /// Adds a camera placed in world space.
    pub fn add_camera(&mut self, camera: Camera) -> CameraKey {
        self.cameras.insert(Placed { value: camera, node: None })
    }

    /// Adds a camera placed in `node`'s space: it follows the node.
    ///
    /// # Errors
    /// An unknown node key.
    pub fn add_camera_to(&mut self, node: NodeKey, camera: Camera) -> Result<CameraKey, SceneError> {
        self.nodes.get(node).ok_or(SceneError::UnknownKey("node"))?;
        Ok(self.cameras.insert(Placed { value: camera, node: Some(node) }))
    }

    /// A camera as it was given: in world space, or in its node's ([`Scene::camera_node`]).
    #[must_use]
    pub fn camera(&self, key: CameraKey) -> Option<&Camera> {
        self.cameras.get(key).map(|p| &p.value)
    }

    /// A camera as it was given, to edit.
    pub fn camera_mut(&mut self, key: CameraKey) -> Option<&mut Camera> {
        self.cameras.get_mut(key).map(|p| &mut p.value)
    }

    /// The node a camera follows, if any.
    #[must_use]
    pub fn camera_node(&self, key: CameraKey) -> Option<NodeKey> {
        self.cameras.get(key)?.node
    }

    /// A camera placed in world space.
    #[must_use]
    pub fn world_camera(&self, key: CameraKey) -> Option<Camera> {
        self.cameras.get(key).map(|p| self.placed(p, Camera::transformed))
    }

    /// Every camera, placed in world space.
    pub fn cameras(&self) -> impl Iterator<Item = (CameraKey, Camera)> + '_ {
        self.cameras.iter().map(|(k, p)| (k, self.placed(p, Camera::transformed)))
    }

    /// Removes every camera.
    pub fn clear_cameras(&mut self) {
        self.cameras.clear();
    }

    /// `p` in world space: moved by its node's world transform when it has a node.
    fn placed<T: Copy>(&self, p: &Placed<T>, transformed: fn(&T, Mat4) -> T) -> T {
        match p.node.and_then(|n| self.nodes.get(n)) {
            Some(node) => transformed(&p.value, node.world),
            None => p.value,
        }
    }
}

/// A light or camera: in world space, or in a node's space, following the node.
#[derive(Clone, Copy, Debug)]
pub(super) struct Placed<T> {
    pub(super) value: T,
    pub(super) node: Option<NodeKey>,
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;
    use crate::Material;

    /// A light count keeps the first lights, or adds turned copies casting as their lights do.
    #[test]
    fn a_light_count_keeps_the_first_lights_or_adds_turned_copies() {
        let mut s = Scene::new();
        let mesh = s.add_mesh(crate::procedural::cuboid(Vec3::ONE).expect("shape"));
        let material = s.add_material(Material::default());
        s.add_instance("box", mesh, material, Mat4::IDENTITY).expect("instance");
        assert!(s.set_light_count(2).is_err(), "nothing to copy");
        let spot = s.add_light(Light::spot(Vec3::new(3.0, 4.0, 0.0), Vec3::ZERO, 50.0));
        s.set_light_shadow(spot, LightShadow::NONE).expect("a light");
        s.add_light(Light::point(Vec3::new(0.0, 5.0, 2.0)));
        assert!(s.set_light_count(0).is_err());
        s.set_light_count(5).expect("copies");
        let lights: Vec<(LightKey, Light)> = s.lights().collect();
        assert_eq!(lights.len(), 5);
        // The copies of the spot light (the first, third and fifth) cast no shadow, as it does not, and
        // stand turned about the vertical through the centre, at its height and distance from it.
        for (k, (key, l)) in lights.iter().enumerate() {
            assert_eq!(s.light_shadow(*key).casts, k % 2 == 1, "light {k}");
            let p = l.position().expect("a position");
            assert_eq!(p.y, if k % 2 == 0 { 4.0 } else { 5.0 });
        }
        let (a, b) = (lights[0].1.position().unwrap(), lights[2].1.position().unwrap());
        assert!((a.length() - b.length()).abs() < 1e-5 && a.distance(b) > 1.0, "{a} {b}");
        s.set_light_count(1).expect("the first");
        assert_eq!(s.lights().map(|(k, _)| k).collect::<Vec<_>>(), vec![spot]);
    }
}
