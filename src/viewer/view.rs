//! The 3D view: the scene rendered at the size the UI gives it, into a texture the UI draws. On wgpu the
//! frame is recorded into the viewer's own encoder through the real-time path (no waits, no read-backs:
//! the texture is drawn by the same submission); on the CPU backend it is rendered there and uploaded.

use shadow_core::image::Rgb8;
use shadow_core::technique::{DebugView, TechniqueSpec};
use shadow_core::{FrameInputs, Image};
use shadow_wgpu::ColorTarget;

use crate::realtime::RealtimeShadows;
use crate::renderer::{Prepared, RunOutput};
use crate::{BackendKind, Error, Renderer, TechniqueRegistry};

/// The view texture's format: egui draws a texture of its own as sRGB-encoded bytes in an Rgba8Unorm
/// one, and the shading pass encodes sRGB itself into a target that does not.
const FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;

/// What is alive on the device (see [`View::memory`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct GpuMemory {
    /// Buffers.
    pub buffers: u64,
    /// Their bytes.
    pub buffer_bytes: u64,
    /// The bytes of the textures (wgpu counts their memory on every backend, their number not).
    pub texture_bytes: u64,
}

impl std::fmt::Display for GpuMemory {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let mb = |b: u64| b as f64 / 1e6;
        write!(
            f,
            "{} buffers ({:.1} MB), textures {:.1} MB",
            self.buffers,
            mb(self.buffer_bytes),
            mb(self.texture_bytes)
        )
    }
}

/// The viewer's device, as winit's surface needs it.
pub struct Gpu {
    /// The adapter.
    pub adapter: wgpu::Adapter,
    /// The device.
    pub device: wgpu::Device,
    /// Its queue.
    pub queue: wgpu::Queue,
}

/// The wgpu view texture, registered with egui's renderer.
struct Target {
    texture: wgpu::Texture,
    view: wgpu::TextureView,
    id: egui::TextureId,
}

/// The CPU backend's side: its renderer, the technique on it, and the last frame.
struct CpuSide {
    renderer: Renderer,
    technique: Prepared,
    last: Option<RunOutput>,
    texture: Option<egui::TextureHandle>,
}

/// The 3D view on either backend.
pub struct View {
    shadows: RealtimeShadows,
    target: Option<Target>,
    cpu: Option<CpuSide>,
    backend: BackendKind,
    /// The instrumented wgpu path (a device of its own), made when debug views are first asked for.
    instrumented: Option<Renderer>,
}

impl View {
    /// The view on `gpu`'s device with the technique of `spec`, drawing on `backend`.
    ///
    /// # Errors
    /// A device shadowlab cannot use, or a spec the registry refuses.
    pub fn new(gpu: &Gpu, spec: &str, backend: BackendKind) -> Result<Self, Error> {
        let registry = TechniqueRegistry::builtin();
        let shadows = RealtimeShadows::new(&gpu.adapter, gpu.device.clone(), gpu.queue.clone(), registry, spec)?;
        let mut view = Self { shadows, target: None, cpu: None, backend: BackendKind::Wgpu, instrumented: None };
        view.set_backend(backend)?;
        Ok(view)
    }

    /// The backend drawing the view.
    #[must_use]
    pub fn backend(&self) -> BackendKind {
        self.backend
    }

    /// The technique's spec.
    #[must_use]
    pub fn technique(&self) -> &TechniqueSpec {
        self.shadows.technique()
    }

    /// The adapter the wgpu backend draws on.
    #[must_use]
    pub fn adapter(&self) -> String {
        let a = &self.shadows.context().adapter;
        format!("{} ({})", a.name, a.backend)
    }

    /// Draws with `backend` from the next frame on; on an error the backend stays.
    ///
    /// # Errors
    /// The technique has no side on that backend.
    pub fn set_backend(&mut self, backend: BackendKind) -> Result<(), Error> {
        if backend == BackendKind::Cpu && self.cpu.is_none() {
            let renderer = Renderer::new(TechniqueRegistry::builtin());
            let technique = renderer.prepare(BackendKind::Cpu, self.shadows.technique())?;
            self.cpu = Some(CpuSide { renderer, technique, last: None, texture: None });
        }
        self.backend = backend;
        Ok(())
    }

    /// Switches both backends to the technique of `spec`; on an error the current one stays.
    ///
    /// # Errors
    /// A spec the registry refuses on either backend.
    pub fn set_technique(&mut self, spec: &str) -> Result<(), Error> {
        let parsed = TechniqueSpec::parse(spec)?;
        if let Some(cpu) = &mut self.cpu {
            let technique = cpu.renderer.prepare(BackendKind::Cpu, &parsed)?;
            self.shadows.set_technique(spec)?;
            cpu.technique = technique;
        } else {
            self.shadows.set_technique(spec)?;
        }
        Ok(())
    }

    /// Forgets every light's last build (after the scene changed under the technique).
    pub fn invalidate(&mut self) {
        self.shadows.invalidate();
    }

    /// The buffers and textures alive on the device and their bytes, as wgpu counts them (the 3D view's,
    /// the UI's and every technique's).
    #[must_use]
    pub fn memory(&self) -> GpuMemory {
        let hal = self.shadows.context().device.get_internal_counters().hal;
        let count = |c: &wgpu::wgt::InternalCounter| u64::try_from(c.read()).unwrap_or(0);
        GpuMemory {
            buffers: count(&hal.buffers),
            buffer_bytes: count(&hal.buffer_memory),
            texture_bytes: count(&hal.texture_memory),
        }
    }

    /// [`Self::memory`] once the device has finished every submitted frame, so the staging buffers of
    /// writes still in flight are freed and not counted: what a script's `memory` step reports.
    #[must_use]
    pub fn settled_memory(&self) -> GpuMemory {
        // A device that cannot wait (lost, or mid-recording) is read as it stands.
        let _ = self.shadows.context().wait();
        self.memory()
    }

    /// Times the wgpu frames on the GPU (where the adapter has timestamps); see [`Self::gpu_times`].
    pub fn time_frames(&mut self) -> bool {
        self.shadows.time_frames(true)
    }

    /// The GPU times of a recent wgpu frame, phase by phase.
    #[must_use]
    pub fn gpu_times(&self) -> Option<&shadow_wgpu::FrameTimes> {
        self.shadows.gpu_times()
    }

    /// Draws `frame` at `width x height` and returns the texture egui shows: on wgpu recorded into
    /// `encoder` (submitted by the caller before egui's pass reads it, in the same submission), on the CPU
    /// rendered now and uploaded through `ui`.
    ///
    /// # Errors
    /// The frame's rendering failed (a technique refusing the light, say).
    pub fn draw(
        &mut self,
        (gpu, egui_renderer, ui): (&Gpu, &mut egui_wgpu::Renderer, &egui::Context),
        encoder: &mut wgpu::CommandEncoder,
        frame: &FrameInputs,
        (width, height): (u32, u32),
    ) -> Result<egui::TextureId, Error> {
        match (self.backend, &mut self.cpu) {
            (BackendKind::Cpu, Some(cpu)) => {
                let run = cpu.renderer.run_prepared(&mut cpu.technique, frame, width, height)?;
                let image = super::overlay::color_image(&run.color);
                let options = egui::TextureOptions::NEAREST;
                let texture = cpu.texture.get_or_insert_with(|| ui.load_texture("cpu view", image.clone(), options));
                texture.set(image, options);
                cpu.last = Some(run);
                Ok(texture.id())
            }
            _ => {
                // The texture of the frame before while the size stays; a new one under the same egui id
                // when it changes.
                let target = match self.target.take() {
                    Some(t) if t.texture.width() == width && t.texture.height() == height => self.target.insert(t),
                    old => {
                        let texture =
                            shadow_wgpu::frame::layered(self.shadows.context(), "view", width, height, 1, FORMAT);
                        let view = texture.create_view(&Default::default());
                        let nearest = wgpu::FilterMode::Nearest;
                        let id = match old {
                            Some(old) => {
                                egui_renderer.update_egui_texture_from_wgpu_texture(
                                    &gpu.device,
                                    &view,
                                    nearest,
                                    old.id,
                                );
                                old.id
                            }
                            None => egui_renderer.register_native_texture(&gpu.device, &view, nearest),
                        };
                        self.target.insert(Target { texture, view, id })
                    }
                };
                let color = ColorTarget { view: &target.view, format: FORMAT, width, height };
                self.shadows.record(encoder, frame, &color)?;
                Ok(target.id)
            }
        }
    }

    /// The last frame drawn, read back from the GPU (after its submission) or as the CPU drew it.
    ///
    /// # Errors
    /// No frame drawn yet, or the read-back failed.
    pub fn screenshot(&self) -> Result<Image<Rgb8>, Error> {
        match (self.backend, &self.cpu) {
            (BackendKind::Cpu, Some(cpu)) => Ok(cpu.last.as_ref().ok_or_else(not_drawn)?.color.clone()),
            _ => {
                let target = self.target.as_ref().ok_or_else(not_drawn)?;
                Ok(shadow_wgpu::readback::read_rgb8(self.shadows.context(), &target.texture)?)
            }
        }
    }

    /// The first light's visibility in the last frame drawn (read back as [`Self::screenshot`] is).
    ///
    /// # Errors
    /// No frame drawn yet, or the read-back failed.
    pub fn visibility(&self) -> Result<Image<f32>, Error> {
        match (self.backend, &self.cpu) {
            (BackendKind::Cpu, Some(cpu)) => {
                Ok(cpu.last.as_ref().and_then(|r| r.visibility.first()).ok_or_else(not_drawn)?.clone())
            }
            _ => {
                let layers = self.shadows.visibility().ok_or_else(not_drawn)?;
                Ok(shadow_wgpu::readback::read_f32(self.shadows.context(), layers, 0, wgpu::TextureAspect::All)?)
            }
        }
    }

    /// The technique's debug views and counters of `frame` at `size`, from one instrumented frame rendered
    /// now by a technique made afresh (so every light is built and counted, none kept from the frame
    /// before): on the CPU, or on wgpu on a device of its own.
    ///
    /// # Errors
    /// The instrumented frame failed, or no wgpu adapter for it.
    pub fn inspect(&mut self, frame: &FrameInputs, (width, height): (u32, u32)) -> Result<Inspection, Error> {
        let spec = self.shadows.technique().clone();
        let run = match (self.backend, &mut self.cpu) {
            (BackendKind::Cpu, Some(cpu)) => {
                cpu.renderer.keep_debug_views(true);
                let run = cpu.renderer.run(BackendKind::Cpu, frame, width, height, &spec);
                cpu.renderer.keep_debug_views(false);
                run?
            }
            _ => {
                let adapter = self.shadows.context().adapter.name.clone();
                let renderer = self.instrumented.get_or_insert_with(|| {
                    let mut renderer = Renderer::new(TechniqueRegistry::builtin()).with_adapter(Some(adapter));
                    renderer.keep_debug_views(true);
                    renderer
                });
                renderer.run(BackendKind::Wgpu, frame, width, height, &spec)?
            }
        };
        Ok(Inspection { views: run.debug_views, counters: run.stats.counters.entries() })
    }
}

/// What an instrumented frame shows of the technique: its debug views and counters.
pub struct Inspection {
    /// The debug views.
    pub views: Vec<DebugView>,
    /// Every measured counter, by name.
    pub counters: Vec<(String, f64)>,
}

fn not_drawn() -> Error {
    Error::Usage("no frame drawn yet".into())
}
