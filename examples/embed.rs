//! An application that owns its window and GPU and draws shadowlab's shadows in its own frame: it makes
//! the wgpu instance, adapter, device and surface, lends the device to shadowlab (`RealtimeShadows`), and
//! every frame records the shadowed scene into its own command encoder before it presents. Space switches
//! the technique; Escape quits.
//!
//! `cargo run --release --example embed` opens a window. Without a display, or with `--frames N`, it
//! renders N frames (30 by default) into a texture of its own and writes the last to `out/embed.png`.

use std::sync::Arc;

use shadow_core::scenes::{self, SceneParams};
use shadow_core::{FrameInputs, Image};
use shadow_wgpu::{ColorTarget, WgpuContext};
use shadowlab::{TechniqueRegistry, bench::moved_light, realtime::RealtimeShadows};
use winit::event::WindowEvent;
use winit::event_loop::{ActiveEventLoop, EventLoop};
use winit::keyboard::{Key, NamedKey};
use winit::window::{Window, WindowId};

type Failure = Box<dyn std::error::Error>;
const TECHNIQUES: [&str; 4] = ["shadow-map", "shadow-volume-zfail", "hybrid", "pcss"];

/// shadowlab's part: the shadows on the application's device, the scene, the technique's place in the list.
struct Shadows {
    shadows: RealtimeShadows,
    frame: FrameInputs,
    which: usize,
    tick: u32,
}

impl Shadows {
    fn new((adapter, device, queue): &Gpu) -> Result<Self, Failure> {
        let registry = TechniqueRegistry::builtin();
        let shadows = RealtimeShadows::new(adapter, device.clone(), queue.clone(), registry, TECHNIQUES[0])?;
        let frame = FrameInputs::from_first_camera(&scenes::build("cubes", &SceneParams::default())?)?;
        Ok(Self { shadows, frame, which: 0, tick: 0 })
    }

    fn next_technique(&mut self) -> Result<(), Failure> {
        self.which = (self.which + 1) % TECHNIQUES.len();
        self.shadows.set_technique(TECHNIQUES[self.which])?;
        println!("technique: {}", self.shadows.technique());
        Ok(())
    }

    /// Records one frame into the application's encoder, the light turned a little further.
    fn draw(&mut self, encoder: &mut wgpu::CommandEncoder, target: &ColorTarget<'_>) -> Result<(), Failure> {
        let (mut frame, center) = (self.frame.clone(), self.frame.bounds.center());
        frame.lights = self.frame.lights.iter().map(|l| moved_light(l, center, self.tick % 240, 60)).collect();
        self.tick += 1;
        self.shadows.record(encoder, &frame, target)?;
        Ok(())
    }
}

/// The application's GPU: a Vulkan, Metal or DirectX adapter that can present to `surface` (any, without
/// one), and a device with what shadowlab requires.
fn gpu(instance: &wgpu::Instance, surface: Option<&wgpu::Surface<'_>>) -> Result<Gpu, Failure> {
    let fits = |a: &wgpu::Adapter| WgpuContext::can_use(a) && surface.is_none_or(|s| a.is_surface_supported(s));
    let adapters = pollster::block_on(instance.enumerate_adapters(wgpu::Backends::PRIMARY));
    let adapter = adapters.into_iter().find(fits).ok_or("no adapter shadowlab can use")?;
    let (device, queue) = pollster::block_on(adapter.request_device(&WgpuContext::device_descriptor()))?;
    Ok((adapter, device, queue))
}
type Gpu = (wgpu::Adapter, wgpu::Device, wgpu::Queue);

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
        let display = Box::new(event_loop.owned_display_handle());
        let instance = wgpu::Instance::new(wgpu::InstanceDescriptor::new_with_display_handle(display));
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
        let view = frame.texture.create_view(&Default::default());
        let (format, width, height) = (self.config.format, self.config.width, self.config.height);
        let mut encoder = self.gpu.1.create_command_encoder(&Default::default());
        self.shadows.draw(&mut encoder, &ColorTarget { view: &view, format, width, height })?;
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
        if self.0.is_none() {
            Windowed::new(event_loop).map(|w| self.0 = Some(w)).unwrap_or_else(|e| self.1 = Some(e));
        }
        if self.1.is_some() {
            event_loop.exit();
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _: WindowId, event: WindowEvent) {
        let Some(app) = &mut self.0 else { return };
        match event {
            WindowEvent::KeyboardInput { event, .. } if event.state.is_pressed() => match event.logical_key {
                Key::Named(NamedKey::Escape) => event_loop.exit(),
                Key::Named(NamedKey::Space) => self.1 = app.shadows.next_technique().err(),
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
        if self.1.is_some() {
            event_loop.exit();
        }
    }
}

/// `frames` frames into a texture of the application's own, the last written to `out/embed.png`.
fn offscreen(frames: u32) -> Result<(), Failure> {
    let gpu = gpu(&wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle()), None)?;
    let (mut shadows, (_, device, queue)) = (Shadows::new(&gpu)?, &gpu);
    let (width, height, format) = (640, 480, wgpu::TextureFormat::Rgba8UnormSrgb);
    let texture = shadow_wgpu::frame::layered(shadows.shadows.context(), "offscreen", width, height, 1, format);
    let view = texture.create_view(&Default::default());
    for _ in 0..frames {
        let mut encoder = device.create_command_encoder(&Default::default());
        shadows.draw(&mut encoder, &ColorTarget { view: &view, format, width, height })?;
        queue.submit([encoder.finish()]);
    }
    let image: Image<_> = shadow_wgpu::readback::read_rgb8(shadows.shadows.context(), &texture)?;
    std::fs::create_dir_all("out")?;
    image.save_png("out/embed.png")?;
    println!("{frames} frames of {}; the last in out/embed.png", TECHNIQUES[shadows.which]);
    Ok(())
}

fn main() -> Result<(), Failure> {
    let frames = std::env::args().skip_while(|a| a != "--frames").nth(1).map(|n| n.parse::<u32>()).transpose()?;
    let display = ["DISPLAY", "WAYLAND_DISPLAY"].iter().any(|v| std::env::var_os(v).is_some());
    if frames == Some(0) {
        return Err("--frames takes at least one frame".into());
    }
    if frames.is_some() || !display {
        return offscreen(frames.unwrap_or(30));
    }
    let mut app = App::default();
    EventLoop::new()?.run_app(&mut app)?;
    app.1.map_or(Ok(()), Err)
}
