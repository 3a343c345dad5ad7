//! Structurally hostile model files, generated here: files that name other files, deep and wide node
//! graphs, transforms that overflow world space, offsets near 2^64, crate-level panics, lines and
//! strips, and malformed numbers. Each must give a one-line error naming the file and the place in it,
//! or load correctly; none may panic, abort or read what it was not asked to.

use std::path::{Path, PathBuf};
use std::time::Instant;

use glam::Vec3;
use shadow_core::assets::{self, AssetFault, FileAccess, LoadOptions};

/// A fresh folder under the system's temp folder for one test.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("shadowlab-hostile-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp folder");
    dir
}

fn write(path: &Path, bytes: impl AsRef<[u8]>) -> PathBuf {
    std::fs::write(path, bytes).expect("write test file");
    path.to_path_buf()
}

/// One triangle's positions: 36 bytes, little-endian f32.
fn triangle_bytes() -> Vec<u8> {
    [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0].iter().flat_map(|f| f.to_le_bytes()).collect()
}

/// A glTF whose one buffer has the given URI and byte length, drawn by the given nodes.
fn gltf_with(uri: &str, byte_length: usize, nodes: &str, scene_nodes: Option<&str>) -> String {
    let scene = scene_nodes.map_or(String::new(), |n| format!(r#""scene": 0, "scenes": [{{"nodes": [{n}]}}],"#));
    format!(
        r#"{{"asset": {{"version": "2.0"}}, {scene}
  "nodes": [{nodes}],
  "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0}}}}]}}],
  "accessors": [{{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                  "min": [0, 0, 0], "max": [1, 1, 0]}}],
  "bufferViews": [{{"buffer": 0, "byteLength": 36}}],
  "buffers": [{{"uri": "{uri}", "byteLength": {byte_length}}}]}}"#
    )
}

fn load_err(path: &Path) -> (String, AssetFault) {
    match assets::load(path) {
        Ok(_) => panic!("{} loaded", path.display()),
        Err(e) => (e.to_string(), e.fault),
    }
}

fn assert_one_line_naming(msg: &str, path: &Path, words: &[&str]) {
    assert!(msg.starts_with(&path.display().to_string()), "does not start with the file: {msg}");
    assert!(!msg.contains('\n'), "more than one line: {msg}");
    for w in words {
        assert!(msg.contains(w), "'{msg}' lacks '{w}'");
    }
}

// ---- files a model names ----

#[test]
fn gltf_buffers_stay_inside_the_model_folder() {
    let dir = scratch("uri");
    write(&dir.join("tri.bin"), triangle_bytes());
    std::fs::create_dir_all(dir.join("model/sub")).expect("sub folder");
    write(&dir.join("model/tri.bin"), triangle_bytes());
    let node = r#"{"mesh": 0}"#;

    let inside = write(&dir.join("model/inside.gltf"), gltf_with("sub/../tri.bin", 36, node, Some("0")));
    assert_eq!(assets::load(&inside).expect("a relative URI inside the folder loads").triangle_count(), 1);

    for (name, uri, words, outside) in [
        ("absolute.gltf", "/etc/passwd", &["buffer 0", "absolute path"][..], true),
        ("device.gltf", "/dev/zero", &["buffer 0", "absolute path"][..], true),
        ("parent.gltf", "../tri.bin", &["buffer 0", "outside the model's folder"][..], true),
        ("scheme.gltf", "https://example.invalid/tri.bin", &["buffer 0", "https"][..], false),
    ] {
        let path = write(&dir.join("model").join(name), gltf_with(uri, 36, node, Some("0")));
        let (msg, fault) = load_err(&path);
        assert_one_line_naming(&msg, &path, words);
        let kind = if outside {
            matches!(fault, AssetFault::OutsideFolder(_))
        } else {
            matches!(fault, AssetFault::Access(_))
        };
        assert!(kind, "{name}: {fault:?}");
    }

    // Wider access is the user's choice: then `..` and absolute paths resolve, but a device still does not.
    let wide = LoadOptions { file_access: FileAccess::Anywhere, ..LoadOptions::default() };
    let parent = dir.join("model/parent.gltf");
    assert_eq!(assets::load_with(&parent, &wide).expect("wide access loads ../").triangle_count(), 1);
    let device = dir.join("model/device.gltf");
    let Err(e) = assets::load_with(&device, &wide) else { panic!("a device was read") };
    assert!(e.to_string().contains("not a regular file"), "{e}");
}

#[cfg(unix)]
#[test]
fn a_link_out_of_the_model_folder_is_refused() {
    let dir = scratch("link");
    write(&dir.join("secret.bin"), triangle_bytes());
    std::fs::create_dir_all(dir.join("model")).expect("model folder");
    std::os::unix::fs::symlink(dir.join("secret.bin"), dir.join("model/tri.bin")).expect("symlink");
    let path = write(&dir.join("model/m.gltf"), gltf_with("tri.bin", 36, r#"{"mesh": 0}"#, Some("0")));
    let (msg, _) = load_err(&path);
    assert_one_line_naming(&msg, &path, &["outside the model's folder"]);
}

#[test]
fn a_buffer_is_read_only_to_its_byte_length() {
    let dir = scratch("length");
    // Ten megabytes behind a 36-byte buffer: the loader reads 36 of them (and the file still loads).
    let mut big = triangle_bytes();
    big.resize(10 << 20, 0xff);
    write(&dir.join("big.bin"), &big);
    let path = write(&dir.join("m.gltf"), gltf_with("big.bin", 36, r#"{"mesh": 0}"#, Some("0")));
    assert_eq!(assets::load(&path).expect("loads").triangle_count(), 1);
    let mut file = std::fs::File::open(dir.join("big.bin")).expect("open");
    assert_eq!(assets::read_at_most(&mut file, 36).expect("read").len(), 36);
}

#[test]
fn obj_material_libraries_follow_the_same_rules() {
    let dir = scratch("mtllib");
    std::fs::create_dir_all(dir.join("model")).expect("model folder");
    write(&dir.join("outside.mtl"), "newmtl red\nKd 0.9 0.1 0.1\n");
    write(&dir.join("model/inside.mtl"), "newmtl red\nKd 0.9 0.1 0.1\n");
    let obj = |lib: &str| format!("mtllib {lib}\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl red\nf 1 2 3\n");
    let colour = |path: &Path, options: &LoadOptions| {
        let s = assets::load_with(path, options).expect("an OBJ with an unreadable library still loads");
        s.drawables().next().expect("one drawable").3.base_color
    };
    let default = LoadOptions::default();
    let inside = write(&dir.join("model/inside.obj"), obj("inside.mtl"));
    assert_eq!(colour(&inside, &default), Vec3::new(0.9, 0.1, 0.1));
    let outside = write(&dir.join("model/outside.obj"), obj("../outside.mtl"));
    assert_eq!(colour(&outside, &default), Vec3::splat(0.8), "a library outside the folder was read");
    let absolute = write(&dir.join("model/absolute.obj"), obj(&dir.join("outside.mtl").display().to_string()));
    assert_eq!(colour(&absolute, &default), Vec3::splat(0.8), "an absolute library path was read");
    let wide = LoadOptions { file_access: FileAccess::Anywhere, ..LoadOptions::default() };
    assert_eq!(colour(&outside, &wide), Vec3::new(0.9, 0.1, 0.1));
}

#[test]
fn the_model_itself_must_be_a_regular_file() {
    let dir = scratch("fifo-or-folder");
    let folder = dir.join("looks.obj");
    std::fs::create_dir_all(&folder).expect("folder");
    let (msg, _) = load_err(&folder);
    assert_one_line_naming(&msg, &folder, &["not a regular file"]);
}

// ---- node graphs ----

/// `n` nodes chained parent to child, the last drawing the triangle.
fn chain(n: usize) -> String {
    (0..n)
        .map(|i| if i + 1 < n { format!(r#"{{"children": [{}]}}"#, i + 1) } else { r#"{"mesh": 0}"#.into() })
        .collect::<Vec<_>>()
        .join(",")
}

#[test]
fn a_deep_hierarchy_loads_without_recursion() {
    let dir = scratch("deep");
    write(&dir.join("tri.bin"), triangle_bytes());
    let path = write(&dir.join("deep.gltf"), gltf_with("tri.bin", 36, &chain(20_000), Some("0")));
    let t = Instant::now();
    let mut s = assets::load(&path).expect("20 000 nested nodes load");
    eprintln!("20 000 nested nodes: {:.2} s", t.elapsed().as_secs_f64());
    assert_eq!(s.triangle_count(), 1);
    assert_eq!(s.node_count(), 20_000);
    shadow_core::scenes::stage_model(&mut s, true);
    assert_eq!(s.triangle_count(), 3);
}

#[test]
fn a_cycle_deep_in_a_chain_is_named() {
    let dir = scratch("deep-cycle");
    write(&dir.join("tri.bin"), triangle_bytes());
    let mut nodes: Vec<String> = (0..5_000).map(|i| format!(r#"{{"children": [{}]}}"#, i + 1)).collect();
    nodes.push(r#"{"mesh": 0, "children": [4000]}"#.into());
    let path = write(&dir.join("cycle.gltf"), gltf_with("tri.bin", 36, &nodes.join(","), Some("0")));
    let (msg, fault) = load_err(&path);
    assert_one_line_naming(&msg, &path, &["node 4000"]);
    assert!(matches!(fault, AssetFault::Cycle(_)), "{fault:?}");
}

/// Loads and stages a scene, printing the time (reported, never asserted).
fn load_and_stage(path: &Path, what: &str) -> shadow_core::Scene {
    let t = Instant::now();
    let mut s = assets::load(path).unwrap_or_else(|e| panic!("{what}: {e}"));
    shadow_core::scenes::stage_model(&mut s, true);
    eprintln!("{what}: loaded and staged in {:.2} s", t.elapsed().as_secs_f64());
    s
}

#[test]
fn wide_files_load_in_near_linear_time() {
    let dir = scratch("wide");
    write(&dir.join("tri.bin"), triangle_bytes());
    const N: usize = 150_000;

    let roots = (0..N).map(|_| r#"{"mesh": 0}"#).collect::<Vec<_>>().join(",");
    let scene_nodes = (0..N).map(|i| i.to_string()).collect::<Vec<_>>().join(",");
    let path = write(&dir.join("roots.gltf"), gltf_with("tri.bin", 36, &roots, Some(&scene_nodes)));
    assert_eq!(load_and_stage(&path, &format!("{N} glTF root nodes")).triangle_count(), N + 2);

    // No `scene`: the roots are found by the loader. One hub with N children.
    let hub_children = (1..=N).map(|i| i.to_string()).collect::<Vec<_>>().join(",");
    let mut nodes = vec![format!(r#"{{"children": [{hub_children}]}}"#)];
    nodes.extend((0..N).map(|_| r#"{"mesh": 0}"#.to_string()));
    let path = write(&dir.join("hub.gltf"), gltf_with("tri.bin", 36, &nodes.join(","), None));
    assert_eq!(load_and_stage(&path, &format!("a glTF hub of {N} children, no scene")).triangle_count(), N + 2);

    let mut obj = String::new();
    for i in 0..N {
        let x = i as f32;
        obj.push_str(&format!("o part{i}\nv {x} 0 0\nv {x} 1 0\nv {x} 0 1\nf -3 -2 -1\n"));
    }
    let path = write(&dir.join("objects.obj"), obj);
    assert_eq!(load_and_stage(&path, &format!("{N} OBJ objects")).triangle_count(), N + 2);
}

// ---- world space ----

#[test]
fn transforms_that_leave_f32_world_space_are_refused() {
    let dir = scratch("world");
    write(&dir.join("tri.bin"), triangle_bytes());
    for (name, nodes, words) in [
        ("far.gltf", r#"{"mesh": 0, "translation": [3e38, 0, 0]}"#.to_string(), &["node 0", "world"][..]),
        (
            "scales.gltf",
            r#"{"children": [1], "scale": [1e30, 1e30, 1e30]}, {"mesh": 0, "scale": [1e30, 1e30, 1e30]}"#.into(),
            &["node 1", "world"][..],
        ),
        ("flat.gltf", r#"{"mesh": 0, "scale": [0, 0, 0]}"#.to_string(), &["node 0", "zero area"][..]),
    ] {
        let path = write(&dir.join(name), gltf_with("tri.bin", 36, &nodes, Some("0")));
        let (msg, _) = load_err(&path);
        assert_one_line_naming(&msg, &path, words);
    }
    // A scale that flattens one axis leaves a card with area: that loads.
    let nodes = r#"{"mesh": 0, "scale": [1, 1, 0]}"#;
    let path = write(&dir.join("card.gltf"), gltf_with("tri.bin", 36, nodes, Some("0")));
    assert_eq!(assets::load(&path).expect("a flattened card loads").triangle_count(), 1);
}

// ---- input the crates underneath would panic on ----

#[test]
fn offsets_near_the_top_of_usize_are_refused() {
    let dir = scratch("offsets");
    write(&dir.join("tri.bin"), triangle_bytes());
    let text = gltf_with("tri.bin", 36, r#"{"mesh": 0}"#, Some("0"))
        .replace(r#""bufferView": 0,"#, r#""bufferView": 0, "byteOffset": 18446744073709551604,"#);
    let path = write(&dir.join("offset.gltf"), text);
    let (msg, _) = load_err(&path);
    assert_one_line_naming(&msg, &path, &["accessor 0"]);
    assert!(!msg.contains("parser failed"), "{msg}");
}

#[test]
fn a_position_naming_a_missing_accessor_is_refused() {
    let dir = scratch("missing-accessor");
    write(&dir.join("tri.bin"), triangle_bytes());
    let text = gltf_with("tri.bin", 36, r#"{"mesh": 0}"#, Some("0")).replace(r#""POSITION": 0"#, r#""POSITION": 7"#);
    let path = write(&dir.join("m.gltf"), text);
    let (msg, _) = load_err(&path);
    assert_one_line_naming(&msg, &path, &["mesh 0", "accessor 7"]);
    assert!(!msg.contains("parser failed"), "{msg}");
}

#[test]
fn a_broken_material_library_only_loses_its_broken_lines() {
    let dir = scratch("broken-mtl");
    write(&dir.join("m.mtl"), "newmtl red\nKd 0.5 0.5\nnewmtl blue\nKd 0.1 0.2 0.9\nNs\n");
    let obj = "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nusemtl red\nf 1 2 3\nusemtl blue\nf 1 3 4\n";
    let path = write(&dir.join("m.obj"), obj);
    let s = assets::load(&path).expect("a broken .mtl does not refuse the model");
    let colours: Vec<Vec3> = s.drawables().map(|d| d.3.base_color).collect();
    assert_eq!(colours, vec![Vec3::splat(0.8), Vec3::new(0.1, 0.2, 0.9)]);
}

// ---- wrong loads ----

#[test]
fn obj_lines_and_points_are_not_faces() {
    let dir = scratch("lines");
    let corners = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n";
    let lines = format!("{corners}l 1 2 3 4\nl 5 6 7 8\nl 1 5\nl 2 6\nl 3 7\nl 4 8\np 1 2 3\n");
    let path = write(&dir.join("lines.obj"), &lines);
    let (msg, fault) = load_err(&path);
    assert_one_line_naming(&msg, &path, &["only lines or points"]);
    assert!(matches!(fault, AssetFault::Unsupported(_)), "{fault:?}");
    // Faces beside the lines: the faces load, the lines do not.
    let path = write(&dir.join("mixed.obj"), format!("{lines}f 1 2 3\n"));
    assert_eq!(assets::load(&path).expect("faces load").triangle_count(), 1);
}

#[test]
fn ply_triangle_strips_are_read() {
    let dir = scratch("tristrips");
    // A 3 x 2 grid of vertices as one strip of four triangles, a restart (-1), then one more triangle.
    let header = "ply\nformat ascii 1.0\nelement vertex 6\nproperty float x\nproperty float y\nproperty float z\n\
                  element tristrips 1\nproperty list int int vertex_indices\nend_header\n";
    let body = "0 0 0\n0 1 0\n1 0 0\n1 1 0\n2 0 0\n2 1 0\n10 0 1 2 3 4 5 -1 2 3 4\n";
    let path = write(&dir.join("strip.ply"), format!("{header}{body}"));
    let s = assets::load(&path).expect("a tristrips PLY loads");
    assert_eq!(s.triangle_count(), 5);
    let (_, _, mesh, _) = s.drawables().next().expect("one drawable");
    let m = s.mesh(mesh).expect("mesh");
    // Every strip triangle keeps the first one's winding: all face the same way (+z or -z alike).
    let normals: Vec<f32> = m
        .triangles()
        .iter()
        .map(|t| {
            let p = t.map(|i| m.positions()[i as usize]);
            (p[1] - p[0]).cross(p[2] - p[0]).z.signum()
        })
        .collect();
    assert!(normals.iter().all(|&z| z == normals[0]), "{normals:?}");
}

#[test]
fn malformed_numbers_name_their_line() {
    let dir = scratch("numbers");
    let path = write(&dir.join("bad.obj"), "v 0 0 0\nv 1 0 0\n# a comment\nv 0 1x 0\nf 1 2 3\n");
    let (msg, _) = load_err(&path);
    assert_one_line_naming(&msg, &path, &["line 4", "1x"]);
    let path = write(&dir.join("bad_face.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 q\n");
    let (msg, _) = load_err(&path);
    assert_one_line_naming(&msg, &path, &["line 4", "q"]);
    let path = write(&dir.join("far_face.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\n\nf 1 2 9\n");
    let (msg, _) = load_err(&path);
    assert_one_line_naming(&msg, &path, &["line 5", "9"]);
    let header = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n\
                  element face 1\nproperty list uchar int vertex_indices\nend_header\n";
    let path = write(&dir.join("bad.ply"), format!("{header}0 0 0\n1 0 0\n0 1.2.3 0\n3 0 1 2\n"));
    let (msg, _) = load_err(&path);
    assert_one_line_naming(&msg, &path, &["line 12", "1.2.3"]);
}

// ---- lights a file brings ----

#[test]
fn gltf_spot_lights_keep_their_cones_intensity_and_range() {
    let dir = scratch("spot");
    write(&dir.join("tri.bin"), triangle_bytes());
    let text = gltf_with(
        "tri.bin",
        36,
        r#"{"mesh": 0}, {"translation": [0, 4, 0], "extensions": {"KHR_lights_punctual": {"light": 0}}}"#,
        Some("0, 1"),
    )
    .replacen(
        r#""asset": {"version": "2.0"},"#,
        r#""asset": {"version": "2.0"}, "extensionsUsed": ["KHR_lights_punctual"],
               "extensions": {"KHR_lights_punctual": {"lights": [{"type": "spot", "intensity": 3.5, "range": 7.0,
                   "spot": {"innerConeAngle": 0.3, "outerConeAngle": 0.5}}]}},"#,
        1,
    );
    let path = write(&dir.join("spot.gltf"), text);
    let s = assets::load(&path).expect("loads");
    let light = s.lights().next().expect("the file's light").1;
    assert_eq!(light.intensity, 3.5);
    assert_eq!(light.range, Some(7.0));
    assert_eq!(light.inner_cone_angle, Some(0.6));
    let (outer, inner) = shadow_core::shading::cone_cosines(&light).expect("a spot");
    assert!((outer - 0.5f32.cos()).abs() < 1e-6 && (inner - 0.3f32.cos()).abs() < 1e-6, "{outer} {inner}");
    // Exported and loaded again, the cone is the same.
    let glb = dir.join("again.glb");
    shadow_core::assets::export::export_glb(&s, &glb).expect("exports");
    let back = assets::load(&glb).expect("loads again").lights().next().expect("a light").1;
    let (o2, i2) = shadow_core::shading::cone_cosines(&back).expect("a spot");
    assert!((o2 - outer).abs() < 1e-5 && (i2 - inner).abs() < 1e-5, "{o2} {i2}");
    assert_eq!(back.intensity, 3.5);
    assert_eq!(back.range, Some(7.0));
}
