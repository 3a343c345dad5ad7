//! Headless wgpu: instance, adapter choice, device and queue, with errors for everything a caller cannot
//! foresee (no adapter, a missing feature, a lost device, a validation failure).
//!
//! Adapter choice: a name substring (through [`AdapterChoice`], the CLI's `--adapter` or the
//! `SHADOWLAB_ADAPTER` variable) picks that adapter; otherwise the first hardware adapter (discrete, then
//! integrated, then virtual). Software adapters (lavapipe) are used only when asked for by name or when
//! [`AdapterChoice::allow_software`] is set.

use std::cell::{Cell, RefCell};
use std::sync::{Arc, Mutex};

use shadow_core::frame::FrameError;
use shadow_core::light::LightViewError;
use shadow_core::technique::{Backend, TechniqueError};

/// Errors of the wgpu backend.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum WgpuError {
    /// No adapter matches the request.
    #[error("no suitable GPU adapter: {0}")]
    NoAdapter(String),
    /// The adapter lacks something the techniques need.
    #[error("adapter '{adapter}' lacks {what}")]
    MissingFeature {
        /// The adapter.
        adapter: String,
        /// What is missing.
        what: String,
    },
    /// The device could not be created.
    #[error("cannot create a device on '{adapter}': {why}")]
    Device {
        /// The adapter.
        adapter: String,
        /// Why.
        why: String,
    },
    /// The device was lost (driver reset, removal).
    #[error("the GPU device was lost: {0}")]
    DeviceLost(String),
    /// A wgpu validation or out-of-memory error.
    #[error("GPU error during {during}: {message}")]
    Gpu {
        /// What was being done.
        during: String,
        /// wgpu's message.
        message: String,
    },
    /// A request over the adapter's limits or this backend's own.
    #[error("{what} of {width}x{height} cannot be rendered: {why}")]
    BadSize {
        /// What was being sized.
        what: &'static str,
        /// Width.
        width: u64,
        /// Height.
        height: u64,
        /// Why not.
        why: String,
    },
    /// A buffer larger than the device allows.
    #[error("{what} would take {bytes} bytes, over the device's limit of {most} for one buffer")]
    TooLarge {
        /// What the buffer holds.
        what: String,
        /// Its size.
        bytes: u64,
        /// The device's limit.
        most: u64,
    },
    /// A material's texture larger than the device takes.
    #[error("texture '{texture}' of {width}x{height} texels is over the device's limit of {most} a side")]
    TextureTooLarge {
        /// The texture's name (its file, or where in the model it is).
        texture: String,
        /// Width of level 0.
        width: u32,
        /// Height of level 0.
        height: u32,
        /// The device's largest side.
        most: u32,
    },
    /// A wait for the GPU or a read-back inside a frame recorded into a host's encoder, which is only
    /// submitted once the recording is done.
    #[error("{what} needs the GPU's results, which a frame recorded into a host's encoder does not wait for")]
    NotRecordable {
        /// What needed them.
        what: String,
    },
    /// More lights than one frame can shade: one visibility layer and one uniform slot each.
    #[error("the frame has {lights} lights; the wgpu backend shades at most {most}")]
    TooManyLights {
        /// Lights in the frame.
        lights: usize,
        /// The most it can shade on this device.
        most: usize,
    },
    /// A shared technique error.
    #[error(transparent)]
    Technique(#[from] TechniqueError),
    /// The frame could not be assembled.
    #[error(transparent)]
    Frame(#[from] FrameError),
    /// No light view could be fitted.
    #[error(transparent)]
    LightView(#[from] LightViewError),
}

/// The wgpu backend.
#[derive(Clone, Copy, Debug, Default)]
pub struct WgpuBackend;

impl Backend for WgpuBackend {
    type Context = WgpuContext;
    type GBuffer = crate::gbuffer::GpuGBuffer;
    type Visibility = crate::frame::GpuVisibility;
    type Error = WgpuError;
    const NAME: &'static str = "wgpu";

    fn view_size(g: &crate::gbuffer::GpuGBuffer) -> (u32, u32) {
        (g.width, g.height)
    }
}

/// Which adapter to use.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct AdapterChoice {
    /// Case-insensitive substring of the adapter's name; `None` reads `SHADOWLAB_ADAPTER`.
    pub name: Option<String>,
    /// Accept a software adapter when no hardware one exists.
    pub allow_software: bool,
}

impl AdapterChoice {
    /// The adapter name asked for: [`Self::name`], else a non-empty `SHADOWLAB_ADAPTER`.
    #[must_use]
    pub fn wanted(&self) -> Option<String> {
        self.name.clone().or_else(|| std::env::var("SHADOWLAB_ADAPTER").ok()).filter(|s| !s.is_empty())
    }

    /// True when an adapter is asked for by name (then a missing one is an error, never a fallback).
    #[must_use]
    pub fn asked_by_name(&self) -> bool {
        self.wanted().is_some()
    }
}

/// What an adapter is.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct AdapterSummary {
    /// Its name.
    pub name: String,
    /// Its backend (Vulkan, Metal, ...).
    pub backend: String,
    /// Discrete, integrated, virtual, CPU or other.
    pub kind: String,
    /// A software rasterizer (lavapipe, WARP, SwiftShader).
    pub software: bool,
    /// The driver and its version, as the driver reports them (empty where it does not).
    pub driver: String,
}

impl AdapterSummary {
    fn of(info: &wgpu::AdapterInfo) -> Self {
        Self {
            name: info.name.clone(),
            backend: format!("{:?}", info.backend),
            kind: format!("{:?}", info.device_type),
            software: info.device_type == wgpu::DeviceType::Cpu,
            driver: format!("{} {}", info.driver, info.driver_info).trim().to_string(),
        }
    }
}

/// Device, queue and what the adapter can do.
///
/// A context on a device of its own (where the machine has an adapter), and the G-buffer of a scene
/// drawn on it; [`WgpuContext::from_host`] takes an application's device instead.
///
/// ```
/// use shadow_core::FrameInputs;
/// use shadow_core::scenes::{self, SceneParams};
/// use shadow_wgpu::{AdapterChoice, WgpuContext};
///
/// let Ok(mut cx) = WgpuContext::new(&AdapterChoice { allow_software: true, ..Default::default() }) else {
/// #   assert_ne!(std::env::var("SHADOWLAB_REQUIRE_GPU").as_deref(), Ok("1"), "no wgpu adapter");
///     return Ok(()); // no adapter on this machine
/// };
/// let frame = FrameInputs::from_first_camera(&scenes::build("cubes", &SceneParams::default())?)?;
/// let g = shadow_wgpu::gbuffer::render(&mut cx, &frame, 160, 120)?;
/// let depth = shadow_wgpu::readback::read_f32(&cx, &g.depth, 0, wgpu::TextureAspect::DepthOnly)?;
/// assert!(depth.data().iter().any(|&d| d < 1.0), "nothing drawn");
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub struct WgpuContext {
    /// The adapter's description.
    pub adapter: AdapterSummary,
    /// The device.
    pub device: wgpu::Device,
    /// Its queue.
    pub queue: wgpu::Queue,
    /// Timestamp queries are available.
    pub timestamps: bool,
    /// The frame's phase clock while [`crate::frame::render_frame`] runs (timestamp adapters only).
    pub(crate) clock: Option<crate::clock::PhaseClock>,
    lost: Arc<Mutex<Option<String>>>,
    /// The scene's meshes and instances on the device, uploaded once per mesh.
    pub cache: crate::upload::SceneCache,
    /// The pipelines and layouts every pass shares (the frame bind group's layout among them).
    pub shared: crate::pipelines::Shared,
    /// Every pipeline, shader module and layout made on the device, each once per description.
    pub pipelines: crate::PipelineCache,
    /// While a frame is recorded into a host's encoder ([`WgpuContext::record_into`]): that encoder,
    /// lent to each pass in turn.
    lent: RefCell<Option<wgpu::CommandEncoder>>,
    recording: Cell<bool>,
    /// The G-buffer's targets of the last frame, reused while the view's size stays.
    pub(crate) gbuffer_targets: Option<crate::gbuffer::GBufferTargets>,
    /// What it has made, and the frame's transient buffer.
    pub(crate) resources: crate::resources::Resources,
    /// The format of the G-buffer's depth and the volumes' stencil: Depth32FloatStencil8 where the
    /// device has it, Depth24PlusStencil8 otherwise.
    pub depth_stencil: wgpu::TextureFormat,
    /// The maps the lights' techniques lend to a host while a frame is recorded.
    pub(crate) host_maps: crate::host_maps::Capture,
    /// The shadow atlas the lights' maps were last drawn into ([`crate::passes::maps::shadow_atlas`]).
    pub(crate) shadow_atlas: Option<wgpu::Texture>,
}

/// The instance. On a headless Linux machine without `XDG_RUNTIME_DIR`, listing its Vulkan adapters makes
/// Mesa's device-selection layer print an `error:` line that is no error; give the process any absolute path
/// there to quiet it (the workspace's tests and the `shadowlab` binary do).
fn instance() -> wgpu::Instance {
    wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle())
}

/// Every adapter the instance sees.
#[must_use]
pub fn list_adapters() -> Vec<AdapterSummary> {
    let inst = instance();
    pollster::block_on(inst.enumerate_adapters(wgpu::Backends::all()))
        .iter()
        .map(|a| AdapterSummary::of(&a.get_info()))
        .collect()
}

fn rank(info: &wgpu::AdapterInfo) -> u8 {
    match info.device_type {
        wgpu::DeviceType::DiscreteGpu => 0,
        wgpu::DeviceType::IntegratedGpu => 1,
        wgpu::DeviceType::VirtualGpu => 2,
        wgpu::DeviceType::Other => 3,
        wgpu::DeviceType::Cpu => 4,
    }
}

/// What an adapter lacks of what shadowlab renders with, if anything: the Depth32FloatStencil8 format,
/// and the float and integer formats of the G-buffer and the techniques' targets as render attachments
/// (an OpenGL adapter such as llvmpipe's cannot render to Rgba32Float).
fn missing(adapter: &wgpu::Adapter) -> Option<String> {
    use wgpu::TextureFormat as F;
    [F::Rgba32Float, F::Rg32Float, F::R32Float, F::R32Uint, F::Rgba8Unorm]
        .into_iter()
        .find(|&f| {
            !adapter.get_texture_format_features(f).allowed_usages.contains(wgpu::TextureUsages::RENDER_ATTACHMENT)
        })
        .map(|f| format!("rendering to {f:?}"))
}

/// The adapter `choice` asks for: one named like it, else the best that can render shadowlab's targets.
fn choose_adapter(choice: &AdapterChoice) -> Result<wgpu::Adapter, WgpuError> {
    let adapters = pollster::block_on(instance().enumerate_adapters(wgpu::Backends::all()));
    // Each adapter once, with its API: llvmpipe is both a Vulkan and an OpenGL adapter of one name.
    let mut all: Vec<String> =
        adapters.iter().map(|a| format!("{} ({:?})", a.get_info().name, a.get_info().backend)).collect();
    all.dedup();
    match choice.wanted() {
        Some(name) => named_adapter(adapters, &name, &all),
        None => best_adapter(adapters, choice.allow_software, &all),
    }
}

/// Of the adapters named like `name` (llvmpipe is both a Vulkan and an OpenGL one), one that can render
/// shadowlab's targets; else the first, refused later with what it lacks. `all` names every adapter.
fn named_adapter(adapters: Vec<wgpu::Adapter>, name: &str, all: &[String]) -> Result<wgpu::Adapter, WgpuError> {
    let n = name.to_lowercase();
    let mut named: Vec<wgpu::Adapter> =
        adapters.into_iter().filter(|a| a.get_info().name.to_lowercase().contains(&n)).collect();
    named.sort_by_key(|a| missing(a).is_some());
    named.into_iter().next().ok_or_else(|| {
        WgpuError::NoAdapter(format!(
            "none named like '{name}' (adapters: {})",
            if all.is_empty() { "none".into() } else { all.join(", ") }
        ))
    })
}

/// The best ranked adapter that can render shadowlab's targets, software ones only if allowed; the error
/// says why none fits. `all` names every adapter.
fn best_adapter(
    adapters: Vec<wgpu::Adapter>,
    allow_software: bool,
    all: &[String],
) -> Result<wgpu::Adapter, WgpuError> {
    let unfit: Vec<String> = adapters
        .iter()
        .filter_map(|a| {
            missing(a).map(|what| format!("{} ({:?}) lacks {what}", a.get_info().name, a.get_info().backend))
        })
        .collect();
    let mut candidates: Vec<wgpu::Adapter> = adapters
        .into_iter()
        .filter(|a| allow_software || a.get_info().device_type != wgpu::DeviceType::Cpu)
        .filter(|a| missing(a).is_none())
        .collect();
    candidates.sort_by_key(|a| rank(&a.get_info()));
    candidates.into_iter().next().ok_or_else(|| {
        WgpuError::NoAdapter(if all.is_empty() {
            "no adapter at all (install a Vulkan driver; mesa-vulkan-drivers gives a software one)".into()
        } else if unfit.len() == all.len() {
            format!(
                "no adapter can render shadowlab's targets: {} (install a Vulkan driver; \
                 mesa-vulkan-drivers gives a software one)",
                unfit.join(", ")
            )
        } else {
            format!(
                "no hardware adapter (software ones: {}); use one with --backend wgpu, or name it with \
                 --adapter NAME",
                all.join(", ")
            )
        })
    })
}

impl WgpuContext {
    /// Opens an adapter and a device.
    ///
    /// # Errors
    /// No matching adapter, a missing feature, or a device that cannot be created.
    pub fn new(choice: &AdapterChoice) -> Result<Self, WgpuError> {
        let adapter = choose_adapter(choice)?;
        let info = adapter.get_info();
        if let Some(what) = missing(&adapter) {
            return Err(WgpuError::MissingFeature { adapter: info.name, what });
        }
        let desc = wgpu::DeviceDescriptor {
            label: Some("shadowlab"),
            required_features: Self::REQUIRED_FEATURES | (Self::OPTIONAL_FEATURES & adapter.features()),
            // Its own device may as well have everything the adapter offers: larger maps, more lights.
            required_limits: adapter.limits(),
            ..Default::default()
        };
        let (device, queue) = pollster::block_on(adapter.request_device(&desc))
            .map_err(|e| WgpuError::Device { adapter: info.name.clone(), why: e.to_string() })?;
        let lost = Arc::new(Mutex::new(None));
        let flag = lost.clone();
        device.set_device_lost_callback(move |reason, msg| {
            if let Ok(mut l) = flag.lock() {
                *l = Some(format!("{reason:?}: {msg}"));
            }
        });
        Ok(Self::on_device(&adapter, device, queue, lost))
    }

    /// The features a device must have: none beyond WebGPU's core.
    pub const REQUIRED_FEATURES: wgpu::Features = wgpu::Features::empty();

    /// The features used where the device has them: Depth32FloatStencil8 for the G-buffer's depth and
    /// the volumes' stencil (an f32 depth, as the CPU backend's; without it Depth24PlusStencil8, which
    /// every device has), timestamp queries, for GPU phase times, and early depth tests forced in a
    /// shader, for passes whose fragments write storage (which otherwise run before their depth test).
    pub const OPTIONAL_FEATURES: wgpu::Features = wgpu::Features::DEPTH32FLOAT_STENCIL8
        .union(wgpu::Features::TIMESTAMP_QUERY)
        .union(wgpu::Features::SHADER_EARLY_DEPTH_TEST);

    /// The limits a device must meet: WebGPU's defaults, but for 64 bytes of colour attachments per
    /// sample (the G-buffer pass writes four 16-byte targets at once). Larger maps and views, more lights
    /// and longer pixel lists are taken where the device's own limits allow them, and refused by name
    /// past them.
    #[must_use]
    pub fn required_limits() -> wgpu::Limits {
        wgpu::Limits { max_color_attachment_bytes_per_sample: 64, ..wgpu::Limits::default() }
    }

    /// Whether shadowlab can work on `adapter`: it has [`Self::REQUIRED_FEATURES`] and renders to every
    /// target format shadowlab uses.
    #[must_use]
    pub fn can_use(adapter: &wgpu::Adapter) -> bool {
        missing(adapter).is_none()
    }

    /// The device a host application asks for to lend it to shadowlab: [`Self::REQUIRED_FEATURES`] and
    /// [`Self::required_limits`] (a host may ask for more: those of [`Self::OPTIONAL_FEATURES`] its adapter
    /// has are used).
    #[must_use]
    pub fn device_descriptor() -> wgpu::DeviceDescriptor<'static> {
        wgpu::DeviceDescriptor {
            label: Some("shadowlab host"),
            required_features: Self::REQUIRED_FEATURES,
            required_limits: Self::required_limits(),
            ..Default::default()
        }
    }

    /// A context on the host application's own device and queue (clones of them: wgpu's handles are
    /// shared), made from `adapter`. Everything shadowlab creates lives on that device, so its textures
    /// can be drawn into the host's surface and sampled by the host's passes.
    ///
    /// # Errors
    /// [`WgpuError::MissingFeature`] naming each thing the device lacks: a feature of
    /// [`Self::REQUIRED_FEATURES`], a limit under [`Self::required_limits`], or a target format the
    /// adapter cannot render to.
    pub fn from_host(adapter: &wgpu::Adapter, device: wgpu::Device, queue: wgpu::Queue) -> Result<Self, WgpuError> {
        let info = adapter.get_info();
        let mut lacks = Vec::new();
        let features = Self::REQUIRED_FEATURES - device.features();
        if !features.is_empty() {
            lacks.push(format!("the device features {features:?}"));
        }
        Self::required_limits().check_limits_with_fail_fn(&device.limits(), false, |name, needed, has| {
            lacks.push(format!("the device limit {name} of {needed} (it has {has})"));
        });
        lacks.extend(missing(adapter));
        if !lacks.is_empty() {
            return Err(WgpuError::MissingFeature { adapter: info.name, what: lacks.join(", ") });
        }
        // The host keeps its own device-lost callback: wgpu holds one per device.
        Ok(Self::on_device(adapter, device, queue, Arc::new(Mutex::new(None))))
    }

    fn on_device(
        adapter: &wgpu::Adapter,
        device: wgpu::Device,
        queue: wgpu::Queue,
        lost: Arc<Mutex<Option<String>>>,
    ) -> Self {
        // The G-buffer's depth and the volumes' stencil: f32 depth where the device has it.
        let depth_stencil = if device.features().contains(wgpu::Features::DEPTH32FLOAT_STENCIL8) {
            wgpu::TextureFormat::Depth32FloatStencil8
        } else {
            wgpu::TextureFormat::Depth24PlusStencil8
        };
        let pipelines = crate::PipelineCache::new(device.clone());
        let shared = crate::pipelines::Shared::new(&pipelines, depth_stencil);
        Self {
            adapter: AdapterSummary::of(&adapter.get_info()),
            timestamps: device.features().contains(wgpu::Features::TIMESTAMP_QUERY),
            device,
            queue,
            clock: None,
            lost,
            cache: crate::upload::SceneCache::default(),
            shared,
            pipelines,
            lent: RefCell::new(None),
            recording: Cell::new(false),
            gbuffer_targets: None,
            resources: Default::default(),
            depth_stencil,
            host_maps: Default::default(),
            shadow_atlas: None,
        }
    }

    /// Fails if the device was lost.
    ///
    /// # Errors
    /// [`WgpuError::DeviceLost`].
    pub fn check_lost(&self) -> Result<(), WgpuError> {
        match self.lost.lock().ok().and_then(|l| l.clone()) {
            Some(why) => Err(WgpuError::DeviceLost(why)),
            None => Ok(()),
        }
    }

    /// The layout of bind group 0 of every pass that reads the frame (a view uniform and the instances):
    /// what a pipeline outside this crate needs to use the G-buffer's `frame_group` or the shared shader
    /// functions of `shaders::shadow_map()`.
    #[must_use]
    pub fn frame_layout(&self) -> &wgpu::BindGroupLayout {
        &self.shared.frame_layout
    }

    /// Runs `f` inside validation and out-of-memory error scopes and turns anything they catch into an
    /// error naming `during`.
    ///
    /// # Errors
    /// What the scopes caught, or a lost device.
    pub fn scoped<R>(&self, during: &str, f: impl FnOnce(&Self) -> R) -> Result<R, WgpuError> {
        self.check_lost()?;
        let oom = self.device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
        let validation = self.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let r = f(self);
        let v = pollster::block_on(validation.pop());
        let o = pollster::block_on(oom.pop());
        if let Some(e) = v.or(o) {
            return Err(WgpuError::Gpu { during: during.into(), message: e.to_string() });
        }
        self.check_lost()?;
        Ok(r)
    }

    /// Marks the end of the technique's own GPU work in the phase under way: what it submits after
    /// this (counter passes and their readbacks) is timed apart as `gpu_counters` (see [`crate::clock`]).
    /// Does nothing outside a frame or on adapters without timestamp queries.
    pub fn end_of_work(&mut self) {
        if let Some(clock) = &mut self.clock {
            clock.mark_work_end(&self.device, &self.queue);
        }
    }

    /// Ends the named step of the phase under way once its work is submitted: where the adapter has
    /// timestamps, the frame reports the GPU time since the phase began or the last step ended as
    /// `gpu_<phase>.<name>` (see [`crate::clock`]). Does nothing outside a frame or without timestamps.
    pub fn step(&self, name: &'static str) {
        if let Some(clock) = &self.clock {
            clock.mark_step(&self.device, &self.queue, name);
        }
    }

    /// An encoder to record a pass's work into; hand it back with [`Self::submit`]. The backend's passes
    /// and the techniques record only into these (the clock's markers aside), in the order the frame
    /// script runs them, so where a frame's work goes is decided here and in `submit` alone.
    #[must_use]
    pub fn encoder(&self, label: &str) -> wgpu::CommandEncoder {
        if let Some(lent) = self.lent.borrow_mut().take() {
            return lent;
        }
        self.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some(label) })
    }

    /// Submits the work recorded into an encoder from [`Self::encoder`] to the queue; while a frame is
    /// recorded into a host's encoder, hands that encoder back for the next pass instead.
    pub fn submit(&self, encoder: wgpu::CommandEncoder) {
        if self.recording.get() {
            *self.lent.borrow_mut() = Some(encoder);
        } else {
            self.queue.submit([encoder.finish()]);
        }
    }

    /// Runs `record` with every pass recording into `host`, the host application's own encoder, which
    /// the host submits: nothing is submitted, waited for or read back meanwhile (a pass that would wait
    /// or read back fails with [`WgpuError::NotRecordable`]), and the instrumentation (counters, clock)
    /// is off ([`Self::instrumented`]). On an error the host's encoder may have lost what was recorded
    /// into it, its own earlier commands included.
    ///
    /// # Errors
    /// What `record` returns.
    pub fn record_into<R>(
        &mut self,
        host: &mut wgpu::CommandEncoder,
        record: impl FnOnce(&mut Self) -> Result<R, WgpuError>,
    ) -> Result<R, WgpuError> {
        let stand_in = self.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("stand-in") });
        *self.lent.get_mut() = Some(std::mem::replace(host, stand_in));
        self.recording.set(true);
        let clock = self.clock.take();
        let result = record(self);
        self.clock = clock;
        self.recording.set(false);
        if let Some(lent) = self.lent.get_mut().take() {
            *host = lent;
        }
        result
    }

    /// Whether passes count what they do (counters read back after each pass) and the clock marks the
    /// phases: in every frame but one recorded into a host's encoder.
    #[must_use]
    pub fn instrumented(&self) -> bool {
        !self.recording.get()
    }

    /// Refuses a wait or read-back for `what` while a frame is recorded into a host's encoder.
    ///
    /// # Errors
    /// [`WgpuError::NotRecordable`] while recording.
    pub fn may_wait(&self, what: &str) -> Result<(), WgpuError> {
        if self.recording.get() {
            return Err(WgpuError::NotRecordable { what: what.into() });
        }
        Ok(())
    }

    /// Waits for all submitted work.
    ///
    /// # Errors
    /// A lost device or a poll failure.
    pub fn wait(&self) -> Result<(), WgpuError> {
        self.may_wait("a wait for the GPU")?;
        self.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| WgpuError::Gpu { during: "wait".into(), message: e.to_string() })?;
        self.check_lost()
    }
}
