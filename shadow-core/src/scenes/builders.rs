//! The geometry of each built-in scene. Sizes are in metres; every scene stands on y = 0.
//!
//! The builders work on fixed data, so a failure here (an empty implicit surface, a bad transform) is a bug
//! in this file, not bad input: they panic, and the scene tests build every scene to prove they do not.

use glam::{Mat4, Quat, Vec2, Vec3};

use super::{Rng, SceneParams, built};
use crate::mesh::Mesh;
use crate::procedural;
use crate::scene::{Camera, Light, Material, MaterialKey, MeshKey, Scene};

/// A scene under construction.
pub(super) struct Stage {
    pub(super) scene: Scene,
}

impl Stage {
    pub(super) fn new() -> Self {
        Self { scene: Scene::new() }
    }

    /// Adds a mesh instance with a colour. The builders only pass finite transforms of their own meshes.
    pub(super) fn add(&mut self, name: &str, mesh: Mesh, color: Vec3, transform: Mat4) {
        let m = self.mesh(mesh);
        self.place(name, m, color, transform);
    }

    /// Adds a mesh to be placed, once or many times, with [`Stage::place`].
    fn mesh(&mut self, mesh: Mesh) -> MeshKey {
        self.scene.add_mesh(mesh)
    }

    /// Places an instance of a mesh added with [`Stage::mesh`], in a material of its own.
    fn place(&mut self, name: &str, mesh: MeshKey, color: Vec3, transform: Mat4) {
        let mat = self.scene.add_material(Material::colored(name, color));
        if let Err(e) = self.scene.add_instance(name, mesh, mat, transform) {
            panic!("built-in scene: {e}");
        }
    }

    /// Places an instance of a mesh added with [`Stage::mesh`] in a material of [`Stage::material`].
    fn place_in(&mut self, name: &str, mesh: MeshKey, material: MaterialKey, transform: Mat4) {
        if let Err(e) = self.scene.add_instance(name, mesh, material, transform) {
            panic!("built-in scene: {e}");
        }
    }

    /// Adds a material for [`Stage::place_in`].
    fn material(&mut self, name: &str, color: Vec3) -> MaterialKey {
        self.scene.add_material(Material::colored(name, color))
    }

    pub(super) fn ground(mut self, size: f32) -> Self {
        self.add("ground", built(procedural::plane(size, size)), Vec3::splat(0.75), Mat4::IDENTITY);
        self
    }

    pub(super) fn finish(mut self, camera: Camera, light: Light) -> Scene {
        self.scene.add_camera(camera);
        self.scene.add_light(light);
        self.scene
    }
}

const WARM: Vec3 = Vec3::new(0.85, 0.45, 0.25);
const BLUE: Vec3 = Vec3::new(0.3, 0.45, 0.85);
const GREEN: Vec3 = Vec3::new(0.35, 0.7, 0.35);
const GOLD: Vec3 = Vec3::new(0.85, 0.7, 0.3);

fn at(x: f32, y: f32, z: f32) -> Mat4 {
    Mat4::from_translation(Vec3::new(x, y, z))
}

pub(super) fn cylinder(_: &SceneParams) -> Scene {
    let mut s = Stage::new().ground(10.0);
    s.add("cylinder", built(procedural::cylinder(0.3, 1.0, 64)), WARM, Mat4::IDENTITY);
    s.finish(
        Camera::look_at(Vec3::new(1.2, 1.9, 3.2), Vec3::new(-0.4, 0.3, -0.5), 45.0),
        Light::spot(Vec3::new(2.0, 4.0, 1.5), Vec3::new(0.0, 0.3, 0.0), 60.0),
    )
}

pub(super) fn primitives(_: &SceneParams) -> Scene {
    let mut s = Stage::new().ground(10.0);
    s.add("box", built(procedural::cuboid(Vec3::splat(0.6))), WARM, at(-0.9, 0.3, 0.3) * Mat4::from_rotation_y(0.5));
    s.add("cylinder", built(procedural::cylinder(0.25, 0.8, 128)), BLUE, at(0.8, 0.0, 0.5));
    s.add("sphere", built(procedural::sphere(0.35, 64, 40)), GREEN, at(0.0, 0.35, -0.6));
    s.add("torus", built(procedural::torus(0.35, 0.12, 80, 24)), GOLD, at(0.9, 0.12, -0.7));
    s.finish(
        Camera::look_at(Vec3::new(0.3, 2.2, 3.4), Vec3::new(-0.2, 0.1, -0.4), 45.0),
        Light::spot(Vec3::new(2.0, 4.0, 1.5), Vec3::new(-0.1, 0.0, -0.1), 60.0),
    )
}

pub(super) fn stacked_boxes(_: &SceneParams) -> Scene {
    let mut s = Stage::new().ground(10.0);
    s.add("lower box", built(procedural::cuboid(Vec3::new(1.2, 0.5, 1.2))), BLUE, at(0.0, 0.25, 0.0));
    s.add(
        "upper box",
        built(procedural::cuboid(Vec3::new(0.6, 0.08, 0.6))),
        WARM,
        at(0.55, 1.4, 0.35) * Mat4::from_rotation_y(0.3),
    );
    s.finish(
        Camera::look_at(Vec3::new(0.8, 2.4, 3.0), Vec3::new(0.3, 0.3, 0.0), 45.0),
        Light::spot(Vec3::new(1.1, 4.5, 0.9), Vec3::new(0.4, 0.0, 0.2), 60.0),
    )
}

pub(super) fn l_shape(_: &SceneParams) -> Scene {
    let mut s = Stage::new().ground(6.0);
    let outline = [(0.0, 0.0), (1.2, 0.0), (1.2, -0.4), (0.4, -0.4), (0.4, -1.2), (0.0, -1.2)].map(Vec2::from);
    s.add("l-shape", built(procedural::prism(&outline, 3, 0.3)), WARM, at(-0.6, 0.5, 0.6));
    s.finish(
        Camera::look_at(Vec3::new(1.3, 2.3, 2.4), Vec3::new(-0.1, 0.2, -0.1), 45.0),
        Light::directional(Vec3::new(0.25, -1.0, 0.15)),
    )
}

/// Genus 2: the smooth union of two overlapping tori lying flat.
fn double_torus_sdf(p: Vec3) -> f32 {
    let torus = |q: Vec3| Vec2::new(Vec2::new(q.x, q.z).length() - 0.5, q.y).length() - 0.17;
    let (a, b) = (torus(p - Vec3::new(-0.45, 0.0, 0.0)), torus(p - Vec3::new(0.45, 0.0, 0.0)));
    let k = 0.08;
    let h = (0.5 + 0.5 * (b - a) / k).clamp(0.0, 1.0);
    b + (a - b) * h - k * h * (1.0 - h)
}

pub(super) fn double_torus(_: &SceneParams) -> Scene {
    let mut s = Stage::new().ground(8.0);
    let mesh =
        built(procedural::implicit(double_torus_sdf, Vec3::new(-1.2, -0.3, -0.75), Vec3::new(1.2, 0.3, 0.75), 48));
    s.add("double torus", mesh, GOLD, at(0.0, 0.6, 0.0) * Mat4::from_rotation_x(0.25));
    s.finish(
        Camera::look_at(Vec3::new(0.6, 2.2, 2.8), Vec3::new(0.0, 0.3, 0.0), 45.0),
        Light::spot(Vec3::new(0.8, 4.0, 0.9), Vec3::new(0.0, 0.0, -0.1), 60.0),
    )
}

/// A bowling pin, 0.38 m tall, about 450 triangles.
fn pin() -> Mesh {
    let profile: Vec<Vec2> = [
        (0.0, 0.0),
        (0.026, 0.0),
        (0.036, 0.02),
        (0.05, 0.06),
        (0.058, 0.1),
        (0.06, 0.13),
        (0.055, 0.17),
        (0.042, 0.21),
        (0.03, 0.245),
        (0.023, 0.27),
        (0.024, 0.3),
        (0.03, 0.325),
        (0.032, 0.345),
        (0.028, 0.365),
        (0.016, 0.378),
        (0.0, 0.38),
    ]
    .map(Vec2::from)
    .to_vec();
    built(procedural::lathe(&profile, 16, false))
}

pub(super) fn strike(_: &SceneParams) -> Scene {
    let mut s = Stage::new();
    s.add("lane", built(procedural::plane(2.2, 8.0)), Vec3::new(0.8, 0.65, 0.45), Mat4::IDENTITY);
    let pin_mesh = pin();
    let spacing = 0.305;
    for row in 0..4 {
        for k in 0..=row {
            let x = (k as f32 - row as f32 * 0.5) * spacing;
            let z = -1.5 - row as f32 * spacing * 0.866;
            s.add(&format!("pin {row}.{k}"), pin_mesh.clone(), Vec3::splat(0.92), at(x, 0.0, z));
        }
    }
    s.add("ball", built(procedural::sphere(0.11, 32, 20)), Vec3::new(0.2, 0.25, 0.7), at(0.12, 0.11, -0.8));
    s.finish(
        Camera::look_at(Vec3::new(0.5, 0.9, 0.6), Vec3::new(-0.1, 0.1, -1.9), 45.0),
        Light::spot(Vec3::new(-0.9, 2.6, 0.2), Vec3::new(0.0, 0.0, -1.7), 60.0),
    )
}

/// A standing figure about 1.7 m tall from capsules and a sphere (about 620 triangles).
fn figure(rng: &mut Rng) -> Mesh {
    let limb = |r: f32, len: f32, from: Vec3, dir: Vec3| {
        let rot = Quat::from_rotation_arc(Vec3::Y, dir.normalize());
        built(procedural::capsule(r, len, 8, 3)).transformed(Mat4::from_rotation_translation(rot, from))
    };
    let sway = rng.range(-0.15, 0.15);
    let parts = [
        limb(0.07, 0.85, Vec3::new(-0.1, 0.0, 0.0), Vec3::new(0.03, 1.0, 0.0)),
        limb(0.07, 0.85, Vec3::new(0.1, 0.0, 0.0), Vec3::new(-0.03, 1.0, 0.0)),
        limb(0.16, 0.7, Vec3::new(0.0, 0.78, 0.0), Vec3::Y),
        limb(0.05, 0.65, Vec3::new(-0.2, 1.38, 0.0), Vec3::new(-0.3 + sway, -1.0, 0.1)),
        limb(0.05, 0.65, Vec3::new(0.2, 1.38, 0.0), Vec3::new(0.3 + sway, -1.0, -0.1)),
        built(procedural::sphere(0.11, 10, 8)).transformed(at(0.0, 1.58, 0.0)),
    ];
    Mesh::merged(&parts).unwrap_or_else(|e| panic!("figure: {e}"))
}

pub(super) fn crowd(p: &SceneParams) -> Scene {
    let mut rng = Rng::new(p.seed);
    let mut s = Stage::new().ground(16.0);
    s.add(
        "wall",
        built(procedural::plane(16.0, 6.0)),
        Vec3::splat(0.8),
        at(0.0, 3.0, -6.0) * Mat4::from_rotation_x(std::f32::consts::FRAC_PI_2),
    );
    for row in 0..4 {
        for col in 0..6 {
            let x = (col as f32 - 2.5) * 0.9 + rng.range(-0.2, 0.2);
            let z = -(row as f32) * 0.9 + rng.range(-0.2, 0.2);
            let t = at(x, 0.0, z)
                * Mat4::from_rotation_y(rng.range(-0.6, 0.6))
                * Mat4::from_scale(Vec3::splat(rng.range(0.9, 1.1)));
            let c = Vec3::new(rng.range(0.3, 0.9), rng.range(0.3, 0.9), rng.range(0.3, 0.9));
            s.add(&format!("figure {row}.{col}"), figure(&mut rng), c, t);
        }
    }
    s.finish(
        Camera::look_at(Vec3::new(2.5, 3.0, 6.5), Vec3::new(-0.3, 1.0, -2.5), 45.0),
        Light::spot(Vec3::new(-1.5, 4.5, 6.0), Vec3::new(0.0, 1.0, -3.0), 60.0),
    )
}

pub(super) fn cubes(p: &SceneParams) -> Scene {
    let mut rng = Rng::new(p.seed);
    let mut s = Stage::new().ground(10.0);
    let unit = built(procedural::cuboid(Vec3::splat(0.13)));
    let parts: Vec<Mesh> = (0..1000)
        .map(|_| {
            let pos = Vec3::new(rng.range(-1.3, 1.3), rng.range(0.2, 1.6), rng.range(-1.3, 1.3));
            let rot =
                Quat::from_euler(glam::EulerRot::XYZ, rng.range(0.0, 3.0), rng.range(0.0, 3.0), rng.range(0.0, 3.0));
            unit.transformed(Mat4::from_rotation_translation(rot, pos))
        })
        .collect();
    s.add("cubes", Mesh::merged(&parts).unwrap_or_else(|e| panic!("cubes: {e}")), WARM, Mat4::IDENTITY);
    s.finish(
        Camera::look_at(Vec3::new(2.6, 3.0, 4.2), Vec3::new(-0.3, 0.4, -0.3), 45.0),
        Light::spot(Vec3::new(2.0, 4.5, 1.5), Vec3::new(0.0, 0.5, 0.0), 60.0),
    )
}

/// A lumpy blob: a sphere displaced by a few seeded waves.
fn blob(rng: &mut Rng) -> Mesh {
    let waves: Vec<(Vec3, f32)> = (0..6)
        .map(|_| {
            (Vec3::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-1.0, 1.0)) * 9.0, rng.range(0.0, 6.0))
        })
        .collect();
    let f = move |q: Vec3| q.length() - 0.42 - waves.iter().map(|(k, ph)| 0.025 * (k.dot(q) + ph).sin()).sum::<f32>();
    built(procedural::implicit(f, Vec3::splat(-0.6), Vec3::splat(0.6), 24))
}

pub(super) fn cage(p: &SceneParams) -> Scene {
    let mut rng = Rng::new(p.seed);
    let mut s = Stage::new().ground(10.0);
    s.add("blob", blob(&mut rng), GREEN, at(0.0, 0.75, 0.0));
    let bars = 16;
    let mut parts = Vec::new();
    for i in 0..bars {
        let a = std::f32::consts::TAU * i as f32 / bars as f32;
        parts.push(built(procedural::cylinder(0.025, 1.6, 10)).transformed(at(0.85 * a.cos(), 0.0, 0.85 * a.sin())));
    }
    for y in [0.05, 1.55] {
        parts.push(built(procedural::torus(0.85, 0.035, 64, 10)).transformed(at(0.0, y, 0.0)));
    }
    s.add("cage", Mesh::merged(&parts).unwrap_or_else(|e| panic!("cage: {e}")), Vec3::splat(0.55), Mat4::IDENTITY);
    s.finish(
        Camera::look_at(Vec3::new(1.8, 2.4, 3.4), Vec3::new(-0.3, 0.5, -0.4), 45.0),
        Light::spot(Vec3::new(1.6, 4.2, 1.2), Vec3::new(-0.2, 0.4, -0.2), 60.0),
    )
}

/// A branch of `length` from `base` along `dir`, and below `depth` more levels three branches from its tip,
/// each shorter and thinner, their meshes pushed to `out`. The twigs (the last level) are pushed to `twigs`
/// as their base and tip.
pub(super) fn branch(
    rng: &mut Rng,
    (base, dir): (Vec3, Vec3),
    (length, radius): (f32, f32),
    depth: u32,
    (out, twigs): (&mut Vec<Mesh>, &mut Vec<(Vec3, Vec3)>),
) {
    let rot = Quat::from_rotation_arc(Vec3::Y, dir);
    out.push(built(procedural::cylinder(radius, length, 9)).transformed(Mat4::from_rotation_translation(rot, base)));
    if depth == 0 {
        twigs.push((base, base + dir * length));
        return;
    }
    let tip = base + dir * length;
    let spin = rng.range(0.0, std::f32::consts::TAU);
    for k in 0..3 {
        let around = spin + std::f32::consts::TAU * k as f32 / 3.0;
        let tilt = rng.range(0.45, 0.8);
        let side = (rot * Vec3::new(around.cos(), 0.0, around.sin())).normalize();
        let child = (dir * tilt.cos() + side * tilt.sin() + Vec3::Y * 0.15).normalize();
        let start = tip - dir * radius;
        let child_length = length * rng.range(0.68, 0.8);
        branch(rng, (start, child), (child_length, radius * 0.62), depth - 1, (&mut *out, &mut *twigs));
    }
}

pub(super) fn tree(p: &SceneParams) -> Scene {
    let mut rng = Rng::new(p.seed);
    let mut s = Stage::new().ground(12.0);
    let mut parts = Vec::new();
    branch(&mut rng, (Vec3::ZERO, Vec3::Y), (0.9, 0.09), 6, (&mut parts, &mut Vec::new()));
    s.add(
        "tree",
        Mesh::merged(&parts).unwrap_or_else(|e| panic!("tree: {e}")),
        Vec3::new(0.55, 0.4, 0.25),
        Mat4::IDENTITY,
    );
    s.finish(
        Camera::look_at(Vec3::new(2.2, 2.6, 4.6), Vec3::new(-0.6, 0.8, -0.8), 45.0),
        Light::spot(Vec3::new(2.2, 5.0, 1.8), Vec3::new(-0.3, 0.6, -0.3), 70.0),
    )
}

/// A room lit from inside near the ceiling. The camera stands in the shadow of a beam hung between it and
/// the light (so every shadow volume that holds the eye crosses the near plane), and a post beside the
/// eye is cut by the near plane itself.
pub(super) fn room(_: &SceneParams) -> Scene {
    use std::f32::consts::FRAC_PI_2;
    let mut s = Stage::new();
    let wall = Vec3::splat(0.8);
    s.add("floor", built(procedural::plane(6.0, 7.0)), Vec3::splat(0.7), at(0.0, 0.0, 0.5));
    s.add("back wall", built(procedural::plane(6.0, 3.6)), wall, at(0.0, 1.8, -3.0) * Mat4::from_rotation_x(FRAC_PI_2));
    s.add(
        "left wall",
        built(procedural::plane(3.6, 7.0)),
        wall,
        at(-3.0, 1.8, 0.5) * Mat4::from_rotation_z(-FRAC_PI_2),
    );
    s.add("right wall", built(procedural::plane(3.6, 7.0)), wall, at(3.0, 1.8, 0.5) * Mat4::from_rotation_z(FRAC_PI_2));
    s.add("beam", built(procedural::cuboid(Vec3::new(1.4, 0.25, 0.9))), WARM, at(0.0, 2.5, 1.25));
    s.add("table", built(procedural::cuboid(Vec3::new(1.2, 0.8, 0.8))), BLUE, at(1.0, 0.4, -0.3));
    s.add("ball", built(procedural::sphere(0.3, 32, 16)), GREEN, at(-1.1, 0.3, -1.0));
    // The eye is at (0, 1.2, 3) with a near plane 0.05 ahead (z = 2.95), whose half-width is 0.026 at
    // 55 degrees: the post reaches 0.025 to the eye's left and spans z 2.935..2.96, so the near plane cuts
    // it. The segment from the eye to the light runs through the beam, so the eye is in its shadow.
    s.add("post", built(procedural::cuboid(Vec3::new(0.18, 3.0, 0.025))), GOLD, at(-0.115, 1.5, 2.9475));
    s.finish(
        Camera::look_at(Vec3::new(0.0, 1.2, 3.0), Vec3::new(0.0, 0.7, -2.0), 55.0),
        Light::spot(Vec3::new(0.0, 3.4, 0.0), Vec3::new(0.0, 0.0, -1.0), 130.0),
    )
}

/// Where the outdoor scene's sun stands, seen from its camera.
#[derive(Clone, Copy)]
enum Sun {
    /// To the right and behind, shining across the road at 45 degrees.
    Side,
    /// Behind the camera: the light's and the eye's frusta look the same way.
    Behind,
    /// Ahead, facing the camera: the duelling frusta.
    Facing,
}

/// The sun's elevation above the horizon, in degrees: low, so shadows are long.
pub(super) const SUN_ELEVATION: f32 = 20.0;

/// Half the outdoor ground's side, in metres.
pub(super) const OUTDOOR_HALF: f32 = 100.0;

/// The outdoor scene of the perspective-aliasing work (Stamminger-Drettakis, the Nealen survey's Fig. 10):
/// a 200 x 200 m ground under a low sun and a few thousand casters of every size (buildings, lamp poles,
/// bollards, crates, trees with thin branches, picket fences along the road), seen by a camera at head
/// height on the road, looking along it to the horizon. Instanced: each kind of caster is one mesh (a few
/// of them for trees and buildings), so the scene stays small on the GPU.
fn outdoor_with(p: &SceneParams, sun: Sun) -> Scene {
    let mut rng = Rng::new(p.seed);
    let mut s = Stage::new();
    let ground = s.mesh(built(procedural::plane(2.0 * OUTDOOR_HALF, 2.0 * OUTDOOR_HALF)));
    s.place("ground", ground, Vec3::new(0.55, 0.6, 0.5), Mat4::IDENTITY);
    // The road runs along z through x = 0; fences line it at x = +-7, bollards at +-5.5, lamp poles at +-6.3.
    let picket = s.mesh(built(procedural::cuboid(Vec3::new(0.06, 1.1, 0.1))));
    let rail = s.mesh(built(procedural::cuboid(Vec3::new(0.05, 0.08, 10.0))));
    let bollard = s.mesh(built(procedural::cylinder(0.12, 0.9, 12)));
    let pole = s.mesh(built(procedural::cylinder(0.09, 6.0, 12)));
    let wood = Vec3::new(0.6, 0.45, 0.3);
    let metal = Vec3::splat(0.35);
    let (start, end) = (-OUTDOOR_HALF + 2.0, OUTDOOR_HALF - 2.0);
    // Positions every `step` metres from `from` to the road's end.
    let along = |from: f32, step: f32| (0..).map(move |i| from + step * i as f32).take_while(move |&z| z < end);
    for side in [-1.0f32, 1.0] {
        for z in along(start, 0.2) {
            s.place("picket", picket, wood, at(side * 7.0, 0.55, z));
        }
        for z in along(start + 5.0, 10.0) {
            for y in [0.3, 0.85] {
                s.place("rail", rail, wood, at(side * 7.0 - side * 0.08, y, z));
            }
        }
        for z in along(start, 2.0) {
            s.place("bollard", bollard, metal, at(side * 5.5, 0.0, z));
        }
        for z in along(start + 3.0, 8.0) {
            s.place("lamp pole", pole, metal, at(side * 6.3, 0.0, z));
        }
    }
    // Lots on both sides of the road: a building, or a stand of trees.
    let building = s.mesh(built(procedural::cuboid(Vec3::ONE)));
    let trees: Vec<_> = (0..6)
        .map(|_| {
            let mut parts = Vec::new();
            let height = rng.range(1.2, 1.8);
            branch(&mut rng, (Vec3::ZERO, Vec3::Y), (height, 0.1), 4, (&mut parts, &mut Vec::new()));
            s.mesh(Mesh::merged(&parts).unwrap_or_else(|e| panic!("outdoor tree: {e}")))
        })
        .collect();
    let crate_mesh = s.mesh(built(procedural::cuboid(Vec3::splat(0.8))));
    let mut lot_z = start + 4.0;
    while lot_z < end - 6.0 {
        for side in [-1.0f32, 1.0] {
            let mut lot_x = 20.0;
            while lot_x < OUTDOOR_HALF - 8.0 {
                let (x, z) = (side * (lot_x + rng.range(-2.0, 2.0)), lot_z + rng.range(-2.0, 2.0));
                if rng.unit() < 0.6 {
                    let size = Vec3::new(rng.range(5.0, 12.0), rng.range(3.0, 25.0), rng.range(5.0, 11.0));
                    let grey = rng.range(0.55, 0.85);
                    let turn = Mat4::from_rotation_y(rng.range(-0.15, 0.15));
                    let shape = at(x, size.y / 2.0, z) * turn * Mat4::from_scale(size);
                    s.place("building", building, Vec3::new(grey, grey * 0.95, grey * 0.9), shape);
                } else {
                    for _ in 0..rng.range(2.0, 5.0) as u32 {
                        let tree = trees[(rng.next_u64() % trees.len() as u64) as usize];
                        let (tx, tz) = (x + rng.range(-5.0, 5.0), z + rng.range(-5.0, 5.0));
                        let scale = Mat4::from_scale(Vec3::splat(rng.range(2.0, 3.5)));
                        let turn = Mat4::from_rotation_y(rng.range(0.0, std::f32::consts::TAU));
                        s.place("tree", tree, Vec3::new(0.5, 0.38, 0.25), at(tx, 0.0, tz) * turn * scale);
                    }
                }
                for _ in 0..4 {
                    let (cx, cz) = (x + rng.range(-7.0, 7.0), z + rng.range(-7.0, 7.0));
                    let turn = Mat4::from_rotation_y(rng.range(0.0, std::f32::consts::TAU));
                    s.place("crate", crate_mesh, wood * 0.8, at(cx, 0.4, cz) * turn);
                }
                lot_x += 16.0;
            }
        }
        lot_z += 14.0;
    }
    // The camera looks along -z; the sun's horizontal direction of travel, then tilted down.
    let elevation = SUN_ELEVATION.to_radians();
    let horizontal = match sun {
        Sun::Side => Vec3::new(-0.71, 0.0, -0.71),
        Sun::Behind => Vec3::new(0.15, 0.0, -1.0).normalize(),
        Sun::Facing => Vec3::new(0.15, 0.0, 1.0).normalize(),
    };
    let travel = horizontal * elevation.cos() - Vec3::Y * elevation.sin();
    s.finish(
        Camera::look_at(Vec3::new(0.0, 1.7, OUTDOOR_HALF - 5.0), Vec3::new(0.0, 1.2, -OUTDOOR_HALF), 60.0),
        Light::directional(travel),
    )
}

pub(super) fn outdoor(p: &SceneParams) -> Scene {
    outdoor_with(p, Sun::Side)
}

pub(super) fn outdoor_behind(p: &SceneParams) -> Scene {
    outdoor_with(p, Sun::Behind)
}

pub(super) fn outdoor_facing(p: &SceneParams) -> Scene {
    outdoor_with(p, Sun::Facing)
}

/// Props: 3000 rocks, crates and posts strewn over a 70 m field, each kind one mesh placed again and again
/// (turned, scaled, crates sometimes stacked), under a low sun and a spot light over the middle.
pub(super) fn props(p: &SceneParams) -> Scene {
    const COUNT: usize = 3000;
    const HALF: f32 = 35.0;
    let mut rng = Rng::new(p.seed);
    let mut s = Stage::new().ground(2.0 * HALF + 10.0);
    let rock = s.mesh(rock());
    let crate_mesh = s.mesh(built(procedural::cuboid(Vec3::splat(0.8))));
    let post = s.mesh(built(procedural::cylinder(0.08, 1.6, 10)));
    let stone = s.material("rock", Vec3::new(0.55, 0.52, 0.48));
    let wood = s.material("crate", Vec3::new(0.62, 0.46, 0.3));
    let metal = s.material("post", Vec3::splat(0.4));
    for i in 0..COUNT {
        let (x, z) = (rng.range(-HALF, HALF), rng.range(-HALF, HALF));
        let turn = Quat::from_rotation_y(rng.range(0.0, std::f32::consts::TAU));
        match i % 10 {
            0..5 => {
                let size = rng.range(0.3, 1.1);
                let scale = Vec3::new(size * rng.range(0.8, 1.3), size * rng.range(0.5, 0.9), size);
                let tilt = Quat::from_rotation_x(rng.range(-0.3, 0.3));
                let shape = Mat4::from_scale_rotation_translation(scale, turn * tilt, Vec3::new(x, 0.1 * size, z));
                s.place_in("rock", rock, stone, shape);
            }
            5..8 => {
                let stacked = rng.unit() < 0.25;
                s.place_in("crate", crate_mesh, wood, Mat4::from_rotation_translation(turn, Vec3::new(x, 0.4, z)));
                if stacked {
                    let top = turn * Quat::from_rotation_y(rng.range(-0.4, 0.4));
                    s.place_in("crate", crate_mesh, wood, Mat4::from_rotation_translation(top, Vec3::new(x, 1.2, z)));
                }
            }
            _ => {
                let lean = Quat::from_rotation_z(rng.range(-0.12, 0.12));
                s.place_in("post", post, metal, Mat4::from_rotation_translation(turn * lean, Vec3::new(x, 0.0, z)));
            }
        }
    }
    // The sun from behind the camera's left, so the shadows run across the view towards it.
    let elevation = 30f32.to_radians();
    let sun = Vec3::new(0.87, 0.0, 0.5) * elevation.cos() - Vec3::Y * elevation.sin();
    let mut scene = s.finish(
        Camera::look_at(Vec3::new(0.0, 9.0, HALF + 4.0), Vec3::new(0.0, 0.0, 6.0), 55.0),
        Light::directional(sun),
    );
    scene.add_light(Light::spot(Vec3::new(3.0, 12.0, 22.0), Vec3::new(0.0, 0.0, 17.0), 70.0));
    scene
}

/// A yard of crates, posts and rocks (instances of three meshes) under 64 lights, spot and point lights
/// in turn, over an 8 x 8 grid and reaching 5, 8 or 12 units; the camera, above one side, looks down on
/// part of the yard and the lights over it.
pub(super) fn yard(p: &SceneParams) -> Scene {
    const COUNT: usize = 480;
    const HALF: f32 = 30.0;
    const SIDE: usize = 8;
    let mut rng = Rng::new(p.seed);
    let mut s = Stage::new().ground(2.0 * HALF + 10.0);
    let crate_mesh = s.mesh(built(procedural::cuboid(Vec3::splat(0.8))));
    let post = s.mesh(built(procedural::cylinder(0.08, 1.6, 10)));
    let rock = s.mesh(rock());
    let wood = s.material("crate", Vec3::new(0.62, 0.46, 0.3));
    let metal = s.material("post", Vec3::splat(0.4));
    let stone = s.material("rock", Vec3::new(0.55, 0.52, 0.48));
    for i in 0..COUNT {
        let (x, z) = (rng.range(-HALF, HALF), rng.range(-HALF, HALF));
        let turn = Quat::from_rotation_y(rng.range(0.0, std::f32::consts::TAU));
        match i % 4 {
            0 | 1 => {
                s.place_in("crate", crate_mesh, wood, Mat4::from_rotation_translation(turn, Vec3::new(x, 0.4, z)));
                if rng.unit() < 0.25 {
                    s.place_in("crate", crate_mesh, wood, Mat4::from_rotation_translation(turn, Vec3::new(x, 1.2, z)));
                }
            }
            2 => s.place_in("post", post, metal, Mat4::from_rotation_translation(turn, Vec3::new(x, 0.0, z))),
            _ => {
                let size = rng.range(0.5, 1.2);
                let shape = Mat4::from_scale_rotation_translation(Vec3::splat(size), turn, Vec3::new(x, 0.1 * size, z));
                s.place_in("rock", rock, stone, shape);
            }
        }
    }
    let spacing = 2.0 * HALF / SIDE as f32;
    let lights: Vec<Light> = (0..SIDE * SIDE)
        .map(|k| {
            let cell = |i: usize| -HALF + spacing * (i as f32 + 0.5);
            let jitter = Vec3::new(rng.range(-1.0, 1.0), 0.0, rng.range(-1.0, 1.0));
            let at = Vec3::new(cell(k % SIDE), rng.range(3.0, 6.0), cell(k / SIDE)) + jitter;
            let mut light = if k % 2 == 0 {
                let target = Vec3::new(at.x + rng.range(-1.5, 1.5), 0.0, at.z + rng.range(-1.5, 1.5));
                Light::spot(at, target, rng.range(60.0, 100.0))
            } else {
                Light::point(at)
            };
            light.range = Some([5.0, 8.0, 12.0][k % 3]);
            light.color = if k % 3 == 1 { Vec3::new(0.75, 0.85, 1.0) } else { Vec3::new(1.0, 0.85, 0.65) };
            light.intensity = 0.6;
            light
        })
        .collect();
    let mut scene = s.finish(Camera::look_at(Vec3::new(-10.0, 7.0, 26.0), Vec3::new(-4.0, 0.0, 12.0), 45.0), lights[0]);
    for &light in &lights[1..] {
        scene.add_light(light);
    }
    scene
}

/// A rock: a coarse sphere pushed in and out by a smooth function of where each vertex lies, so
/// vertices at one place (the seams) move together and the rock stays closed.
fn rock() -> Mesh {
    let sphere = built(procedural::sphere(0.5, 12, 8));
    let bumpy: Vec<Vec3> = sphere
        .positions()
        .iter()
        .map(|&q| {
            let bump = (7.1 * q.x + 1.7).sin() * (8.3 * q.y + 0.3).sin() * (6.7 * q.z + 2.1).sin();
            q * (1.0 + 0.3 * bump)
        })
        .collect();
    built(
        Mesh::new(bumpy, sphere.triangles().to_vec())
            .map_err(|source| procedural::ShapeError::Mesh { shape: "rock", source }),
    )
}
