//! The viewer's state and its UI: the side panel (scene, backend, technique and its settings as controls
//! generated from the settings table, the light, readouts, screenshot and the command that reproduces
//! the view) and the 3D view's input (orbit, zoom, fly, the light dragged). This module holds the state
//! and a frame's course through it; the panel's sections, the view's input and the command are beside
//! it.

mod command;
mod controls;
mod input;

use std::collections::VecDeque;
use std::path::PathBuf;

use shadow_core::FrameInputs;
use shadow_core::technique::settings::key_values;
use shadow_wgpu::FrameTimes;

use super::overlay::{Overlay, ViewKey};
use super::script::Step;
use super::view::{Gpu, View};
use super::{FrameClock, Scene, screenshot_path};
use crate::setup::SceneSetup;
use crate::{BackendKind, TechniqueRegistry};

/// Radians a dragged pixel turns the camera or the light.
const TURN_PER_PIXEL: f32 = 0.008;
/// Radians a second the turning light moves, and the arrow keys move it.
const LIGHT_TURN_RATE: f32 = 0.6;
/// The side panel's width in points.
const PANEL_WIDTH: f32 = 330.0;
/// GPU times kept for the plot.
const PLOTTED: usize = 240;

/// Everything the viewer shows and changes.
pub(super) struct Viewer {
    view: View,
    scene: Scene,
    registry: TechniqueRegistry,
    /// The technique's settings as the controls show them, committed when a control settles.
    settings: Vec<(String, String)>,
    script: VecDeque<Step>,
    wait: u32,
    quit: bool,
    animate: bool,
    /// The view's size in pixels as the UI laid it out.
    size: (u32, u32),
    /// The last frame drawn, and what it depends on.
    drawn: Option<(ViewKey, FrameInputs)>,
    /// What is laid over the view, and whether a comparison waits for the next frame drawn.
    overlay: Option<Overlay>,
    compare_asked: bool,
    inspect_asked: bool,
    texture: Option<egui::TextureId>,
    screenshot: Option<PathBuf>,
    screenshots: u32,
    /// The model file field.
    file: String,
    error: Option<String>,
    /// Whether the error line is the last frame's failure to draw (a later frame drawn clears it).
    draw_failed: bool,
    status: Option<String>,
    clock: FrameClock,
    gpu_times: VecDeque<FrameTimes>,
    timed: bool,
}

impl Viewer {
    pub(super) fn new(mut view: View, scene: Scene, script: Vec<Step>) -> Self {
        let timed = view.time_frames();
        let mut viewer = Self {
            view,
            scene,
            registry: TechniqueRegistry::builtin(),
            settings: Vec::new(),
            script: script.into(),
            wait: 0,
            quit: false,
            animate: false,
            size: (640, 480),
            drawn: None,
            overlay: None,
            compare_asked: false,
            inspect_asked: false,
            texture: None,
            screenshot: None,
            screenshots: 0,
            file: String::new(),
            error: None,
            draw_failed: false,
            status: None,
            clock: FrameClock::default(),
            gpu_times: VecDeque::new(),
            timed,
        };
        viewer.reset_settings();
        viewer
    }

    pub(super) fn quitting(&self) -> bool {
        self.quit
    }

    /// Takes the script's next step, unless it waits.
    pub(super) fn step_script(&mut self) {
        if self.wait > 0 {
            self.wait -= 1;
            return;
        }
        // A screenshot or a comparison asked for is made before the next step changes the view.
        if self.screenshot.is_some()
            || self.compare_asked
            || self.inspect_asked
            || matches!(self.overlay, Some(Overlay::Computing { .. }))
        {
            return;
        }
        let Some(step) = self.script.pop_front() else { return };
        let orbit = &mut self.scene.orbit;
        match step {
            Step::Orbit(yaw, pitch) => orbit.turn(yaw.to_radians(), pitch.to_radians()),
            Step::Zoom(f) => orbit.zoom(f),
            Step::Fly(f, r, u) => orbit.fly(f, r, u),
            Step::Light(yaw, pitch) => {
                if let Some(rig) = &mut self.scene.light {
                    rig.turn(yaw.to_radians(), pitch.to_radians());
                }
            }
            Step::Technique(spec) => self.set_technique(&spec),
            Step::Backend(name) => self.set_backend(if name == "cpu" { BackendKind::Cpu } else { BackendKind::Wgpu }),
            Step::Scene(source) => self.open_scene(source),
            Step::Wait(n) => self.wait = n,
            Step::Screenshot(path) => self.screenshot = Some(path),
            Step::Command => println!("{}", self.command()),
            Step::Memory => {
                let m = self.view.settled_memory();
                println!(
                    "gpu memory: {} buffers, {} buffer bytes, {} texture bytes",
                    m.buffers, m.buffer_bytes, m.texture_bytes
                );
            }
            Step::Time(t) => self.scrub(t),
            Step::Play(playing) => {
                if let Some(clip) = &mut self.scene.clip {
                    clip.playing = playing;
                }
            }
            Step::Compare => self.compare_asked = true,
            Step::Inspect => self.inspect_asked = true,
            Step::Quit => self.quit = true,
        }
    }

    /// Draws the 3D view for this frame (see [`View::draw`]).
    pub(super) fn draw_view(
        &mut self,
        painter: (&Gpu, &mut egui_wgpu::Renderer, &egui::Context),
        encoder: &mut wgpu::CommandEncoder,
    ) {
        let dt = painter.2.input(|i| i.stable_dt).min(0.1);
        if self.animate
            && let Some(rig) = &mut self.scene.light
        {
            rig.turn(LIGHT_TURN_RATE * dt, 0.0);
        }
        if let Err(e) = self.scene.advance(dt) {
            self.fail(e.to_string());
        }
        let frame = self.scene.frame();
        let key = self.key(&frame);
        // An overlay shows the view it was made for only.
        if self.overlay.as_ref().is_some_and(|o| *o.key() != key) {
            self.overlay = None;
        }
        if let Some(overlay) = self.overlay.take() {
            let computing = matches!(overlay, Overlay::Computing { .. });
            match overlay.poll(painter.2) {
                Ok(o) => {
                    if let (true, Overlay::Errors { score, .. }) = (computing, &o) {
                        self.say(score.clone());
                    }
                    self.overlay = Some(o);
                }
                Err(e) => self.fail(format!("the reference: {e}")),
            }
        }
        match self.view.draw(painter, encoder, &frame, self.size) {
            Ok(id) => {
                self.texture = Some(id);
                self.drawn = Some((key, frame));
                if std::mem::take(&mut self.draw_failed) {
                    self.error = None;
                }
            }
            Err(e) => {
                // No picture rather than the last technique's: the error line says why.
                self.texture = None;
                self.drawn = None;
                self.draw_failed = true;
                self.fail(e.to_string());
            }
        }
        self.clock.tick();
        if let Some(times) = self.view.gpu_times() {
            self.gpu_times.push_back(times.clone());
            if self.gpu_times.len() > PLOTTED {
                self.gpu_times.pop_front();
            }
        }
    }

    /// Takes an asked-for screenshot of the frame just submitted, once the view is drawn at the size the
    /// UI gives it.
    pub(super) fn after_submit(&mut self, ui: &egui::Context) {
        let Some((key, frame)) = self.drawn.as_ref().filter(|(key, _)| key.size == self.size) else { return };
        if std::mem::take(&mut self.inspect_asked) {
            match self.view.inspect(frame, key.size) {
                Ok(inspection) => {
                    let counters: Vec<String> = inspection.counters.iter().map(|(k, v)| format!("{k}={v}")).collect();
                    println!("counters: {}", counters.join(", "));
                    self.overlay = Some(Overlay::inspect(key.clone(), inspection, ui));
                }
                Err(e) => self.fail(e.to_string()),
            }
            return;
        }
        if std::mem::take(&mut self.compare_asked) {
            let soft = self.registry.get(&self.view.technique().name).is_ok_and(|e| e.soft);
            match self.view.visibility().and_then(|v| Ok((v, self.view.screenshot()?))) {
                Ok((test, picture)) => {
                    self.overlay = Some(Overlay::compare(key.clone(), frame.clone(), soft, test, picture));
                    self.say("computing the reference for this view".into());
                }
                Err(e) => self.fail(e.to_string()),
            }
        }
        let Some(path) = self.screenshot.take() else { return };
        let written = self.view.screenshot().and_then(|image| {
            if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
                std::fs::create_dir_all(dir)
                    .map_err(|e| crate::Error::Write { path: dir.to_path_buf(), why: e.to_string() })?;
            }
            Ok(image.save_png(&path)?)
        });
        match written {
            Ok(()) => self.say(format!("wrote {}", path.display())),
            Err(e) => self.fail(e.to_string()),
        }
    }

    fn say(&mut self, message: String) {
        eprintln!("{message}");
        self.status = Some(message);
    }

    /// What the picture of `frame` depends on.
    fn key(&self, frame: &FrameInputs) -> ViewKey {
        ViewKey {
            scene: self.scene.setup.source.clone(),
            time: self.scene.time(),
            camera: frame.camera,
            lights: frame.lights.clone(),
            shadows: frame.shadows.clone(),
            technique: self.view.technique().to_string(),
            backend: self.view.backend(),
            size: self.size,
        }
    }

    /// Shows `message` as the error line (and prints it once).
    fn fail(&mut self, message: String) {
        if self.error.as_ref() != Some(&message) {
            eprintln!("{message}");
        }
        self.error = Some(message);
    }

    fn set_technique(&mut self, spec: &str) {
        match self.view.set_technique(spec) {
            Ok(()) => self.error = None,
            Err(e) => self.fail(e.to_string()),
        }
        self.reset_settings();
    }

    /// Stops the timeline at `t` seconds; on an error the error line says why.
    fn scrub(&mut self, t: f32) {
        if let Err(e) = self.scene.scrub(t) {
            self.fail(e.to_string());
        }
    }

    fn set_backend(&mut self, backend: BackendKind) {
        match self.view.set_backend(backend) {
            Ok(()) => self.error = None,
            Err(e) => self.fail(e.to_string()),
        }
    }

    /// Opens a built-in scene or model file; on an error the scene stays and the error line says why.
    pub(super) fn open_scene(&mut self, source: String) {
        let setup = SceneSetup { source, camera: None, light: None, ..self.scene.setup.clone() };
        match Scene::open(setup) {
            Ok(scene) => {
                self.scene = scene;
                self.error = None;
                self.view.invalidate();
            }
            Err(e) => self.fail(e.to_string()),
        }
    }

    /// The controls' settings from the technique now drawing.
    fn reset_settings(&mut self) {
        let canonical = self.registry.canonical(self.view.technique()).unwrap_or_default();
        self.settings = key_values(&canonical).unwrap_or_default();
    }

    /// The whole UI: the side panel and the 3D view.
    pub(super) fn ui(&mut self, ui: &mut egui::Ui) {
        // A panel of a fixed width: one that grew with its text would resize the view, which clears its
        // overlay.
        egui::Panel::left("controls").exact_size(PANEL_WIDTH).resizable(false).show(ui, |ui| {
            egui::ScrollArea::vertical().show(ui, |ui| self.panel(ui));
        });
        egui::CentralPanel::no_frame().show(ui, |ui| self.view_input(ui));
    }

    fn next_screenshot(&mut self) {
        self.screenshots += 1;
        self.screenshot = Some(screenshot_path(self.screenshots));
    }

    fn reset_view(&mut self) {
        (self.scene.orbit, self.scene.light) = self.scene.home;
    }
}
