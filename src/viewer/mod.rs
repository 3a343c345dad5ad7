//! `shadowlab view`: a window onto a scene, drawn every frame through the real-time path, with a side
//! panel to switch scene, backend, technique and its settings live, a camera to fly and a light to move.
//!
//! The window is winit's, the UI egui's (egui-winit for input, egui-wgpu to draw it), on one wgpu device
//! that shadowlab's shadows share ([`crate::realtime::RealtimeShadows`] on the viewer's device). The 3D
//! view is a texture the UI draws (`view::View`); a script ([`script`]) can stand in for the user.

mod clip;
mod overlay;
mod panel;
pub mod rig;
pub mod script;
mod view;

use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

use shadow_core::FrameInputs;
use winit::application::ApplicationHandler;
use winit::event::WindowEvent;
use winit::event_loop::{ActiveEventLoop, EventLoop};
use winit::window::{Window, WindowId};

use crate::setup::SceneSetup;
use crate::{BackendKind, Error};
use rig::{LightRig, Orbit};
use script::Step;
use view::{Gpu, View};

/// What the viewer opens with.
pub struct ViewerOptions {
    /// The scene.
    pub setup: SceneSetup,
    /// The technique's spec.
    pub technique: String,
    /// The backend drawing the view.
    pub backend: BackendKind,
    /// Steps to take, one per frame, before the user's hands (see [`script`]).
    pub script: Vec<Step>,
    /// The window's inner size in pixels.
    pub size: (u32, u32),
}

/// Opens the viewer and runs it until its window closes (or its script quits).
///
/// # Errors
/// A scene that does not load, no display or no adapter that can present, or a failure drawing.
pub fn run(options: ViewerOptions) -> Result<(), Error> {
    let scene = Scene::open(options.setup.clone())?;
    #[cfg(all(unix, not(target_os = "macos")))]
    if ["DISPLAY", "WAYLAND_DISPLAY", "WAYLAND_SOCKET"].iter().all(|v| std::env::var_os(v).is_none()) {
        return Err(Error::Window(
            "no display to open it on (DISPLAY and WAYLAND_DISPLAY are unset); `xvfb-run -a shadowlab view ...` \
             gives it a virtual one"
                .into(),
        ));
    }
    let event_loop = EventLoop::new().map_err(|e| Error::Window(e.to_string()))?;
    let mut app = App { options, scene: Some(scene), open: None, failure: None };
    event_loop.run_app(&mut app).map_err(|e| Error::Window(e.to_string()))?;
    app.failure.map_or(Ok(()), Err)
}

/// A loaded scene with the two rigs that move its camera and first light.
struct Scene {
    setup: SceneSetup,
    frame: FrameInputs,
    orbit: Orbit,
    light: Option<LightRig>,
    /// The rigs as the scene gave them, for a reset.
    home: (Orbit, Option<LightRig>),
    /// The timeline of a scene with animations.
    clip: Option<clip::Clip>,
}

impl Scene {
    fn open(setup: SceneSetup) -> Result<Self, Error> {
        let scene = setup.build()?;
        let frame = FrameInputs::from_first_camera(&scene)?;
        let orbit = Orbit::around(&frame.camera);
        let radius = 0.5 * frame.bounds.size().length();
        let light = frame.lights.first().map(|l| LightRig::around(l, frame.bounds.center(), radius));
        let clip = clip::Clip::of(scene, setup.time);
        let mut opened = Self { setup, frame, orbit, light, home: (orbit, light), clip };
        opened.pose()?;
        Ok(opened)
    }

    /// Runs the timeline on by `dt` seconds while it plays, posing the frame anew when its time moved.
    ///
    /// # Errors
    /// A pose that fails.
    fn advance(&mut self, dt: f32) -> Result<(), Error> {
        if self.clip.as_mut().is_some_and(|c| c.advance(dt)) { self.pose() } else { Ok(()) }
    }

    /// Stops the timeline at `t` seconds and poses the frame there.
    ///
    /// # Errors
    /// A pose that fails.
    fn scrub(&mut self, t: f32) -> Result<(), Error> {
        if self.clip.as_mut().is_some_and(|c| c.scrub(t)) { self.pose() } else { Ok(()) }
    }

    /// The frame of the scene posed at the timeline's time, each light's shadow as the panel set it.
    fn pose(&mut self) -> Result<(), Error> {
        let Some(clip) = &mut self.clip else { return Ok(()) };
        let mut frame = clip.frame()?;
        frame.shadows = std::mem::take(&mut self.frame.shadows);
        self.frame = frame;
        Ok(())
    }

    /// The time the timeline shows, for a scene with one.
    fn time(&self) -> Option<f32> {
        self.clip.as_ref().map(clip::Clip::time)
    }

    /// This frame's inputs: the scene's, seen through the orbit, lit by the rig's light first.
    fn frame(&self) -> FrameInputs {
        let mut frame = self.frame.clone();
        frame.camera = self.orbit.camera();
        if let (Some(rig), Some(first)) = (&self.light, frame.lights.first_mut()) {
            *first = rig.light();
        }
        frame
    }
}

/// The application: the scene before the window opens, then the open window.
struct App {
    options: ViewerOptions,
    scene: Option<Scene>,
    open: Option<Open>,
    failure: Option<Error>,
}

impl ApplicationHandler for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.open.is_some() {
            return;
        }
        let Some(scene) = self.scene.take() else { return };
        match Open::new(event_loop, &self.options, scene) {
            Ok(open) => self.open = Some(open),
            Err(e) => {
                self.failure = Some(e);
                event_loop.exit();
            }
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _: WindowId, event: WindowEvent) {
        let Some(open) = &mut self.open else { return };
        let response = open.egui.on_window_event(&open.window, &event);
        match event {
            WindowEvent::CloseRequested => event_loop.exit(),
            WindowEvent::Resized(size) => {
                (open.config.width, open.config.height) = (size.width.max(1), size.height.max(1));
                open.surface.configure(&open.gpu.device, &open.config);
            }
            WindowEvent::DroppedFile(path) => open.viewer.open_scene(path.to_string_lossy().into_owned()),
            WindowEvent::RedrawRequested => match open.redraw() {
                Ok(true) => open.window.request_redraw(),
                Ok(false) => event_loop.exit(),
                Err(e) => {
                    self.failure = Some(e);
                    event_loop.exit();
                }
            },
            _ if response.repaint => open.window.request_redraw(),
            _ => {}
        }
    }
}

/// The open window: its surface, the device, egui, and the viewer's state.
struct Open {
    window: Arc<Window>,
    surface: wgpu::Surface<'static>,
    config: wgpu::SurfaceConfiguration,
    gpu: Gpu,
    egui: egui_winit::State,
    painter: egui_wgpu::Renderer,
    viewer: panel::Viewer,
}

impl Open {
    fn new(event_loop: &ActiveEventLoop, options: &ViewerOptions, scene: Scene) -> Result<Self, Error> {
        let failed = |e: &dyn std::fmt::Display| Error::Window(e.to_string());
        let (w, h) = options.size;
        let attributes =
            Window::default_attributes().with_title("shadowlab").with_inner_size(winit::dpi::PhysicalSize::new(w, h));
        let window = Arc::new(event_loop.create_window(attributes).map_err(|e| failed(&e))?);
        let display = Box::new(event_loop.owned_display_handle());
        let instance = wgpu::Instance::new(wgpu::InstanceDescriptor::new_with_display_handle(display));
        let surface = instance.create_surface(window.clone()).map_err(|e| failed(&e))?;
        let gpu = gpu_for(&instance, &surface)?;
        let size = window.inner_size();
        let mut config = surface
            .get_default_config(&gpu.adapter, size.width.max(1), size.height.max(1))
            .ok_or_else(|| Error::Window(format!("{} cannot present to this window", gpu.adapter.get_info().name)))?;
        config.present_mode = wgpu::PresentMode::AutoVsync;
        surface.configure(&gpu.device, &config);
        let context = egui::Context::default();
        let max_side = gpu.device.limits().max_texture_dimension_2d as usize;
        let ppp = Some(window.scale_factor() as f32);
        let egui = egui_winit::State::new(context, egui::ViewportId::ROOT, &window, ppp, None, Some(max_side));
        let painter = egui_wgpu::Renderer::new(&gpu.device, config.format, egui_wgpu::RendererOptions::default());
        let view = View::new(&gpu, &options.technique, options.backend)?;
        let viewer = panel::Viewer::new(view, scene, options.script.clone());
        Ok(Self { window, surface, config, gpu, egui, painter, viewer })
    }

    /// Draws one frame: the 3D view, then the UI over the window. False once the viewer should close.
    fn redraw(&mut self) -> Result<bool, Error> {
        use wgpu::CurrentSurfaceTexture::{Suboptimal, Success};
        let (Success(output) | Suboptimal(output)) = self.surface.get_current_texture() else {
            self.surface.configure(&self.gpu.device, &self.config);
            return Ok(true);
        };
        self.viewer.step_script();
        let mut encoder = self.gpu.device.create_command_encoder(&Default::default());
        let context = self.egui.egui_ctx().clone();
        self.viewer.draw_view((&self.gpu, &mut self.painter, &context), &mut encoder);
        let input = self.egui.take_egui_input(&self.window);
        let out = context.run_ui(input, |ui| self.viewer.ui(ui));
        self.egui.handle_platform_output(&self.window, out.platform_output);
        let jobs = context.tessellate(out.shapes, out.pixels_per_point);
        for (id, deltas) in &out.textures_delta.set {
            for delta in deltas {
                self.painter.update_texture(&self.gpu.device, &self.gpu.queue, *id, delta);
            }
        }
        let screen = egui_wgpu::ScreenDescriptor {
            size_in_pixels: [self.config.width, self.config.height],
            pixels_per_point: out.pixels_per_point,
        };
        let extra = self.painter.update_buffers(&self.gpu.device, &self.gpu.queue, &mut encoder, &jobs, &screen);
        let target = output.texture.create_view(&Default::default());
        let mut pass = encoder
            .begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("egui"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &target,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: None,
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            })
            .forget_lifetime();
        self.painter.render(&mut pass, &jobs, &screen);
        drop(pass);
        self.gpu.queue.submit(extra.into_iter().chain([encoder.finish()]));
        for id in &out.textures_delta.free {
            self.painter.free_texture(id);
        }
        self.viewer.after_submit(&context);
        self.window.pre_present_notify();
        self.gpu.queue.present(output);
        Ok(!self.viewer.quitting())
    }
}

/// An adapter that can present to `surface` and shadowlab can use, with a device as shadowlab asks.
fn gpu_for(instance: &wgpu::Instance, surface: &wgpu::Surface<'_>) -> Result<Gpu, Error> {
    let adapters = pollster::block_on(instance.enumerate_adapters(wgpu::Backends::PRIMARY));
    let fits = |a: &wgpu::Adapter| shadow_wgpu::WgpuContext::can_use(a) && a.is_surface_supported(surface);
    let adapter = adapters
        .into_iter()
        .find(fits)
        .ok_or_else(|| Error::Window("no adapter that shadowlab can use presents to this window".into()))?;
    // What shadowlab's own context asks for: the optional features too (f32 depth-stencil, so the view
    // is drawn as `shadowlab render` draws it; timestamps, for the readouts).
    use shadow_wgpu::WgpuContext;
    let descriptor = wgpu::DeviceDescriptor {
        required_features: WgpuContext::REQUIRED_FEATURES | (WgpuContext::OPTIONAL_FEATURES & adapter.features()),
        ..WgpuContext::device_descriptor()
    };
    let (device, queue) =
        pollster::block_on(adapter.request_device(&descriptor)).map_err(|e| Error::Window(e.to_string()))?;
    Ok(Gpu { adapter, device, queue })
}

/// Where the n-th screenshot of a session goes.
fn screenshot_path(n: u32) -> PathBuf {
    PathBuf::from(format!("out/view-{n}.png"))
}

/// The frames per second of the last second's frames.
#[derive(Default)]
struct FrameClock {
    times: std::collections::VecDeque<Instant>,
}

impl FrameClock {
    fn tick(&mut self) {
        let now = Instant::now();
        self.times.push_back(now);
        while self.times.front().is_some_and(|t| now.duration_since(*t).as_secs_f64() > 1.0) {
            self.times.pop_front();
        }
    }

    fn fps(&self) -> f64 {
        match (self.times.front(), self.times.back()) {
            (Some(a), Some(b)) if self.times.len() > 1 => (self.times.len() - 1) as f64 / (*b - *a).as_secs_f64(),
            _ => 0.0,
        }
    }
}
