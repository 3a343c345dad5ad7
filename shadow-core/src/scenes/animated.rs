//! The animated scenes: casters that move over a clip, for techniques to be measured at several times
//! of it against their error at rest. Their animations are generated here, keyed as a glTF file keys
//! them.

use std::f32::consts::TAU;

use glam::{Mat4, Quat, Vec3};

use super::builders::Stage;
use super::{SceneParams, built};
use crate::procedural;
use crate::scene::{Animation, Camera, Channel, Interpolation, Keyframes, Light, Material, NodeKey, Scene};

/// Seconds the mill's rotor takes to turn once.
pub const MILL_TURN: f32 = 6.0;

/// Adds a node drawing `mesh` in `color` under `parent`. The builders pass their own finite transforms.
pub(super) fn part(
    scene: &mut Scene,
    name: &str,
    parent: Option<NodeKey>,
    mesh: crate::Mesh,
    color: Vec3,
    local: Mat4,
) -> NodeKey {
    let mesh = scene.add_mesh(mesh);
    let material = scene.add_material(Material::colored(name, color));
    let node = scene.add_node(name, parent, local).unwrap_or_else(|e| panic!("built-in scene: {e}"));
    scene.set_mesh(node, Some((mesh, material))).unwrap_or_else(|e| panic!("built-in scene: {e}"));
    node
}

/// A wind mill: a tower, a nacelle and a rotor of three pitched blades turning once every
/// [`MILL_TURN`] seconds about the nacelle's axis, keyed every quarter turn (LINEAR, so the rotor turns
/// at an even speed), under a sun from in front of it that throws the blades' shadows on the tower and
/// the ground behind.
pub(super) fn mill(_: &SceneParams) -> Scene {
    const GREY: Vec3 = Vec3::new(0.8, 0.8, 0.78);
    let mut s = Stage::new().ground(30.0).scene;
    part(&mut s, "tower", None, built(procedural::cylinder(0.45, 8.0, 48)), GREY, Mat4::IDENTITY);
    let nacelle = Mat4::from_translation(Vec3::new(0.0, 8.3, 0.0));
    part(&mut s, "nacelle", None, built(procedural::cuboid(Vec3::new(0.9, 0.9, 2.2))), GREY, nacelle);
    let rotor = Mat4::from_translation(Vec3::new(0.0, 8.3, 1.25));
    let hub = part(&mut s, "hub", None, built(procedural::sphere(0.4, 24, 12)), GREY, rotor);
    let blade = built(procedural::cuboid(Vec3::new(0.55, 4.2, 0.1)));
    for k in 0..3 {
        // Radially out from the hub, pitched a quarter of a right angle about the blade's own length.
        let place = Mat4::from_rotation_z(k as f32 * TAU / 3.0)
            * Mat4::from_translation(Vec3::new(0.0, 2.45, 0.0))
            * Mat4::from_rotation_y(0.4);
        part(&mut s, &format!("blade {k}"), Some(hub), blade.clone(), Vec3::new(0.85, 0.85, 0.9), place);
    }
    let quarter = MILL_TURN / 4.0;
    let turn = Channel {
        node: hub,
        times: (0..5).map(|k| k as f32 * quarter).collect(),
        interpolation: Interpolation::Linear,
        values: Keyframes::Rotation((0..5).map(|k| Quat::from_rotation_z(-(k as f32) * TAU / 4.0)).collect()),
    };
    let spin = Animation::new("spin", vec![turn]).unwrap_or_else(|e| panic!("built-in scene: {e}"));
    s.add_animation(spin).unwrap_or_else(|e| panic!("built-in scene: {e}"));
    s.add_camera(Camera::look_at(Vec3::new(13.0, 11.0, 2.0), Vec3::new(2.0, 1.0, -6.5), 45.0));
    s.add_light(Light::directional(Vec3::new(0.25, -0.75, -0.6)));
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The rotor turns a third of the way round in a third of the clip and is back where it began at
    /// its end; the tower does not move.
    #[test]
    fn the_mill_turns_its_rotor_and_nothing_else() {
        let mut s = mill(&SceneParams::default());
        let at = |s: &Scene, name: &str| {
            let (_, n, _, _) = s.drawables().find(|(_, n, _, _)| n.name() == name).expect(name);
            n.world_transform()
        };
        let (blade, tower) = (at(&s, "blade 0"), at(&s, "tower"));
        assert_eq!(s.animation_duration(), MILL_TURN);
        s.pose(MILL_TURN / 3.0).unwrap();
        // A third of a turn (clockwise seen from the front) brings blade 0 where blade 2 stood at rest.
        let rest = mill(&SceneParams::default());
        assert!(at(&s, "blade 0").abs_diff_eq(at(&rest, "blade 2"), 1e-5));
        assert_eq!(at(&s, "tower"), tower);
        s.pose(MILL_TURN).unwrap();
        assert!(at(&s, "blade 0").abs_diff_eq(blade, 1e-5));
    }
}
