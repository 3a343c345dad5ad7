//! The many-lights part of the results: `yard` with 1, 4, 16 and 64 of its lights, every frame with the
//! light's reach and the shadow atlas and every frame without them (`bench --savings both`), on each
//! backend; on a GPU adapter the real-time path too, with the host's time to record a frame. From them the
//! growth exponent of the frame time in the light count (the slope of a least-squares line through
//! log time against log lights) and the recording cost a light adds. Then the 64 lights standing still
//! while the camera turns (`bench --move camera`), beside the same frames with no shadows at all.

use std::fmt::Write as _;

use shadow_core::frame::Savings;
use shadow_core::scenes::{self, SceneParams};
use shadow_core::technique::TechniqueSpec;

use crate::Error;
use crate::bench::realtime::{RealtimeReport, run_realtime_bench};
use crate::bench::{BenchJob, BenchReport, Motion, run_bench};
use crate::renderer::{BackendKind, Renderer};

/// The light counts measured.
pub const LIGHT_COUNTS: [usize; 4] = [1, 4, 16, 64];
/// The technique measured.
const TECHNIQUE: &str = "shadow-map";
/// Frames timed (after two unmeasured ones).
const FRAMES: u32 = 5;

/// The frames of one light count.
struct Count {
    lights: usize,
    bench: BenchReport,
    realtime: Option<RealtimeReport>,
}

/// The measurements.
pub struct LightsReport {
    counts: Vec<Count>,
    /// The lights still and the camera turning: with shadows, then with none.
    still: [Count; 2],
    size: (u32, u32),
}

/// Measures `yard` at `size` on `backends` with each of [`LIGHT_COUNTS`] lights.
///
/// # Errors
/// A failed frame.
pub fn run_lights(
    renderer: &mut Renderer,
    size: (u32, u32),
    backends: &[BackendKind],
    progress: &mut impl FnMut(&str),
) -> Result<LightsReport, Error> {
    let yard = || scenes::build("yard", &SceneParams::default()).map_err(|e| Error::Usage(e.to_string()));
    let mut counts = Vec::new();
    for lights in LIGHT_COUNTS {
        let mut scene = yard()?;
        scene.set_light_count(lights).map_err(|e| Error::Usage(e.to_string()))?;
        let frame = shadow_core::FrameInputs::from_first_camera(&scene)?;
        let both = vec![Savings::ALL, Savings::NONE];
        let run = Run { label: format!("yard, {lights} lights"), motion: Motion::Lights, savings: both };
        counts.push(run.measure(renderer, &frame, (size, backends), progress)?);
    }
    let shadowed = shadow_core::FrameInputs::from_first_camera(&yard()?)?;
    let unshadowed = shadow_core::FrameInputs {
        shadows: vec![shadow_core::LightShadow::NONE; shadowed.lights.len()],
        ..shadowed.clone()
    };
    let mut still = Vec::new();
    for (frame, what) in [(&shadowed, "shadowed"), (&unshadowed, "no shadows")] {
        let run =
            Run { label: format!("yard, still lights, {what}"), motion: Motion::Camera, savings: vec![Savings::ALL] };
        still.push(run.measure(renderer, frame, (size, backends), progress)?);
    }
    let still: [Count; 2] = still.try_into().unwrap_or_else(|_| unreachable!("two runs"));
    Ok(LightsReport { counts, still, size })
}

/// One bench of the lights section: what moves and what the frames save.
struct Run {
    label: String,
    motion: Motion<'static>,
    savings: Vec<Savings>,
}

impl Run {
    /// The instrumented frames of `frame` on `backends` at `size`, and the real-time path's on a GPU adapter.
    fn measure(
        self,
        renderer: &mut Renderer,
        frame: &shadow_core::FrameInputs,
        (size, backends): ((u32, u32), &[BackendKind]),
        progress: &mut impl FnMut(&str),
    ) -> Result<Count, Error> {
        let label = self.label;
        let job = BenchJob {
            scene: label.clone(),
            frame,
            width: size.0,
            height: size.1,
            frames: FRAMES,
            warmup: 2,
            techniques: vec![TechniqueSpec::named(TECHNIQUE)],
            backends: backends.to_vec(),
            rebuild: false,
            motion: self.motion,
            savings: self.savings,
        };
        let bench = run_bench(renderer, &job, |m| progress(&format!("{label}: {m}")))?;
        let realtime = if backends.contains(&BackendKind::Wgpu) {
            let job = BenchJob { backends: vec![BackendKind::Wgpu], ..job };
            Some(run_realtime_bench(renderer, &job, |m| progress(&format!("{label}, real-time: {m}")))?)
        } else {
            None
        };
        Ok(Count { lights: frame.lights.len(), bench, realtime })
    }
}

/// The slope of the least-squares line through (ln x, ln y): the exponent b of y = a x^b.
#[must_use]
pub fn growth_exponent(points: &[(f64, f64)]) -> f64 {
    slope(&points.iter().map(|&(x, y)| (x.ln(), y.ln())).collect::<Vec<_>>())
}

/// The slope of the least-squares line through `points`.
fn slope(points: &[(f64, f64)]) -> f64 {
    let n = points.len() as f64;
    let (mx, my) = (points.iter().map(|p| p.0).sum::<f64>() / n, points.iter().map(|p| p.1).sum::<f64>() / n);
    let sxy: f64 = points.iter().map(|(x, y)| (x - mx) * (y - my)).sum();
    let sxx: f64 = points.iter().map(|(x, _)| (x - mx) * (x - mx)).sum();
    sxy / sxx
}

impl LightsReport {
    /// The median total of the instrumented frames of `backend` with `savings` ("all" or "none"), per count.
    fn totals(&self, backend: &str, savings: &str) -> Vec<(f64, f64)> {
        self.counts
            .iter()
            .filter_map(|c| {
                let e = c.bench.results.iter().find(|e| e.backend == backend && e.savings == savings)?;
                Some((c.lights as f64, e.timings_ms.get("total")?.median))
            })
            .collect()
    }

    /// The real-time path's frame and the host's recording time per count, with `savings`.
    fn realtime(&self, savings: &str) -> Vec<(usize, f64, f64)> {
        self.counts
            .iter()
            .filter_map(|c| {
                let e = c.realtime.as_ref()?.results.iter().find(|e| e.savings == savings)?;
                Some((c.lights, e.frame_ms?, e.record_ms?.median))
            })
            .collect()
    }
}

/// Appends the section to `s`.
pub fn markdown(s: &mut String, r: &LightsReport) {
    let _ = writeln!(s, "\n## Many lights\n");
    let _ = writeln!(
        s,
        "`yard` (480 props; spot and point lights of ranges 5, 8 and 12) with its first 1, 4, 16 and 64 lights, \
         `{TECHNIQUE}` at {}x{} (`bench --lights N --savings both`, {FRAMES} frames, median ms): with each light \
         queried within its reach, lights out of view skipped and the maps sized by the shadow atlas (*saving*), \
         and without (*whole view*, every map at the technique's `res`). The growth exponent is the slope of \
         log frame time against log lights over the four counts.\n",
        r.size.0, r.size.1
    );
    let _ = writeln!(s, "| lights | backend | saving: build / query / shade / total | whole view: the same | ratio |");
    let _ = writeln!(s, "|---:|---|---|---|---:|");
    for c in &r.counts {
        for saving in c.bench.results.iter().filter(|e| e.savings == "all") {
            let whole = c.bench.results.iter().find(|e| e.backend == saving.backend && e.savings == "none");
            let phases = |e: &crate::bench::BenchEntry| {
                ["build", "query", "shade", "total"]
                    .map(|p| e.timings_ms.get(p).map_or("-".into(), |st| format!("{:.1}", st.median)))
                    .join(" / ")
            };
            let total = |e: &crate::bench::BenchEntry| e.timings_ms.get("total").map_or(f64::NAN, |t| t.median);
            let _ = writeln!(
                s,
                "| {} | {} | {} | {} | {:.2} |",
                c.lights,
                saving.backend,
                phases(saving),
                whole.map_or("-".into(), phases),
                whole.map_or(f64::NAN, |w| total(saving) / total(w))
            );
        }
    }
    let _ = writeln!(s, "\n| backend | growth exponent, saving | whole view |\n|---|---:|---:|");
    for backend in ["cpu", "wgpu"] {
        let (saving, whole) = (r.totals(backend, "all"), r.totals(backend, "none"));
        if saving.len() == LIGHT_COUNTS.len() && whole.len() == LIGHT_COUNTS.len() {
            let _ = writeln!(s, "| {backend} | {:.2} | {:.2} |", growth_exponent(&saving), growth_exponent(&whole));
        }
    }
    still_markdown(s, r);
    let (saving, whole) = (r.realtime("all"), r.realtime("none"));
    if saving.is_empty() {
        return;
    }
    let _ = writeln!(
        s,
        "\nThe real-time path on the GPU adapter (`bench --realtime`): the frame with two in flight and the host's \
         time to record it, in ms; the recording cost a light adds is the slope of recording time over lights \
         (least squares over the four counts).\n"
    );
    let _ = writeln!(s, "| lights | saving: frame / record | whole view: frame / record |\n|---:|---|---|");
    for (k, &(lights, frame, record)) in saving.iter().enumerate() {
        let other = whole.get(k).map_or("-".into(), |&(_, f, r)| format!("{f:.1} / {r:.2}"));
        let _ = writeln!(s, "| {lights} | {frame:.1} / {record:.2} | {other} |");
    }
    let per_light_us =
        |p: &[(usize, f64, f64)]| slope(&p.iter().map(|&(n, _, r)| (n as f64, r)).collect::<Vec<_>>()) * 1e3;
    let frames = |p: &[(usize, f64, f64)]| p.iter().map(|&(n, f, _)| (n as f64, f)).collect::<Vec<_>>();
    let _ = writeln!(
        s,
        "\nRecording cost per light: {:.0} us saving, {:.0} us over the whole view. Growth exponent of the real-time \
         frame: {:.2} saving, {:.2} whole view.",
        per_light_us(&saving),
        per_light_us(&whole),
        growth_exponent(&frames(&saving)),
        growth_exponent(&frames(&whole))
    );
}

/// The still lights' table: each backend's frame with shadows beside the frame with none.
fn still_markdown(s: &mut String, r: &LightsReport) {
    let [shadowed, none] = &r.still;
    let _ = writeln!(
        s,
        "\nThe {} lights standing still while the camera turns an eighth of a turn about the point it looks at over \
         the frames (`bench --move camera`, each light's build kept while it keeps its tiles), beside the same \
         frames with no shadows at all (`--no-shadows`), median ms; *kept* is the builds kept in the last frame.\n",
        shadowed.lights
    );
    let _ = writeln!(s, "| backend | shadowed: build / query / shade / total | kept | no shadows: total | ratio |");
    let _ = writeln!(s, "|---|---|---:|---:|---:|");
    let total = |e: &crate::bench::BenchEntry| e.timings_ms.get("total").map_or(f64::NAN, |t| t.median);
    for e in &shadowed.bench.results {
        let Some(bare) = none.bench.results.iter().find(|b| b.backend == e.backend) else { continue };
        let phases = ["build", "query", "shade", "total"]
            .map(|p| e.timings_ms.get(p).map_or("-".into(), |st| format!("{:.1}", st.median)))
            .join(" / ");
        let kept = e.counters.get("cached_builds").copied().unwrap_or(0.0);
        let _ = writeln!(
            s,
            "| {} | {phases} | {kept:.0} | {:.1} | {:.2} |",
            e.backend,
            total(bare),
            total(e) / total(bare)
        );
    }
    let frame = |c: &Count| c.realtime.as_ref()?.results.first()?.frame_ms;
    if let (Some(a), Some(b)) = (frame(shadowed), frame(none)) {
        let _ = writeln!(s, "| wgpu real-time | frame {a:.1} | - | {b:.1} | {:.2} |", a / b);
    }
}

#[cfg(test)]
mod tests {
    use super::growth_exponent;

    #[test]
    fn the_growth_exponent_of_a_power_law_is_its_power() {
        let points: Vec<(f64, f64)> = [1.0, 4.0, 16.0, 64.0].iter().map(|&n: &f64| (n, 3.0 * n.powf(0.75))).collect();
        assert!((growth_exponent(&points) - 0.75).abs() < 1e-9);
        let flat: Vec<(f64, f64)> = [1.0, 4.0, 16.0].iter().map(|&n| (n, 5.0)).collect();
        assert!(growth_exponent(&flat).abs() < 1e-12);
    }
}
