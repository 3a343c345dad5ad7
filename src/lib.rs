//! shadowlab: real-time shadow techniques on a GPU (wgpu) and a CPU reference backend, measured against a
//! ray-traced ground truth.
//!
//! This crate is the facade: it re-exports the workspace crates and resolves what a user names on the
//! command line (a built-in scene or a model file) into a scene.

pub mod bench;
pub mod compare;
mod error;
pub mod flicker;
pub mod plot;
pub mod realtime;
pub mod registry;
pub mod renderer;
pub mod results;
pub mod setup;
pub mod sheet;
#[cfg(feature = "viewer")]
pub mod viewer;

use std::path::Path;

pub use error::Error;

/// The README's Rust code, compiled and run as doctests (its "In an application" section).
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
struct ReadmeDoctests;

pub use registry::{RegistryError, TechniqueEntry, TechniqueRegistry};
pub use renderer::{BackendChoice, BackendKind, Renderer};
pub use shadow_core as core;
use shadow_core::Scene;
use shadow_core::assets::{self, AssetError};
use shadow_core::scenes::{self, SceneParams, UnknownScene};
pub use shadow_cpu as cpu;
pub use shadow_wgpu as gpu;
pub use wgpu;

/// Why a scene could not be had.
#[derive(Debug, thiserror::Error)]
pub enum SceneSourceError {
    /// Neither a built-in scene nor a model file.
    #[error(transparent)]
    Unknown(#[from] UnknownScene),
    /// A model file that did not load.
    #[error(transparent)]
    Asset(#[from] AssetError),
}

/// A built-in scene by name, or a model file staged on a ground plane with the default light and camera
/// (DESIGN 11). A name with a model extension, or an existing path, is read as a file.
///
/// # Errors
/// An unknown scene name, or a model file that does not load.
pub fn load_scene(source: &str, params: &SceneParams, ground: bool) -> Result<Scene, SceneSourceError> {
    load_scene_with(source, params, ground, &assets::LoadOptions::default())
}

/// [`load_scene`] with the given model loading options.
///
/// # Errors
/// An unknown scene name, or a model file that does not load.
pub fn load_scene_with(
    source: &str,
    params: &SceneParams,
    ground: bool,
    options: &assets::LoadOptions,
) -> Result<Scene, SceneSourceError> {
    let path = Path::new(source);
    if assets::is_model_path(path) || (path.exists() && scenes::info(source).is_none()) {
        let mut scene = assets::load_with(path, options)?;
        scenes::stage_model(&mut scene, ground);
        if let Some(t) = params.light {
            scenes::retype_lights(&mut scene, t);
        }
        Ok(scene)
    } else {
        Ok(scenes::build(source, params)?)
    }
}

/// A model file loaded as it is, unstaged (for `inspect`, which reports the file's own bounds).
///
/// # Errors
/// A model file that does not load.
pub fn load_model(path: &Path) -> Result<Scene, AssetError> {
    assets::load(path)
}
