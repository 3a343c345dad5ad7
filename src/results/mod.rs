//! `shadowlab results`: measures every technique on every built-in scene and writes `docs/results.md`,
//! so each number there comes from one command on a named machine and adapter.
//!
//! The error of each technique against its reference on each scene (both backends), the largest
//! disagreement between the backends, the frame time per phase on one scene (`bench`), on a GPU adapter
//! the real-time path on that scene (`bench --realtime`), perspective aliasing on the outdoor street
//! ([`outdoor`]), the soft techniques against the area light ([`soft`]), the scenes of cut-out casters
//! ([`cutouts`]), the animated scenes at rest and posed ([`animated`]), the scenes of many objects with
//! their meshes shared and unshared ([`many`]), a scene of many lights ([`lights`]), and the kernels under
//! them all timed on their own ([`kernels`]).

pub mod animated;
pub mod cutouts;
pub mod kernels;
pub mod lights;
pub mod many;
pub mod outdoor;
pub mod soft;

use std::collections::BTreeMap;
use std::fmt::Write as _;

use shadow_core::FrameInputs;
use shadow_core::scenes::{self, SceneParams};

use crate::bench::realtime::{RealtimeReport, run_realtime_bench};
use crate::bench::{BenchJob, BenchReport, run_bench};
use crate::compare::{CompareJob, CompareReport, references_for, run_compare};
use crate::renderer::{BackendKind, Renderer};
use crate::{Error, TechniqueRegistry};

/// The view size of the many-lights measurements.
const LIGHTS_SIZE: (u32, u32) = (1024, 768);

/// What to measure.
pub struct ResultsJob {
    /// The command line that produced the run, quoted at the top of the file.
    pub command: String,
    /// View size of the error measurements.
    pub size: (u32, u32),
    /// Backends to measure on.
    pub backends: Vec<BackendKind>,
    /// The scene timed.
    pub bench_scene: String,
    /// View size of the timing.
    pub bench_size: (u32, u32),
    /// Frames timed (after two unmeasured ones).
    pub bench_frames: u32,
    /// View size of the outdoor street's measurements.
    pub outdoor_size: (u32, u32),
    /// The folder the pictures go to, beside the results page.
    pub pictures: std::path::PathBuf,
}

/// The machine: CPU model and thread count, OS and architecture.
#[must_use]
pub fn machine() -> String {
    let cpu = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|info| {
            info.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split(':').nth(1))
                .map(str::trim)
                .map(String::from)
        })
        .unwrap_or_else(|| "an unnamed CPU".into());
    let threads = std::thread::available_parallelism().map_or(1, std::num::NonZeroUsize::get);
    format!("{cpu}, {threads} threads, {} {}", std::env::consts::OS, std::env::consts::ARCH)
}

/// The frame of a built-in scene from its own camera.
fn scene_frame(name: &str) -> Result<FrameInputs, Error> {
    let scene = scenes::build(name, &SceneParams::default()).map_err(|e| Error::Usage(format!("{name}: {e}")))?;
    Ok(FrameInputs::from_first_camera(&scene)?)
}

/// Runs the job and returns the markdown of `docs/results.md`.
///
/// # Errors
/// A scene that cannot be built, or a rendering failure.
pub fn run_results(renderer: &mut Renderer, job: &ResultsJob, mut progress: impl FnMut(&str)) -> Result<String, Error> {
    let mut reports = Vec::new();
    for name in scenes::ALL.iter().map(|s| s.name) {
        let frame = scene_frame(name)?;
        let (techniques, _) = renderer.registry().measurable(&frame);
        let (reference, soft_reference) = references_for(renderer.registry(), &techniques);
        let compare = CompareJob {
            scene: name.to_string(),
            frame: &frame,
            width: job.size.0,
            height: job.size.1,
            techniques,
            reference,
            soft_reference,
            backends: job.backends.clone(),
            out_dir: None,
        };
        reports.push(run_compare(renderer, &compare, |m| progress(&format!("{name}: {m}")))?);
    }
    let frame = scene_frame(&job.bench_scene)?;
    let (techniques, _) = renderer.registry().measurable(&frame);
    let bench = BenchJob {
        scene: job.bench_scene.clone(),
        frame: &frame,
        width: job.bench_size.0,
        height: job.bench_size.1,
        frames: job.bench_frames,
        warmup: 2,
        techniques,
        backends: job.backends.clone(),
        rebuild: false,
        motion: crate::bench::Motion::Lights,
        savings: vec![shadow_core::frame::Savings::ALL],
    };
    let timing = run_bench(renderer, &bench, |m| progress(&format!("{}: {m}", job.bench_scene)))?;
    // The real-time path where there is a GPU adapter: the same frames recorded, two in flight.
    let realtime = if job.backends.contains(&BackendKind::Wgpu) {
        let realtime = BenchJob { backends: vec![BackendKind::Wgpu], ..bench };
        Some(run_realtime_bench(renderer, &realtime, |m| progress(&format!("{} real-time: {m}", job.bench_scene)))?)
    } else {
        None
    };
    let outdoor_job =
        outdoor::OutdoorJob { size: job.outdoor_size, backends: job.backends.clone(), pictures: job.pictures.clone() };
    let outdoor = outdoor::run_outdoor(renderer, &outdoor_job, &mut progress)?;
    let soft_job = soft::SoftJob { backends: job.backends.clone(), pictures: job.pictures.clone() };
    let soft = soft::run_soft(renderer, &soft_job, &mut progress)?;
    let cutout_job =
        cutouts::CutoutJob { size: job.size, backends: job.backends.clone(), pictures: job.pictures.clone() };
    let cutouts = cutouts::run_cutouts(renderer, &cutout_job, &mut progress)?;
    let animated = animated::run_animated(renderer, job.size, &job.backends, &mut progress)?;
    let many = many::run_many(renderer, job.bench_size, &job.backends, &mut progress)?;
    let lights = lights::run_lights(renderer, LIGHTS_SIZE, &job.backends, &mut progress)?;
    let kernels = kernels::run_kernels(&mut progress)?;
    let mut text = markdown(renderer, job, &reports, (&timing, realtime.as_ref()));
    outdoor::markdown(&mut text, &outdoor);
    soft::markdown(&mut text, &soft);
    cutouts::markdown(&mut text, &cutouts);
    animated::markdown(&mut text, &animated);
    many::markdown(&mut text, &many);
    lights::markdown(&mut text, &lights);
    kernels::markdown(&mut text, &kernels);
    Ok(text)
}

fn markdown(
    renderer: &Renderer,
    job: &ResultsJob,
    reports: &[CompareReport],
    (timing, realtime): (&BenchReport, Option<&RealtimeReport>),
) -> String {
    let adapter = renderer.adapter().map_or_else(
        || "none (CPU backend only)".to_string(),
        |a| {
            format!(
                "{} ({}, {}{})",
                a.name,
                a.backend,
                a.kind,
                if a.driver.is_empty() { String::new() } else { format!(", {}", a.driver) }
            )
        },
    );
    let mut s = String::new();
    let _ = writeln!(s, "# Results\n");
    let _ = writeln!(s, "Written by `{}`; that command regenerates this file.\n", job.command);
    let _ = writeln!(s, "- machine: {}", machine());
    let _ = writeln!(s, "- GPU adapter: {adapter}");
    let _ = writeln!(s, "- shadowlab {}\n", env!("CARGO_PKG_VERSION"));
    errors_table(&mut s, renderer.registry(), job, reports);
    cross_table(&mut s, reports);
    timing_table(&mut s, timing);
    if let Some(r) = realtime {
        realtime_table(&mut s, r);
    }
    s
}

/// The real-time path against the instrumented frames of the same run.
fn realtime_table(s: &mut String, r: &RealtimeReport) {
    let _ = writeln!(s, "\n## Real-time path\n");
    let _ = writeln!(
        s,
        "`{}` at {}x{}, {} frames with the light turning, recorded into an encoder of the bench's own with {} \
         in flight, no counters and no read-backs (`shadowlab bench --realtime`). Wall time per frame, its ratio \
         to the instrumented frame's median above, the host's time to record a frame (median), and the GPU's \
         own time per frame where the adapter has timestamp queries (median), in ms.\n",
        r.scene, r.width, r.height, r.frames, r.in_flight
    );
    let _ = writeln!(s, "| technique | real-time | ratio | record (CPU) | GPU |\n|---|---:|---:|---:|---:|");
    for e in &r.results {
        match (&e.refused, e.frame_ms, e.ratio) {
            (None, Some(f), Some(ratio)) => {
                let median = |st: Option<&crate::bench::Stat>| st.map_or("-".into(), |st| format!("{:.2}", st.median));
                let _ = writeln!(
                    s,
                    "| {} | {f:.1} | {ratio:.2} | {} | {} |",
                    e.technique,
                    median(e.record_ms.as_ref()),
                    median(e.gpu_ms.as_ref())
                );
            }
            _ => {
                let why = e.refused.as_deref().unwrap_or("not measured");
                let _ = writeln!(s, "| {} | refused: {why} | | | |", e.technique);
            }
        }
    }
}

/// One row per technique and backend, one column per scene.
fn errors_table(s: &mut String, registry: &TechniqueRegistry, job: &ResultsJob, reports: &[CompareReport]) {
    let _ = writeln!(s, "## Error against the reference\n");
    let _ = writeln!(
        s,
        "{}x{}, each scene's own camera and light, every setting at its default. Hard techniques: the \
         percentage of measured pixels whose lit/shadowed state differs from `ray-traced`'s (measured pixels \
         are receivers the light reaches whose seen side faces it). Soft techniques (marked RMSE): the RMS \
         visibility difference from `area-light-reference`'s. Each backend is measured at its own pixels: \
         the references are traced on the CPU over the G-buffer that backend rendered. A dash: the scene's \
         light is of a kind the technique or its reference does not take.\n",
        job.size.0, job.size.1
    );
    let mut rows: BTreeMap<(usize, String, String), BTreeMap<&str, String>> = BTreeMap::new();
    let order = |technique: &str| reports.iter().flat_map(|r| &r.results).position(|e| e.technique == technique);
    for r in reports {
        for e in &r.results {
            let soft = registry.get(&e.technique).is_ok_and(|t| t.soft);
            let value =
                if soft { format!("{:.4}", e.metrics.rmse) } else { format!("{:.3}", 100.0 * e.metrics.mismatch) };
            let name = if soft { format!("{} (RMSE)", e.technique) } else { e.technique.clone() };
            let key = (order(&e.technique).unwrap_or(usize::MAX), name, e.backend.clone());
            rows.entry(key).or_default().insert(r.scene.as_str(), value);
        }
    }
    let _ = write!(s, "| technique | backend |");
    for r in reports {
        let _ = write!(s, " {} |", r.scene);
    }
    let _ = write!(s, "\n|---|---|");
    for _ in reports {
        let _ = write!(s, "---:|");
    }
    s.push('\n');
    for ((_, name, backend), cells) in &rows {
        let _ = write!(s, "| {name} | {backend} |");
        for r in reports {
            let _ = write!(s, " {} |", cells.get(r.scene.as_str()).map_or("-", String::as_str));
        }
        s.push('\n');
    }
    s.push('\n');
}

/// The largest cross-backend mismatch of each technique, with the scene it is on.
fn cross_table(s: &mut String, reports: &[CompareReport]) {
    let mut worst: Vec<(String, f64, String)> = Vec::new();
    for r in reports {
        for c in &r.cross_backend {
            match worst.iter_mut().find(|(t, _, _)| *t == c.technique) {
                Some(w) if c.mismatch > w.1 => *w = (c.technique.clone(), c.mismatch, r.scene.clone()),
                Some(_) => {}
                None => worst.push((c.technique.clone(), c.mismatch, r.scene.clone())),
            }
        }
    }
    if worst.is_empty() {
        return;
    }
    let _ = writeln!(s, "## CPU against GPU\n");
    let _ = writeln!(s, "The largest share of measured pixels where the two backends disagree, over every scene.\n");
    let _ = writeln!(s, "| technique | largest mismatch | on |\n|---|---:|---|");
    for (t, m, scene) in worst {
        let _ = writeln!(s, "| {t} | {:.3}% | {scene} |", 100.0 * m);
    }
    s.push('\n');
}

/// Medians per phase, in milliseconds.
fn timing_table(s: &mut String, r: &BenchReport) {
    let _ = writeln!(s, "## Frame time\n");
    let _ = writeln!(
        s,
        "`{}` at {}x{}, {} frames with the light turning, medians in ms (`shadowlab bench` gives the ranges). \
         `gpu` rows, where the adapter has timestamp queries, are the GPU's own time per phase, the counters' \
         passes taken out.\n",
        r.scene, r.width, r.height, r.frames
    );
    let _ = writeln!(
        s,
        "| technique | backend | G-buffer | build | query | shade | total |\n|---|---|---:|---:|---:|---:|---:|"
    );
    for e in &r.results {
        let cell = |k: &str| e.timings_ms.get(k).map_or("-".to_string(), |t| format!("{:.1}", t.median));
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} | {} | {} |",
            e.technique,
            e.backend,
            cell("gbuffer"),
            cell("build"),
            cell("query"),
            cell("shade"),
            cell("total")
        );
        if e.timings_ms.contains_key("gpu_query") {
            let _ = writeln!(
                s,
                "| | gpu | {} | {} | {} | {} | |",
                cell("gpu_gbuffer"),
                cell("gpu_build"),
                cell("gpu_query"),
                cell("gpu_shade")
            );
        }
    }
}
