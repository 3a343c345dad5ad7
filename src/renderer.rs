//! Runtime backend choice: one [`Renderer`] runs any registered technique on any available backend.

use shadow_core::image::Rgb8;
use shadow_core::technique::{DebugView, FrameStats, TechniqueSpec};
use shadow_core::{FrameInputs, Image};
use shadow_cpu::{CpuContext, CpuFrame};
use shadow_wgpu::{AdapterChoice, WgpuContext};

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
    adapter: AdapterChoice,
    gpu: Option<WgpuContext>,
}

impl Renderer {
    /// A renderer over a registry.
    #[must_use]
    pub fn new(registry: TechniqueRegistry) -> Self {
        Self { registry, cpu: CpuContext::new(), adapter: AdapterChoice::default(), gpu: None }
    }

    /// Picks the wgpu adapter by name substring (else `SHADOWLAB_ADAPTER`, else the first hardware one).
    #[must_use]
    pub fn with_adapter(mut self, name: Option<String>) -> Self {
        self.adapter.name = name;
        self
    }

    /// The wgpu context, opened on first use. A software adapter is accepted when `allow_software`.
    fn gpu(&mut self, allow_software: bool) -> Result<&mut WgpuContext, Error> {
        if self.gpu.is_none() {
            let choice =
                AdapterChoice { allow_software: allow_software || self.adapter.allow_software, ..self.adapter.clone() };
            self.gpu = Some(WgpuContext::new(&choice)?);
        }
        match self.gpu.as_mut() {
            Some(g) => Ok(g),
            None => unreachable!("just opened"),
        }
    }

    /// The adapter in use, once the wgpu backend has been opened.
    #[must_use]
    pub fn adapter(&self) -> Option<&shadow_wgpu::AdapterSummary> {
        self.gpu.as_ref().map(|g| &g.adapter)
    }

    /// The registry.
    #[must_use]
    pub fn registry(&self) -> &TechniqueRegistry {
        &self.registry
    }

    /// The backends a choice resolves to, with a line saying which adapter and why.
    ///
    /// # Errors
    /// [`Error::Gpu`] when wgpu is asked for and cannot be had.
    pub fn resolve(&mut self, choice: BackendChoice) -> Result<(Vec<BackendKind>, String), Error> {
        let describe = |g: &WgpuContext| format!("{} ({}, {})", g.adapter.name, g.adapter.backend, g.adapter.kind);
        match choice {
            BackendChoice::Cpu => Ok((vec![BackendKind::Cpu], "backend: cpu".into())),
            BackendChoice::Auto => match self.gpu(false) {
                Ok(g) => {
                    let note = format!("backend: wgpu on {} (auto: a GPU adapter was found)", describe(g));
                    Ok((vec![BackendKind::Wgpu], note))
                }
                Err(e) => {
                    self.gpu = None;
                    Ok((vec![BackendKind::Cpu], format!("backend: cpu (auto: {e})")))
                }
            },
            BackendChoice::Wgpu => {
                let g = self.gpu(true)?;
                Ok((vec![BackendKind::Wgpu], format!("backend: wgpu on {}", describe(g))))
            }
            BackendChoice::Both => {
                let g = self.gpu(true)?;
                Ok((vec![BackendKind::Cpu, BackendKind::Wgpu], format!("backends: cpu and wgpu on {}", describe(g))))
            }
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
            BackendKind::Wgpu => {
                let mut t = self.registry.wgpu(spec)?;
                let g = self.gpu(true)?;
                let f = shadow_wgpu::render_frame(g, frame, width, height, t.as_mut())?;
                let debug_views = t.debug_views(g)?;
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
        }
    }
}
