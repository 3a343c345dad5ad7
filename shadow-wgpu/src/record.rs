//! A frame recorded into the host application's own command encoder: the frame script of shadow-core
//! with steps that only record. Nothing is submitted, waited for or read back; the host submits its
//! encoder when it likes, and the shaded image lands in the host's colour target (any renderable format,
//! sRGB or not, RGBA or BGRA). The techniques' counters and the phase clock are off
//! ([`WgpuContext::instrumented`]).
//!
//! An engine that renders its own depth and normals and shades itself lends them in place of the G-buffer
//! pass ([`FrameRecorder::record_visibility`]) and reads each light's visibility, or looks into the
//! depth maps of the techniques that lend them itself ([`FrameRecorder::map`]), both in WGSL of its
//! own ([`crate::host_wgsl`]).
//!
//! A technique that needs the GPU's results within the frame (one reconstructing on the CPU from a map
//! it reads back, or drawing in rectangles read back from the GPU) fails here with
//! [`WgpuError::NotRecordable`].

use std::collections::HashMap;

use shadow_core::light::Reach;
use shadow_core::script::{FrameSteps, LightTechniques, run_frame};
use shadow_core::technique::FrameStats;
use shadow_core::{FrameInputs, LightView};

use crate::context::{WgpuBackend, WgpuContext, WgpuError};
use crate::frame::{GpuVisibility, check_lights, clear_lit, full_screen_shade, layer_view, layered, shade_group};
use crate::gbuffer::{self, GpuGBuffer, HostSurfaces, ImportPass};
use crate::host_maps::HostMap;
use crate::pipelines::{VISIBILITY, full_screen_pipeline};
use crate::timer::{FrameTimer, FrameTimes};

/// Records frames into a host's encoder, keeping what it made for them: the visibility targets (remade
/// when the view's size or the number of lights changes) and a shading pipeline per
/// colour format.
///
/// A frame recorded into an encoder with a technique of one's own, here a shadow map filtered by a 3x3
/// PCF kernel through the backend's shared map passes:
///
/// ```
/// use shadow_core::FrameInputs;
/// use shadow_core::scenes::{self, SceneParams};
/// use shadow_core::technique::maps::DepthMap;
/// use shadow_core::technique::settings::BiasMode;
/// use shadow_core::technique::settings::Filter;
/// use shadow_core::technique::{LightPass, ShadowTechnique, Stateful, TechniqueError};
/// use shadow_wgpu::passes::maps::{DepthMaps, MapQuery, QueryExtras};
/// use shadow_wgpu::{AdapterChoice, ColorTarget, FrameRecorder, GpuGBuffer, GpuVisibility};
/// use shadow_wgpu::{WgpuBackend, WgpuContext, WgpuError, shaders};
///
/// struct Pcf;
///
/// impl ShadowTechnique<WgpuBackend> for Pcf {
///     type State = (DepthMaps, MapQuery);
///
///     fn name(&self) -> &'static str {
///         "pcf"
///     }
///
///     fn create_state(&self, cx: &mut WgpuContext) -> Result<Self::State, WgpuError> {
///         let module = cx.pipelines.module("shadow_map", shaders::shadow_map());
///         let map = DepthMap { resolution: 1024, bias: BiasMode::Slope, bias_constant: 16.0, bias_slope: 2.0, bias_world: 0.0 };
///         Ok((DepthMaps::with_module(cx, &module, &map), MapQuery::new(cx, &module, Filter::Pcf3x3)))
///     }
///
///     fn build(&self, cx: &mut WgpuContext, (maps, _): &mut Self::State, pass: LightPass<'_>) -> Result<(), WgpuError> {
///         maps.render(cx, pass.frame, pass.light, 1024)
///     }
///
///     fn query(
///         &self,
///         cx: &mut WgpuContext,
///         (maps, query): &mut Self::State,
///         pass: LightPass<'_>,
///         g: &GpuGBuffer,
///         out: &mut GpuVisibility,
///     ) -> Result<(), WgpuError> {
///         let maps = maps.maps().ok_or_else(|| TechniqueError::NotBuilt("pcf".into()))?;
///         query.run(cx, maps, pass.light, g, out, &QueryExtras::NONE)
///     }
/// }
///
/// let Ok(mut cx) = WgpuContext::new(&AdapterChoice { allow_software: true, ..Default::default() }) else {
/// #   assert_ne!(std::env::var("SHADOWLAB_REQUIRE_GPU").as_deref(), Ok("1"), "no wgpu adapter");
///     return Ok(()); // no adapter on this machine
/// };
/// let frame = FrameInputs::from_first_camera(&scenes::build("cubes", &SceneParams::default())?)?;
/// let format = wgpu::TextureFormat::Rgba8UnormSrgb;
/// let texture = shadow_wgpu::frame::layered(&cx, "target", 320, 240, 1, format);
/// let view = texture.create_view(&Default::default());
/// let mut recorder = FrameRecorder::new();
/// let mut technique = Stateful::new(Pcf, String::new());
/// let mut encoder = cx.device.create_command_encoder(&Default::default());
/// let target = ColorTarget { view: &view, format, width: 320, height: 240 };
/// recorder.record(&mut cx, &mut encoder, &frame, &mut technique, &target)?;
/// cx.queue.submit([encoder.finish()]);
/// // The picture is in `texture`; each light's visibility stays for engines that shade themselves.
/// let layers = recorder.visibility().expect("a recorded frame");
/// let visibility = shadow_wgpu::readback::read_f32(&cx, layers, 0, wgpu::TextureAspect::All)?;
/// assert!(visibility.data().contains(&0.0) && visibility.data().contains(&1.0));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Default)]
pub struct FrameRecorder {
    visibility: Option<Visibility>,
    shade: HashMap<wgpu::TextureFormat, wgpu::RenderPipeline>,
    /// The pass that makes the G-buffer from a host's surfaces, once one lends them.
    import: Option<ImportPass>,
    /// With frames timed: their GPU times, read back frames later.
    timer: Option<FrameTimer>,
    /// The maps each light of the last frame lent (see [`Self::map`]).
    maps: Vec<Option<HostMap>>,
}

/// Every light's visibility, a layer each of one R32Float array texture (1 lit, 0 shadowed).
struct Visibility {
    texture: wgpu::Texture,
    width: u32,
    height: u32,
    layers: u32,
}

/// What a recorded frame draws on: a colour target to shade into (its G-buffer pass its own), or an
/// engine's depth and normals standing in for the G-buffer, with no shading.
#[derive(Clone, Copy)]
enum Surfaces<'a> {
    Shaded(&'a ColorTarget<'a>),
    Host(&'a HostSurfaces<'a>),
}

/// Where a recorded frame's shading goes: a view of the host's texture, its format and size.
pub struct ColorTarget<'a> {
    /// The view to shade into (cleared first).
    pub view: &'a wgpu::TextureView,
    /// Its texture's format (an sRGB format gets linear values, which its stores encode; any other
    /// gets sRGB-encoded values).
    pub format: wgpu::TextureFormat,
    /// Its width in pixels: the frame's view width.
    pub width: u32,
    /// Its height in pixels.
    pub height: u32,
}

impl FrameRecorder {
    /// A recorder with nothing made yet.
    #[must_use]
    pub fn new() -> Self {
        Self::default()
    }

    /// Records one frame of `frame` into `encoder`: the G-buffer, every light's build and query (with the
    /// frame's technique or the light's own, from `techniques`; a single technique converts into them),
    /// and shading into `target`. Returns the fitted view of each light.
    ///
    /// # Errors
    /// Too many lights, a light the technique does not take, a technique that needs the GPU's results
    /// within the frame ([`WgpuError::NotRecordable`]), or a GPU failure. On an error, what `encoder`
    /// held may be lost.
    pub fn record<'t, 'o: 't>(
        &mut self,
        cx: &mut WgpuContext,
        encoder: &mut wgpu::CommandEncoder,
        frame: &FrameInputs,
        techniques: impl Into<LightTechniques<'t, 'o, WgpuBackend>>,
        target: &ColorTarget<'_>,
    ) -> Result<Vec<LightView>, WgpuError> {
        self.record_frame(cx, encoder, frame, techniques.into(), Surfaces::Shaded(target))
    }

    /// Records one frame's shadows into `encoder` for an engine that renders its own depth and normals
    /// and shades itself: the G-buffer made from `host`'s surfaces in place of its pass, every light's
    /// build and query, and no shading; each light's visibility is then in [`Self::visibility`].
    /// Returns the fitted view of each light.
    ///
    /// # Errors
    /// As [`Self::record`].
    pub fn record_visibility<'t, 'o: 't>(
        &mut self,
        cx: &mut WgpuContext,
        encoder: &mut wgpu::CommandEncoder,
        frame: &FrameInputs,
        techniques: impl Into<LightTechniques<'t, 'o, WgpuBackend>>,
        host: &HostSurfaces<'_>,
    ) -> Result<Vec<LightView>, WgpuError> {
        self.record_frame(cx, encoder, frame, techniques.into(), Surfaces::Host(host))
    }

    /// The body of both: the frame's targets and steps for `surfaces`, recorded into `encoder`.
    fn record_frame(
        &mut self,
        cx: &mut WgpuContext,
        encoder: &mut wgpu::CommandEncoder,
        frame: &FrameInputs,
        techniques: LightTechniques<'_, '_, WgpuBackend>,
        surfaces: Surfaces<'_>,
    ) -> Result<Vec<LightView>, WgpuError> {
        check_lights(cx, frame)?;
        let (width, height) = match surfaces {
            Surfaces::Shaded(target) => (target.width, target.height),
            Surfaces::Host(host) => (host.width, host.height),
        };
        let visibility = visibility_for(&mut self.visibility, cx, width, height, frame.lights.len() as u32);
        let (host, shade) = match surfaces {
            Surfaces::Shaded(target) => {
                let shade = self.shade.entry(target.format).or_insert_with(|| shade_pipeline(cx, target.format));
                (None, Some((&*shade, target.view)))
            }
            Surfaces::Host(host) => (Some((host, &*self.import.get_or_insert_with(|| ImportPass::new(cx)))), None),
        };
        let steps = RecordSteps { width, height, visibility, host, shade, timer: self.timer.as_mut() };
        cx.host_maps.begin(frame.lights.len());
        let run = cx.record_into(encoder, |cx| run_frame(cx, frame, steps, techniques));
        self.maps = cx.host_maps.end();
        Ok(run?.light_views)
    }

    /// Times every frame on the GPU from now on (or stops): timestamps at its start, after the G-buffer,
    /// after the lights' shadows and at its end, read back a few frames later without waiting (see
    /// [`FrameTimer`]), for [`Self::gpu_times`]. Returns whether the device has timestamp queries; without
    /// them nothing is timed.
    pub fn time_frames(&mut self, cx: &WgpuContext, on: bool) -> bool {
        self.timer = if on { self.timer.take().or_else(|| FrameTimer::new(cx)) } else { None };
        self.timer.is_some()
    }

    /// The GPU times of the latest timed frame whose times have come back (`G-buffer`, `shadows`,
    /// `shading`): a few frames behind, once the host submits its frames and its device polls (as
    /// presenting does).
    #[must_use]
    pub fn gpu_times(&self) -> Option<&FrameTimes> {
        self.timer.as_ref().and_then(FrameTimer::last)
    }

    /// The depth maps light `light` of the last recorded frame was shadowed through, and how to look into
    /// them, where its technique lends them (`shadow-map`, cascades, LiSPSM, perspective shadow maps;
    /// see [`crate::host_maps`]): for a host that samples them in its own shader with
    /// `host_wgsl::MAPS`. `None` for other techniques and lights past the frame's.
    #[must_use]
    pub fn map(&self, light: usize) -> Option<&HostMap> {
        self.maps.get(light).and_then(Option::as_ref)
    }

    /// The last recorded frame's visibility, a layer per light (R32Float: 1 lit, 0 shadowed), for engines
    /// that shade themselves; `None` before the first frame.
    #[must_use]
    pub fn visibility(&self) -> Option<&wgpu::Texture> {
        self.visibility.as_ref().map(|v| &v.texture)
    }
}

/// The visibility targets in `slot` for a `width x height` view of `lights` lights, made again only when
/// either changed.
fn visibility_for<'a>(
    slot: &'a mut Option<Visibility>,
    cx: &WgpuContext,
    width: u32,
    height: u32,
    lights: u32,
) -> &'a wgpu::Texture {
    let layers = lights.max(1);
    let fits = |v: &Visibility| v.width == width && v.height == height && v.layers == layers;
    if !slot.as_ref().is_some_and(fits) {
        *slot = None;
    }
    let made = slot.get_or_insert_with(|| Visibility {
        texture: layered(cx, "recorded visibility", width, height, layers, VISIBILITY),
        width,
        height,
        layers,
    });
    &made.texture
}

/// The shading pipeline for a target of `format`.
fn shade_pipeline(cx: &WgpuContext, format: wgpu::TextureFormat) -> wgpu::RenderPipeline {
    let module = cx.pipelines.module("shade", crate::shaders::shade());
    let entry = if format.is_srgb() { "fs_shade_linear" } else { "fs_shade" };
    let groups = [&cx.shared.frame_layout, &cx.shared.shade_layout];
    full_screen_pipeline(&cx.pipelines, "recorded shade", &module, entry, &groups, Some(format), None)
}

/// The recording steps: the frame's targets, the host's surfaces in place of the G-buffer pass when it
/// lends them, and the shading pipeline with the host's colour target when it shades into one.
struct RecordSteps<'a> {
    width: u32,
    height: u32,
    visibility: &'a wgpu::Texture,
    host: Option<(&'a HostSurfaces<'a>, &'a ImportPass)>,
    shade: Option<(&'a wgpu::RenderPipeline, &'a wgpu::TextureView)>,
    timer: Option<&'a mut FrameTimer>,
}

impl RecordSteps<'_> {
    /// Marks the end of the phase `name` on the frame's timer, when it has one.
    fn mark(&mut self, cx: &WgpuContext, name: &'static str) {
        if let Some(timer) = self.timer.as_deref_mut() {
            let mut enc = cx.encoder("phase mark");
            timer.mark(&mut enc, name);
            cx.submit(enc);
        }
    }
}

impl FrameSteps<WgpuBackend> for RecordSteps<'_> {
    type Shaded = ();
    type Output = ();

    fn gbuffer(&mut self, cx: &mut WgpuContext, frame: &FrameInputs) -> Result<GpuGBuffer, WgpuError> {
        if let Some(timer) = self.timer.as_deref_mut() {
            let mut enc = cx.encoder("frame start");
            timer.begin(&mut enc);
            cx.submit(enc);
        }
        let g = match self.host {
            Some((host, import)) => gbuffer::import(cx, frame, host, import),
            None => gbuffer::render(cx, frame, self.width, self.height),
        }?;
        self.mark(cx, "G-buffer");
        Ok(g)
    }

    fn visibility(&mut self, cx: &mut WgpuContext, k: usize, reach: &Reach) -> Result<GpuVisibility, WgpuError> {
        cx.host_maps.light(k);
        let view = layer_view(self.visibility, k as u32);
        Ok(GpuVisibility { view, width: self.width, height: self.height, rect: reach.rect })
    }

    fn keep(&mut self, _k: usize, _visibility: GpuVisibility) {}

    fn lit(&mut self, cx: &mut WgpuContext, visibility: &mut GpuVisibility) -> Result<(), WgpuError> {
        clear_lit(cx, visibility);
        Ok(())
    }

    fn shade(
        &mut self,
        cx: &mut WgpuContext,
        lights: (&FrameInputs, &[Reach]),
        g: &GpuGBuffer,
    ) -> Result<(), WgpuError> {
        let Some((pipeline, target)) = self.shade else { return Ok(()) };
        self.mark(cx, "shadows");
        cx.scoped("the recorded shading pass", |cx| {
            let group = shade_group(cx, lights, g, self.visibility);
            let mut enc = cx.encoder("shade");
            full_screen_shade(&mut enc, target, pipeline, g, &group, None);
            cx.submit(enc);
        })
    }

    fn finish(
        mut self,
        cx: &mut WgpuContext,
        _gbuffer: GpuGBuffer,
        _shaded: (),
        _stats: &mut FrameStats,
    ) -> Result<(), WgpuError> {
        if let Some(timer) = self.timer.as_deref_mut() {
            let mut enc = cx.encoder("frame end");
            timer.end(&mut enc, if self.shade.is_some() { "shading" } else { "shadows" });
            cx.submit(enc);
        }
        Ok(())
    }
}
