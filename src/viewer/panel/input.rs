//! The 3D view's input: the last frame's texture and its overlay drawn, the pointer turning the camera
//! or the light, the wheel zooming, the keys flying and acting.

use egui::{Color32, PointerButton};

use super::{LIGHT_TURN_RATE, TURN_PER_PIXEL, Viewer};
use crate::viewer::overlay::Overlay;

impl Viewer {
    /// The 3D view: draws the last frame's texture and takes the pointer and keys.
    pub(super) fn view_input(&mut self, ui: &mut egui::Ui) {
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
            (i.stable_dt.min(0.1), axes, [Key::R, Key::L, Key::P, Key::Space].map(|k| i.key_pressed(k)))
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
        if pressed[3]
            && let Some(clip) = &mut self.scene.clip
        {
            clip.playing = !clip.playing;
        }
        let playing = self.scene.clip.as_ref().is_some_and(|c| c.playing);
        if down.iter().any(|&a| a != 0.0) || self.animate || playing {
            ui.ctx().request_repaint();
        }
    }
}
