//! Shadows inside a host application's own wgpu frame: shadowlab's context on the host's device, a frame
//! recorder, and a technique chosen by its spec at runtime and switched between frames.
//!
//! ```no_run
//! # fn frame(adapter: &wgpu::Adapter, device: &wgpu::Device, queue: &wgpu::Queue,
//! #          frame: &shadowlab::core::FrameInputs, view: &wgpu::TextureView) -> Result<(), shadowlab::Error> {
//! use shadowlab::realtime::RealtimeShadows;
//! use shadowlab::TechniqueRegistry;
//!
//! let mut shadows =
//!     RealtimeShadows::new(adapter, device.clone(), queue.clone(), TechniqueRegistry::builtin(), "shadow-map")?;
//! let target = shadow_wgpu::ColorTarget { view, format: wgpu::TextureFormat::Bgra8UnormSrgb, width: 800, height: 600 };
//! let mut encoder = device.create_command_encoder(&Default::default());
//! shadows.record(&mut encoder, frame, &target)?;
//! queue.submit([encoder.finish()]);
//! shadows.set_technique("shadow-volume-zfail")?;
//! # Ok(()) }
//! ```

use shadow_core::script::LightTechniques;
use shadow_core::technique::{DynShadowTechnique, TechniqueSpec};
use shadow_core::{FrameInputs, LightView};
use shadow_wgpu::{ColorTarget, FrameRecorder, FrameTimes, WgpuBackend, WgpuContext};

use crate::renderer::Named;
use crate::{Error, TechniqueRegistry};

/// Shadows recorded into a host's frames (see the module docs).
pub struct RealtimeShadows {
    cx: WgpuContext,
    recorder: FrameRecorder,
    registry: TechniqueRegistry,
    spec: TechniqueSpec,
    technique: Box<dyn DynShadowTechnique<WgpuBackend>>,
    /// The techniques lights name for themselves.
    named: Named<WgpuBackend>,
}

impl RealtimeShadows {
    /// Shadows on the host's device and queue (made from `adapter`), with the technique of `spec`
    /// (`NAME[:key=value,...]`) from `registry`.
    ///
    /// # Errors
    /// A device short of what shadowlab requires, or a spec the registry refuses or has no GPU side for.
    pub fn new(
        adapter: &wgpu::Adapter,
        device: wgpu::Device,
        queue: wgpu::Queue,
        registry: TechniqueRegistry,
        spec: &str,
    ) -> Result<Self, Error> {
        let cx = WgpuContext::from_host(adapter, device, queue)?;
        let spec = TechniqueSpec::parse(spec)?;
        let technique = registry.wgpu(&spec)?;
        Ok(Self { cx, recorder: FrameRecorder::new(), registry, spec, technique, named: Vec::new() })
    }

    /// Switches to the technique of `spec` from the next frame on; on an error the current one stays.
    ///
    /// # Errors
    /// A spec the registry refuses or has no GPU side for.
    pub fn set_technique(&mut self, spec: &str) -> Result<(), Error> {
        let spec = TechniqueSpec::parse(spec)?;
        self.technique = self.registry.wgpu(&spec)?;
        self.spec = spec;
        Ok(())
    }

    /// Forgets every light's last build, so the next frame builds each light afresh: after a change a
    /// build cannot see (lights whose view and casters are unchanged are otherwise not built again).
    pub fn invalidate(&mut self) {
        self.technique.invalidate();
        self.named.iter_mut().for_each(|(_, t)| t.invalidate());
    }

    /// The technique's spec.
    #[must_use]
    pub fn technique(&self) -> &TechniqueSpec {
        &self.spec
    }

    /// Records one frame into the host's `encoder`, shading into `target` (see [`FrameRecorder::record`]):
    /// each light shadowed as its [`shadow_core::LightShadow`] says, by the technique it names (made from
    /// the registry on its first frame and kept) or by this one. Returns the fitted view of each light.
    ///
    /// # Errors
    /// As [`FrameRecorder::record`], or a light naming a technique the registry refuses.
    pub fn record(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        frame: &FrameInputs,
        target: &ColorTarget<'_>,
    ) -> Result<Vec<LightView>, Error> {
        let registry = &self.registry;
        crate::renderer::name_techniques(frame, &mut self.named, |s| Ok(registry.wgpu(s)?))?;
        let techniques = LightTechniques { frame: self.technique.as_mut(), named: &mut self.named };
        Ok(self.recorder.record(&mut self.cx, encoder, frame, techniques, target)?)
    }

    /// Times every frame on the GPU from now on (or stops), phase by phase, the times read back a few
    /// frames later without waiting (see [`FrameRecorder::time_frames`]), for [`Self::gpu_times`].
    /// Returns whether the device has timestamp queries; without them nothing is timed.
    pub fn time_frames(&mut self, on: bool) -> bool {
        self.recorder.time_frames(&self.cx, on)
    }

    /// The GPU times of the latest timed frame whose times have come back: a few frames behind, once the
    /// host submits its frames and its device polls (as presenting does).
    #[must_use]
    pub fn gpu_times(&self) -> Option<&FrameTimes> {
        self.recorder.gpu_times()
    }

    /// The last frame's visibility, a layer per light (see [`FrameRecorder::visibility`]).
    #[must_use]
    pub fn visibility(&self) -> Option<&wgpu::Texture> {
        self.recorder.visibility()
    }

    /// The depth maps light `light` of the last frame was shadowed through, where its technique lends
    /// them (see [`FrameRecorder::map`]).
    #[must_use]
    pub fn map(&self, light: usize) -> Option<&shadow_wgpu::HostMap> {
        self.recorder.map(light)
    }

    /// shadowlab's context on the host's device.
    #[must_use]
    pub fn context(&self) -> &WgpuContext {
        &self.cx
    }
}
