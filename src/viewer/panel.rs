//! The viewer's state and its UI: the side panel (scene, backend, technique and its settings as controls
//! generated from the settings table, the light, readouts, screenshot and the command that reproduces
//! the view) and the 3D view's input (orbit, zoom, fly, the light dragged).

use std::collections::VecDeque;
use std::path::PathBuf;

use egui::{Color32, ComboBox, PointerButton, Slider};
use shadow_core::glam::Vec3;
use shadow_core::scenes;
use shadow_core::technique::TechniqueSpec;
use shadow_core::technique::settings::SettingKind;
use shadow_core::technique::settings::key_values;
use shadow_core::{FrameInputs, LightKind, LightShadow};
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
                let m = self.view.memory();
                println!(
                    "gpu memory: {} buffers, {} buffer bytes, {} texture bytes",
                    m.buffers, m.buffer_bytes, m.texture_bytes
                );
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
        if self.animate {
            let dt = painter.2.input(|i| i.stable_dt).min(0.1);
            if let Some(rig) = &mut self.scene.light {
                rig.turn(LIGHT_TURN_RATE * dt, 0.0);
            }
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
                    if let (true, Overlay::Errors { mismatch, false_shadow, false_light, .. }) = (computing, &o) {
                        self.say(mismatch_line(*mismatch, *false_shadow, *false_light));
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

    fn panel(&mut self, ui: &mut egui::Ui) {
        ui.heading("shadowlab");
        ui.separator();
        self.scene_controls(ui);
        ui.separator();
        ui.horizontal(|ui| {
            ui.label("Backend");
            for kind in [BackendKind::Wgpu, BackendKind::Cpu] {
                if ui.radio(self.view.backend() == kind, kind.name()).clicked() {
                    self.set_backend(kind);
                }
            }
        });
        ui.small(format!("adapter: {}", self.view.adapter()));
        ui.separator();
        self.technique_controls(ui);
        ui.separator();
        self.light_controls(ui);
        ui.checkbox(&mut self.animate, "Turn the light (L)");
        if ui.button("Reset camera and light (R)").clicked() {
            self.reset_view();
        }
        ui.separator();
        self.overlay_controls(ui);
        ui.separator();
        self.readouts(ui);
        ui.separator();
        ui.horizontal_wrapped(|ui| {
            if ui.button("Screenshot (P)").clicked() {
                self.next_screenshot();
            }
            if ui.button("Copy as command").clicked() {
                let command = self.command();
                println!("{command}");
                ui.ctx().copy_text(command);
                self.status = Some("copied the render command (also printed)".into());
            }
        });
        if let Some(e) = &self.error {
            ui.colored_label(Color32::LIGHT_RED, e);
        }
        if let Some(s) = &self.status {
            ui.label(s);
        }
    }

    fn scene_controls(&mut self, ui: &mut egui::Ui) {
        let current = self.scene.setup.source.clone();
        let mut chosen = None;
        ComboBox::from_label("Scene").selected_text(&current).show_ui(ui, |ui| {
            for s in scenes::ALL {
                if ui.selectable_label(current == s.name, s.name).on_hover_text(s.description).clicked() {
                    chosen = Some(s.name.to_string());
                }
            }
        });
        ui.horizontal(|ui| {
            ui.add(egui::TextEdit::singleline(&mut self.file).hint_text("model file").desired_width(180.0));
            if ui.button("Open").clicked() && !self.file.trim().is_empty() {
                chosen = Some(self.file.trim().to_string());
            }
        });
        ui.small("or drop a model file on the window");
        if let Some(source) = chosen {
            self.open_scene(source);
        }
    }

    fn technique_controls(&mut self, ui: &mut egui::Ui) {
        let name = self.view.technique().name.clone();
        let mut chosen = None;
        ComboBox::from_label("Technique").selected_text(&name).show_ui(ui, |ui| {
            for entry in self.registry.entries() {
                if ui.selectable_label(name == entry.name, entry.name).on_hover_text(entry.description).clicked() {
                    chosen = Some(entry.name);
                }
            }
        });
        if let Some(spec) = chosen {
            self.set_technique(spec);
            return;
        }
        let Ok(entry) = self.registry.get(&name) else { return };
        let mut commit = false;
        for key in (entry.keys)() {
            let Some((_, value)) = self.settings.iter_mut().find(|(k, _)| k == key.key) else { continue };
            // A control settles when a drag ends, or at once for a click or a typed value: a drag would
            // otherwise make a technique (and compile its changed pipelines) for every value it passes.
            let settled = |r: &egui::Response| r.drag_stopped() || (r.changed() && !r.dragged());
            // A word the key takes besides its numbers (`auto`, `0` for off) is a box to tick.
            if let Some(word) = key.word {
                let mut is_word = value == word;
                if ui.checkbox(&mut is_word, format!("{} {word}", key.key)).on_hover_text(key.help).changed() {
                    let number = |lo: String| if key.default == word { lo } else { key.default.to_string() };
                    *value = match (is_word, key.kind) {
                        (true, _) => word.to_string(),
                        (false, SettingKind::Int { lo, .. }) => number(lo.to_string()),
                        (false, SettingKind::Float { lo, .. }) => number(lo.to_string()),
                        (false, SettingKind::Choice(names)) => names.first().copied().unwrap_or(word).to_string(),
                    };
                    commit = true;
                }
                if is_word {
                    continue;
                }
            }
            match key.kind {
                SettingKind::Int { lo, hi } => match value.parse::<u32>() {
                    Ok(mut v) => {
                        let slider = Slider::new(&mut v, lo..=hi).text(key.key).logarithmic(hi / lo.max(1) > 64);
                        let r = ui.add(slider).on_hover_text(key.help);
                        *value = v.to_string();
                        commit |= settled(&r);
                    }
                    Err(_) => drop(ui.label(format!("{} = {value}", key.key)).on_hover_text(key.help)),
                },
                SettingKind::Float { lo, hi } => match value.parse::<f32>() {
                    Ok(mut v) => {
                        let slider = Slider::new(&mut v, lo..=hi).text(key.key).logarithmic(lo > 0.0 && hi / lo > 64.0);
                        let r = ui.add(slider).on_hover_text(key.help);
                        *value = v.to_string();
                        commit |= settled(&r);
                    }
                    Err(_) => drop(ui.label(format!("{} = {value}", key.key)).on_hover_text(key.help)),
                },
                SettingKind::Choice(names) => {
                    ComboBox::from_label(key.key).selected_text(value.as_str()).show_ui(ui, |ui| {
                        for &n in names {
                            if ui.selectable_label(value == n, n).clicked() {
                                *value = n.to_string();
                                commit = true;
                            }
                        }
                    });
                }
            }
        }
        if commit {
            let values: Vec<String> = self.settings.iter().map(|(k, v)| format!("{k}={v}")).collect();
            self.set_technique(&format!("{name}:{}", values.join(",")));
        }
    }

    /// Each light's shadow: whether it casts, and the technique that shadows it (the frame's, or one of
    /// its own with default settings).
    fn light_controls(&mut self, ui: &mut egui::Ui) {
        let frame = &mut self.scene.frame;
        frame.shadows.resize(frame.lights.len().max(frame.shadows.len()), LightShadow::default());
        for (k, (light, shadow)) in frame.lights.iter().zip(&mut frame.shadows).enumerate() {
            let kind = match light.kind {
                LightKind::Spot { .. } => "spot",
                LightKind::Point { .. } => "point",
                LightKind::Directional { .. } => "directional",
            };
            ui.horizontal(|ui| {
                ui.checkbox(&mut shadow.casts, format!("light {} ({kind}) casts", k + 1));
                let shown = shadow.technique.as_ref().map_or("the frame's".to_string(), |t| t.name.clone());
                ComboBox::from_id_salt(("light technique", k)).selected_text(shown).show_ui(ui, |ui| {
                    if ui.selectable_label(shadow.technique.is_none(), "the frame's").clicked() {
                        shadow.technique = None;
                    }
                    for entry in self.registry.entries() {
                        let chosen = shadow.technique.as_ref().is_some_and(|t| t.name == entry.name);
                        if ui.selectable_label(chosen, entry.name).clicked() {
                            shadow.technique = Some(TechniqueSpec::named(entry.name));
                        }
                    }
                });
            });
        }
    }

    fn readouts(&mut self, ui: &mut egui::Ui) {
        ui.label(format!("{:.1} frames a second", self.clock.fps()));
        match (self.gpu_times.back(), self.view.backend()) {
            (Some(t), BackendKind::Wgpu) => {
                let phases: Vec<String> = t.phases.iter().map(|(name, ms)| format!("{name} {ms:.1}")).collect();
                ui.label(format!("GPU: {:.2} ms a frame", t.total_ms));
                ui.small(phases.join(", "));
                plot(ui, &self.gpu_times);
            }
            (_, BackendKind::Wgpu) if !self.timed => drop(ui.small("the adapter has no timestamp queries")),
            _ => {}
        }
        ui.small(format!("on the GPU: {}", self.view.memory()));
    }

    fn overlay_controls(&mut self, ui: &mut egui::Ui) {
        ui.horizontal_wrapped(|ui| {
            if ui.button("Compare with reference").on_hover_text("false shadow red, false light blue").clicked() {
                self.compare_asked = true;
            }
            let inspect = ui.button("Inspect frame").on_hover_text("an instrumented frame: counters, debug views");
            if inspect.clicked() {
                self.inspect_asked = true;
            }
            if self.overlay.is_some() && ui.button("Clear").clicked() {
                self.overlay = None;
            }
        });
        match &mut self.overlay {
            Some(Overlay::Computing { .. }) => drop(ui.label("computing the reference...")),
            Some(Overlay::Errors { mismatch, false_shadow, false_light, .. }) => {
                ui.label(mismatch_line(*mismatch, *false_shadow, *false_light));
            }
            Some(Overlay::Inspect { views, shown, counters, .. }) => {
                let names: Vec<String> = views.iter().map(|(n, _)| n.clone()).collect();
                if let Some(name) = names.get(*shown) {
                    ComboBox::from_label("debug view").selected_text(name).show_ui(ui, |ui| {
                        for (i, n) in names.iter().enumerate() {
                            ui.selectable_value(shown, i, n);
                        }
                    });
                }
                egui::Grid::new("counters").striped(true).show(ui, |ui| {
                    for (name, value) in counters.iter() {
                        ui.small(name);
                        ui.small(format!("{value}"));
                        ui.end_row();
                    }
                });
            }
            None => {}
        }
    }

    fn next_screenshot(&mut self) {
        self.screenshots += 1;
        self.screenshot = Some(screenshot_path(self.screenshots));
    }

    fn reset_view(&mut self) {
        (self.scene.orbit, self.scene.light) = self.scene.home;
    }

    /// The 3D view: draws the last frame's texture and takes the pointer and keys.
    fn view_input(&mut self, ui: &mut egui::Ui) {
        let (rect, response) = ui.allocate_exact_size(ui.available_size(), egui::Sense::click_and_drag());
        let ppp = ui.ctx().pixels_per_point();
        self.size = ((rect.width() * ppp).round().max(1.0) as u32, (rect.height() * ppp).round().max(1.0) as u32);
        let uv = egui::Rect::from_min_max(egui::pos2(0.0, 0.0), egui::pos2(1.0, 1.0));
        match (self.texture, &self.error) {
            (Some(id), _) => {
                ui.painter().image(id, rect, uv, Color32::WHITE);
            }
            (None, Some(e)) => {
                let font = egui::FontId::proportional(16.0);
                ui.painter().text(rect.center(), egui::Align2::CENTER_CENTER, e, font, Color32::LIGHT_RED);
            }
            (None, None) => {}
        }
        match &self.overlay {
            Some(Overlay::Errors { texture, .. }) => {
                ui.painter().image(texture.id(), rect, uv, Color32::WHITE);
            }
            Some(Overlay::Inspect { views, shown, .. }) if !views.is_empty() => {
                // A debug view keeps its own aspect, centred over the view.
                let texture = &views[*shown].1;
                let [w, h] = texture.size().map(|s| s as f32);
                let scale = (rect.width() / w).min(rect.height() / h);
                let at = egui::Rect::from_center_size(rect.center(), egui::vec2(w, h) * scale);
                ui.painter().rect_filled(rect, 0.0, Color32::from_black_alpha(200));
                ui.painter().image(texture.id(), at, uv, Color32::WHITE);
            }
            _ => {}
        }
        let shift = ui.input(|i| i.modifiers.shift);
        let d = response.drag_delta() * TURN_PER_PIXEL;
        if response.dragged_by(PointerButton::Secondary) || (response.dragged_by(PointerButton::Primary) && shift) {
            if let Some(rig) = &mut self.scene.light {
                rig.turn(d.x, -d.y);
            }
        } else if response.dragged_by(PointerButton::Primary) {
            self.scene.orbit.turn(-d.x, d.y);
        }
        if response.hovered() {
            let scroll = ui.input(|i| i.smooth_scroll_delta.y);
            if scroll != 0.0 {
                self.scene.orbit.zoom((-scroll * 0.002).exp());
            }
        }
        if ui.ctx().egui_wants_keyboard_input() {
            return;
        }
        use egui::Key;
        let (dt, down, pressed) = ui.input(|i| {
            let down = |k: Key| if i.key_down(k) { 1.0 } else { 0.0 };
            let axes = [
                down(Key::W) - down(Key::S),
                down(Key::D) - down(Key::A),
                down(Key::E) - down(Key::Q),
                down(Key::ArrowRight) - down(Key::ArrowLeft),
                down(Key::ArrowUp) - down(Key::ArrowDown),
            ];
            (i.stable_dt.min(0.1), axes, [Key::R, Key::L, Key::P].map(|k| i.key_pressed(k)))
        });
        let speed = 0.5 * self.scene.orbit.distance * dt;
        self.scene.orbit.fly(speed * down[0], speed * down[1], speed * down[2]);
        if let Some(rig) = &mut self.scene.light {
            rig.turn(LIGHT_TURN_RATE * dt * down[3], LIGHT_TURN_RATE * dt * down[4]);
        }
        if pressed[0] {
            self.reset_view();
        }
        if pressed[1] {
            self.animate = !self.animate;
        }
        if pressed[2] {
            self.next_screenshot();
        }
        if down.iter().any(|&a| a != 0.0) || self.animate {
            ui.ctx().request_repaint();
        }
    }

    /// The `shadowlab render` command that draws this view offline: the scene, the camera and first
    /// light as they are now (the light by position and aim; its colour, cone and radius are the
    /// scene's), the technique with its settings, the backend and the view's size.
    pub(super) fn command(&self) -> String {
        let setup = &self.scene.setup;
        let frame = self.scene.frame();
        let v = |p: Vec3| format!("{},{},{}", p.x, p.y, p.z);
        let mut words = vec!["shadowlab render --scene".to_string(), quoted(&setup.source)];
        if !setup.ground {
            words.push("--ground none".into());
        }
        if setup.params.seed != 1 {
            words.push(format!("--seed {}", setup.params.seed));
        }
        if setup.file_access == shadow_core::assets::FileAccess::Anywhere {
            words.push("--allow-outside-files".into());
        }
        let c = frame.camera;
        words.push(format!("--camera eye={},target={},fov={}", v(c.eye), v(c.target), c.fov_y.to_degrees()));
        if let Some(light) = frame.lights.first() {
            let text = match light.kind {
                LightKind::Spot { position, direction, .. } => {
                    format!("spot,pos={},target={}", v(position), v(position + direction))
                }
                LightKind::Point { position } => format!("point,pos={}", v(position)),
                LightKind::Directional { direction } => format!("directional,pos={},target=0,0,0", v(-direction)),
            };
            words.push(format!("--light {text}"));
        }
        let spec = self.view.technique();
        let settings = self.registry.canonical(spec).unwrap_or_default();
        let spec = if settings.is_empty() { spec.name.clone() } else { format!("{}:{settings}", spec.name) };
        words.push(format!("--technique {}", quoted(&spec)));
        words.push(format!(
            "--backend {} --size {}x{} --out view.png",
            self.view.backend().name(),
            self.size.0,
            self.size.1
        ));
        words.join(" ")
    }
}

/// The comparison's numbers, as the panel and the script print them.
fn mismatch_line(mismatch: f64, false_shadow: f64, false_light: f64) -> String {
    let pc = |f: f64| 100.0 * f;
    format!(
        "mismatch {:.2}% (false shadow {:.2}%, false light {:.2}%)",
        pc(mismatch),
        pc(false_shadow),
        pc(false_light)
    )
}

/// `text` as one shell word.
fn quoted(text: &str) -> String {
    let plain = |c: char| c.is_ascii_alphanumeric() || "._/-:=,+".contains(c);
    if !text.is_empty() && text.chars().all(plain) { text.into() } else { format!("'{}'", text.replace('\'', r"'\''")) }
}

/// Colours of the plot's lines: the whole frame, then its phases in order.
const PLOT_COLOURS: [Color32; 4] = [Color32::WHITE, Color32::LIGHT_BLUE, Color32::LIGHT_GREEN, Color32::GOLD];

/// A small rolling plot of the last [`PLOTTED`] frames' GPU times, the newest at the right: the whole
/// frame and each phase, scaled to the largest frame (always as many points, the missing ones at zero,
/// so the UI's geometry does not grow as the history fills).
fn plot(ui: &mut egui::Ui, times: &VecDeque<FrameTimes>) {
    let (rect, _) = ui.allocate_exact_size(egui::vec2(ui.available_width(), 56.0), egui::Sense::hover());
    let top = times.iter().map(|t| t.total_ms).fold(f64::MIN_POSITIVE, f64::max);
    let step = rect.width() / (PLOTTED - 1) as f32;
    let missing = PLOTTED.saturating_sub(times.len());
    let painter = ui.painter_at(rect);
    painter.rect_filled(rect, 2.0, ui.visuals().extreme_bg_color);
    let phases = times.back().map_or(0, |t| t.phases.len());
    for (line, colour) in PLOT_COLOURS.iter().enumerate().take(phases + 1) {
        let value = |t: &FrameTimes| if line == 0 { t.total_ms } else { t.phases.get(line - 1).map_or(0.0, |p| p.1) };
        let padded = std::iter::repeat_n(0.0, missing).chain(times.iter().map(value));
        let points = padded
            .enumerate()
            .map(|(i, v)| egui::pos2(rect.left() + i as f32 * step, rect.bottom() - (v / top) as f32 * rect.height()))
            .collect();
        painter.add(egui::Shape::line(points, egui::Stroke::new(1.0, *colour)));
    }
    let legend: Vec<&str> = times.back().map_or(Vec::new(), |t| t.phases.iter().map(|p| p.0).collect());
    let font = egui::FontId::monospace(10.0);
    let mut x = rect.left() + 2.0;
    for (text, colour) in
        std::iter::once(format!("{top:.1} ms")).chain(legend.iter().map(|s| s.to_string())).zip(PLOT_COLOURS)
    {
        let r = painter.text(egui::pos2(x, rect.top()), egui::Align2::LEFT_TOP, text, font.clone(), colour);
        x = r.right() + 8.0;
    }
}
