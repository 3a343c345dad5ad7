//! `walker`: a jointed figure, skinned, walking through a spot light's cone between a ground and a wall.
//!
//! The figure is one mesh of capsules, one a bone, bound to eleven joints (pelvis, spine, head, and
//! each side's thigh, shin, upper arm and forearm). Each vertex is weighted by its distance to every
//! bone, `exp(-(d / 0.07 m)^2)`, its four largest weights kept: two to four joints a vertex near a joint,
//! one or two along a bone. The clip walks it 5 m along +x in four strides, the pelvis keyed every
//! twelfth of a stride (LINEAR, bobbing), the limbs' swings with CUBICSPLINE keys whose tangents are the
//! swing's derivative.

use std::f32::consts::{PI, TAU};

use glam::{Mat4, Quat, Vec3};

use super::animated::part;
use super::builders::Stage;
use super::{SceneParams, built};
use crate::deform::{Deformers, SkinWeights};
use crate::mesh::Mesh;
use crate::procedural;
use crate::scene::{Animation, Camera, Channel, Interpolation, Keyframes, Light, Material, NodeKey, Scene, Skin};

/// Seconds a stride (two steps) takes.
pub const STRIDE: f32 = 1.2;
/// Strides in the clip.
pub const STRIDES: u32 = 4;
/// Where the pelvis starts and ends along x.
const PATH: (f32, f32) = (-2.5, 2.5);
const PELVIS_HEIGHT: f32 = 0.95;

/// A bone: its joint's place at rest, where it ends, its thickness, and its parent.
struct Bone {
    name: &'static str,
    parent: Option<usize>,
    head: Vec3,
    tail: Vec3,
    radius: f32,
}

/// The skeleton at rest, standing at the origin facing +x (z to its left).
fn skeleton() -> Vec<Bone> {
    let bone = |name, parent, head: [f32; 3], tail: [f32; 3], radius| Bone {
        name,
        parent,
        head: Vec3::from(head),
        tail: Vec3::from(tail),
        radius,
    };
    let h = PELVIS_HEIGHT;
    vec![
        bone("pelvis", None, [0.0, h, 0.0], [0.0, h + 0.12, 0.0], 0.15),
        bone("spine", Some(0), [0.0, h + 0.1, 0.0], [0.0, h + 0.55, 0.0], 0.16),
        bone("head", Some(1), [0.0, h + 0.6, 0.0], [0.0, h + 0.82, 0.0], 0.11),
        bone("thigh L", Some(0), [0.0, h - 0.05, 0.1], [0.0, h - 0.48, 0.1], 0.08),
        bone("shin L", Some(3), [0.0, h - 0.48, 0.1], [0.0, 0.06, 0.1], 0.06),
        bone("thigh R", Some(0), [0.0, h - 0.05, -0.1], [0.0, h - 0.48, -0.1], 0.08),
        bone("shin R", Some(5), [0.0, h - 0.48, -0.1], [0.0, 0.06, -0.1], 0.06),
        bone("upper arm L", Some(1), [0.0, h + 0.5, 0.23], [0.0, h + 0.22, 0.25], 0.05),
        bone("forearm L", Some(7), [0.0, h + 0.22, 0.25], [0.0, h - 0.05, 0.26], 0.045),
        bone("upper arm R", Some(1), [0.0, h + 0.5, -0.23], [0.0, h + 0.22, -0.25], 0.05),
        bone("forearm R", Some(9), [0.0, h + 0.22, -0.25], [0.0, h - 0.05, -0.26], 0.045),
    ]
}

/// The figure's mesh: a capsule along each bone, reaching a radius past both ends, weighted to the
/// bones by distance.
fn body(bones: &[Bone]) -> Mesh {
    let capsules: Vec<Mesh> = bones
        .iter()
        .map(|b| {
            let axis = b.tail - b.head;
            let length = axis.length() + 2.0 * b.radius;
            let along = Quat::from_rotation_arc(Vec3::Y, axis.normalize());
            let place = Mat4::from_rotation_translation(along, b.head - axis.normalize() * b.radius);
            built(procedural::capsule(b.radius, length, 20, 6)).transformed(place)
        })
        .collect();
    let mesh = Mesh::merged(&capsules).unwrap_or_else(|e| panic!("built-in scene: {e}"));
    let (joints, weights): (Vec<[u16; 4]>, Vec<[f32; 4]>) = mesh.positions().iter().map(|&p| weigh(bones, p)).unzip();
    let skin = SkinWeights::new(joints, weights).unwrap_or_else(|e| panic!("built-in scene: {e}"));
    let deformers = Deformers { skin: Some(skin), morph_targets: Vec::new() };
    mesh.with_deformers(deformers).unwrap_or_else(|e| panic!("built-in scene: {e}"))
}

/// A vertex's four largest bone weights, by its distance to each bone's segment.
fn weigh(bones: &[Bone], p: Vec3) -> ([u16; 4], [f32; 4]) {
    let mut w: Vec<(f32, u16)> = bones
        .iter()
        .enumerate()
        .map(|(i, b)| {
            let axis = b.tail - b.head;
            let s = ((p - b.head).dot(axis) / axis.length_squared()).clamp(0.0, 1.0);
            let d = ((p - (b.head + axis * s)).length() - b.radius).max(0.0);
            ((-(d / 0.07).powi(2)).exp(), i as u16)
        })
        .collect();
    w.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
    let mut joints = [0; 4];
    let mut weights = [0.0; 4];
    for (k, (weight, joint)) in w.into_iter().take(4).enumerate() {
        (joints[k], weights[k]) = (joint, weight);
    }
    // Weights under a thousandth of the largest do nothing visible: left out, so a vertex along a bone
    // is moved by its own joint alone.
    let top = weights[0];
    (joints, weights.map(|x| if x < top * 1e-3 { 0.0 } else { x }))
}

/// A swing of `amplitude` radians about +z over a stride, `phase` strides late, keyed as a CUBICSPLINE
/// (in-tangent, value, out-tangent a key, the tangents the derivative of the rotation) every
/// `1 / keys` of a stride; `bend` adds a knee's one-sided bend.
fn swing(node: NodeKey, amplitude: f32, phase: f32, bend: Option<f32>, keys: u32) -> Channel {
    let n = keys * STRIDES;
    let angle = |t: f32| {
        let x = TAU * (t / STRIDE - phase);
        match bend {
            None => amplitude * x.sin(),
            // The knee bends back, most as the leg swings forward: (1 - cos) / 2 shaped, never forward.
            Some(rest) => -(rest + amplitude * 0.5 * (1.0 - (x + PI / 2.0).cos())),
        }
    };
    let rate = |t: f32| {
        let x = TAU * (t / STRIDE - phase);
        let w = TAU / STRIDE;
        match bend {
            None => amplitude * w * x.cos(),
            Some(_) => -amplitude * 0.5 * w * (x + PI / 2.0).sin(),
        }
    };
    let mut times = Vec::new();
    let mut values = Vec::new();
    for k in 0..=n {
        let t = k as f32 * STRIDE / keys as f32;
        let (a, da) = (angle(t), rate(t));
        let q = Quat::from_rotation_z(a);
        // d/dt of (0, 0, sin(a/2), cos(a/2)) is da/2 (0, 0, cos(a/2), -sin(a/2)).
        let dq = Quat::from_xyzw(0.0, 0.0, 0.5 * da * (a / 2.0).cos(), -0.5 * da * (a / 2.0).sin());
        times.push(t);
        values.extend([dq, q, dq]);
    }
    Channel { node, times, interpolation: Interpolation::CubicSpline, values: Keyframes::Rotation(values) }
}

pub(super) fn walker(_: &SceneParams) -> Scene {
    let mut s = Stage::new().ground(12.0).scene;
    part(
        &mut s,
        "wall",
        None,
        built(procedural::cuboid(Vec3::new(10.0, 2.6, 0.2))),
        Vec3::new(0.7, 0.68, 0.62),
        Mat4::from_translation(Vec3::new(0.0, 1.3, -1.4)),
    );
    let bones = skeleton();
    let mut joints: Vec<NodeKey> = Vec::new();
    for b in &bones {
        let parent_head = b.parent.map_or(Vec3::ZERO, |p| bones[p].head);
        let parent = b.parent.map(|p| joints[p]);
        let local = Mat4::from_translation(b.head - parent_head);
        joints.push(s.add_node(b.name, parent, local).unwrap_or_else(|e| panic!("built-in scene: {e}")));
    }
    let mesh = s.add_mesh(body(&bones));
    let skin_material = s.add_material(Material::colored("walker", Vec3::new(0.35, 0.55, 0.85)));
    let figure = s.add_node("figure", None, Mat4::IDENTITY).unwrap_or_else(|e| panic!("built-in scene: {e}"));
    let fail = |e: crate::scene::SceneError| -> ! { panic!("built-in scene: {e}") };
    s.set_mesh(figure, Some((mesh, skin_material))).unwrap_or_else(|e| fail(e));
    let inverse_bind_matrices = bones.iter().map(|b| Mat4::from_translation(-b.head)).collect();
    let skin = Skin { name: "walker".into(), joints: joints.clone(), inverse_bind_matrices };
    let skin = s.add_skin(skin).unwrap_or_else(|e| fail(e));
    s.set_skin(figure, Some(skin)).unwrap_or_else(|e| fail(e));
    // The pelvis walks along x, bobbing twice a stride (at each step), keyed every twelfth of a stride.
    let steps = 12 * STRIDES;
    let duration = STRIDE * STRIDES as f32;
    let times: Vec<f32> = (0..=steps).map(|k| k as f32 * duration / steps as f32).collect();
    let walk = times
        .iter()
        .map(|&t| {
            let x = PATH.0 + (PATH.1 - PATH.0) * t / duration;
            Vec3::new(x, PELVIS_HEIGHT + 0.025 * (2.0 * TAU * t / STRIDE).cos(), 0.0)
        })
        .collect();
    let by = |name: &str| joints[bones.iter().position(|b| b.name == name).unwrap_or(0)];
    let channels = vec![
        Channel { node: joints[0], times, interpolation: Interpolation::Linear, values: Keyframes::Translation(walk) },
        swing(by("thigh L"), 0.45, 0.0, None, 8),
        swing(by("thigh R"), 0.45, 0.5, None, 8),
        swing(by("shin L"), 0.9, 0.0, Some(0.05), 8),
        swing(by("shin R"), 0.9, 0.5, Some(0.05), 8),
        swing(by("upper arm L"), 0.35, 0.5, None, 8),
        swing(by("upper arm R"), 0.35, 0.0, None, 8),
        swing(by("forearm L"), 0.25, 0.5, None, 8),
        swing(by("forearm R"), 0.25, 0.0, None, 8),
    ];
    let walk = Animation::new("walk", channels).unwrap_or_else(|e| fail(e));
    s.add_animation(walk).unwrap_or_else(|e| fail(e));
    s.add_camera(Camera::look_at(Vec3::new(1.2, 2.2, 6.5), Vec3::new(0.0, 0.8, -0.6), 45.0));
    s.add_light(Light::spot(Vec3::new(1.5, 2.8, 4.0), Vec3::new(0.0, 0.8, -1.0), 70.0));
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Thousands of triangles, every vertex on one to four joints and some on each count from two up, and
    /// the figure walking: its bounds move along x with the clip and its feet stay near the ground.
    #[test]
    fn the_walker_is_skinned_and_walks() {
        let mut s = walker(&SceneParams::default());
        let (_, _, mesh, _) = s.drawables().find(|(_, n, _, _)| n.name() == "figure").expect("the figure");
        let mesh = s.mesh(mesh).expect("its mesh").clone();
        assert!((2000..8000).contains(&mesh.triangle_count()), "{}", mesh.triangle_count());
        let skin = mesh.deformers().and_then(|d| d.skin.as_ref()).expect("skin weights");
        let used = |w: &[f32; 4]| w.iter().filter(|x| **x > 0.0).count();
        let mut counts = [0usize; 5];
        for w in skin.weights() {
            counts[used(w)] += 1;
        }
        assert_eq!(counts[0], 0);
        assert!(counts[2] > 0 && counts[3] > 0 && counts[4] > 0, "{counts:?}");
        let figure_bounds = |s: &Scene| {
            let node = s.drawables().find(|(_, n, _, _)| n.name() == "figure").expect("figure").0;
            let d = s.deformed(node).expect("skinned").expect("finite");
            d.mesh.bounds().transformed(d.world_from_local)
        };
        s.pose(0.0).unwrap();
        let start = figure_bounds(&s);
        s.pose(STRIDE * STRIDES as f32).unwrap();
        let end = figure_bounds(&s);
        assert!((end.center().x - start.center().x - (PATH.1 - PATH.0)).abs() < 0.3, "{start:?} {end:?}");
        for t in [0.3, 1.0, 2.2] {
            s.pose(t).unwrap();
            let b = figure_bounds(&s);
            assert!(b.min.y > -0.05 && b.min.y < 0.15, "the feet at {t}: {b:?}");
        }
    }
}
