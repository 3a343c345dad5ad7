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
    assert_eq!(v.len(), shadow_core::scenes::ALL.len());
    assert!(v.iter().all(|s| s["triangles"].as_u64().unwrap() > 0 && s["name"].is_string()));
}

#[test]
fn usage_errors_exit_2() {
    assert_eq!(shadowlab(&["inspect"]).0, 2);
    assert_eq!(shadowlab(&["frobnicate"]).0, 2);
    let (code, _, err) = shadowlab(&["inspect", "no-such-scene"]);
    assert_eq!(code, 2);
    assert!(err.contains("no-such-scene"), "{err}");
}
