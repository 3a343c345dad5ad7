//! Runtime backend choice: one [`Renderer`] runs any registered technique on any available backend.

use shadow_core::image::Rgb8;
use shadow_core::light::AtlasPlan;
use shadow_core::script::LightTechniques;
use shadow_core::technique::{Backend, DebugView, DynShadowTechnique, FrameStats, TechniqueSpec};
use shadow_core::{FrameInputs, Image};
use shadow_cpu::{CpuBackend, CpuContext, CpuFrame};
use shadow_wgpu::{AdapterChoice, WgpuBackend, WgpuContext};

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
    /// The shadow atlas: the tiles and their side each light was given.
    pub atlas: Option<AtlasPlan>,
    /// Counters and timings.
    pub stats: FrameStats,
    /// Pictures of the technique's internals, where the renderer was asked for them
    /// ([`Renderer::keep_debug_views`]).
    pub debug_views: Vec<DebugView>,
}

/// Runs techniques on backends chosen at runtime.
pub struct Renderer {
    registry: TechniqueRegistry,
    cpu: CpuContext,
    adapter: AdapterChoice,
    gpu: Option<WgpuContext>,
    /// Whether a run makes the technique's debug views (a read-back of its maps on the GPU).
    debug_views: bool,
}

impl Renderer {
    /// A renderer over a registry.
    #[must_use]
    pub fn new(registry: TechniqueRegistry) -> Self {
        Self { registry, cpu: CpuContext::new(), adapter: AdapterChoice::default(), gpu: None, debug_views: false }
    }

    /// Makes each run's [`RunOutput::debug_views`] from now on (`true`), or leaves them empty (`false`, the
    /// default: on the GPU they read the technique's maps back, a cost no frame should pay unasked).
    pub fn keep_debug_views(&mut self, on: bool) {
        self.debug_views = on;
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

    /// The GPU context, made on first use (a software adapter allowed), for driving the wgpu backend
    /// directly: recording frames into an encoder of the caller's, say.
    ///
    /// # Errors
    /// No adapter, or a device that cannot be created.
    pub fn wgpu_context(&mut self) -> Result<&mut WgpuContext, Error> {
        self.gpu(true)
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
            BackendChoice::Auto => {
                let named = self.adapter.asked_by_name();
                match self.gpu(false) {
                    Ok(g) => {
                        let note = format!("backend: wgpu on {} (auto: a GPU adapter was found)", describe(g));
                        Ok((vec![BackendKind::Wgpu], note))
                    }
                    // An adapter asked for by name that is not there is an error, not a reason to fall back.
                    Err(e) if named => Err(e),
                    Err(e) => {
                        self.gpu = None;
                        Ok((vec![BackendKind::Cpu], format!("backend: cpu (auto: {e})")))
                    }
                }
            }
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

    /// A full CPU frame (G-buffer included) of one technique (and of those the frame's lights name).
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
        let mut named = Vec::new();
        name_techniques(frame, &mut named, |s| Ok(self.registry.cpu(s)?))?;
        let techniques = LightTechniques { frame: t.as_mut(), named: &mut named };
        let f = shadow_cpu::render_frame(&mut self.cpu, frame, width, height, techniques)?;
        let views = t.debug_views(&mut self.cpu)?;
        Ok((f, views))
    }

    /// A CPU frame of a technique made earlier (`prepare` it for the CPU), built for `frame` and queried
    /// over the receivers of `gbuffer`, another view's (see [`shadow_cpu::render_frame_over`]); the lights'
    /// own techniques are made for the frame as [`Renderer::run_prepared`] makes them.
    ///
    /// # Errors
    /// A technique prepared for the GPU, or a rendering failure.
    pub fn run_cpu_over(
        &mut self,
        p: &mut Prepared,
        frame: &FrameInputs,
        gbuffer: &shadow_cpu::GBuffer,
    ) -> Result<CpuFrame, Error> {
        let PreparedKind::Cpu(t, named) = &mut p.technique else {
            return Err(Error::Usage(format!("'{}' was prepared for the GPU, not the CPU", p.name)));
        };
        name_techniques(frame, named, |s| Ok(self.registry.cpu(s)?))?;
        let techniques = LightTechniques { frame: t.as_mut(), named };
        Ok(shadow_cpu::render_frame_over(&mut self.cpu, frame, gbuffer, techniques)?)
    }

    /// The surfaces a backend's G-buffer shows in `frame`'s view, as a CPU G-buffer: the points its
    /// techniques are queried at, so a reference traced over them measures that backend at its own points.
    ///
    /// # Errors
    /// A bad size, or a GPU failure.
    pub fn gbuffer_of(
        &mut self,
        backend: BackendKind,
        frame: &FrameInputs,
        width: u32,
        height: u32,
    ) -> Result<shadow_cpu::GBuffer, Error> {
        match backend {
            BackendKind::Cpu => Ok(shadow_cpu::gbuffer::render(frame, width, height)?),
            BackendKind::Wgpu => {
                let surfaces = shadow_wgpu::gbuffer::read(self.gpu(true)?, frame, width, height)?;
                Ok(shadow_cpu::GBuffer::from_surfaces(frame, surfaces))
            }
        }
    }

    /// Drops what the backends keep from frame to frame for a still scene (the CPU's ray-casting BVH), so
    /// the next frame rebuilds it and its time shows in that frame's build phase.
    pub fn forget_caches(&mut self) {
        self.cpu.forget();
    }

    /// The BVH of a frame's casters (for measurements against the reference).
    pub fn bvh(&mut self, frame: &FrameInputs) -> std::sync::Arc<shadow_cpu::bvh::SceneBvh> {
        self.cpu.bvh(frame)
    }

    /// A technique made for a backend, keeping its state (pipelines, maps) from frame to frame.
    ///
    /// # Errors
    /// Unknown technique, bad settings, or a technique missing on that backend.
    pub fn prepare(&self, backend: BackendKind, spec: &TechniqueSpec) -> Result<Prepared, Error> {
        let settings = self.registry.canonical(spec)?;
        let technique = match backend {
            BackendKind::Cpu => PreparedKind::Cpu(self.registry.cpu(spec)?, Vec::new()),
            BackendKind::Wgpu => PreparedKind::Wgpu(self.registry.wgpu(spec)?, Vec::new()),
        };
        Ok(Prepared { name: spec.name.clone(), settings, technique })
    }

    /// Renders one frame with a prepared technique.
    ///
    /// # Errors
    /// A rendering failure, or no GPU for a wgpu technique.
    pub fn run_prepared(
        &mut self,
        p: &mut Prepared,
        frame: &FrameInputs,
        width: u32,
        height: u32,
    ) -> Result<RunOutput, Error> {
        let keep_views = self.debug_views;
        let (backend, color, visibility, atlas, stats, debug_views) = match &mut p.technique {
            PreparedKind::Cpu(t, named) => {
                name_techniques(frame, named, |s| Ok(self.registry.cpu(s)?))?;
                let techniques = LightTechniques { frame: t.as_mut(), named };
                let f = shadow_cpu::render_frame(&mut self.cpu, frame, width, height, techniques)?;
                let views = if keep_views { t.debug_views(&mut self.cpu)? } else { Vec::new() };
                self.cpu.recycle(f.gbuffer);
                (BackendKind::Cpu, f.color, f.visibility, f.atlas, f.stats, views)
            }
            PreparedKind::Wgpu(t, named) => {
                name_techniques(frame, named, |s| Ok(self.registry.wgpu(s)?))?;
                let g = self.gpu(true)?;
                let techniques = LightTechniques { frame: t.as_mut(), named };
                let f = shadow_wgpu::render_frame(g, frame, width, height, techniques)?;
                let views = if keep_views { t.debug_views(g)? } else { Vec::new() };
                (BackendKind::Wgpu, f.color, f.visibility, f.atlas, f.stats, views)
            }
        };
        Ok(RunOutput {
            technique: p.name.clone(),
            settings: p.settings.clone(),
            backend,
            color,
            visibility,
            atlas,
            stats,
            debug_views,
        })
    }

    /// Runs one technique on one backend, from a fresh state.
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
        let mut p = self.prepare(backend, spec)?;
        self.run_prepared(&mut p, frame, width, height)
    }
}

enum PreparedKind {
    Cpu(Box<dyn DynShadowTechnique<CpuBackend>>, Named<CpuBackend>),
    Wgpu(Box<dyn DynShadowTechnique<WgpuBackend>>, Named<WgpuBackend>),
}

/// The techniques lights name for themselves, each made once for its spec and kept with its state.
pub type Named<B> = Vec<(TechniqueSpec, Box<dyn DynShadowTechnique<B>>)>;

/// Makes with `make` each technique a light of `frame` names that `named` lacks.
///
/// # Errors
/// What `make` refuses: an unknown technique, bad settings, one missing on the backend.
pub fn name_techniques<B: Backend>(
    frame: &FrameInputs,
    named: &mut Named<B>,
    make: impl Fn(&TechniqueSpec) -> Result<Box<dyn DynShadowTechnique<B>>, Error>,
) -> Result<(), Error> {
    for shadow in &frame.shadows {
        if let Some(spec) = shadow.technique.as_ref().filter(|s| !named.iter().any(|(n, _)| n == *s)) {
            named.push((spec.clone(), make(spec)?));
        }
    }
    Ok(())
}

/// A technique ready to run on one backend, with its state.
pub struct Prepared {
    name: String,
    settings: String,
    technique: PreparedKind,
}

impl Prepared {
    /// Registry name.
    #[must_use]
    pub fn name(&self) -> &str {
        &self.name
    }
    /// Canonical settings.
    #[must_use]
    pub fn settings(&self) -> &str {
        &self.settings
    }
    /// Forgets every light's last build (its own and the named techniques'), so the next frame builds
    /// each light afresh.
    pub fn invalidate(&mut self) {
        match &mut self.technique {
            PreparedKind::Cpu(t, named) => {
                t.invalidate();
                named.iter_mut().for_each(|(_, t)| t.invalidate());
            }
            PreparedKind::Wgpu(t, named) => {
                t.invalidate();
                named.iter_mut().for_each(|(_, t)| t.invalidate());
            }
        }
    }

    /// The backend it runs on.
    #[must_use]
    pub fn backend(&self) -> BackendKind {
        match self.technique {
            PreparedKind::Cpu(..) => BackendKind::Cpu,
            PreparedKind::Wgpu(..) => BackendKind::Wgpu,
        }
    }
}
