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

/// The bar of the bend tests: 0.5 either side of the y axis, from y = 0 to y = 2, vertices at y = 0, 1
/// and 2 (left then right), two triangles a storey.
fn bar() -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let positions = (0..3).flat_map(|y| [Vec3::new(-0.5, y as f32, 0.0), Vec3::new(0.5, y as f32, 0.0)]).collect();
    let triangles = vec![[0, 1, 3], [0, 3, 2], [2, 3, 5], [2, 5, 4]];
    (positions, triangles)
}

/// Its joints and weights: the foot storey to the lower joint, the middle halved, the top to the upper.
fn bar_weights() -> (Vec<[u16; 4]>, Vec<[f32; 4]>) {
    let joints = vec![[0, 1, 0, 0]; 6];
    let w = |lower: f32| [lower, 1.0 - lower, 0.0, 0.0];
    (joints, vec![w(1.0), w(1.0), w(0.5), w(0.5), w(0.0), w(0.0)])
}

/// The bar bent a quarter turn about +z at its middle joint, by hand: the upper joint's skin matrix is
/// T(0, 1, 0) Rz(90) T(0, -1, 0), which takes (x, y) to (1 - y, 1 + x) as Rz takes (x, y) to (-y, x). The
/// top corners (-0.5, 2) and (0.5, 2) go to (-1, 0.5) and (-1, 1.5); the middle ones, half on each
/// joint, to the mean of where each joint takes them: (-0.5, 1) and (0, 0.5) give (-0.25, 0.75), (0.5, 1)
/// and (0, 1.5) give (0.25, 1.25); the foot stays.
fn bent_bar() -> Vec<Vec3> {
    [(-0.5, 0.0), (0.5, 0.0), (-0.25, 0.75), (0.25, 1.25), (-1.0, 0.5), (-1.0, 1.5)]
        .map(|(x, y)| Vec3::new(x, y, 0.0))
        .to_vec()
}

fn assert_near(got: &[Vec3], want: &[Vec3]) {
    assert_eq!(got.len(), want.len());
    for (v, (g, w)) in got.iter().zip(want).enumerate() {
        assert!((*g - *w).length() < 1e-6, "vertex {v}: {g} against {w}");
    }
}

/// The frame's instance of the first drawn node: its posed positions in world space.
fn drawn(scene: &Scene) -> Vec<Vec3> {
    let camera = shadow_core::Camera::look_at(Vec3::new(0.0, 1.0, 5.0), Vec3::new(0.0, 1.0, 0.0), 45.0);
    let frame = shadow_core::FrameInputs::new(scene, camera, Vec::new()).unwrap();
    let i = &frame.instances[0];
    i.mesh.positions().iter().map(|p| i.world_from_local.transform_point3(*p)).collect()
}

/// A two-joint skin built through the scene's API and bent by an animation of the upper joint: the
/// frame's posed positions are the hand-computed ones, whatever the skinned node's own transform.
#[test]
fn a_two_joint_skin_bends_as_worked_out_by_hand() {
    use shadow_core::deform::{Deformers, SkinWeights};
    use shadow_core::scene::{Animation, Channel, Interpolation, Keyframes, Skin};
    let (positions, triangles) = bar();
    let (joints, weights) = bar_weights();
    let skin = Some(SkinWeights::new(joints, weights).unwrap());
    let mesh = shadow_core::Mesh::new(positions.clone(), triangles)
        .unwrap()
        .with_deformers(Deformers { skin, morph_targets: Vec::new() })
        .unwrap();
    let mut scene = Scene::new();
    let lower = scene.add_node("lower", None, Mat4::IDENTITY).unwrap();
    let upper = scene.add_node("upper", Some(lower), Mat4::from_translation(Vec3::Y)).unwrap();
    let m = scene.add_mesh(mesh);
    let grey = scene.add_material(shadow_core::Material::default());
    // The skinned node stands far off: glTF ignores its transform, the joints place the mesh.
    let body = scene.add_instance("body", m, grey, Mat4::from_translation(Vec3::new(5.0, 0.0, 0.0))).unwrap();
    let inverse_bind_matrices = vec![Mat4::IDENTITY, Mat4::from_translation(Vec3::NEG_Y)];
    let skin = scene.add_skin(Skin { name: "legs".into(), joints: vec![lower, upper], inverse_bind_matrices }).unwrap();
    scene.set_skin(body, Some(skin)).unwrap();
    assert_near(&drawn(&scene), &positions);
    let bend = Quat::from_rotation_z(std::f32::consts::FRAC_PI_2);
    let c = Channel {
        node: upper,
        times: vec![0.0, 1.0],
        interpolation: Interpolation::Linear,
        values: Keyframes::Rotation(vec![Quat::IDENTITY, bend]),
    };
    scene.add_animation(Animation::new("bend", vec![c]).unwrap()).unwrap();
    scene.pose(1.0).unwrap();
    assert_near(&drawn(&scene), &bent_bar());
    // The scene's bounds follow the pose: the top now reaches x = -1.
    assert!((scene.bounds().min.x + 1.0).abs() < 1e-6, "{:?}", scene.bounds());
    // A skin whose joints the mesh's weights outnumber is refused.
    let one = Skin { name: "short".into(), joints: vec![lower], inverse_bind_matrices: vec![Mat4::IDENTITY] };
    let short = scene.add_skin(one).unwrap();
    let e = scene.set_skin(body, Some(short)).unwrap_err().to_string();
    assert!(e.contains("its mesh names joint 1, but skin 'short' has 1 joints"), "{e}");
}

/// Morph targets through the scene's API, their weights keyed by an animation: the base plus each
/// target's displacement times its weight, by hand.
#[test]
fn morph_targets_move_by_their_weights() {
    use shadow_core::deform::{Deformers, MorphTarget};
    use shadow_core::scene::{Animation, Channel, Interpolation, Keyframes};
    let (positions, triangles) = bar();
    let up = MorphTarget { positions: vec![Vec3::Y; 6], normals: None };
    let out = MorphTarget { positions: (0..6).map(|v| Vec3::new(0.0, 0.0, v as f32)).collect(), normals: None };
    let mesh = shadow_core::Mesh::new(positions.clone(), triangles)
        .unwrap()
        .with_deformers(Deformers { skin: None, morph_targets: vec![up, out] })
        .unwrap();
    let mut scene = Scene::new();
    let m = scene.add_mesh(mesh);
    let grey = scene.add_material(shadow_core::Material::default());
    let node = scene.add_instance("blob", m, grey, Mat4::from_translation(Vec3::X)).unwrap();
    scene.set_morph_weights(node, vec![0.5, 0.0]).unwrap();
    let want = |a: f32, b: f32| -> Vec<Vec3> {
        positions
            .iter()
            .enumerate()
            .map(|(v, p)| *p + Vec3::X + Vec3::Y * a + Vec3::new(0.0, 0.0, v as f32) * b)
            .collect()
    };
    assert_near(&drawn(&scene), &want(0.5, 0.0));
    // Weights keyed from (0.5, 0) at 0 s to (1, 2) at 2 s, LINEAR: at 1 s, (0.75, 1).
    let c = Channel {
        node,
        times: vec![0.0, 2.0],
        interpolation: Interpolation::Linear,
        values: Keyframes::Weights { targets: 2, values: vec![0.5, 0.0, 1.0, 2.0] },
    };
    scene.add_animation(Animation::new("swell", vec![c]).unwrap()).unwrap();
    scene.pose(1.0).unwrap();
    assert_eq!(scene.morph_weights(node), &[0.75, 1.0]);
    assert_near(&drawn(&scene), &want(0.75, 1.0));
    let bad = Channel {
        node,
        times: vec![0.0],
        interpolation: Interpolation::Step,
        values: Keyframes::Weights { targets: 2, values: vec![0.5, 0.0, 1.0] },
    };
    let e = Animation::new("odd", vec![bad]).unwrap_err().to_string();
    assert!(e.contains("3 weights do not make keys of 2 targets"), "{e}");
}

/// The bar as a glTF mesh: POSITION, indices, the `attributes` given, and its morph `targets`.
fn bar_mesh(g: &mut Gltf, attributes: Value, targets: Value) -> Value {
    let (positions, triangles) = bar();
    let p: Vec<f32> = positions.iter().flat_map(|p| p.to_array()).collect();
    let idx: Vec<u16> = triangles.iter().flatten().map(|&i| i as u16).collect();
    let pos =
        g.accessor(bytemuck::cast_slice(&p), 5126, "VEC3", 6, json!({"min": [-0.5, 0.0, 0.0], "max": [0.5, 2.0, 0.0]}));
    let indices = g.accessor(bytemuck::cast_slice(&idx), 5123, "SCALAR", idx.len(), json!({}));
    let mut attrs = json!({"POSITION": pos});
    if let (Some(a), Some(extra)) = (attrs.as_object_mut(), attributes.as_object()) {
        a.extend(extra.clone());
    }
    json!({"primitives": [{"attributes": attrs, "indices": indices, "targets": targets}]})
}

/// A skinned bar written as glTF: joints as unsigned bytes, weights as floats, the inverse bind matrices,
/// the body node far off (ignored, as glTF asks); `weights` replaces the bar's.
fn skinned_bar(dir: &Path, weights: &[[f32; 4]], inverse_binds: usize) -> PathBuf {
    let mut g = Gltf::default();
    let (joints, _) = bar_weights();
    let j: Vec<u8> = joints.iter().flatten().map(|&j| j as u8).collect();
    let w: Vec<f32> = weights.iter().flatten().copied().collect();
    let joints = g.accessor(&j, 5121, "VEC4", 6, json!({}));
    let weights = g.floats(&w, "VEC4");
    let mesh = bar_mesh(&mut g, json!({"JOINTS_0": joints, "WEIGHTS_0": weights}), json!([]));
    let binds: Vec<f32> = [Mat4::IDENTITY, Mat4::from_translation(Vec3::NEG_Y)]
        .iter()
        .take(inverse_binds)
        .flat_map(|m| m.to_cols_array())
        .collect();
    let binds = g.floats(&binds, "MAT4");
    let times = g.floats(&[0.0, 1.0], "SCALAR");
    let bend = Quat::from_rotation_z(std::f32::consts::FRAC_PI_2);
    let turn = g.floats(&[0.0, 0.0, 0.0, 1.0, bend.x, bend.y, bend.z, bend.w], "VEC4");
    g.write(
        dir,
        json!({
            "scenes": [{"nodes": [0, 1]}],
            "nodes": [
                {"name": "body", "mesh": 0, "skin": 0, "translation": [5.0, 0.0, 0.0]},
                {"name": "lower", "children": [2]},
                {"name": "upper", "translation": [0.0, 1.0, 0.0]},
            ],
            "meshes": [mesh],
            "skins": [{"name": "legs", "joints": [1, 2], "inverseBindMatrices": binds}],
            "animations": [{
                "name": "bend",
                "samplers": [{"input": times, "output": turn}],
                "channels": [{"sampler": 0, "target": {"node": 2, "path": "rotation"}}],
            }],
        }),
    )
}

/// A two-joint skin written as glTF and bent a quarter turn: the posed vertices are the ones worked out
/// by hand.
#[test]
fn a_skinned_gltf_bends_as_worked_out_by_hand() {
    let dir = folder("skin");
    let (_, weights) = bar_weights();
    let mut scene = load(&skinned_bar(&dir, &weights, 2));
    assert!(scene.warnings().is_empty(), "{:?}", scene.warnings());
    assert_eq!(scene.skins().count(), 1);
    assert_near(&drawn(&scene), &bar().0);
    scene.pose(1.0).unwrap();
    assert_near(&drawn(&scene), &bent_bar());
}

#[test]
fn bad_skins_are_refused_by_name() {
    let (_, mut weights) = bar_weights();
    let e = assets::load(skinned_bar(&folder("binds"), &weights, 1)).map(|_| ()).unwrap_err().to_string();
    assert!(e.contains("skin 'legs': 1 inverse bind matrices for 2 joints"), "{e}");
    weights[3] = [0.0; 4];
    let e = assets::load(skinned_bar(&folder("zero"), &weights, 2)).map(|_| ()).unwrap_err().to_string();
    assert!(e.contains("mesh 0 primitive 0: vertex 3's weights sum to zero"), "{e}");
}

/// Morph targets written as glTF, the mesh's default weights and an animation of them (CUBICSPLINE with
/// flat tangents, so halfway is the mean): the posed vertices by hand.
#[test]
fn gltf_morph_targets_and_their_weights_play() {
    let dir = folder("morph");
    let mut g = Gltf::default();
    let up = g.floats(&[0.0, 1.0, 0.0].repeat(6), "VEC3");
    let out: Vec<f32> = (0..6).flat_map(|v| [0.0, 0.0, v as f32]).collect();
    let out = g.floats(&out, "VEC3");
    let mut mesh = bar_mesh(&mut g, json!({}), json!([{"POSITION": up}, {"POSITION": out}]));
    mesh["weights"] = json!([0.5, 0.0]);
    let times = g.floats(&[0.0, 2.0], "SCALAR");
    // Per key: in-tangents (2), values (2), out-tangents (2).
    let keys = g.floats(&[0.0, 0.0, 0.5, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 2.0, 0.0, 0.0], "SCALAR");
    let path = g.write(
        &dir,
        json!({
            "scenes": [{"nodes": [0]}],
            "nodes": [{"name": "blob", "mesh": 0, "translation": [1.0, 0.0, 0.0]}],
            "meshes": [mesh],
            "animations": [{
                "name": "swell",
                "samplers": [{"input": times, "output": keys, "interpolation": "CUBICSPLINE"}],
                "channels": [{"sampler": 0, "target": {"node": 0, "path": "weights"}}],
            }],
        }),
    );
    let mut scene = load(&path);
    let want = |a: f32, b: f32| -> Vec<Vec3> {
        bar()
            .0
            .iter()
            .enumerate()
            .map(|(v, p)| *p + Vec3::X + Vec3::Y * a + Vec3::new(0.0, 0.0, v as f32) * b)
            .collect()
    };
    assert_near(&drawn(&scene), &want(0.5, 0.0));
    scene.pose(1.0).unwrap();
    assert_near(&drawn(&scene), &want(0.75, 1.0));
}

/// Every drawn instance's world-space positions, by node name.
fn placed(scene: &Scene) -> std::collections::BTreeMap<String, Vec<Vec3>> {
    let camera = shadow_core::Camera::look_at(Vec3::new(0.0, 1.0, 9.0), Vec3::ZERO, 45.0);
    let frame = shadow_core::FrameInputs::new(scene, camera, Vec::new()).unwrap();
    frame
        .instances
        .iter()
        .map(|i| {
            let name = scene.node(i.node).unwrap().name().to_string();
            (name, i.mesh.positions().iter().map(|p| i.world_from_local.transform_point3(*p)).collect())
        })
        .collect()
}

/// The Khronos validator's error and warning counts on a file, where `SHADOWLAB_GLTF_VALIDATOR` names
/// its `node_modules` folder (as CI sets it); `None` without it.
fn validator_counts(path: &Path) -> Option<(u64, u64, String)> {
    let modules = std::env::var_os("SHADOWLAB_GLTF_VALIDATOR")?;
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/validate_gltf.cjs");
    let out = std::process::Command::new("node").arg(script).arg(path).env("NODE_PATH", modules).output().ok()?;
    let report: Value = serde_json::from_slice(&out.stdout).ok()?;
    Some((report["numErrors"].as_u64()?, report["numWarnings"].as_u64()?, report["messages"].to_string()))
}

/// `walker` (a skin of eleven joints, CUBICSPLINE and LINEAR keys) and `mill` (node animation), and the
/// morph targets' file, exported and loaded back: posed at several times, every vertex stands where the
/// original's does, and the Khronos validator finds no error or warning in what was written.
#[test]
fn exported_animations_play_back_the_same() {
    let dir = folder("export");
    let mut morph = {
        // The morph test's file, loaded.
        let mut g = Gltf::default();
        let up = g.floats(&[0.0, 1.0, 0.0].repeat(6), "VEC3");
        let mut mesh = bar_mesh(&mut g, json!({}), json!([{"POSITION": up}]));
        mesh["weights"] = json!([0.25]);
        let times = g.floats(&[0.0, 1.0], "SCALAR");
        let keys = g.floats(&[0.25, 1.0], "SCALAR");
        let path = g.write(
            &dir,
            json!({
                "scenes": [{"nodes": [0]}],
                "nodes": [{"name": "blob", "mesh": 0}],
                "meshes": [mesh],
                "animations": [{"name": "swell", "samplers": [{"input": times, "output": keys}],
                    "channels": [{"sampler": 0, "target": {"node": 0, "path": "weights"}}]}],
            }),
        );
        load(&path)
    };
    let mut walker = shadow_core::scenes::build("walker", &Default::default()).unwrap();
    let mut mill = shadow_core::scenes::build("mill", &Default::default()).unwrap();
    for (name, scene) in [("walker", &mut walker), ("mill", &mut mill), ("morph", &mut morph)] {
        for file in [format!("{name}.glb"), format!("{name}.gltf")] {
            let out = dir.join(&file);
            assets::export::export(scene, &out).unwrap();
            let mut back = load(&out);
            assert_eq!(back.animations().count(), scene.animations().count(), "{file}");
            let duration = scene.animation_duration();
            for t in [0.0, 0.37 * duration, duration] {
                scene.pose(t).unwrap();
                back.pose(t).unwrap();
                let (want, got) = (placed(scene), placed(&back));
                assert_eq!(want.keys().collect::<Vec<_>>(), got.keys().collect::<Vec<_>>(), "{file}");
                for (node, w) in &want {
                    let g = &got[node];
                    let worst = w.iter().zip(g).map(|(a, b)| (*a - *b).length()).fold(0.0f32, f32::max);
                    assert!(worst < 1e-4, "{file} at {t} s: {node} off by {worst}");
                }
            }
            if let Some((errors, warnings, messages)) = validator_counts(&out) {
                assert_eq!((errors, warnings), (0, 0), "{file}: {messages}");
            }
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}
