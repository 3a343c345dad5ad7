//! Model loading: every crafted bad file gives an error naming the file and its fault; good files load
//! with the right geometry; the shared test models load with the right closedness.

use std::path::{Path, PathBuf};

use glam::{Mat4, Vec3};
use shadow_core::assets::{self, AssetFault};
use shadow_core::scene::LightKind;

fn data(p: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data").join(p)
}

/// (file, words the message must contain, fault kind check)
#[allow(clippy::type_complexity)]
const BAD: &[(&str, &str, fn(&AssetFault) -> bool)] = &[
    ("bad/missing_file.obj", "file not found", |f| matches!(f, AssetFault::NotFound(_))),
    ("bad/index_out_of_range.obj", "vertex index 9", |f| matches!(f, AssetFault::Malformed(_))),
    ("bad/nan_position.obj", "non-finite position", |f| matches!(f, AssetFault::Mesh(..))),
    ("bad/huge_position.obj", "too large for f32", |f| matches!(f, AssetFault::Mesh(..))),
    ("bad/no_area.obj", "zero area", |f| matches!(f, AssetFault::Mesh(..))),
    ("bad/lines_only.obj", "only lines or points", |f| matches!(f, AssetFault::Unsupported(_))),
    ("bad/empty.obj", "no faces", |f| matches!(f, AssetFault::Unsupported(_))),
    ("bad/bad_number.obj", "is not a number", |f| matches!(f, AssetFault::Malformed(_))),
    ("bad/draco.gltf", "Draco", |f| matches!(f, AssetFault::Unsupported(_))),
    ("bad/points_only.gltf", "only points or lines", |f| matches!(f, AssetFault::Unsupported(_))),
    ("bad/index_out_of_range.gltf", "vertex index 7", |f| matches!(f, AssetFault::Mesh(..))),
    ("bad/nan_position.gltf", "non-finite position", |f| matches!(f, AssetFault::Mesh(..))),
    ("bad/node_cycle.gltf", "own ancestor", |f| matches!(f, AssetFault::Cycle(_))),
    ("bad/wrong_accessor_type.gltf", "expected Vec3 of F32", |f| matches!(f, AssetFault::WrongAccessor(_))),
    ("bad/truncated_buffer.gltf", "declares 64", |f| matches!(f, AssetFault::Truncated(_))),
    ("bad/accessor_past_view.gltf", "past the end", |f| matches!(f, AssetFault::Truncated(_))),
    ("bad/missing_buffer_file.gltf", "no_such_buffer.bin", |f| matches!(f, AssetFault::NotFound(_))),
    ("bad/empty_mesh.gltf", "no triangles", |f| matches!(f, AssetFault::Mesh(..))),
    ("bad/not_json.gltf", "JSON", |f| matches!(f, AssetFault::Malformed(_))),
    ("bad/truncated.glb", "GLB header says", |f| matches!(f, AssetFault::Truncated(_))),
    ("bad/truncated_binary.ply", "ends at byte", |f| matches!(f, AssetFault::Truncated(_))),
    ("bad/huge_count.ply", "4000000000 entries", |f| matches!(f, AssetFault::Truncated(_))),
    ("bad/index_out_of_range.ply", "vertex index 5", |f| matches!(f, AssetFault::Mesh(..))),
    ("bad/nan_position.ply", "non-finite position", |f| matches!(f, AssetFault::Mesh(..))),
    ("bad/lines_only.ply", "only points or lines", |f| matches!(f, AssetFault::Unsupported(_))),
    ("bad/not_ply.ply", "does not start with 'ply'", |f| matches!(f, AssetFault::Malformed(_))),
    ("bad/corrupt.ply.gz", "gzip", |f| matches!(f, AssetFault::Truncated(_))),
    ("bad/model.stl", "unknown model format 'stl'", |f| matches!(f, AssetFault::UnknownFormat(_))),
];

#[test]
fn every_bad_file_names_itself_and_its_fault() {
    for (file, words, kind) in BAD {
        let path = data(file);
        let err = match assets::load(&path) {
            Ok(_) => panic!("{file} loaded"),
            Err(e) => e,
        };
        let msg = err.to_string();
        assert!(msg.starts_with(&path.display().to_string()), "{file}: message does not start with the path: {msg}");
        assert!(msg.contains(words), "{file}: '{msg}' lacks '{words}'");
        assert!(kind(&err.fault), "{file}: wrong fault kind {:?}", err.fault);
    }
}

#[test]
fn every_bad_file_in_the_folder_is_tested() {
    for entry in std::fs::read_dir(data("bad")).unwrap() {
        let name = format!("bad/{}", entry.unwrap().file_name().to_string_lossy());
        assert!(BAD.iter().any(|(f, _, _)| *f == name), "{name} has no test");
    }
}

#[test]
fn ply_in_every_encoding_gives_the_same_quad() {
    for f in ["good/quad_ascii.ply", "good/quad_le.ply", "good/quad_be.ply.gz"] {
        let s = assets::load(data(f)).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(s.triangle_count(), 2, "{f}");
        let b = s.bounds();
        assert_eq!((b.min, b.max), (Vec3::new(0.0, 0.0, -1.0), Vec3::new(1.0, 0.0, 0.0)), "{f}");
    }
}

#[test]
fn obj_polygons_are_triangulated_with_their_colour() {
    let s = assets::load(data("good/quad.obj")).unwrap();
    assert_eq!(s.triangle_count(), 2);
    let (_, _, _, mat) = s.drawables().next().unwrap();
    assert_eq!(mat.base_color, Vec3::new(0.9, 0.1, 0.1));
}

#[test]
fn gltf_hierarchy_strips_fans_camera_and_light() {
    let s = assets::load(data("good/hierarchy.gltf")).unwrap();
    // Parent: a strip of 4 indices (2 triangles); child: a fan of 4 vertices (2 triangles) and a line
    // primitive that is skipped.
    assert_eq!(s.triangle_count(), 4);
    let b = s.bounds();
    // Parent at (0, 1, 0) scaled 2: x 0..2; child 3 further along x in the parent's frame: x 6..8.
    assert_eq!((b.min.x, b.max.x), (0.0, 8.0));
    assert_eq!(b.min.y, 1.0);
    let (_, _, _, mat) = s.drawables().next().unwrap();
    assert_eq!(mat.base_color, Vec3::new(0.2, 0.4, 0.6));
    assert!(mat.two_sided);
    let cam = s.cameras().next().unwrap().1;
    assert_eq!(cam.eye, Vec3::new(0.0, 1.0, 5.0));
    let light = s.lights().next().unwrap().1;
    match light.kind {
        LightKind::Spot { position, direction, cone_angle } => {
            assert_eq!(position, Vec3::new(0.0, 4.0, 0.0));
            assert!((direction - Vec3::NEG_Y).length() < 1e-5, "{direction}");
            assert!((cone_angle - 1.0).abs() < 1e-6);
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn a_lamp_under_a_turned_scaled_parent_is_placed_by_the_whole_hierarchy() {
    let s = assets::load(data("good/lamp_under_turned_parent.gltf")).unwrap();
    let light = s.lights().next().unwrap().1;
    // Parent: at (1, 2, 0), a quarter turn about +y (+z goes to +x), scale 2; lamp 3 along the parent's
    // +z: 6 along world +x from the parent. It shines down its -z, world -x.
    match light.kind {
        LightKind::Spot { position, direction, cone_angle } => {
            assert!((position - Vec3::new(7.0, 2.0, 0.0)).length() < 1e-5, "{position}");
            assert!((direction - Vec3::NEG_X).length() < 1e-5, "{direction}");
            assert!((cone_angle - 0.8).abs() < 1e-6, "{cone_angle}");
        }
        other => panic!("{other:?}"),
    }
    assert!(light.inner_cone_angle.is_some_and(|a| (a - 0.4).abs() < 1e-6), "{:?}", light.inner_cone_angle);
    assert_eq!((light.intensity, light.range, light.color), (5.0, Some(10.0), Vec3::new(1.0, 0.5, 0.25)));
}

#[test]
fn a_lamp_follows_its_node_when_the_parent_moves_and_goes_with_it() {
    let mut s = assets::load(data("good/lamp_under_turned_parent.gltf")).unwrap();
    let (key, _) = s.lights().next().unwrap();
    let lamp = s.light_node(key).expect("the lamp follows its node");
    let parent = s.node(lamp).and_then(|n| n.parent()).expect("the lamp's node has a parent");
    // The parent moved 4 along world +z and turned back to face +z: the lamp is 6 along +z from it.
    let moved = Mat4::from_translation(Vec3::new(1.0, 2.0, 4.0)) * Mat4::from_scale(Vec3::splat(2.0));
    s.set_local_transform(parent, moved).unwrap();
    match s.world_light(key).unwrap().kind {
        LightKind::Spot { position, direction, .. } => {
            assert!((position - Vec3::new(1.0, 2.0, 10.0)).length() < 1e-5, "{position}");
            assert!((direction - Vec3::NEG_Z).length() < 1e-5, "{direction}");
        }
        other => panic!("{other:?}"),
    }
    s.remove_node(parent).unwrap();
    assert!(s.lights().next().is_none(), "the lamp outlived its node");
}

#[test]
fn glb_with_binary_chunk_loads() {
    let s = assets::load(data("good/triangle.glb")).unwrap();
    assert_eq!(s.triangle_count(), 1);
}

#[test]
fn shared_models_closedness() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/models");
    if !dir.exists() {
        eprintln!("skipping: {} not found", dir.display());
        return;
    }
    for (file, closed) in [("spot.obj", true), ("teapot.obj", false), ("cornell_box.obj", false)] {
        let s = assets::load(dir.join(file)).unwrap_or_else(|e| panic!("{e}"));
        let all_closed = s.drawables().all(|(_, _, m, _)| s.adjacency(m).unwrap().closed());
        assert_eq!(all_closed, closed, "{file}");
    }
}
