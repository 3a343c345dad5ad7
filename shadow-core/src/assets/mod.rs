//! Model loading: OBJ (tobj), glTF 2.0 (.gltf with external or data-URI buffers, .glb) and PLY (ASCII,
//! binary little and big endian, optionally gzipped).
//!
//! Every loader returns a [`Scene`] or an [`AssetError`] that names the file and the fault. Input is
//! untrusted: counts are checked against the bytes actually present before anything is allocated, every
//! index is range-checked, and every position must be finite. Nothing panics on bad input, nothing loops
//! on it, and nothing quietly drops what it cannot read if that would change the picture.

pub mod export;
mod gltf;
mod images;
mod obj;
mod ply;

use std::fmt;
use std::io::Read;
use std::path::Path;

pub use images::TextureLimits;

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
    /// A file the model names outside its own folder (an absolute path, `..` out of it, a link out of
    /// it): refused under [`FileAccess::ModelFolder`], read under [`FileAccess::Anywhere`].
    OutsideFolder(String),
    /// A file the loader never reads: not a regular file (a device, a FIFO, a folder), or named by a URI
    /// scheme other than `data:`.
    Access(String),
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
            Self::OutsideFolder(what) | Self::Access(what) => write!(f, "{what}"),
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

/// Which files a model may name besides itself (glTF buffers, OBJ material libraries).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum FileAccess {
    /// Relative paths that stay inside the model's folder, links included (the default).
    #[default]
    ModelFolder,
    /// Any regular file, absolute paths and `..` included.
    Anywhere,
}

/// How a model is loaded.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LoadOptions {
    /// Which files the model may name.
    pub file_access: FileAccess,
    /// How large its images may be, one by one and together.
    pub textures: TextureLimits,
}

/// Loads a model file into a new scene (meshes, materials and nodes; cameras and lights where the format
/// has them), with the default [`LoadOptions`].
///
/// # Errors
/// An [`AssetError`] naming the file and the fault.
pub fn load(path: impl AsRef<Path>) -> Result<Scene, AssetError> {
    load_with(path, &LoadOptions::default())
}

/// Loads a model file with the given options.
///
/// # Errors
/// An [`AssetError`] naming the file and the fault.
pub fn load_with(path: impl AsRef<Path>, options: &LoadOptions) -> Result<Scene, AssetError> {
    let path = path.as_ref();
    let err = |fault| AssetError::new(path, fault);
    if !path.exists() {
        return Err(err(AssetFault::NotFound(path.display().to_string())));
    }
    let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("").to_ascii_lowercase();
    let ext = name.rsplit('.').next().unwrap_or("");
    // The parsers are hardened, but a bug in a dependency must not take the process down with it.
    let result = std::panic::catch_unwind(|| match ext {
        "obj" => obj::load(path, options),
        "gltf" | "glb" => gltf::load(path, options),
        "ply" => ply::load(path),
        "gz" if name.ends_with(".ply.gz") => ply::load(path),
        _ => Err(err(AssetFault::UnknownFormat(ext.to_string()))),
    });
    let mut scene =
        result.unwrap_or_else(|_| Err(err(AssetFault::Malformed("the parser failed on this input".into()))))?;
    scene.prefix_warnings(&path.display().to_string());
    Ok(scene)
}

/// The most bytes read of an image file a model names: 256 MiB. A longer (or endless) file stops there
/// and its image is left out with a warning; the limits on texels, [`TextureLimits`], are checked on the
/// header before decoding.
pub const IMAGE_FILE_LIMIT: u64 = 256 << 20;

/// Reads the model file itself. The user named it, so it is read whole, but only if it is a regular file:
/// a FIFO or a device could block or never end.
fn read_model(path: &Path) -> Result<Vec<u8>, AssetFault> {
    regular_file(path, &path.display().to_string())?;
    std::fs::read(path).map_err(|e| io_fault(path, &e))
}

fn io_fault(path: &Path, e: &std::io::Error) -> AssetFault {
    match e.kind() {
        std::io::ErrorKind::NotFound => AssetFault::NotFound(path.display().to_string()),
        _ => AssetFault::Io(format!("{}: {e}", path.display())),
    }
}

/// Fails unless `path` is (or links to) a regular file.
fn regular_file(path: &Path, what: &str) -> Result<(), AssetFault> {
    let meta = std::fs::metadata(path).map_err(|e| io_fault(path, &e))?;
    if meta.is_file() { Ok(()) } else { Err(AssetFault::Access(format!("{what} is not a regular file"))) }
}

/// Reads a file that a model names (`reference`, as the model writes it; `what` says where, e.g.
/// "buffer 0"), resolved against the model's `folder` under `options.file_access`, and at most `limit`
/// bytes of it when given.
///
/// Under [`FileAccess::ModelFolder`] the reference must be a relative path whose `..` never climbs out of
/// the folder, and whose real location (links followed) is inside it. Under either rule it must be a
/// regular file, and URI schemes (`http:`, `file:`, ...) are not read.
fn read_referenced(
    folder: &Path,
    reference: &str,
    what: &str,
    limit: Option<u64>,
    options: &LoadOptions,
) -> Result<Vec<u8>, AssetFault> {
    let named = |why: String| format!("{what} names '{reference}', {why}");
    // A model named without a folder ("m.gltf") has the empty path as its parent: the current folder.
    let folder = if folder.as_os_str().is_empty() { Path::new(".") } else { folder };
    // A scheme is two or more characters before a colon (one is a Windows drive letter).
    if let Some((scheme, _)) = reference.split_once(':')
        && scheme.len() > 1
        && scheme.chars().all(|c| c.is_ascii_alphanumeric() || "+-.".contains(c))
    {
        return Err(AssetFault::Access(named(format!(
            "a '{scheme}:' URI; only relative paths and data: URIs are read"
        ))));
    }
    let relative = Path::new(reference);
    let confined = options.file_access == FileAccess::ModelFolder;
    if confined {
        use std::path::Component;
        let absolute = relative.is_absolute()
            || reference.starts_with(['/', '\\'])
            || relative.components().any(|c| matches!(c, Component::Prefix(_) | Component::RootDir));
        if absolute {
            let why = "an absolute path; a model may name only files inside its own folder";
            return Err(AssetFault::OutsideFolder(named(why.into())));
        }
        let mut depth = 0i64;
        for c in relative.components() {
            depth += match c {
                Component::Normal(_) => 1,
                Component::ParentDir => -1,
                _ => 0,
            };
            if depth < 0 {
                return Err(AssetFault::OutsideFolder(named("a path outside the model's folder".into())));
            }
        }
    }
    let file = folder.join(relative);
    regular_file(&file, &format!("{what} ('{}')", file.display()))?;
    if confined {
        let real = |p: &Path| p.canonicalize().map_err(|e| io_fault(p, &e));
        if !real(&file)?.starts_with(real(folder)?) {
            return Err(AssetFault::OutsideFolder(named("a link to a file outside the model's folder".into())));
        }
    }
    let mut reader = std::fs::File::open(&file).map_err(|e| io_fault(&file, &e))?;
    read_at_most(&mut reader, limit.unwrap_or(u64::MAX)).map_err(|e| io_fault(&file, &e))
}

/// Reads at most `limit` bytes.
///
/// # Errors
/// The reader's error.
pub fn read_at_most(reader: &mut impl std::io::Read, limit: u64) -> std::io::Result<Vec<u8>> {
    let mut out = Vec::new();
    reader.take(limit).read_to_end(&mut out)?;
    Ok(out)
}
