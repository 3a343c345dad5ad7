//! Model loading: OBJ (tobj), glTF 2.0 (.gltf with external or data-URI buffers, .glb) and PLY (ASCII,
//! binary little and big endian, optionally gzipped).
//!
//! Every loader returns a [`Scene`] or an [`AssetError`] that names the file and the fault. Input is
//! untrusted: counts are checked against the bytes actually present before anything is allocated, every
//! index is range-checked, and every position must be finite. Nothing panics on bad input, nothing loops
//! on it, and nothing quietly drops what it cannot read if that would change the picture.

pub mod export;
mod gltf;
mod obj;
mod ply;

use std::fmt;
use std::path::Path;

use crate::mesh::MeshError;
use crate::scene::Scene;

/// What is wrong with a model file.
#[derive(Debug, Clone, PartialEq)]
pub enum AssetFault {
    /// The file (or a file it refers to) does not exist.
    NotFound(String),
    /// Reading failed for another reason.
    Io(String),
    /// The extension names no format this crate reads.
    UnknownFormat(String),
    /// A feature this loader does not implement (Draco, sparse accessors, only points or lines, ...).
    Unsupported(String),
    /// The file does not follow its format.
    Malformed(String),
    /// The data ends before what the header or an accessor promised.
    Truncated(String),
    /// An accessor with the wrong type or component type for its use.
    WrongAccessor(String),
    /// The node graph has a cycle or a node with two parents.
    Cycle(String),
    /// A mesh that would render wrong: index out of range, non-finite position, no triangles.
    Mesh(String, MeshError),
}

impl fmt::Display for AssetFault {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::NotFound(p) => write!(f, "file not found: {p}"),
            Self::Io(e) => write!(f, "cannot read: {e}"),
            Self::UnknownFormat(ext) => {
                write!(f, "unknown model format '{ext}' (expected .obj, .gltf, .glb, .ply or .ply.gz)")
            }
            Self::Unsupported(what) => write!(f, "unsupported: {what}"),
            Self::Malformed(what) => write!(f, "malformed: {what}"),
            Self::Truncated(what) => write!(f, "truncated: {what}"),
            Self::WrongAccessor(what) => write!(f, "wrong accessor type: {what}"),
            Self::Cycle(what) => write!(f, "bad node graph: {what}"),
            Self::Mesh(which, e) => write!(f, "{which}: {e}"),
        }
    }
}

/// A model file that could not be loaded: the file and what is wrong with it.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{path}: {fault}")]
pub struct AssetError {
    /// The file, as given.
    pub path: String,
    /// The fault.
    pub fault: AssetFault,
}

impl AssetError {
    pub(crate) fn new(path: &Path, fault: AssetFault) -> Self {
        Self { path: path.display().to_string(), fault }
    }
}

/// The formats [`load`] reads, by lower-case extension.
pub const EXTENSIONS: &[&str] = &["obj", "gltf", "glb", "ply", "gz"];

/// True when the path's extension names a model format (so `--scene` can tell files from scene names).
#[must_use]
pub fn is_model_path(path: &Path) -> bool {
    path.extension().and_then(|e| e.to_str()).is_some_and(|e| EXTENSIONS.contains(&e.to_ascii_lowercase().as_str()))
}

/// Loads a model file into a new scene (meshes, materials and nodes; cameras and lights where the format
/// has them).
///
/// # Errors
/// An [`AssetError`] naming the file and the fault.
pub fn load(path: impl AsRef<Path>) -> Result<Scene, AssetError> {
    let path = path.as_ref();
    let err = |fault| AssetError::new(path, fault);
    if !path.exists() {
        return Err(err(AssetFault::NotFound(path.display().to_string())));
    }
    let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("").to_ascii_lowercase();
    let ext = name.rsplit('.').next().unwrap_or("");
    // The parsers are hardened, but a bug in a dependency must not take the process down with it.
    let result = std::panic::catch_unwind(|| match ext {
        "obj" => obj::load(path),
        "gltf" | "glb" => gltf::load(path),
        "ply" => ply::load(path),
        "gz" if name.ends_with(".ply.gz") => ply::load(path),
        _ => Err(err(AssetFault::UnknownFormat(ext.to_string()))),
    });
    result.unwrap_or_else(|_| Err(err(AssetFault::Malformed("the parser failed on this input".into()))))
}

/// Reads a whole file, mapping failures to faults.
fn read_file(path: &Path) -> Result<Vec<u8>, AssetFault> {
    std::fs::read(path).map_err(|e| match e.kind() {
        std::io::ErrorKind::NotFound => AssetFault::NotFound(path.display().to_string()),
        _ => AssetFault::Io(e.to_string()),
    })
}
