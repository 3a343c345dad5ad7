//! The backend-neutral technique traits (DESIGN 3), settings parsing, and the settings every technique
//! built on a light depth map shares ([`maps`]). The techniques themselves live in shadow-hard and
//! shadow-soft, one folder each.
//!
//! A technique is a plain settings struct (in [`settings`]). Each backend implements
//! [`ShadowTechnique`] for it, which the orphan rule allows because the backend type is local to the
//! backend crate. [`DynShadowTechnique`] is the one object-safe layer, for choosing at runtime.
//!
//! Refinements of the DESIGN 3 sketch, and why:
//! - `build` and `query` both receive a [`LightPass`]: the frame, the light's view and `&mut FrameStats`.
//!   A query needs the light's projection (shadow maps) or position (volumes), and passing it is simpler
//!   than every state keeping a copy; the stats let techniques report counters and sub-phase times (a
//!   readback, say) through one channel instead of a return value the frame driver has to merge.
//! - `Backend::Error: From<TechniqueError> + From<LightViewError>`, so the shared checks (unsupported
//!   light, bad settings, a light no view can be fitted to) give the same error on every backend, and the
//!   one frame script ([`crate::script`]) can report them.

pub mod maps;
pub mod registry;
pub mod settings;

use crate::frame::FrameInputs;
use crate::image::{Image, Rgb8};
use crate::light::{LightView, LightViewError};
use crate::scene::Light;
use crate::stats::{Counters, Timings};

pub use registry::LightKinds;
pub use settings::{SettingKey, SettingsError, TechniqueSettings, TechniqueSpec, key_values};

/// A backend: a bundle of associated types (after wgpu-hal's `Api`).
pub trait Backend: Sized + 'static {
    /// Device, queues, caches, thread pool, counters.
    type Context;
    /// The camera view: depth, normal, position, receiver mask.
    type GBuffer;
    /// One light's visibility over the view, f32 in [0, 1].
    type Visibility;
    /// What can go wrong that a caller cannot foresee.
    type Error: std::error::Error + Send + Sync + 'static + From<TechniqueError> + From<LightViewError>;
    /// Short name for reports ("cpu", "wgpu").
    const NAME: &'static str;
}

/// Errors every backend shares.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum TechniqueError {
    /// The technique cannot handle this kind of light.
    #[error("technique '{technique}' does not support {light} lights")]
    UnsupportedLight {
        /// Technique name.
        technique: String,
        /// Light type name.
        light: &'static str,
    },
    /// Settings that parse but cannot work together, or exceed a limit.
    #[error("technique '{technique}': {message}")]
    BadSettings {
        /// Technique name.
        technique: String,
        /// What is wrong.
        message: String,
    },
    /// `build` was not called before `query`.
    #[error("technique '{0}' was queried before it was built")]
    NotBuilt(String),
    /// A light names a technique the frame was not given.
    #[error("a light is shadowed by '{0}', which the frame was not given (make it from the registry)")]
    Unprepared(String),
}

impl TechniqueError {
    /// `technique` refuses `light`'s kind.
    #[must_use]
    pub fn unsupported_light(technique: &str, light: &Light) -> Self {
        Self::UnsupportedLight { technique: technique.into(), light: light.type_name() }
    }
}

/// Counters and timings a technique reports for one light in one frame.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FrameStats {
    /// Counters (DESIGN 8).
    pub counters: Counters,
    /// Phase times, filled by the frame driver; techniques add sub-phases to `timings.extra`.
    pub timings: Timings,
}

impl FrameStats {
    /// Adds one light's stats into the frame's: counters and sub-phase times are summed over lights.
    pub fn add_light(&mut self, light: FrameStats) {
        self.counters.merge(&light.counters);
        for (key, v) in light.timings.extra {
            *self.timings.extra.entry(key).or_insert(0.0) += v;
        }
    }
}

/// What a technique's build and query see of one light in one frame: the frame's inputs, the light's
/// fitted view, and the stats they report into.
pub struct LightPass<'a> {
    /// The frame: instances, lights, camera.
    pub frame: &'a FrameInputs,
    /// The light and its fitted projections.
    pub light: &'a LightView,
    /// The light's place among the frame's lights. A device whose buffer writes all land before the
    /// frame's commands run (a frame recorded into one command buffer) needs the data of each light in
    /// a place of its own: techniques index it by this.
    pub slot: usize,
    /// Counters and sub-phase times for this light.
    pub stats: &'a mut FrameStats,
}

/// A named picture of a technique's internals (a depth map, an edge map, a silhouette-point overlay).
#[derive(Clone, Debug)]
pub struct DebugView {
    /// Short name, used in file names.
    pub name: String,
    /// The picture.
    pub image: Image<Rgb8>,
}

/// A shadow technique on backend `B`: a build phase per light, then a query phase per view.
pub trait ShadowTechnique<B: Backend>: Send + Sync {
    /// What the technique keeps between frames: pipelines, maps, buffers.
    type State: Send;

    /// The registry name.
    fn name(&self) -> &'static str;

    /// Creates the state once; it is reused for every later frame.
    ///
    /// # Errors
    /// Backend failures (pipeline creation, allocation).
    fn create_state(&self, cx: &mut B::Context) -> Result<Self::State, B::Error>;

    /// Build phase: the light-space representation (maps, volumes, smoothies) for one light.
    ///
    /// # Errors
    /// Backend failures, or settings the backend cannot meet.
    fn build(&self, cx: &mut B::Context, state: &mut Self::State, pass: LightPass<'_>) -> Result<(), B::Error>;

    /// Query phase: the light's visibility at every G-buffer pixel.
    ///
    /// # Errors
    /// Backend failures, or a query before a build.
    fn query(
        &self,
        cx: &mut B::Context,
        state: &mut Self::State,
        pass: LightPass<'_>,
        gbuffer: &B::GBuffer,
        out: &mut B::Visibility,
    ) -> Result<(), B::Error>;

    /// Pictures of the internals after the last build (default: none).
    ///
    /// # Errors
    /// Backend failures (a readback).
    fn debug_views(&self, _cx: &mut B::Context, _state: &Self::State) -> Result<Vec<DebugView>, B::Error> {
        Ok(Vec::new())
    }
}

/// The object-safe face of a technique with its state, for choosing at runtime.
pub trait DynShadowTechnique<B: Backend>: Send {
    /// The registry name.
    fn name(&self) -> &'static str;
    /// The settings, as `key=value,...` (every key, defaults included).
    fn settings(&self) -> String;
    /// See [`ShadowTechnique::build`]; refuses lights the technique does not support.
    ///
    /// # Errors
    /// As [`ShadowTechnique::build`], or [`TechniqueError::UnsupportedLight`].
    fn build(&mut self, cx: &mut B::Context, pass: LightPass<'_>) -> Result<(), B::Error>;
    /// See [`ShadowTechnique::query`].
    ///
    /// # Errors
    /// As [`ShadowTechnique::query`], or [`TechniqueError::NotBuilt`].
    fn query(
        &mut self,
        cx: &mut B::Context,
        pass: LightPass<'_>,
        gbuffer: &B::GBuffer,
        out: &mut B::Visibility,
    ) -> Result<(), B::Error>;
    /// See [`ShadowTechnique::debug_views`].
    ///
    /// # Errors
    /// As [`ShadowTechnique::debug_views`].
    fn debug_views(&mut self, cx: &mut B::Context) -> Result<Vec<DebugView>, B::Error>;
}

/// A technique with its lazily created state: the standard [`DynShadowTechnique`].
pub struct Stateful<B: Backend, T: ShadowTechnique<B>> {
    technique: T,
    settings: String,
    lights: LightKinds,
    state: Option<T::State>,
}

impl<B: Backend, T: ShadowTechnique<B>> Stateful<B, T> {
    /// Wraps a technique taking every kind of light; `settings` is its canonical settings string for
    /// reports.
    pub fn new(technique: T, settings: String) -> Self {
        Self { technique, settings, lights: LightKinds::ALL, state: None }
    }

    /// The same, refusing lights of kinds outside `lights` before any build.
    #[must_use]
    pub fn taking(self, lights: LightKinds) -> Self {
        Self { lights, ..self }
    }

    /// Boxed, ready for a registry.
    pub fn boxed(technique: T, settings: String) -> Box<dyn DynShadowTechnique<B>>
    where
        T: 'static,
    {
        Box::new(Self::new(technique, settings))
    }
}

impl<B: Backend, T: ShadowTechnique<B>> DynShadowTechnique<B> for Stateful<B, T> {
    fn name(&self) -> &'static str {
        self.technique.name()
    }

    fn settings(&self) -> String {
        self.settings.clone()
    }

    fn build(&mut self, cx: &mut B::Context, pass: LightPass<'_>) -> Result<(), B::Error> {
        if !self.lights.takes(&pass.light.light) {
            return Err(TechniqueError::unsupported_light(self.technique.name(), &pass.light.light).into());
        }
        let state = match &mut self.state {
            Some(s) => s,
            slot => slot.insert(self.technique.create_state(cx)?),
        };
        self.technique.build(cx, state, pass)
    }

    fn query(
        &mut self,
        cx: &mut B::Context,
        pass: LightPass<'_>,
        gbuffer: &B::GBuffer,
        out: &mut B::Visibility,
    ) -> Result<(), B::Error> {
        let state = self.state.as_mut().ok_or_else(|| TechniqueError::NotBuilt(self.technique.name().into()))?;
        self.technique.query(cx, state, pass, gbuffer, out)
    }

    fn debug_views(&mut self, cx: &mut B::Context) -> Result<Vec<DebugView>, B::Error> {
        match &self.state {
            Some(s) => self.technique.debug_views(cx, s),
            None => Ok(Vec::new()),
        }
    }
}
