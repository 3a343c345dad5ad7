//! The `shadowlab render` command that draws the viewer's view offline.

use shadow_core::LightKind;
use shadow_core::glam::Vec3;

use super::Viewer;

impl Viewer {
    /// The `shadowlab render` command that draws this view offline: the scene (posed at the timeline's
    /// time, for one with animations), the camera and first light as they are now (the light by position and aim; its colour, cone and radius are the
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
        if let Some(t) = self.scene.time() {
            words.push(format!("--time {t}"));
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

/// `text` as one shell word.
fn quoted(text: &str) -> String {
    let plain = |c: char| c.is_ascii_alphanumeric() || "._/-:=,+".contains(c);
    if !text.is_empty() && text.chars().all(plain) { text.into() } else { format!("'{}'", text.replace('\'', r"'\''")) }
}
