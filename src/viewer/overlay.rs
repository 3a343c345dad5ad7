//! What the viewer lays over the 3D view on demand, for the view it was made for (it clears as soon as
//! the view changes): the error map against the reference (ray-traced, or area-light for a soft
//! technique), whose reference is computed on a background thread while the viewer goes on drawing; or
//! an instrumented frame's debug views (one of them shown) and counters.

use std::sync::mpsc::{Receiver, TryRecvError};

use shadow_core::image::{Rgb8, error_map_over};
use shadow_core::metrics::{VisibilityMetrics, compare_visibility, measured_pixels};
use shadow_core::scene::{Camera, Light, LightShadow};
use shadow_core::technique::TechniqueSpec;
use shadow_core::{FrameInputs, Image};

use super::view::Inspection;
use crate::{BackendKind, Renderer, TechniqueRegistry};

/// What a picture of the view depends on: an overlay made for one key is shown only while it holds.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct ViewKey {
    pub scene: String,
    /// The timeline's time, for a scene with animations.
    pub time: Option<f32>,
    pub camera: Camera,
    pub lights: Vec<Light>,
    pub shadows: Vec<LightShadow>,
    pub technique: String,
    pub backend: BackendKind,
    pub size: (u32, u32),
}

/// The reference's side of a comparison: its visibility and the pixels measured (receivers in the light's
/// reach facing it) and shown (in its reach).
pub(super) struct Reference {
    visibility: Image<f32>,
    measured: Image<bool>,
    shown: Image<bool>,
}

/// An overlay, being made or made.
pub(super) enum Overlay {
    /// The reference (soft or not) is being computed; the technique's visibility and picture wait for it.
    Computing {
        key: ViewKey,
        soft: bool,
        against: TechniqueSpec,
        reference: Receiver<Result<Reference, String>>,
        test: Image<f32>,
        picture: Image<Rgb8>,
    },
    /// The error map, with the score over the measured pixels ([`score_line`]).
    Errors { key: ViewKey, texture: egui::TextureHandle, score: String },
    /// An instrumented frame of the technique: its debug views (one of them shown) and counters.
    Inspect { key: ViewKey, views: Vec<(String, egui::TextureHandle)>, shown: usize, counters: Vec<(String, f64)> },
}

impl Overlay {
    /// Starts comparing the view of `key` (`frame` at its size): the technique's visibility `test` and
    /// shaded `picture` against the reference `soft` asks for, computed on a thread of its own.
    pub(super) fn compare(
        key: ViewKey,
        frame: FrameInputs,
        soft: bool,
        test: Image<f32>,
        picture: Image<Rgb8>,
    ) -> Self {
        let (send, reference) = std::sync::mpsc::channel();
        let (width, height) = key.size;
        let against = crate::compare::reference_of(&TechniqueRegistry::builtin(), soft);
        let spec = against.clone();
        std::thread::spawn(move || {
            let made = reference_of(&frame, width, height, &spec).map_err(|e| e.to_string());
            // The viewer may have moved on and dropped the receiver: nothing waits for this result then.
            let _ = send.send(made);
        });
        Self::Computing { key, soft, against, reference, test, picture }
    }

    /// The inspection of the view of `key`, its debug views as egui textures.
    pub(super) fn inspect(key: ViewKey, inspection: Inspection, ui: &egui::Context) -> Self {
        let views = inspection
            .views
            .into_iter()
            .map(|v| {
                let texture = ui.load_texture(format!("debug {}", v.name), color_image(&v.image), Default::default());
                (v.name, texture)
            })
            .collect();
        Self::Inspect { key, views, shown: 0, counters: inspection.counters }
    }

    /// The key it was made for.
    pub(super) fn key(&self) -> &ViewKey {
        match self {
            Self::Computing { key, .. } | Self::Errors { key, .. } | Self::Inspect { key, .. } => key,
        }
    }

    /// Turns a finished comparison into its error map. An error computing the reference is returned.
    pub(super) fn poll(self, ui: &egui::Context) -> Result<Self, String> {
        let Self::Computing { key, soft, against, reference, test, picture } = self else { return Ok(self) };
        let r = match reference.try_recv() {
            Ok(made) => made?,
            Err(TryRecvError::Empty) => return Ok(Self::Computing { key, soft, against, reference, test, picture }),
            Err(TryRecvError::Disconnected) => return Err("the reference's thread stopped".into()),
        };
        let metrics = compare_visibility(&test, &r.visibility, &r.measured).map_err(|e| e.to_string())?;
        let map = error_map_over(&test, &r.visibility, &r.measured, &r.shown, &picture);
        let texture = ui.load_texture("error map", color_image(&map), Default::default());
        Ok(Self::Errors { key, texture, score: score_line(&metrics, soft, &against.name) })
    }
}

/// What a comparison says, as `compare` scores it ([`crate::compare::score`]), against `reference`: a
/// soft technique's RMSE with its mean difference, a hard one's mismatch split into false shadow and false
/// light.
fn score_line(m: &VisibilityMetrics, soft: bool, reference: &str) -> String {
    let pc = |f: f64| 100.0 * f;
    let detail = if soft {
        format!("mean difference {:.4}", m.mean_abs)
    } else {
        format!("false shadow {:.2}%, false light {:.2}%", pc(m.false_shadow), pc(m.false_light))
    };
    format!("{} against {reference} ({detail})", crate::compare::score(m, soft))
}

/// The reference `spec` renders of `frame`, with the pixels compared.
fn reference_of(frame: &FrameInputs, width: u32, height: u32, spec: &TechniqueSpec) -> Result<Reference, crate::Error> {
    let mut renderer = Renderer::new(TechniqueRegistry::builtin());
    let (f, _) = renderer.run_cpu_frame(frame, width, height, spec)?;
    let view = f.light_views.first().ok_or_else(|| crate::Error::Usage("the scene has no light".into()))?;
    let g = &f.gbuffer;
    let measured = measured_pixels(&g.receiver, &g.position, &g.geometric_normal, view);
    let shown = Image::from_fn(width, height, |x, y| *g.receiver.get(x, y) && view.in_domain(*g.position.get(x, y)));
    let visibility = f.visibility.into_iter().next().unwrap_or_default();
    Ok(Reference { visibility, measured, shown })
}

/// An image as egui takes it.
pub(super) fn color_image(image: &Image<Rgb8>) -> egui::ColorImage {
    let pixels: Vec<u8> = image.data().iter().flatten().copied().collect();
    egui::ColorImage::from_rgb([image.width() as usize, image.height() as usize], &pixels)
}
