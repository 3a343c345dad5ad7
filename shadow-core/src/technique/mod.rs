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
use crate::light::{LightTiles, LightView, LightViewError, Reach};
use crate::scene::{Light, ShadowUpdate};
use crate::stats::{Counters, Timings};

pub use registry::{CasterHandling, CasterKinds, LightKinds};
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

    /// A G-buffer's width and height in pixels.
    fn view_size(gbuffer: &Self::GBuffer) -> (u32, u32);
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
    /// The frame's shadow atlas cannot hold its lights' maps.
    #[error(transparent)]
    AtlasFull(#[from] crate::light::atlas::AtlasFull),
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
    /// Where the light reaches in the view: a query need answer only the pixels within it (those outside are
    /// lit, as its direct term there is 0), a build may leave out what lights nothing within it.
    pub reach: Reach,
    /// Where the light's maps lie in the frame's shadow atlas, and their side, for a technique that asks
    /// for tiles ([`ShadowTechnique::atlas_side`]); `None`: its maps are its own, of its own size.
    pub tiles: Option<&'a LightTiles>,
    /// When the light's build is made again ([`crate::LightShadow::update`]).
    pub update: ShadowUpdate,
    /// The light's place among the frame's lights. A device whose buffer writes all land before the
    /// frame's commands run (a frame recorded into one command buffer) needs the data of each light in
    /// a place of its own: techniques index it by this.
    pub slot: usize,
    /// The view's width over its height: with the camera's field of view, the frustum a build may fit
    /// its maps to (cascades, perspective maps).
    pub aspect: f32,
    /// Counters and sub-phase times for this light.
    pub stats: &'a mut FrameStats,
}

/// Which instances a light's build reads ([`ShadowTechnique::build_reads`]): the cache of static lights
/// keeps a light's build while none of them changes, whatever else moves.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum BuildReads {
    /// Every instance of the frame: a build that extrudes casters' silhouettes or casts rays reads casters
    /// wherever they are.
    #[default]
    EveryInstance,
    /// The instances in the light's views ([`LightView::sees`]): a build that only rasterizes casters into
    /// the light's projections reads nothing outside them.
    LightViews,
}

impl LightPass<'_> {
    /// The same pass with its stats borrowed for a shorter while: one pass handed to a build, then to a
    /// query.
    pub fn reborrow(&mut self) -> LightPass<'_> {
        LightPass {
            frame: self.frame,
            light: self.light,
            reach: self.reach,
            tiles: self.tiles,
            update: self.update,
            slot: self.slot,
            aspect: self.aspect,
            stats: &mut *self.stats,
        }
    }

    /// A digest of what a light's build reads: the light's position (or direction), its radius, its
    /// fitted projections (which hold its cone) and its atlas tiles, and each instance's index, mesh, version, placement and shadow
    /// flags, of every instance or of those in the light's views as `reads` says (the camera is not among
    /// them: a build that reads it is not kept, see [`ShadowTechnique::build_is_reusable`]).
    #[must_use]
    pub fn build_key(&self, reads: BuildReads) -> u64 {
        use std::hash::{Hash, Hasher};
        let floats = |h: &mut dyn Hasher, v: &[f32]| v.iter().for_each(|x| h.write_u32(x.to_bits()));
        let mut h = std::collections::hash_map::DefaultHasher::new();
        floats(&mut h, &self.light.source().homogeneous().to_array());
        floats(&mut h, &[self.light.light.radius]);
        self.tiles.map(|t| (t.side, t.origins.iter().map(|o| o.to_array()).collect::<Vec<_>>())).hash(&mut h);
        for p in &self.light.projections {
            floats(&mut h, &p.clip_from_world.to_cols_array());
        }
        let read = |inst: &crate::frame::Instance| reads == BuildReads::EveryInstance || self.light.sees(inst.bounds);
        crate::hash::digest(h.finish(), &self.frame.instances, |i, inst, h| {
            if read(inst) {
                (i, inst.mesh_key, inst.mesh_version, inst.casts_shadow, inst.receives_shadow).hash(h);
                floats(h, &inst.world_from_local.to_cols_array());
            }
        })
    }
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
///
/// A technique is written once per backend (`impl ShadowTechnique<CpuBackend>` in shadow-cpu's terms,
/// `ShadowTechnique<WgpuBackend>` in shadow-wgpu's; their crates' docs show one each), or once for every
/// backend, as this wrapper that counts the builds of the technique it wraps:
///
/// ```
/// use std::sync::atomic::{AtomicUsize, Ordering};
/// use shadow_core::technique::{Backend, LightPass, ShadowTechnique};
///
/// struct Counted<T> {
///     inner: T,
///     builds: AtomicUsize,
/// }
///
/// impl<B: Backend, T: ShadowTechnique<B>> ShadowTechnique<B> for Counted<T> {
///     type State = T::State;
///
///     fn name(&self) -> &'static str {
///         self.inner.name()
///     }
///
///     fn create_state(&self, cx: &mut B::Context) -> Result<T::State, B::Error> {
///         self.inner.create_state(cx)
///     }
///
///     fn build(&self, cx: &mut B::Context, state: &mut T::State, pass: LightPass<'_>) -> Result<(), B::Error> {
///         self.builds.fetch_add(1, Ordering::Relaxed);
///         self.inner.build(cx, state, pass)
///     }
///
///     fn query(
///         &self,
///         cx: &mut B::Context,
///         state: &mut T::State,
///         pass: LightPass<'_>,
///         gbuffer: &B::GBuffer,
///         out: &mut B::Visibility,
///     ) -> Result<(), B::Error> {
///         self.inner.query(cx, state, pass, gbuffer, out)
///     }
/// }
/// ```
///
/// [`Stateful`] gives it a state per light and the object-safe [`DynShadowTechnique`] face that frames and
/// registries take.
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

    /// Whether a light's build of `frame` may be kept for later frames while the light's view, the
    /// casters and the meshes it reads stay the same (default: yes). A technique whose build reads the
    /// camera, or leaves its query data that lasts one frame only (the frame's transient buffer), says no.
    fn build_is_reusable(&self, frame: &FrameInputs) -> bool {
        let _ = frame;
        true
    }

    /// Which instances a light's build reads (default: every one). A technique whose build only
    /// rasterizes casters into the light's projections says [`BuildReads::LightViews`], and a light's
    /// build is kept while casters outside its views move.
    fn build_reads(&self) -> BuildReads {
        BuildReads::EveryInstance
    }

    /// Pictures of the internals after the last build (default: none).
    ///
    /// # Errors
    /// Backend failures (a readback).
    fn debug_views(&self, _cx: &mut B::Context, _state: &Self::State) -> Result<Vec<DebugView>, B::Error> {
        Ok(Vec::new())
    }

    /// The map side a spot or point light shadowed by this technique asks of the frame's shadow atlas
    /// ([`crate::light::atlas`]), which grants it that side or less as [`LightPass::tiles`]; `None` (the
    /// default): the technique keeps maps of its own.
    fn atlas_side(&self) -> Option<u32> {
        None
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
    /// Forgets every light's last build, so the next frame builds each light afresh (after a change the
    /// build cannot see: a mesh edited in place, say).
    fn invalidate(&mut self);
    /// Forgets light `slot`'s last build where it lies in tiles of the frame's shadow atlas: the light was
    /// given none this frame (it reached no pixel, or cast no shadow), so other lights may draw there.
    fn release_tiles(&mut self, slot: usize);
    /// The atlas tiles light `slot`'s last build lies in, if it is held: the frame's atlas leaves them
    /// where they are while the light's size stays near them, so the build may be kept.
    fn held_tiles(&self, slot: usize) -> Option<LightTiles>;
    /// See [`ShadowTechnique::atlas_side`].
    fn atlas_side(&self) -> Option<u32>;
}

/// A technique with its lazily created state, one per light of the frame ([`LightPass::slot`]): the
/// standard [`DynShadowTechnique`].
///
/// A light is built again as its [`ShadowUpdate`] says. By default, one whose view, casters and meshes
/// are what its last build read is not: its state still holds that build (the three.js `autoUpdate`
/// idea, made automatic). A technique whose build cannot be kept ([`ShadowTechnique::build_is_reusable`])
/// builds every frame whatever the light says. The frame's counters say how many lights were spared
/// (`cached_builds`); [`DynShadowTechnique::invalidate`] forgets every build.
pub struct Stateful<B: Backend, T: ShadowTechnique<B>> {
    technique: T,
    settings: String,
    lights: LightKinds,
    /// Per light slot.
    slots: Vec<Option<Slot<T::State>>>,
    /// The slot last built or queried, for the debug views.
    last: usize,
}

/// One light's state and what its last build was.
struct Slot<S> {
    state: S,
    /// What the last build read ([`LightPass::build_key`]), where it may be kept.
    read: Option<u64>,
    /// The state holds a whole build.
    built: bool,
    /// Frames its build has been kept since it was made.
    kept: u32,
    /// The atlas tiles the build lies in: it is kept only while the light holds them.
    tiles: Option<LightTiles>,
}

impl<S> Slot<S> {
    /// Whether the build it holds serves a frame whose build would read `read` (`None`: a build that
    /// cannot be kept) into `tiles`, as `update` says. A build in other tiles than the frame gives the light
    /// is never kept, whatever `update` says: other lights' maps may lie there now.
    fn keeps(&self, read: Option<u64>, tiles: Option<&LightTiles>, update: ShadowUpdate) -> bool {
        if !self.built || read.is_none() || self.tiles.as_ref() != tiles {
            return false;
        }
        match update {
            ShadowUpdate::EveryFrame => false,
            ShadowUpdate::OnChange => self.read == read,
            ShadowUpdate::Every(n) => self.kept + 1 < n,
            ShadowUpdate::Once => true,
        }
    }
}

impl<B: Backend, T: ShadowTechnique<B>> Stateful<B, T> {
    /// Wraps a technique taking every kind of light; `settings` is its canonical settings string for
    /// reports.
    pub fn new(technique: T, settings: String) -> Self {
        Self { technique, settings, lights: LightKinds::ALL, slots: Vec::new(), last: 0 }
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
        let reads = self.technique.build_is_reusable(pass.frame).then(|| pass.build_key(self.technique.build_reads()));
        if self.slots.len() <= pass.slot {
            self.slots.resize_with(pass.slot + 1, || None);
        }
        self.last = pass.slot;
        let slot = match &mut self.slots[pass.slot] {
            Some(s) => s,
            slot => {
                let state = self.technique.create_state(cx)?;
                slot.insert(Slot { state, read: None, built: false, kept: 0, tiles: None })
            }
        };
        if slot.keeps(reads, pass.tiles, pass.update) {
            slot.kept += 1;
            *pass.stats.counters.extra.entry("cached_builds".into()).or_insert(0.0) += 1.0;
            return Ok(());
        }
        (slot.read, slot.built, slot.kept) = (None, false, 0);
        slot.tiles = pass.tiles.cloned();
        self.technique.build(cx, &mut slot.state, pass)?;
        (slot.read, slot.built) = (reads, true);
        Ok(())
    }

    fn query(
        &mut self,
        cx: &mut B::Context,
        pass: LightPass<'_>,
        gbuffer: &B::GBuffer,
        out: &mut B::Visibility,
    ) -> Result<(), B::Error> {
        let not_built = || TechniqueError::NotBuilt(self.technique.name().into());
        let slot = self.slots.get_mut(pass.slot).and_then(Option::as_mut).ok_or_else(not_built)?;
        self.last = pass.slot;
        self.technique.query(cx, &mut slot.state, pass, gbuffer, out)
    }

    fn debug_views(&mut self, cx: &mut B::Context) -> Result<Vec<DebugView>, B::Error> {
        match self.slots.get(self.last).and_then(Option::as_ref) {
            Some(s) => self.technique.debug_views(cx, &s.state),
            None => Ok(Vec::new()),
        }
    }

    fn invalidate(&mut self) {
        for slot in self.slots.iter_mut().flatten() {
            (slot.read, slot.built) = (None, false);
        }
    }

    fn release_tiles(&mut self, slot: usize) {
        if let Some(Some(slot)) = self.slots.get_mut(slot)
            && slot.tiles.take().is_some()
        {
            (slot.read, slot.built) = (None, false);
        }
    }

    fn held_tiles(&self, slot: usize) -> Option<LightTiles> {
        self.slots.get(slot)?.as_ref().filter(|s| s.built)?.tiles.clone()
    }

    fn atlas_side(&self) -> Option<u32> {
        self.technique.atlas_side()
    }
}
