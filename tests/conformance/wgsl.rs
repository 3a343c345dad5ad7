//! Every WGSL file in the workspace is parsed and validated with naga as it is compiled (appended to the
//! backend shader it extends), so a shader error fails `cargo test`, not a user. The files are found on
//! disk, and each must appear in some validated shader: a file no registry entry's WGSL (nor the backend's)
//! holds fails here.

use std::path::{Path, PathBuf};

use shadowlab::TechniqueRegistry;

/// The backend's shaders, then each registered technique's (its entry's WGSL).
fn every_shader() -> Vec<(&'static str, String)> {
    let mut registry = TechniqueRegistry::builtin();
    crate::planar::register(&mut registry);
    let mut all = shadow_wgpu::shaders::all();
    for entry in registry.entries() {
        all.extend((entry.wgsl)());
    }
    all
}

fn wgsl_files(dir: &Path, found: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).expect("a source folder") {
        let path = entry.expect("a folder entry").path();
        if path.is_dir() {
            wgsl_files(&path, found);
        } else if path.extension().is_some_and(|e| e == "wgsl") {
            found.push(path);
        }
    }
}

#[test]
fn every_shader_validates() {
    for (name, src) in every_shader() {
        let module =
            naga::front::wgsl::parse_str(&src).unwrap_or_else(|e| panic!("{name}: {}", e.emit_to_string(&src)));
        let mut v = naga::valid::Validator::new(naga::valid::ValidationFlags::all(), naga::valid::Capabilities::all());
        if let Err(e) = v.validate(&module) {
            panic!("{name}: {}", e.emit_to_string(&src));
        }
    }
}

#[test]
fn every_wgsl_file_is_in_a_validated_shader() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut files = Vec::new();
    for krate in ["shadow-wgpu", "shadow-hard", "shadow-soft"] {
        wgsl_files(&root.join(krate).join("src"), &mut files);
    }
    assert!(files.len() >= 20, "found only {} WGSL files", files.len());
    let shaders = every_shader();
    for file in files {
        let text = std::fs::read_to_string(&file).expect("a readable WGSL file");
        assert!(
            shaders.iter().any(|(_, src)| src.contains(text.trim())),
            "{} is in no validated shader",
            file.display()
        );
    }
}
