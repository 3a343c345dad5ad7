//! The cut-out casters' part of the results: the scenes whose textures cut their casters out
//! ([`scenes::CUTOUT`]) on each backend, every technique that takes such casters against its reference.
//! How much of `cutout`'s checkerboard shadow each lights (half is right), under the scene's sun and under
//! a spot light in its place; each one's error on `foliage` beside its error on `tree` (the same branches,
//! bare), and on `fence` beside `outdoor` (the same street's scale and sun), with the two backends'
//! mismatch on the scenes of cut-out casters; and the contact sheet of `foliage`.

use std::fmt::Write as _;
use std::path::PathBuf;

use shadow_core::FrameInputs;
use shadow_core::scenes::cutouts::card_shadow_lit_share;
use shadow_core::scenes::{self, LightType, SceneParams};
use shadow_core::technique::TechniqueSpec;

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
    /// The backends to measure (the references run on the CPU, at each backend's pixels).
    pub backends: Vec<BackendKind>,
    /// The folder the pictures go to, beside the results page.
    pub pictures: PathBuf,
}

/// The lit shares of one technique: per backend of the job, under the sun and under a spot light (`None`
/// where it takes no such light or does not run on that backend).
type LitShares = (String, Vec<[Option<f64>; 2]>);

/// The measurements.
pub struct CutoutReport {
    /// Each technique's lit shares of the card's shadow, references first.
    lit_shares: Vec<LitShares>,
    /// The reports of the scenes of [`PAIRS`], each with its partner's.
    pairs: Vec<(CompareReport, CompareReport)>,
    backends: Vec<BackendKind>,
    size: (u32, u32),
}

/// How much of `cutout`'s card shadow `spec` lights on `backend` at `width x height` (the mean visibility
/// over the ground under the card, at the backend's own pixels), and over how many pixels.
///
/// # Errors
/// A rendering failure, or no wgpu adapter for `BackendKind::Wgpu`.
pub fn card_lit_share(
    renderer: &mut Renderer,
    backend: BackendKind,
    frame: &FrameInputs,
    spec: &TechniqueSpec,
    (width, height): (u32, u32),
) -> Result<(f64, usize), Error> {
    if backend == BackendKind::Cpu {
        let (f, _) = renderer.run_cpu_frame(frame, width, height, spec)?;
        return Ok(card_shadow_lit_share(f.receiver_points(0)));
    }
    let run = renderer.run(backend, frame, width, height, spec)?;
    let surfaces = shadow_wgpu::gbuffer::read(renderer.wgpu_context()?, frame, width, height)?;
    let pixels = surfaces.position.data().iter().zip(surfaces.receiver.data()).zip(run.visibility[0].data());
    Ok(card_shadow_lit_share(pixels.filter(|((_, receiver), _)| **receiver).map(|((&p, _), &v)| (p, v))))
}

/// Measures the scenes of cut-out casters and their partners on the job's backends; copies the contact
/// sheet of `foliage` into `job.pictures`.
///
/// # Errors
/// A scene that cannot be built, a rendering failure, or a picture that cannot be written.
pub fn run_cutouts(
    renderer: &mut Renderer,
    job: &CutoutJob,
    mut progress: impl FnMut(&str),
) -> Result<CutoutReport, Error> {
    let (w, h) = job.size;
    let mut lit_shares: Vec<LitShares> = Vec::new();
    for (k, light) in [None, Some(LightType::Spot)].into_iter().enumerate() {
        let scene = scenes::build("cutout", &SceneParams { light, ..SceneParams::default() })
            .map_err(|e| Error::Usage(format!("cutout: {e}")))?;
        let frame = FrameInputs::from_first_camera(&scene)?;
        let (taken, _) = renderer.registry().measurable(&frame);
        let (reference, soft_reference) = references_for(renderer.registry(), &taken);
        let references = 1 + usize::from(soft_reference.is_some());
        let mut specs = vec![reference];
        specs.extend(soft_reference);
        specs.extend(taken);
        for (i, spec) in specs.iter().enumerate() {
            let on_wgpu = renderer.registry().get(&spec.name)?.wgpu.is_some();
            let runs = |b: &BackendKind| match b {
                // The references at the CPU's pixels only: the wgpu rows measure the techniques.
                BackendKind::Cpu => true,
                BackendKind::Wgpu => i >= references && on_wgpu,
            };
            let slot = match lit_shares.iter().position(|(name, _)| *name == spec.name) {
                Some(slot) => slot,
                None => {
                    lit_shares.push((spec.name.clone(), vec![[None; 2]; job.backends.len()]));
                    lit_shares.len() - 1
                }
            };
            for (b, backend) in job.backends.iter().enumerate().filter(|(_, b)| runs(b)) {
                progress(&format!("cutout: lit share of {spec} on {}", backend.name()));
                lit_shares[slot].1[b][k] = Some(card_lit_share(renderer, *backend, &frame, spec, job.size)?.0);
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
                backends: job.backends.clone(),
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
    Ok(CutoutReport { lit_shares, pairs, backends: job.backends.clone(), size: job.size })
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
    let names: Vec<&str> = r.backends.iter().map(|b| b.name()).collect();
    let _ = writeln!(s, "\n## Cut-out casters\n");
    let _ = writeln!(
        s,
        "{}x{}, on {}: the scenes whose textures cut their casters out. A clear texel blocks no light: the \
         references test each ray's hit against its texel (level 0, the magnification filter), the light \
         passes of both backends discard the fragments of clear texels, each read over the footprint of one \
         map texel by the same rule. The techniques that extrude silhouettes (the shadow volumes, `hybrid`, \
         `penumbra-wedges`) give cut-out casters no volume or wedge and take their shadows from a depth map \
         of them alone, alpha-tested the same way (`cutout_res`, `cutout_filter`, `cutout_cascades`): a \
         receiver is lit only where both say lit (the soft visibility times the map's for the wedges).\n",
        r.size.0,
        r.size.1,
        names.join(" and ")
    );
    let _ = writeln!(
        s,
        "The lit share of `cutout`'s shadow: the mean visibility over the ground under the checkerboard card, \
         of which half is clear, at each backend's own pixels; under the scene's sun straight above the card, \
         and under a spot light in its place (which the soft techniques take). A dash: a light the technique \
         does not take (the references run on the CPU).\n"
    );
    let _ = write!(s, "| technique |");
    for light in ["sun", "spot"] {
        for name in &names {
            let _ = write!(s, " {light}, {name} |");
        }
    }
    let _ = writeln!(s, "\n|---|{}", "---:|".repeat(2 * names.len()));
    for (name, shares) in &r.lit_shares {
        let cell = |v: Option<f64>| v.map_or("-".into(), |v| format!("{:.2}%", v * 100.0));
        let _ = write!(s, "| `{name}` |");
        for light in 0..2 {
            for per_backend in shares {
                let _ = write!(s, " {} |", cell(per_backend[light]));
            }
        }
        s.push('\n');
    }
    let _ = writeln!(
        s,
        "\nEach technique's error on a scene of cut-out casters beside its error on the scene they were made \
         from, with the same settings, on each backend: hard techniques by mismatch, soft ones (marked RMSE) \
         by RMSE. A dash: the scene's light is of a kind the technique or its reference does not take.\n"
    );
    let _ = write!(s, "| technique | backend |");
    for (with, without) in &r.pairs {
        let _ = write!(s, " {} | {} | x |", with.scene, without.scene);
    }
    let _ = writeln!(s, "\n|---|---|{}", "---:|---:|---:|".repeat(r.pairs.len()));
    let mut rows: Vec<(&str, &str, bool)> = Vec::new();
    for (with, _) in &r.pairs {
        for e in &with.results {
            if !rows.iter().any(|(n, b, _)| *n == e.technique && *b == e.backend) {
                rows.push((&e.technique, &e.backend, e.reference != shadow_hard::RayTraced::NAME));
            }
        }
    }
    for (name, backend, soft) in rows {
        let _ = write!(s, "| `{name}`{} | {backend} |", if soft { " (RMSE)" } else { "" });
        for (with, without) in &r.pairs {
            let find =
                |r: &CompareReport| r.results.iter().find(|e| e.technique == name && e.backend == backend).map(error);
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
    if r.pairs.iter().any(|(with, _)| !with.cross_backend.is_empty()) {
        let _ = writeln!(
            s,
            "\nThe two backends against each other on the scenes of cut-out casters: the share of pixels where \
             one says lit and the other shadowed, and the RMS difference of their visibilities.\n"
        );
        let _ = write!(s, "| technique |");
        for (with, _) in &r.pairs {
            let _ = write!(s, " {0} mismatch | {0} RMSE |", with.scene);
        }
        let _ = writeln!(s, "\n|---|{}", "---:|---:|".repeat(r.pairs.len()));
        let mut names: Vec<&str> = Vec::new();
        for (with, _) in &r.pairs {
            for c in &with.cross_backend {
                if !names.contains(&c.technique.as_str()) {
                    names.push(&c.technique);
                }
            }
        }
        for name in names {
            let _ = write!(s, "| `{name}` |");
            for (with, _) in &r.pairs {
                match with.cross_backend.iter().find(|c| c.technique == name) {
                    Some(c) => {
                        let _ = write!(s, " {:.3}% | {:.4} |", c.mismatch * 100.0, c.rmse);
                    }
                    None => {
                        let _ = write!(s, " - | - |");
                    }
                }
            }
            s.push('\n');
        }
    }
    let _ = writeln!(
        s,
        "\nThe contact sheet of `foliage` (each technique's picture over its errors, the inset where they \
         disagree most):\n\n![foliage](foliage-contact.png)"
    );
}
