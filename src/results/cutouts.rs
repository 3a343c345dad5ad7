//! The cut-out casters' part of the results: the scenes whose textures cut their casters out
//! ([`scenes::CUTOUT`]) on the CPU backend, every technique that takes such casters against its
//! reference. How much of `cutout`'s checkerboard shadow each lights (half is right), under the scene's
//! sun and under a spot light in its place; each one's error on `foliage` beside its error on `tree` (the
//! same branches, bare), and on `fence` beside `outdoor` (the same street's scale and sun); and the
//! contact sheet of `foliage`.

use std::fmt::Write as _;
use std::path::PathBuf;

use shadow_core::FrameInputs;
use shadow_core::scenes::cutouts::card_shadow_lit_share;
use shadow_core::scenes::{self, LightType, SceneParams};

use super::scene_frame;
use crate::Error;
use crate::compare::{CompareJob, CompareReport, ResultEntry, references_for, run_compare};
use crate::renderer::{BackendKind, Renderer};

/// Each scene of cut-out casters, with the scene without them its errors are set beside.
const PAIRS: [(&str, &str); 2] = [("foliage", "tree"), ("fence", "outdoor")];

/// What to measure.
pub struct CutoutJob {
    /// View size.
    pub size: (u32, u32),
    /// The folder the pictures go to, beside the results page.
    pub pictures: PathBuf,
}

/// The measurements.
pub struct CutoutReport {
    /// Each technique's lit share of the card's shadow under the sun and under a spot light (`None`
    /// where it takes no such light), references first.
    lit_shares: Vec<(String, [Option<f64>; 2])>,
    /// The reports of the scenes of [`PAIRS`], each with its partner's.
    pairs: Vec<(CompareReport, CompareReport)>,
    size: (u32, u32),
}

/// Measures the scenes of cut-out casters and their partners on the CPU; copies the contact sheet of
/// `foliage` into `job.pictures`.
///
/// # Errors
/// A scene that cannot be built, a rendering failure, or a picture that cannot be written.
pub fn run_cutouts(
    renderer: &mut Renderer,
    job: &CutoutJob,
    mut progress: impl FnMut(&str),
) -> Result<CutoutReport, Error> {
    let (w, h) = job.size;
    let mut lit_shares: Vec<(String, [Option<f64>; 2])> = Vec::new();
    for (k, light) in [None, Some(LightType::Spot)].into_iter().enumerate() {
        let scene = scenes::build("cutout", &SceneParams { light, ..SceneParams::default() })
            .map_err(|e| Error::Usage(format!("cutout: {e}")))?;
        let frame = FrameInputs::from_first_camera(&scene)?;
        let (taken, _) = renderer.registry().measurable(&frame);
        let (reference, soft_reference) = references_for(renderer.registry(), &taken);
        let mut specs = vec![reference];
        specs.extend(soft_reference);
        specs.extend(taken);
        for spec in specs {
            progress(&format!("cutout: lit share of {spec}"));
            let (f, _) = renderer.run_cpu_frame(&frame, w, h, &spec)?;
            let share = card_shadow_lit_share(f.receiver_points(0)).0;
            match lit_shares.iter_mut().find(|(name, _)| *name == spec.name) {
                Some((_, shares)) => shares[k] = Some(share),
                None => lit_shares.push((spec.name.clone(), std::array::from_fn(|i| (i == k).then_some(share)))),
            }
        }
    }
    let mut pairs = Vec::new();
    for (cut, partner) in PAIRS {
        let measure = |renderer: &mut Renderer, name: &str, progress: &mut dyn FnMut(&str)| {
            let frame = scene_frame(name)?;
            let (techniques, _) = renderer.registry().measurable(&frame);
            let (reference, soft_reference) = references_for(renderer.registry(), &techniques);
            let scratch = std::env::temp_dir().join(format!("shadowlab-results-{name}"));
            let compare = CompareJob {
                scene: name.to_string(),
                frame: &frame,
                width: w,
                height: h,
                techniques,
                reference,
                soft_reference,
                backends: vec![BackendKind::Cpu],
                out_dir: Some(scratch.clone()),
            };
            let report = run_compare(renderer, &compare, |m| progress(&format!("{name}: {m}")))?;
            if name == "foliage" {
                let to = job.pictures.join("foliage-contact.png");
                std::fs::copy(scratch.join("contact.png"), &to)
                    .map_err(|e| Error::Write { path: to.clone(), why: e.to_string() })?;
            }
            let _ = std::fs::remove_dir_all(&scratch);
            Ok::<_, Error>(report)
        };
        let with = measure(renderer, cut, &mut progress)?;
        let without = measure(renderer, partner, &mut progress)?;
        pairs.push((with, without));
    }
    Ok(CutoutReport { lit_shares, pairs, size: job.size })
}

/// A result's error: the mismatch for a hard technique (as a percentage), the RMSE for a soft one.
fn error(e: &ResultEntry) -> (f64, String) {
    if e.reference == shadow_hard::RayTraced::NAME {
        (e.metrics.mismatch, format!("{:.3}%", e.metrics.mismatch * 100.0))
    } else {
        (e.metrics.rmse, format!("{:.4}", e.metrics.rmse))
    }
}

/// The markdown section.
pub fn markdown(s: &mut String, r: &CutoutReport) {
    let _ = writeln!(s, "\n## Cut-out casters (CPU backend)\n");
    let _ = writeln!(
        s,
        "{}x{}, on the CPU backend: the scenes whose textures cut their casters out. A clear texel blocks no \
         light: the references test each ray's hit against its texel (level 0, the magnification filter), \
         the light passes discard the fragments of clear texels, each read over the footprint of one map \
         texel. The techniques that extrude silhouettes take no cut-out casters and are left out.\n",
        r.size.0, r.size.1
    );
    let _ = writeln!(
        s,
        "The lit share of `cutout`'s shadow: the mean visibility over the ground under the checkerboard card, \
         of which half is clear; under the scene's sun straight above the card, and under a spot light in its \
         place (which the soft techniques take). A dash: a light the technique does not take.\n"
    );
    let _ = writeln!(s, "| technique | lit share, sun | lit share, spot |\n|---|---:|---:|");
    for (name, shares) in &r.lit_shares {
        let cell = |v: &Option<f64>| v.map_or("-".into(), |v| format!("{:.2}%", v * 100.0));
        let _ = writeln!(s, "| `{name}` | {} | {} |", cell(&shares[0]), cell(&shares[1]));
    }
    let _ = writeln!(
        s,
        "\nEach technique's error on a scene of cut-out casters beside its error on the scene they were made \
         from, with the same settings: hard techniques by mismatch, soft ones (marked RMSE) by RMSE. A dash: \
         the scene's light is of a kind the technique or its reference does not take.\n"
    );
    let _ = write!(s, "| technique |");
    for (with, without) in &r.pairs {
        let _ = write!(s, " {} | {} | x |", with.scene, without.scene);
    }
    let _ = write!(s, "\n|---|");
    for _ in &r.pairs {
        let _ = write!(s, "---:|---:|---:|");
    }
    s.push('\n');
    let mut names: Vec<(&str, bool)> = Vec::new();
    for (with, _) in &r.pairs {
        for e in &with.results {
            if !names.iter().any(|(n, _)| *n == e.technique) {
                names.push((&e.technique, e.reference != shadow_hard::RayTraced::NAME));
            }
        }
    }
    for (name, soft) in names {
        let _ = write!(s, "| `{name}`{} |", if soft { " (RMSE)" } else { "" });
        for (with, without) in &r.pairs {
            let find = |r: &CompareReport| r.results.iter().find(|e| e.technique == name).map(error);
            match (find(with), find(without)) {
                (Some((a, a_text)), Some((b, b_text))) => {
                    let _ = write!(s, " {a_text} | {b_text} | {:.2} |", a / b);
                }
                (Some((_, a_text)), None) => {
                    let _ = write!(s, " {a_text} | - | - |");
                }
                _ => {
                    let _ = write!(s, " - | - | - |");
                }
            }
        }
        s.push('\n');
    }
    let _ = writeln!(
        s,
        "\nThe contact sheet of `foliage` (each technique's picture over its errors, the inset where they \
         disagree most):\n\n![foliage](foliage-contact.png)"
    );
}
