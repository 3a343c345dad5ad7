//! The sources read as the code is cut: no Rust file of the library, the tools or the examples runs past
//! 700 lines (test files aside), and every shader is a `.wgsl` file of its own, none written inside a Rust
//! string.

use std::path::{Path, PathBuf};

/// Every `.rs` file under the workspace's root, build outputs and version control left out.
fn rust_files(dir: &Path, found: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).expect("a source folder") {
        let path = entry.expect("a folder entry").path();
        let name = path.file_name().and_then(|n| n.to_str()).unwrap_or_default();
        if path.is_dir() {
            if !matches!(name, "target" | ".git" | "node_modules") {
                rust_files(&path, found);
            }
        } else if name.ends_with(".rs") {
            found.push(path);
        }
    }
}

fn workspace_rust_files() -> Vec<PathBuf> {
    let mut files = Vec::new();
    rust_files(Path::new(env!("CARGO_MANIFEST_DIR")), &mut files);
    assert!(files.len() >= 100, "found only {} Rust files", files.len());
    files
}

/// A test's file: under a `tests` folder, or a module of tests (`tests.rs`, `proptests.rs`).
fn is_test(path: &Path) -> bool {
    path.components().any(|c| c.as_os_str() == "tests")
        || path.file_name().is_some_and(|n| n == "tests.rs" || n == "proptests.rs")
}

#[test]
fn no_source_file_runs_past_700_lines() {
    let long: Vec<String> = workspace_rust_files()
        .into_iter()
        .filter(|path| !is_test(path))
        .filter_map(|path| {
            let lines = std::fs::read_to_string(&path).expect("a readable file").lines().count();
            (lines > 700).then(|| format!("{} ({lines} lines)", path.display()))
        })
        .collect();
    assert!(long.is_empty(), "split along the seams the code has: {}", long.join(", "));
}

#[test]
fn no_shader_is_written_in_a_rust_string() {
    // WGSL's attributes of entry points and bindings: what every shader has and no Rust code does (made
    // here, so this file does not hold them).
    let marks = ["vertex", "fragment", "compute", "group("].map(|attribute| format!("@{attribute}"));
    let inline: Vec<String> = workspace_rust_files()
        .into_iter()
        .filter(|path| {
            let text = std::fs::read_to_string(path).expect("a readable file");
            text.lines().any(|l| !l.trim_start().starts_with("//") && marks.iter().any(|m| l.contains(m)))
        })
        .map(|path| path.display().to_string())
        .collect();
    assert!(inline.is_empty(), "WGSL inside Rust (each shader belongs in a .wgsl file): {}", inline.join(", "));
}
