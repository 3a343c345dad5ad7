//! Runtime backend choice: one [`Renderer`] runs any registered technique on any available backend.

use shadow_core::image::Rgb8;
use shadow_core::technique::{DebugView, FrameStats, TechniqueSpec};
use shadow_core::{FrameInputs, Image};
use shadow_cpu::{CpuContext, CpuFrame};

use crate::Error;
use crate::registry::TechniqueRegistry;

/// A concrete backend.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum BackendKind {
    /// The CPU reference backend.
    Cpu,
    /// wgpu.
    Wgpu,
}

impl BackendKind {
    /// Report name.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Self::Cpu => "cpu",
            Self::Wgpu => "wgpu",
        }
    }
}

shadow_core::named_enum! {
    /// What the user asked for.
    pub enum BackendChoice {
        /// wgpu on a hardware GPU if there is one, else the CPU.
        Auto = "auto",
        /// The CPU backend.
        Cpu = "cpu",
        /// The wgpu backend (any adapter, software ones included).
        Wgpu = "wgpu",
        /// Both, compared with each other.
        Both = "both",
    }
}

/// One technique's run on one backend.
pub struct RunOutput {
    /// Registry name.
    pub technique: String,
    /// Canonical settings.
    pub settings: String,
    /// Backend it ran on.
    pub backend: BackendKind,
    /// Shaded image.
    pub color: Image<Rgb8>,
    /// Visibility of each light.
    pub visibility: Vec<Image<f32>>,
    /// Counters and timings.
    pub stats: FrameStats,
    /// Pictures of the technique's internals.
    pub debug_views: Vec<DebugView>,
}

/// Runs techniques on backends chosen at runtime.
pub struct Renderer {
    registry: TechniqueRegistry,
    cpu: CpuContext,
}

impl Renderer {
    /// A renderer over a registry.
    #[must_use]
    pub fn new(registry: TechniqueRegistry) -> Self {
        Self { registry, cpu: CpuContext::new() }
    }

    /// The registry.
    #[must_use]
    pub fn registry(&self) -> &TechniqueRegistry {
        &self.registry
    }

    /// The backends a choice resolves to, with a line saying why.
    ///
    /// # Errors
    /// [`Error::NoGpu`] when wgpu is asked for and cannot be had.
    pub fn resolve(&self, choice: BackendChoice) -> Result<(Vec<BackendKind>, String), Error> {
        match choice {
            BackendChoice::Cpu => Ok((vec![BackendKind::Cpu], "backend: cpu".into())),
            BackendChoice::Auto => {
                Ok((vec![BackendKind::Cpu], "backend: cpu (auto: no GPU backend in this build)".into()))
            }
            BackendChoice::Wgpu | BackendChoice::Both => Err(Error::NoGpu("the wgpu backend is not built yet".into())),
        }
    }

    /// A full CPU frame (G-buffer included) of one technique.
    ///
    /// # Errors
    /// Unknown technique, bad settings, or a rendering failure.
    pub fn run_cpu_frame(
        &mut self,
        frame: &FrameInputs,
        width: u32,
        height: u32,
        spec: &TechniqueSpec,
    ) -> Result<(CpuFrame, Vec<DebugView>), Error> {
        let mut t = self.registry.cpu(spec)?;
        let f = shadow_cpu::render_frame(&mut self.cpu, frame, width, height, t.as_mut())?;
        let views = t.debug_views(&mut self.cpu)?;
        Ok((f, views))
    }

    /// Runs one technique on one backend.
    ///
    /// # Errors
    /// Unknown technique, bad settings, a technique missing on that backend, or a rendering failure.
    pub fn run(
        &mut self,
        backend: BackendKind,
        frame: &FrameInputs,
        width: u32,
        height: u32,
        spec: &TechniqueSpec,
    ) -> Result<RunOutput, Error> {
        let settings = self.registry.canonical(spec)?;
        match backend {
            BackendKind::Cpu => {
                let (f, debug_views) = self.run_cpu_frame(frame, width, height, spec)?;
                Ok(RunOutput {
                    technique: spec.name.clone(),
                    settings,
                    backend,
                    color: f.color,
                    visibility: f.visibility,
                    stats: f.stats,
                    debug_views,
                })
            }
            BackendKind::Wgpu => Err(Error::NoGpu("the wgpu backend is not built yet".into())),
        }
    }
}
