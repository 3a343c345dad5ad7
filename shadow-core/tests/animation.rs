//! Animated glTF: node animations read into the scene graph and posed at a time, checked against poses
//! worked out by hand; bad animation data refused with one line naming the animation and the channel.
//! Every file is written here.

use std::path::{Path, PathBuf};

use glam::{Mat4, Quat, Vec3};
use serde_json::{Value, json};
use shadow_core::Scene;
use shadow_core::assets;

/// A fresh folder for one test's files.
fn folder(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("shadowlab-animation-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp folder");
    dir
}

/// A glTF document under construction: one binary buffer, an accessor (with a view of its own) per call.
#[derive(Default)]
struct Gltf {
    bin: Vec<u8>,
    views: Vec<Value>,
    accessors: Vec<Value>,
}

impl Gltf {
    /// Adds `data` as an accessor of `kind` ("SCALAR", "VEC3", ...) with `component` (5126 float, ...);
    /// returns its index.
    fn accessor(&mut self, data: &[u8], component: u32, kind: &str, count: usize, extra: Value) -> usize {
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        self.views.push(json!({"buffer": 0, "byteOffset": self.bin.len(), "byteLength": data.len()}));
        self.bin.extend_from_slice(data);
        let mut a =
            json!({"bufferView": self.views.len() - 1, "componentType": component, "count": count, "type": kind});
        if let (Some(a), Some(extra)) = (a.as_object_mut(), extra.as_object()) {
            a.extend(extra.clone());
        }
        self.accessors.push(a);
        self.accessors.len() - 1
    }

    fn floats(&mut self, values: &[f32], kind: &str) -> usize {
        let per = match kind {
            "SCALAR" => 1,
            "VEC2" => 2,
            "VEC3" => 3,
            "VEC4" => 4,
            _ => 16,
        };
        let extra = if kind == "SCALAR" {
            let (lo, hi) = values.iter().fold((f32::MAX, f32::MIN), |(l, h), &v| (l.min(v), h.max(v)));
            json!({"min": [lo], "max": [hi]})
        } else {
            json!({})
        };
        self.accessor(bytemuck::cast_slice(values), 5126, kind, values.len() / per, extra)
    }

    /// A unit cube's corners and its twelve triangles: (POSITION accessor, indices accessor).
    fn cube(&mut self) -> (usize, usize) {
        let p: Vec<f32> =
            (0..8).flat_map(|i| [(i & 1) as f32 - 0.5, (i >> 1 & 1) as f32 - 0.5, (i >> 2) as f32 - 0.5]).collect();
        let idx: [u16; 36] = [
            0, 2, 1, 1, 2, 3, 4, 5, 6, 5, 7, 6, 0, 1, 4, 1, 5, 4, 2, 6, 3, 3, 6, 7, 0, 4, 2, 2, 4, 6, 1, 3, 5, 3, 7, 5,
        ];
        let positions = self.accessor(
            bytemuck::cast_slice(&p),
            5126,
            "VEC3",
            8,
            json!({"min": [-0.5, -0.5, -0.5], "max": [0.5, 0.5, 0.5]}),
        );
        let indices = self.accessor(bytemuck::cast_slice(&idx), 5123, "SCALAR", 36, json!({}));
        (positions, indices)
    }

    /// Writes the document with `rest` (nodes, meshes, animations, ...) merged in.
    fn write(self, dir: &Path, rest: Value) -> PathBuf {
        let mut doc = json!({
            "asset": {"version": "2.0"},
            "accessors": self.accessors,
            "bufferViews": self.views,
            "buffers": [{"byteLength": self.bin.len(), "uri": "data.bin"}],
        });
        if let (Some(d), Some(r)) = (doc.as_object_mut(), rest.as_object()) {
            d.extend(r.clone());
        }
        std::fs::write(dir.join("data.bin"), &self.bin).expect("write bin");
        let path = dir.join("model.gltf");
        std::fs::write(&path, doc.to_string()).expect("write gltf");
        path
    }
}

fn load(path: &Path) -> Scene {
    assets::load(path).unwrap_or_else(|e| panic!("{e}"))
}

fn world(scene: &Scene, name: &str) -> Mat4 {
    let key = scene.depth_first().into_iter().find(|&k| scene.node(k).unwrap().name() == name).expect(name);
    scene.node(key).unwrap().world_transform()
}

/// A hinge at (1, 0, 0) swings a door (one unit along +x from it) a quarter turn about +y over a second
/// (LINEAR), a lift steps up at 0.5 s (STEP), and a box grows along a spline: at 0.25 s every pose is
/// worked out by hand.
#[test]
fn node_animations_play_as_gltf_samples_them() {
    let dir = folder("nodes");
    let mut g = Gltf::default();
    let (positions, indices) = g.cube();
    let times = g.floats(&[0.0, 1.0], "SCALAR");
    let turn = Quat::from_rotation_y(std::f32::consts::FRAC_PI_2);
    let rotations = g.floats(&[0.0, 0.0, 0.0, 1.0, turn.x, turn.y, turn.z, turn.w], "VEC4");
    let lift = g.floats(&[0.0, 0.0, 0.0, 0.0, 2.0, 0.0], "VEC3");
    let step_times = g.floats(&[0.0, 0.5], "SCALAR");
    // Scale x from 1 to 3 over a second, out-tangent 4 at the first key, in-tangent 0 at the second.
    let spline =
        g.floats(&[0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 4.0, 0.0, 0.0, 0.0, 0.0, 0.0, 3.0, 1.0, 1.0, 0.0, 0.0, 0.0], "VEC3");
    let path = g.write(
        &dir,
        json!({
            "scene": 0,
            "scenes": [{"nodes": [0, 2, 3]}],
            "nodes": [
                {"name": "hinge", "translation": [1.0, 0.0, 0.0], "children": [1]},
                {"name": "door", "translation": [1.0, 0.0, 0.0], "mesh": 0},
                {"name": "lift", "mesh": 0},
                {"name": "box", "translation": [0.0, 0.0, 5.0], "mesh": 0},
            ],
            "meshes": [{"primitives": [{"attributes": {"POSITION": positions}, "indices": indices}]}],
            "animations": [{
                "name": "open",
                "samplers": [
                    {"input": times, "output": rotations},
                    {"input": step_times, "output": lift, "interpolation": "STEP"},
                    {"input": times, "output": spline, "interpolation": "CUBICSPLINE"},
                ],
                "channels": [
                    {"sampler": 0, "target": {"node": 0, "path": "rotation"}},
                    {"sampler": 1, "target": {"node": 2, "path": "translation"}},
                    {"sampler": 2, "target": {"node": 3, "path": "scale"}},
                ],
            }],
        }),
    );
    let mut scene = load(&path);
    let (_, open) = scene.animations().next().expect("an animation");
    assert_eq!((open.name(), open.channels().len(), open.duration()), ("open", 3, 1.0));
    assert!(scene.warnings().is_empty(), "{:?}", scene.warnings());
    // At rest (before posing) the door stands where the file puts it.
    assert_eq!(world(&scene, "door").w_axis.truncate(), Vec3::new(2.0, 0.0, 0.0));
    scene.pose(0.25).unwrap();
    // An eighth of the way round... a quarter of a quarter turn: 22.5 degrees about +y from the hinge.
    let a = std::f32::consts::FRAC_PI_8;
    let door = world(&scene, "door").w_axis.truncate();
    assert!((door - Vec3::new(1.0 + a.cos(), 0.0, -a.sin())).length() < 1e-6, "{door}");
    assert_eq!(world(&scene, "lift").w_axis.truncate(), Vec3::ZERO, "the step has not come");
    // Hermite at s = 1/4 over one second: 27/32 * 1 + 9/64 * 4 + 5/32 * 3 + (-3/64) * 0 = 1.875.
    let sx = world(&scene, "box").x_axis.length();
    assert!((sx - 1.875).abs() < 1e-6, "{sx}");
    scene.pose(0.75).unwrap();
    assert_eq!(world(&scene, "lift").w_axis.truncate(), Vec3::new(0.0, 2.0, 0.0));
    scene.pose(5.0).unwrap();
    let door = world(&scene, "door").w_axis.truncate();
    assert!((door - Vec3::new(1.0, 0.0, -1.0)).length() < 1e-6, "after the end the last key holds: {door}");
}

/// One document with one flaw, written and loaded: the error is one line naming the animation, the
/// channel and the flaw.
fn refused(name: &str, times: &[f32], output: (&[f32], &str), node: Value, interpolation: &str) -> String {
    let dir = folder(name);
    let mut g = Gltf::default();
    let (positions, indices) = g.cube();
    let input = g.floats(times, "SCALAR");
    let output = g.floats(output.0, output.1);
    let path = g.write(
        &dir,
        json!({
            "scenes": [{"nodes": [0]}],
            "nodes": [node],
            "meshes": [{"primitives": [{"attributes": {"POSITION": positions}, "indices": indices}]}],
            "animations": [{
                "name": "bad",
                "samplers": [{"input": input, "output": output, "interpolation": interpolation}],
                "channels": [{"sampler": 0, "target": {"node": 0, "path": "translation"}}],
            }],
        }),
    );
    let e = assets::load(&path).map(|_| ()).expect_err(name).to_string();
    assert!(!e.contains('\n'), "{e}");
    e
}

#[test]
fn bad_animation_data_is_refused_by_animation_and_channel() {
    let node = json!({"mesh": 0});
    let e = refused("order", &[0.0, 2.0, 1.0], (&[0.0; 9], "VEC3"), node.clone(), "LINEAR");
    assert!(e.contains("animation 'bad', channel 0 (translation of node 0): key times are not increasing"), "{e}");
    let e = refused("count", &[0.0, 1.0], (&[0.0; 9], "VEC3"), node.clone(), "LINEAR");
    assert!(e.contains("2 keys with LINEAR interpolation need 2 values, not 3"), "{e}");
    let e = refused("spline", &[0.0, 1.0], (&[0.0; 6], "VEC3"), node.clone(), "CUBICSPLINE");
    assert!(e.contains("2 keys with CUBICSPLINE interpolation need 6 values, not 2"), "{e}");
    let e = refused("type", &[0.0, 1.0], (&[0.0; 4], "VEC2"), node, "LINEAR");
    assert!(e.contains("channel 0 (translation of node 0): wrong accessor type"), "{e}");
    let matrix = json!({"mesh": 0, "matrix": [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]});
    let e = refused("matrix", &[0.0], (&[0.0; 3], "VEC3"), matrix, "LINEAR");
    assert!(e.contains("given by a matrix"), "{e}");
}
