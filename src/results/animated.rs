//! The animated scenes' part of the results ([`scenes::ANIMATED`]): each technique's error against its
//! reference on each backend with the scene at rest and posed at ten times spread over its clip, the
//! largest of the ten over the error at rest, the backends' largest disagreement over the ten, and each
//! technique's flicker on the CPU as the animation plays.

use std::fmt::Write as _;

use shadow_core::scenes::{self, SceneParams};
use shadow_core::technique::TechniqueSpec;
use shadow_core::{FrameInputs, Scene};

use crate::Error;
use crate::compare::{CompareJob, CompareReport, ResultEntry, references_for, run_compare};
use crate::flicker::FlickerWalk;
use crate::renderer::{BackendKind, Renderer};

/// Times measured over a clip of `duration` seconds: the middles of its ten tenths.
#[must_use]
pub fn times(duration: f32) -> Vec<f32> {
    (0..10).map(|i| (i as f32 + 0.5) * duration / 10.0).collect()
}

/// The flicker walk: frames, seconds of the clip per frame (the camera stands still), view size.
const WALK: (usize, f32, (u32, u32)) = (24, 0.05, (320, 320));

/// One scene's measurements.
struct SceneReport {
    name: &'static str,
    duration: f32,
    rest: CompareReport,
    posed: Vec<CompareReport>,
    flicker: Vec<(String, f64)>,
}

/// The measurements.
pub struct AnimatedReport {
    scenes: Vec<SceneReport>,
    size: (u32, u32),
    backends: Vec<BackendKind>,
}

fn frame_of(scene: &Scene) -> Result<FrameInputs, Error> {
    Ok(FrameInputs::from_first_camera(scene)?)
}

/// Measures every animated scene at rest and at ten times of its clip on `backends`, and its flicker on
/// the CPU as it plays.
///
/// # Errors
/// A scene that cannot be built or posed, or a rendering failure.
pub fn run_animated(
    renderer: &mut Renderer,
    size: (u32, u32),
    backends: &[BackendKind],
    mut progress: impl FnMut(&str),
) -> Result<AnimatedReport, Error> {
    let mut out = Vec::new();
    for info in scenes::ANIMATED {
        let name = info.name;
        let mut scene =
            scenes::build(name, &SceneParams::default()).map_err(|e| Error::Usage(format!("{name}: {e}")))?;
        let duration = scene.animation_duration();
        let mut measure = |renderer: &mut Renderer, frame: &FrameInputs, when: &str| {
            let (techniques, _) = renderer.registry().measurable(frame);
            let (reference, soft_reference) = references_for(renderer.registry(), &techniques);
            let job = CompareJob {
                scene: name.to_string(),
                frame,
                width: size.0,
                height: size.1,
                techniques,
                reference,
                soft_reference,
                backends: backends.to_vec(),
                out_dir: None,
            };
            run_compare(renderer, &job, |m| progress(&format!("{name} {when}: {m}")))
        };
        let rest = measure(renderer, &frame_of(&scene)?, "at rest")?;
        let mut posed = Vec::new();
        for t in times(duration) {
            scene.pose(t).map_err(|e| Error::Usage(e.to_string()))?;
            posed.push(measure(renderer, &frame_of(&scene)?, &format!("at {t:.2} s"))?);
        }
        let (frames, step, walk_size) = WALK;
        let mut walk = Vec::with_capacity(frames);
        for k in 0..frames {
            scene.pose(k as f32 * step).map_err(|e| Error::Usage(e.to_string()))?;
            walk.push(frame_of(&scene)?);
        }
        let walked = FlickerWalk::through(renderer, walk, walk_size)?;
        let mut flicker = Vec::new();
        let cpu = BackendKind::Cpu.name();
        for e in rest.results.iter().filter(|e| e.reference == shadow_hard::RayTraced::NAME && e.backend == cpu) {
            progress(&format!("{name}: flicker of {}", e.technique));
            let spec = if e.settings.is_empty() {
                TechniqueSpec::named(&e.technique)
            } else {
                TechniqueSpec::parse(&format!("{}:{}", e.technique, e.settings))?
            };
            flicker.push((e.technique.clone(), walked.flicker(renderer, &spec, |_| {})?));
        }
        out.push(SceneReport { name, duration, rest, posed, flicker });
    }
    Ok(AnimatedReport { scenes: out, size, backends: backends.to_vec() })
}

/// A result's error: the mismatch for a hard technique (a fraction), the RMSE for a soft one.
fn error(e: &ResultEntry) -> f64 {
    if e.reference == shadow_hard::RayTraced::NAME { e.metrics.mismatch } else { e.metrics.rmse }
}

/// The markdown section.
pub fn markdown(s: &mut String, r: &AnimatedReport) {
    let _ = writeln!(s, "\n## Animated scenes\n");
    let backends: Vec<&str> = r.backends.iter().map(|b| b.name()).collect();
    let _ = writeln!(
        s,
        "{}x{}, on {}: the scenes whose casters move (`mill`: a rotor turned by node animation; `walker`: a \
         skinned figure, posed by a compute pass on wgpu). Each technique's error at rest (the scene as built), \
         then posed at the middles of the ten tenths of its clip: the least, the median and the most of the \
         ten, and the most over the error at rest. Hard techniques by mismatch, soft ones (marked RMSE) by \
         RMSE; each light kind's techniques only (`mill`'s sun leaves the soft ones out). Across: the most \
         the two backends' visibilities disagree (lit against shadowed) at rest or at any of the ten times. \
         Flicker, on the CPU: the share of measured points and frame pairs where the technique's lit state \
         changes and the reference's does not, or the other way round, over {} frames of {} s of the clip \
         at {}x{} (the camera still, the points the receivers of the first frame that do not move).\n",
        r.size.0,
        r.size.1,
        backends.join(" and "),
        WALK.0,
        WALK.1,
        WALK.2.0,
        WALK.2.1
    );
    for sc in &r.scenes {
        let _ = writeln!(s, "### {} ({:.1} s clip)\n", sc.name, sc.duration);
        let _ =
            writeln!(s, "| technique | backend | at rest | least | median | most | most / rest | across | flicker |");
        let _ = writeln!(s, "|---|---|---:|---:|---:|---:|---:|---:|---:|");
        for e in &sc.rest.results {
            let soft = e.reference != shadow_hard::RayTraced::NAME;
            let show = |v: f64| if soft { format!("{v:.4}") } else { format!("{:.3}%", v * 100.0) };
            let mut posed: Vec<f64> = sc
                .posed
                .iter()
                .filter_map(|p| {
                    p.results.iter().find(|x| x.technique == e.technique && x.backend == e.backend).map(error)
                })
                .collect();
            posed.sort_by(f64::total_cmp);
            let (Some(least), Some(most)) = (posed.first(), posed.last()) else { continue };
            let median = posed[posed.len() / 2];
            let rest = error(e);
            let ratio = if rest > 0.0 { format!("{:.2}", most / rest) } else { "-".into() };
            let flicker = sc
                .flicker
                .iter()
                .find(|(n, _)| *n == e.technique && e.backend == BackendKind::Cpu.name())
                .map_or("-".into(), |(_, f)| format!("{:.3}%", f * 100.0));
            let across = std::iter::once(&sc.rest)
                .chain(&sc.posed)
                .filter_map(|p| p.cross_backend.iter().find(|c| c.technique == e.technique).map(|c| c.mismatch))
                .reduce(f64::max)
                .map_or("-".into(), |m| format!("{:.3}%", m * 100.0));
            let _ = writeln!(
                s,
                "| `{}`{} | {} | {} | {} | {} | {} | {ratio} | {across} | {flicker} |",
                e.technique,
                if soft { " (RMSE)" } else { "" },
                e.backend,
                show(rest),
                show(*least),
                show(median),
                show(*most)
            );
        }
        s.push('\n');
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_times_are_the_middles_of_the_tenths() {
        let t = times(6.0);
        assert_eq!(t.len(), 10);
        assert!((t[0] - 0.3).abs() < 1e-6 && (t[9] - 5.7).abs() < 1e-6, "{t:?}");
    }
}
