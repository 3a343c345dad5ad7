//! The error of every job in this crate. The CLI prints it as one line.

use std::path::PathBuf;

/// Why a job failed.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// Scene, model file or override.
    #[error(transparent)]
    Setup(#[from] crate::setup::SetupError),
    /// Technique name or settings.
    #[error(transparent)]
    Registry(#[from] crate::registry::RegistryError),
    /// A technique spec that does not parse.
    #[error(transparent)]
    Settings(#[from] shadow_core::technique::SettingsError),
    /// The frame (camera, light, empty scene).
    #[error(transparent)]
    Frame(#[from] shadow_core::frame::FrameError),
    /// The CPU backend.
    #[error(transparent)]
    Cpu(#[from] shadow_cpu::CpuError),
    /// The wgpu backend.
    #[error(transparent)]
    Gpu(#[from] shadow_wgpu::WgpuError),
    /// A file could not be written.
    #[error("cannot write {path}: {why}")]
    Write {
        /// The file.
        path: PathBuf,
        /// What went wrong.
        why: String,
    },
    /// Images of different sizes compared.
    #[error(transparent)]
    Compare(#[from] shadow_core::metrics::SizeMismatch),
    /// The viewer's window, or presenting to it.
    #[error("the window: {0}")]
    Window(String),
    /// Anything else the user asked for that cannot be done.
    #[error("{0}")]
    Usage(String),
}

impl Error {
    /// True for errors in what the user typed (exit status 2), false for failures of the work (1).
    #[must_use]
    pub fn is_usage(&self) -> bool {
        use crate::setup::SetupError;
        matches!(
            self,
            Self::Setup(SetupError::Option(_) | SetupError::Source(crate::SceneSourceError::Unknown(_)))
                | Self::Registry(_)
                | Self::Settings(_)
                | Self::Usage(_)
                | Self::Frame(shadow_core::frame::FrameError::NoCamera)
        )
    }

    /// The technique error inside, when a backend's technique refused or failed (an unsupported light,
    /// bad settings, a query before a build).
    #[must_use]
    pub fn technique(&self) -> Option<&shadow_core::technique::TechniqueError> {
        match self {
            Self::Cpu(shadow_cpu::CpuError::Technique(e)) | Self::Gpu(shadow_wgpu::WgpuError::Technique(e)) => Some(e),
            _ => None,
        }
    }
}

impl From<shadow_core::image::ImageWriteError> for Error {
    fn from(e: shadow_core::image::ImageWriteError) -> Self {
        Self::Write { path: e.path.into(), why: e.source.to_string() }
    }
}
