//! The side panel's sections: scene, backend, technique and its settings as controls generated from the
//! settings table, each light's shadow, the overlays, the readouts and the actions.

use std::collections::VecDeque;

use egui::{Color32, ComboBox, Slider};
use shadow_core::scenes;
use shadow_core::technique::TechniqueSpec;
use shadow_core::technique::settings::SettingKind;
use shadow_core::{LightKind, LightShadow};
use shadow_wgpu::FrameTimes;

use super::{PLOTTED, Viewer};
use crate::BackendKind;
use crate::viewer::overlay::Overlay;

impl Viewer {
    pub(super) fn panel(&mut self, ui: &mut egui::Ui) {
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
        self.clip_controls(ui);
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
            for s in scenes::every() {
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

    /// The timeline of a scene with animations: play or pause it, and scrub it.
    fn clip_controls(&mut self, ui: &mut egui::Ui) {
        let Some(clip) = &mut self.scene.clip else { return };
        let mut scrubbed = None;
        ui.horizontal(|ui| {
            if ui.button(if clip.playing { "Pause (space)" } else { "Play (space)" }).clicked() {
                clip.playing = !clip.playing;
            }
            let mut t = clip.time();
            let slider = Slider::new(&mut t, 0.0..=clip.duration()).suffix(" s").max_decimals(2);
            if ui.add(slider).on_hover_text("the animations' time: drag to scrub (pauses)").changed() {
                scrubbed = Some(t);
            }
        });
        if let Some(t) = scrubbed {
            self.scrub(t);
        }
        ui.separator();
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
            Some(Overlay::Errors { score, .. }) => drop(ui.label(score.as_str())),
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
