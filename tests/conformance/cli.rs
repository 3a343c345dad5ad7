//! The `shadowlab` binary: exit codes and one-line errors.

use std::path::Path;
use std::process::Command;

fn shadowlab(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_shadowlab")).args(args).output().expect("the binary runs");
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into(),
        String::from_utf8_lossy(&out.stderr).into(),
    )
}

#[test]
fn inspect_refuses_every_crafted_bad_file_with_one_line() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("shadow-core/tests/data/bad");
    let mut seen = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        let (code, _, err) = shadowlab(&["inspect", path.to_str().unwrap()]);
        assert_eq!(code, 1, "{}: exit {code}, stderr {err}", path.display());
        let lines: Vec<&str> = err.lines().collect();
        assert_eq!(lines.len(), 1, "{}: {err}", path.display());
        assert!(lines[0].contains(path.file_name().unwrap().to_str().unwrap()), "{}", lines[0]);
        seen += 1;
    }
    assert!(seen >= 20);
}

#[test]
fn inspect_json_has_the_design_keys() {
    let (code, out, err) = shadowlab(&["inspect", "cylinder", "--json"]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    for key in ["triangles", "vertices", "closed", "boundary_edges", "non_manifold_edges", "bounds", "silhouette_edges"]
    {
        assert!(v.get(key).is_some(), "missing {key}");
    }
    assert_eq!(v["triangles"], 258);
    assert_eq!(v["closed"], false);
}

#[test]
fn scenes_json_lists_every_scene() {
    let (code, out, _) = shadowlab(&["scenes", "--json"]);
    assert_eq!(code, 0);
    let v: Vec<serde_json::Value> = serde_json::from_str(&out).unwrap();
    assert_eq!(v.len(), shadow_core::scenes::every().count());
    assert!(v.iter().all(|s| s["triangles"].as_u64().unwrap() > 0 && s["name"].is_string()));
}

#[test]
fn bad_usage_exits_2() {
    assert_eq!(shadowlab(&["inspect"]).0, 2);
    assert_eq!(shadowlab(&["frobnicate"]).0, 2);
    let (code, _, err) = shadowlab(&["inspect", "no-such-scene"]);
    assert_eq!(code, 2);
    assert!(err.contains("no-such-scene"), "{err}");
}

/// Every bad input gives exit status 2 (usage) or 1 (the work failed) and one line naming the cause.
#[test]
fn bad_inputs_give_one_line_and_the_right_status() {
    let cycle = Path::new(env!("CARGO_MANIFEST_DIR")).join("shadow-core/tests/data/bad/node_cycle.gltf");
    let cycle = cycle.to_str().unwrap();
    let out = std::env::temp_dir().join(format!("shadowlab-cli-{}", std::process::id()));
    let out = out.to_str().unwrap();
    // A model whose buffer is an absolute path.
    let outside = std::env::temp_dir().join(format!("shadowlab-cli-outside-{}.gltf", std::process::id()));
    let gltf = r#"{"asset": {"version": "2.0"}, "buffers": [{"uri": "/etc/hostname", "byteLength": 4}]}"#;
    std::fs::write(&outside, gltf).unwrap();
    let outside = outside.display().to_string();
    let cases: &[(&[&str], i32, &str)] = &[
        (&["render", "--scene", "atlantis", "-o", out], 2, "unknown scene 'atlantis'"),
        (&["render", "--technique", "shadow-mop", "-o", out], 2, "unknown technique 'shadow-mop'"),
        (&["render", "--technique", "shadow-map:colour=red", "-o", out], 2, "has no setting 'colour'"),
        (&["render", "--technique", "shadow-map:res=abc", "-o", out], 2, "bad value 'abc' for 'res'"),
        (&["render", "--technique", "shadow-map:filter=gauss", "-o", out], 2, "pcf3x3"),
        (&["render", "--technique", "shadow-map:res", "-o", out], 2, "is not key=value"),
        (&["render", "--size", "512", "-o", out], 2, "expected WxH"),
        (&["render", "--size", "0x512", "-o", out], 2, "at least 1"),
        (&["render", "--size", "20000x20000", "--backend", "cpu", "-o", out], 2, "would take about 160.0 GB"),
        (&["render", "--size", "16384x16384", "-o", out], 2, "the budget is 8 GB"),
        (&["render", "--scene", "no/such/model.obj", "-o", out], 1, "file not found"),
        (&["render", "--scene", cycle, "-o", out], 1, "own ancestor"),
        (&["render", "--scene", outside.as_str(), "-o", out], 1, "--allow-outside-files reads it"),
        (&["render", "--camera", "eye=1,2,target=0,0,0", "-o", out], 2, "eye must be three"),
        (&["render", "--light", "laser", "-o", out], 2, "type must be one of spot, directional, point"),
        (&["render", "--light", "spot,fov=250", "-o", out], 2, "cone angle"),
        (&["render", "--light", "directional,fov=0", "-o", out], 2, "a directional light has none"),
        (&["render", "--light", "point,target=0,0,0", "-o", out], 2, "takes no target"),
        (&["render", "--light", "spot,pos=1,2,3,pos=4,5,6", "-o", out], 2, "'pos' is given twice"),
        (&["render", "--camera", "eye=1,2,3,target=0,0,0,eye=0,1,2", "-o", out], 2, "'eye' is given twice"),
        (&["render", "--backend", "cpu", "--adapter", "llvmpipe", "-o", out], 2, "--backend cpu uses none"),
        (&["render", "--adapter", "no-such-adapter", "-o", out], 1, "none named like 'no-such-adapter'"),
        (&["compare", "--backend", "quantum", "--out-dir", out], 2, "bad --backend 'quantum'"),
        (&["bench", "--frames", "0", "--backend", "cpu"], 2, "--frames must be at least 1"),
        (&["bench", "--sweep", "speed=1,2", "--backend", "cpu"], 2, "must be res or tris"),
        (&["bench", "--sweep", "res=256,-3", "--backend", "cpu"], 2, "positive whole numbers"),
        (&["bench", "--realtime", "--backend", "cpu"], 2, "--realtime runs on the wgpu backend, not 'cpu'"),
        (&["bench", "--realtime", "--sweep", "res=256"], 2, "--realtime does not sweep"),
        (&["bench", "--animate", "--sweep", "res=256", "--backend", "cpu"], 2, "--animate plays the scene's own clip"),
        (&["bench", "--animate", "--backend", "cpu"], 2, "--animate: the scene has no animations to play"),
        // A sphere of 2 billion vertices, refused before it is allocated.
        (
            &["bench", "--sweep", "tris=4000000000", "--backend", "cpu"],
            2,
            "sphere: 2000091504 vertices, over the limit",
        ),
        (
            &["render", "--technique", "ray-traced", "--backend", "wgpu", "-o", out],
            2,
            "not implemented on the wgpu backend",
        ),
        (&["export", "--scene", "cylinder", "-o", "/no/such/dir/x.glb"], 1, "cannot write /no/such/dir/x.glb"),
        (&["export", "--scene", "cylinder", "-o", "cylinder.obj"], 2, "expected a .glb or .gltf file"),
    ];
    for (args, status, words) in cases {
        let (code, _, err) = shadowlab(args);
        // Input is checked before anything is said: a refusal is its one line.
        let lines: Vec<&str> = err.lines().collect();
        assert_eq!(code, *status, "{args:?}: status {code}, stderr: {err}");
        assert_eq!(lines.len(), 1, "{args:?}: not one line: {err}");
        assert!(
            lines[0].starts_with("error: ") && lines[0].contains(words),
            "{args:?}: '{}' lacks '{words}'",
            lines[0]
        );
    }
    let _ = std::fs::remove_file(out);
    let _ = std::fs::remove_file(&outside);
}

#[test]
fn a_refused_run_leaves_no_output_folder() {
    let out = std::env::temp_dir().join(format!("shadowlab-refused-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&out);
    for bad in [&["--light", "laser"][..], &["--scene", "no/such/model.obj"][..], &["--size", "0x9"][..]] {
        let mut args = vec!["compare", "--backend", "cpu", "--out-dir", out.to_str().unwrap()];
        args.extend_from_slice(bad);
        let (code, _, err) = shadowlab(&args);
        assert_ne!(code, 0, "{bad:?} ran");
        assert_eq!(err.lines().count(), 1, "{bad:?}: {err}");
        assert!(!out.exists(), "{bad:?} left {} behind", out.display());
    }
}

#[test]
fn a_closed_pipe_ends_the_program_quietly() {
    use std::process::Stdio;
    for command in ["techniques", "scenes"] {
        let mut child = Command::new(env!("CARGO_BIN_EXE_shadowlab"))
            .arg(command)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .expect("the binary runs");
        // Closing the read end before the program writes makes its first write fail with a broken pipe.
        drop(child.stdout.take());
        let out = child.wait_with_output().expect("it ends");
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(0), "{command}: {err}");
        assert!(err.is_empty(), "{command}: {err}");
    }
}

#[test]
fn a_run_that_succeeds_without_a_runtime_folder_raises_no_alarm() {
    let out = std::env::temp_dir().join(format!("shadowlab-xdg-{}.png", std::process::id()));
    let out = out.to_str().unwrap();
    let status = Command::new(env!("CARGO_BIN_EXE_shadowlab"))
        .args(["render", "--size", "32x32", "-o", out])
        .env_remove("XDG_RUNTIME_DIR")
        .output()
        .expect("the binary runs");
    let err = String::from_utf8_lossy(&status.stderr);
    assert!(status.status.success(), "{err}");
    assert!(!err.lines().any(|l| l.starts_with("error")), "{err}");
    let _ = std::fs::remove_file(out);
    let _ = std::fs::remove_file(out.replace(".png", ".vis.png"));
}

/// `cargo test` on a headless machine: the GPU tests, run with the environment cargo gives them, print no
/// line with "error" when they pass (the workspace's `.cargo/config.toml` quiets the Vulkan layers).
#[test]
fn gpu_tests_that_pass_raise_no_alarm() {
    let Some(_) = crate::with_wgpu("the test run's error lines") else { return };
    let out = Command::new(std::env::current_exe().expect("the test binary"))
        .args(["--exact", "host::a_host_device_short_of_the_limits_is_refused_by_name", "--nocapture"])
        .output()
        .expect("the test binary runs");
    let all = format!("{}{}", String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
    assert!(out.status.success() && all.contains("1 passed"), "{all}");
    assert!(!all.lines().any(|l| l.contains("error")), "{all}");
    // Nor does a test's name, printed beside its "ok".
    let list = Command::new(std::env::current_exe().expect("the test binary")).arg("--list").output().expect("a list");
    let names = String::from_utf8_lossy(&list.stdout);
    let alarming: Vec<&str> = names.lines().filter(|l| l.contains("error")).collect();
    assert!(alarming.is_empty(), "test names a passing run prints as 'error': {alarming:?}");
}

#[test]
fn help_says_what_runs_and_what_the_exit_codes_mean() {
    let (_, top, _) = shadowlab(&["--help"]);
    assert!(top.contains("Exit status: 0 on success"), "{top}");
    let (_, export, _) = shadowlab(&["export", "--help"]);
    for meaningless in ["--size", "--adapter"] {
        assert!(!export.contains(meaningless), "export --help lists {meaningless}");
    }
    for command in ["compare", "bench"] {
        let (_, help, _) = shadowlab(&[command, "--help"]);
        let help = help.split_whitespace().collect::<Vec<_>>().join(" ");
        assert!(help.contains("default: every technique but the references"), "{command}: {help}");
    }
}

#[test]
fn a_mixed_compare_scores_each_technique_against_its_own_reference() {
    let out = std::env::temp_dir().join(format!("shadowlab-mixed-{}", std::process::id()));
    let args = [
        "compare",
        "--scene",
        "cylinder",
        "--size",
        "64x64",
        "--backend",
        "cpu",
        "--technique",
        "shadow-map",
        "--technique",
        "pcss",
        "--out-dir",
        out.to_str().unwrap(),
    ];
    let (code, stdout, err) = shadowlab(&args);
    assert_eq!(code, 0, "{err}");
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).expect("report.json")).unwrap();
    let reference_of = |name: &str| {
        report["results"].as_array().unwrap().iter().find(|r| r["technique"] == name).unwrap()["reference"].clone()
    };
    assert_eq!(reference_of("shadow-map"), "ray-traced");
    assert_eq!(reference_of("pcss"), "area-light-reference");
    let pcss_line = stdout.lines().find(|l| l.starts_with("pcss")).expect("a pcss row");
    assert!(pcss_line.contains("area-light-reference"), "{pcss_line}");
    assert!(out.join("reference-area-light-reference.png").exists());
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn a_model_named_by_a_bare_file_name_finds_its_buffers() {
    let dir = std::env::temp_dir().join(format!("shadowlab-bare-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let triangle: Vec<u8> =
        [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0].iter().flat_map(|f| f.to_le_bytes()).collect();
    std::fs::write(dir.join("tri.bin"), triangle).unwrap();
    let gltf = r#"{"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]}],
        "bufferViews": [{"buffer": 0, "byteLength": 36}], "buffers": [{"uri": "tri.bin", "byteLength": 36}]}"#;
    std::fs::write(dir.join("m.gltf"), gltf).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_shadowlab"))
        .args(["inspect", "m.gltf", "--json"])
        .current_dir(&dir)
        .output()
        .expect("the binary runs");
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["triangles"], 1);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn techniques_list_the_lights_they_take() {
    let (code, out, err) = shadowlab(&["techniques", "--json"]);
    assert_eq!(code, 0, "{err}");
    let v: Vec<serde_json::Value> = serde_json::from_str(&out).unwrap();
    let lights = |name: &str| v.iter().find(|t| t["name"] == name).map(|t| t["lights"].clone()).unwrap();
    assert_eq!(lights("shadow-map"), serde_json::json!(["spot", "directional", "point"]));
    assert_eq!(lights("pcss"), serde_json::json!(["spot"]));
    assert_eq!(lights("smoothies"), serde_json::json!(["spot", "directional"]));
    assert_eq!(lights("area-light-reference"), serde_json::json!(["spot", "point"]));
}

#[test]
fn compare_of_every_technique_leaves_out_those_the_lights_refuse() {
    // l-shape is lit by a directional light: no soft technique has a reference for it, and pcss takes
    // spot lights only.
    let out = std::env::temp_dir().join(format!("shadowlab-cli-lights-{}", std::process::id()));
    let (code, stdout, err) = shadowlab(&[
        "compare",
        "--scene",
        "l-shape",
        "--size",
        "32x32",
        "--backend",
        "cpu",
        "--out-dir",
        out.to_str().unwrap(),
    ]);
    let _ = std::fs::remove_dir_all(&out);
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("pcss") && err.contains("smoothies"), "{err}");
    assert!(stdout.contains("shadow-map") && !stdout.contains("pcss"), "{stdout}");
    // Named explicitly, a technique refused by the light is an error naming both.
    let png = out.with_extension("png");
    let args = ["render", "--scene", "l-shape", "--size", "32x32", "--backend", "cpu", "--technique", "pcss", "--out"];
    let (code, _, err) = shadowlab(&[&args[..], &[png.to_str().unwrap()]].concat());
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("pcss") && err.contains("directional"), "{err}");
}

#[test]
fn view_without_a_display_says_how_to_get_one() {
    let out = Command::new(env!("CARGO_BIN_EXE_shadowlab"))
        .args(["view", "--scene", "cubes"])
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .env_remove("WAYLAND_SOCKET")
        .output()
        .expect("the binary runs");
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.contains("no display") && err.contains("xvfb-run"), "{err}");
}

/// A 256-texel checkerboard card, masked at 0.5, written by `export` as `card.gltf` with `card.bin` and
/// the image `card-0.png` beside it in `dir`.
fn write_checkerboard_card(dir: &Path) -> std::path::PathBuf {
    use glam::{Mat4, Vec2, Vec3};
    use shadow_core::material::{AlphaMode, Filter, Sampler, Texture, TextureRef, UvTransform};
    let texels =
        (0..256 * 256).map(|i| if (i % 256 / 32 + i / 256 / 32) % 2 == 0 { [255; 4] } else { [0; 4] }).collect();
    let mut scene = shadow_core::Scene::new();
    let texture = scene.add_texture(Texture::from_rgba8("checker", 256, 256, texels).expect("a texture"));
    let sampler = Sampler { mag: Filter::Nearest, ..Sampler::default() };
    let material = scene.add_material(shadow_core::Material {
        base_color_texture: Some(TextureRef { texture, sampler, transform: UvTransform::IDENTITY }),
        alpha_mode: AlphaMode::Mask { cutoff: 0.5 },
        two_sided: true,
        ..shadow_core::Material::colored("checker", Vec3::ONE)
    });
    let corners = vec![
        Vec3::new(-1.0, 0.0, 1.0),
        Vec3::new(1.0, 0.0, 1.0),
        Vec3::new(1.0, 0.0, -1.0),
        Vec3::new(-1.0, 0.0, -1.0),
    ];
    let uvs = vec![Vec2::new(0.0, 1.0), Vec2::ONE, Vec2::new(1.0, 0.0), Vec2::ZERO];
    let card =
        shadow_core::Mesh::new(corners, vec![[0, 1, 2], [0, 2, 3]]).and_then(|m| m.with_uvs(uvs)).expect("a card");
    let mesh = scene.add_mesh(card);
    scene.add_instance("card", mesh, material, Mat4::IDENTITY).expect("an instance");
    let path = dir.join("card.gltf");
    shadow_core::assets::export::export(&scene, &path).expect("export");
    path
}

#[test]
fn inspect_lists_a_textured_cards_material_and_texture_and_names_a_bad_image() {
    let dir = std::env::temp_dir().join(format!("shadowlab-cli-card-{}", std::process::id()));
    let model = dir.join("model");
    std::fs::create_dir_all(&model).unwrap();
    let card = write_checkerboard_card(&model);
    let card = card.to_str().unwrap();
    let (code, out, err) = shadowlab(&["inspect", card, "--json"]);
    assert_eq!((code, err.as_str()), (0, ""));
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    let material = &v["materials"][0];
    assert_eq!((&material["name"], &material["alpha_mode"]), (&"checker".into(), &"MASK".into()), "{v}");
    assert_eq!((&material["alpha_cutoff"], &material["double_sided"]), (&0.5.into(), &true.into()), "{v}");
    let sampler = serde_json::json!({"mag": "nearest", "min": "linear", "mipmap": "linear", "wrap_u": "repeat", "wrap_v": "repeat"});
    assert_eq!(material["sampler"], sampler, "{v}");
    let texture = &v["textures"][material["base_color_texture"].as_u64().expect("a texture") as usize];
    assert_eq!((&texture["width"], &texture["height"]), (&256.into(), &256.into()), "{v}");
    assert_eq!(texture["bytes_with_mips"], 349_524, "{v}");
    assert_eq!(v["meshes_with_texture_coordinates"], 1);
    // Without its image the card still loads, untextured, with one warning naming model, material and image.
    std::fs::rename(model.join("card-0.png"), dir.join("card-0.png")).unwrap();
    let (code, out, err) = shadowlab(&["inspect", card]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("textures            0"), "{out}");
    let lines: Vec<&str> = err.lines().collect();
    assert_eq!(lines.len(), 1, "{err}");
    assert!(lines[0].contains(card) && lines[0].contains("'card-0.png'") && lines[0].contains("material 'checker'"));
    // Named outside the model's folder, it is refused, in one line naming the model and the path.
    let text = std::fs::read_to_string(card).unwrap().replace("\"card-0.png\"", "\"../card-0.png\"");
    std::fs::write(card, text).unwrap();
    let (code, _, err) = shadowlab(&["inspect", card]);
    assert_eq!(code, 1, "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.contains(card) && err.contains("'../card-0.png'"), "{err}");
    let (code, _, err) = shadowlab(&["inspect", card, "--allow-outside-files"]);
    assert_eq!((code, err.as_str()), (0, ""));
    let _ = std::fs::remove_dir_all(&dir);
}

/// `--time` poses the scene's animations: the mill's rotor throws its shadow elsewhere a second later,
/// `inspect` lists the clip, a time that is not a number is a usage error, a scene with nothing to pose
/// says so, and `flicker --time-step` walks the clip.
#[test]
fn time_poses_the_animations_and_inspect_lists_them() {
    let dir = std::env::temp_dir().join(format!("shadowlab-cli-time-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let vis = |t: &str| {
        let out = dir.join(format!("mill-{t}.png"));
        let args = ["render", "--scene", "mill", "--backend", "cpu", "--technique", "ray-traced", "--size", "96x96"];
        let (code, _, err) = shadowlab(&[&args[..], &["--time", t, "-o", out.to_str().unwrap()]].concat());
        assert_eq!(code, 0, "{err}");
        let png = shadow_core::Image::<[u8; 3]>::load_png(out.with_extension("vis.png")).unwrap();
        let pixels: Vec<u8> = png.data().iter().map(|p| p[0]).collect();
        assert!(pixels.iter().any(|&p| p < 128) && pixels.iter().any(|&p| p > 128), "a shadow and light at {t}");
        pixels
    };
    assert_ne!(vis("0"), vis("1"), "the rotor has turned");
    let (code, out, err) = shadowlab(&["inspect", "mill", "--json"]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["animations"][0]["name"], "spin");
    assert_eq!(v["animations"][0]["duration_s"], 6.0);
    let (code, _, err) = shadowlab(&["render", "--scene", "mill", "--time", "soon"]);
    assert_eq!(code, 2);
    assert!(err.contains("'soon' is not a number of seconds"), "{err}");
    let out = dir.join("still.png");
    let args = ["render", "--scene", "cylinder", "--backend", "cpu", "--technique", "ray-traced", "--size", "32x32"];
    let (code, _, err) = shadowlab(&[&args[..], &["--time", "2", "-o", out.to_str().unwrap()]].concat());
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("cylinder: no animations to pose at 2 s"), "{err}");
    // Flicker steps through the clip; a scene without one has nothing to step.
    let walk =
        ["flicker", "--technique", "shadow-volume-zfail", "--frames", "3", "--size", "48x48", "--time-step", "0.5"];
    let (code, out, err) = shadowlab(&[&walk[..], &["--scene", "mill"]].concat());
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("0.5 s of the animation per frame"), "{out}");
    let (code, _, err) = shadowlab(&[&walk[..], &["--scene", "cylinder"]].concat());
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("cylinder has no animations to step"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}
