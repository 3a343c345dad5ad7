//! An application that owns its window and GPU and draws shadowlab's shadows in its own frame: it makes
//! the wgpu instance, adapter, device and surface, lends the device to shadowlab (`RealtimeShadows`), and
//! every frame records the shadowed scene into its own encoder before it presents. Space switches the
//! technique; Escape quits. Without a display, or with `--frames N`, it renders N frames (30 by default)
//! into a texture of its own and writes the last to `out/embed.png`.

use std::{num::NonZeroU32, sync::Arc};

use shadow_core::FrameInputs;
use shadow_core::scenes::{self, SceneParams};
use shadow_wgpu::{ColorTarget, WgpuContext};
use shadowlab::{TechniqueRegistry, bench::moved_light, realtime::RealtimeShadows};
use winit::event::WindowEvent;
use winit::event_loop::{ActiveEventLoop, EventLoop};
use winit::keyboard::{Key, NamedKey};
use winit::window::{Window, WindowId};

type Failure = Box<dyn std::error::Error>;
const TECHNIQUES: [&str; 4] = ["shadow-map", "shadow-volume-zfail", "hybrid", "pcss"];

/// shadowlab's part: the shadows on the application's device, the scene, the frames drawn.
struct Shadows(RealtimeShadows, FrameInputs, u32);

impl Shadows {
    fn new((adapter, device, queue): &Gpu) -> Result<Self, Failure> {
        let registry = TechniqueRegistry::builtin();
        let shadows = RealtimeShadows::new(adapter, device.clone(), queue.clone(), registry, TECHNIQUES[0])?;
        Ok(Self(shadows, FrameInputs::from_first_camera(&scenes::build("cubes", &SceneParams::default())?)?, 0))
    }

    /// Records a frame into the application's encoder, shading into `view`, the light turned further.
    fn draw(&mut self, encoder: &mut wgpu::CommandEncoder, view: &wgpu::TextureView, f: Format) -> Result<(), Failure> {
        let (mut frame, center) = (self.1.clone(), self.1.bounds.center());
        frame.lights = self.1.lights.iter().map(|l| moved_light(l, center, self.2 % 240, 60)).collect();
        self.2 += 1;
        Ok(self.0.record(encoder, &frame, &ColorTarget { view, format: f.0, width: f.1, height: f.2 }).map(drop)?)
    }
}

/// The application's GPU: an adapter that can present to `surface` and a device with what shadowlab needs.
fn gpu(instance: &wgpu::Instance, surface: Option<&wgpu::Surface<'_>>) -> Result<Gpu, Failure> {
    let fits = |a: &wgpu::Adapter| WgpuContext::can_use(a) && surface.is_none_or(|s| a.is_surface_supported(s));
    let adapters = pollster::block_on(instance.enumerate_adapters(wgpu::Backends::PRIMARY));
    let adapter = adapters.into_iter().find(fits).ok_or("no adapter shadowlab can use")?;
    let (device, queue) = pollster::block_on(adapter.request_device(&WgpuContext::device_descriptor()))?;
    Ok((adapter, device, queue))
}
type Gpu = (wgpu::Adapter, wgpu::Device, wgpu::Queue);
type Format = (wgpu::TextureFormat, u32, u32);

/// The application with its window open.
struct Windowed {
    window: Arc<Window>,
    surface: wgpu::Surface<'static>,
    config: wgpu::SurfaceConfiguration,
    gpu: Gpu,
    shadows: Shadows,
}

impl Windowed {
    fn new(event_loop: &ActiveEventLoop) -> Result<Self, Failure> {
        let display = wgpu::InstanceDescriptor::new_with_display_handle(Box::new(event_loop.owned_display_handle()));
        let instance = wgpu::Instance::new(display);
        let window = Arc::new(event_loop.create_window(Window::default_attributes().with_title("shadowlab"))?);
        let surface = instance.create_surface(window.clone())?;
        let (gpu, size) = (gpu(&instance, Some(&surface))?, window.inner_size());
        let config = surface.get_default_config(&gpu.0, size.width, size.height).ok_or("cannot present")?;
        surface.configure(&gpu.1, &config);
        Ok(Self { window, surface, config, shadows: Shadows::new(&gpu)?, gpu })
    }

    fn redraw(&mut self) -> Result<(), Failure> {
        use wgpu::CurrentSurfaceTexture::{Suboptimal, Success};
        let (Success(frame) | Suboptimal(frame)) = self.surface.get_current_texture() else {
            self.surface.configure(&self.gpu.1, &self.config);
            return Ok(());
        };
        let (view, c) = (frame.texture.create_view(&Default::default()), &self.config);
        let mut encoder = self.gpu.1.create_command_encoder(&Default::default());
        self.shadows.draw(&mut encoder, &view, (c.format, c.width, c.height))?;
        self.gpu.2.submit([encoder.finish()]);
        self.gpu.2.present(frame);
        self.window.request_redraw();
        Ok(())
    }
}

/// The windowed application, once its window is open, and why it stopped if it failed.
#[derive(Default)]
struct App(Option<Windowed>, Option<Failure>);

impl winit::application::ApplicationHandler for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        self.0 = self.0.take().or_else(|| Windowed::new(event_loop).map_err(|e| self.1 = Some(e)).ok());
        self.1.is_some().then(|| event_loop.exit());
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _: WindowId, event: WindowEvent) {
        let Some(app) = &mut self.0 else { return };
        match event {
            WindowEvent::KeyboardInput { event, .. } if event.state.is_pressed() => match event.logical_key {
                Key::Named(NamedKey::Escape) => event_loop.exit(),
                Key::Named(NamedKey::Space) => {
                    let now = TECHNIQUES.iter().position(|t| app.shadows.0.technique().name == *t).unwrap_or(0);
                    self.1 =
                        app.shadows.0.set_technique(TECHNIQUES[(now + 1) % TECHNIQUES.len()]).err().map(Into::into);
                }
                _ => {}
            },
            WindowEvent::Resized(size) => {
                (app.config.width, app.config.height) = (size.width.max(1), size.height.max(1));
                app.surface.configure(&app.gpu.1, &app.config);
            }
            WindowEvent::RedrawRequested => self.1 = app.redraw().err(),
            WindowEvent::CloseRequested => event_loop.exit(),
            _ => {}
        }
        self.1.is_some().then(|| event_loop.exit());
    }
}

/// `frames` frames into a texture of the application's own, the last written to `out/embed.png`.
fn offscreen(frames: u32) -> Result<(), Failure> {
    let gpu = gpu(&wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle()), None)?;
    let (mut shadows, (_, device, queue)) = (Shadows::new(&gpu)?, &gpu);
    let (width, height, format) = (640, 480, wgpu::TextureFormat::Rgba8UnormSrgb);
    let texture = shadow_wgpu::frame::layered(shadows.0.context(), "offscreen", width, height, 1, format);
    let view = texture.create_view(&Default::default());
    for _ in 0..frames {
        let mut encoder = device.create_command_encoder(&Default::default());
        shadows.draw(&mut encoder, &view, (format, width, height))?;
        queue.submit([encoder.finish()]);
    }
    std::fs::create_dir_all("out")?;
    shadow_wgpu::readback::read_rgb8(shadows.0.context(), &texture)?.save_png("out/embed.png")?;
    println!("{frames} frames of {}; the last in out/embed.png", shadows.0.technique());
    Ok(())
}

fn main() -> Result<(), Failure> {
    let frames = std::env::args().skip_while(|a| a != "--frames").nth(1);
    let frames = frames.map(|n| n.parse::<NonZeroU32>().map_err(|e| format!("--frames {n}: {e}"))).transpose()?;
    if frames.is_some() || !["DISPLAY", "WAYLAND_DISPLAY"].iter().any(|v| std::env::var_os(v).is_some()) {
        return offscreen(frames.map_or(30, NonZeroU32::get));
    }
    let mut app = App::default();
    EventLoop::new()?.run_app(&mut app)?;
    app.1.map_or(Ok(()), Err)
}
