//! `bench --realtime`: the real-time path measured as an application runs it. Each technique's frames
//! are recorded into an encoder of the bench's own (the host, here), shaded into a Bgra8UnormSrgb target
//! as a window's surface would be, and submitted with at most [`IN_FLIGHT`] frames queued; nothing inside
//! a frame waits or reads back. The bench, as the host, waits only for the frame [`IN_FLIGHT`] behind,
//! and reads its own timestamps after the run.
//!
//! Beside each technique's real-time frames, its instrumented frames (`bench`'s: a wait after each phase,
//! counters, read-backs) run in the same process, so their ratio holds on a machine whose speed drifts.

use std::collections::VecDeque;
use std::time::Instant;

use serde::Serialize;
use shadow_core::frame::Savings;
use shadow_core::stats::{Summary, ms};
use shadow_wgpu::{ColorTarget, FrameRecorder, WgpuContext, WgpuError};

use super::{BenchJob, Stat};
use crate::Error;
use crate::renderer::{BackendKind, Renderer};

/// Frames submitted and not yet finished, at most: what a swap chain of three images allows.
pub const IN_FLIGHT: usize = 2;

/// One technique's real-time frames and its instrumented ones.
#[derive(Clone, Debug, Serialize)]
pub struct RealtimeEntry {
    /// Technique name.
    pub technique: String,
    /// Canonical settings.
    pub settings: String,
    /// What the frames saved ([`super::savings_name`]).
    pub savings: String,
    /// Wall time per frame with frames in flight: the measured frames' time over their count, in ms.
    pub frame_ms: Option<f64>,
    /// The host's time to record one frame (CPU), its submission left out, in ms.
    pub record_ms: Option<Stat>,
    /// The GPU's time for one frame, from timestamps around it, in ms (adapters with timestamps).
    pub gpu_ms: Option<Stat>,
    /// The instrumented frame's total, in ms.
    pub instrumented_ms: Stat,
    /// `frame_ms` over the instrumented frame's median.
    pub ratio: Option<f64>,
    /// Why the real-time path could not run it.
    pub refused: Option<String>,
}

/// The whole `bench --realtime --json` output.
#[derive(Clone, Debug, Serialize)]
pub struct RealtimeReport {
    /// Scene name.
    pub scene: String,
    /// View width.
    pub width: u32,
    /// View height.
    pub height: u32,
    /// Measured frames.
    pub frames: u32,
    /// The adapter.
    pub adapter: String,
    /// Frames in flight.
    pub in_flight: usize,
    /// With a clip played (`--animate`), the host's time to pose the scene and gather a frame's inputs,
    /// per frame, in ms: what an application spends on the pose before it records the frame.
    pub pose_ms: Option<Stat>,
    /// One entry per technique.
    pub results: Vec<RealtimeEntry>,
}

/// How many times [`run_realtime_bench`] reports progress: twice per technique.
#[must_use]
pub fn realtime_steps(job: &BenchJob<'_>) -> u64 {
    2 * job.variants().len() as u64
}

/// Runs the job on the wgpu backend (whatever backends it names), technique by technique: its
/// instrumented frames, then its real-time ones.
///
/// # Errors
/// No adapter, or a failure of an instrumented frame or of the GPU.
pub fn run_realtime_bench(
    renderer: &mut Renderer,
    job: &BenchJob<'_>,
    mut progress: impl FnMut(&str),
) -> Result<RealtimeReport, Error> {
    let mut results = Vec::new();
    for (_, spec, savings) in job.variants() {
        progress(&format!("{spec}: instrumented frames"));
        let mut prepared = renderer.prepare(BackendKind::Wgpu, spec)?;
        let total = job.warmup + job.frames;
        let mut totals = Vec::new();
        for k in 0..total {
            let run = renderer.run_prepared(&mut prepared, &job.frame_at(k, total, savings), job.width, job.height)?;
            if k >= job.warmup {
                totals.push(run.stats.timings.total);
            }
        }
        let instrumented = stat(&totals);
        progress(&format!("{spec}: real-time frames"));
        let mut technique = renderer.registry().wgpu(spec)?;
        let mut named = Vec::new();
        let registry = renderer.registry();
        crate::renderer::name_techniques(job.frame, &mut named, |s| Ok(registry.wgpu(s)?))?;
        let cx = renderer.wgpu_context()?;
        let entry = match realtime_frames(cx, (job, savings), technique.as_mut(), &mut named) {
            Ok(times) => {
                let frame_ms = times.wall_ms / f64::from(job.frames.max(1));
                RealtimeEntry {
                    technique: prepared.name().into(),
                    settings: prepared.settings().into(),
                    savings: super::savings_name(savings).into(),
                    frame_ms: Some(frame_ms),
                    record_ms: Some(stat(&times.record_ms)),
                    gpu_ms: (!times.gpu_ms.is_empty()).then(|| stat(&times.gpu_ms)),
                    instrumented_ms: instrumented,
                    ratio: Some(frame_ms / instrumented.median),
                    refused: None,
                }
            }
            Err(e @ (WgpuError::NotRecordable { .. } | WgpuError::Technique(_))) => RealtimeEntry {
                technique: prepared.name().into(),
                settings: prepared.settings().into(),
                savings: super::savings_name(savings).into(),
                frame_ms: None,
                record_ms: None,
                gpu_ms: None,
                instrumented_ms: instrumented,
                ratio: None,
                refused: Some(e.to_string()),
            },
            Err(e) => return Err(e.into()),
        };
        results.push(entry);
    }
    let adapter = renderer.adapter().map_or_else(String::new, |a| format!("{} ({})", a.name, a.backend));
    Ok(RealtimeReport {
        scene: job.scene.clone(),
        width: job.width,
        height: job.height,
        frames: job.frames,
        adapter,
        in_flight: IN_FLIGHT,
        pose_ms: match job.motion {
            crate::bench::Motion::Clip(c) => Some(stat(c.pose_ms())),
            _ => None,
        },
        results,
    })
}

fn stat(samples: &[f64]) -> Stat {
    let s = Summary::of(samples);
    Stat { median: s.median, min: s.min, max: s.max }
}

/// What one technique's real-time run measured.
struct Times {
    wall_ms: f64,
    record_ms: Vec<f64>,
    gpu_ms: Vec<f64>,
}

/// The job's frames of one technique (and of those its lights name, `named`) with `savings` through the
/// real-time path: warm-up frames each waited for, then the measured frames with at most [`IN_FLIGHT`] in flight.
fn realtime_frames(
    cx: &mut WgpuContext,
    (job, savings): (&BenchJob<'_>, Savings),
    technique: &mut dyn shadow_core::technique::DynShadowTechnique<shadow_wgpu::WgpuBackend>,
    named: &mut crate::renderer::Named<shadow_wgpu::WgpuBackend>,
) -> Result<Times, WgpuError> {
    let target = surface_like(cx, job.width, job.height);
    let view = target.create_view(&Default::default());
    let color = ColorTarget { view: &view, format: target.format(), width: job.width, height: job.height };
    let mut recorder = FrameRecorder::new();
    let clock = cx.timestamps.then(|| FrameClock::new(cx, job.frames));
    let total = job.warmup + job.frames;
    let mut in_flight = VecDeque::new();
    let mut times = Times { wall_ms: 0.0, record_ms: Vec::new(), gpu_ms: Vec::new() };
    let mut start = Instant::now();
    for k in 0..total {
        let frame = job.frame_at(k, total, savings);
        let measured = k.checked_sub(job.warmup);
        if measured == Some(0) {
            cx.wait()?;
            in_flight.clear();
            start = Instant::now();
        }
        let t = Instant::now();
        let mut encoder = cx.encoder("frame");
        let marks = clock.as_ref().zip(measured);
        if let Some((c, m)) = marks {
            c.mark(&mut encoder, 2 * m);
        }
        let techniques = shadow_core::script::LightTechniques { frame: &mut *technique, named: &mut *named };
        recorder.record(cx, &mut encoder, &frame, techniques, &color)?;
        if let Some((c, m)) = marks {
            c.mark(&mut encoder, 2 * m + 1);
        }
        let commands = encoder.finish();
        if measured.is_some() {
            times.record_ms.push(ms(t.elapsed()));
        }
        let index = cx.queue.submit([commands]);
        in_flight.push_back(index);
        while in_flight.len() > IN_FLIGHT {
            if let Some(oldest) = in_flight.pop_front() {
                cx.device
                    .poll(wgpu::PollType::Wait { submission_index: Some(oldest), timeout: None })
                    .map_err(|e| WgpuError::Gpu { during: "waiting for a frame".into(), message: e.to_string() })?;
            }
        }
    }
    cx.wait()?;
    times.wall_ms = ms(start.elapsed());
    if let Some(c) = clock {
        times.gpu_ms = c.read(cx)?;
    }
    Ok(times)
}

/// A Bgra8UnormSrgb target of the view's size, as a window's surface usually is.
fn surface_like(cx: &WgpuContext, width: u32, height: u32) -> wgpu::Texture {
    cx.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("surface-like target"),
        size: wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::Bgra8UnormSrgb,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
        view_formats: &[],
    })
}

/// Timestamps at the start and end of every measured frame, written into the frame's own encoder and
/// read once the run is over.
struct FrameClock {
    set: wgpu::QuerySet,
    count: u32,
}

impl FrameClock {
    fn new(cx: &WgpuContext, frames: u32) -> Self {
        let count = 2 * frames.max(1);
        let set = cx.device.create_query_set(&wgpu::QuerySetDescriptor {
            label: Some("frame clock"),
            ty: wgpu::QueryType::Timestamp,
            count,
        });
        Self { set, count }
    }

    /// Writes timestamp `index` where `encoder` stands.
    fn mark(&self, encoder: &mut wgpu::CommandEncoder, index: u32) {
        shadow_wgpu::clock::write_mark(encoder, &self.set, index);
    }

    /// Each frame's GPU time in ms.
    fn read(&self, cx: &WgpuContext) -> Result<Vec<f64>, WgpuError> {
        let ticks = shadow_wgpu::clock::read_ticks(cx, &self.set, self.count)?;
        let period = f64::from(cx.queue.get_timestamp_period());
        Ok(ticks.chunks_exact(2).map(|p| p[1].saturating_sub(p[0]) as f64 * period / 1e6).collect())
    }
}

/// The real-time bench as a table.
#[must_use]
pub fn realtime_table(r: &RealtimeReport) -> String {
    let mut s = format!(
        "{} at {}x{} on {}, {} frames, {} in flight (ms; median, min..max in brackets)\n",
        r.scene, r.width, r.height, r.adapter, r.frames, r.in_flight
    );
    if let Some(p) = &r.pose_ms {
        s.push_str(&format!(
            "clip played: posing a frame on the host (CPU) {:.3} ms [{:.3}..{:.3}]; recording it below\n",
            p.median, p.min, p.max
        ));
    }
    s.push_str(&format!(
        "{:<24} {:>20} {:>10} {:>8} {:>20} {:>20}\n",
        "technique", "instrumented", "real-time", "ratio", "record (CPU)", "GPU"
    ));
    let cell = |st: &Stat| format!("{:.2} [{:.2}..{:.2}]", st.median, st.min, st.max);
    // A technique run with more than one set of settings is told apart by them.
    let label = |e: &RealtimeEntry| {
        let twice = r.results.iter().filter(|o| o.technique == e.technique && o.savings == e.savings).count() > 1;
        let name = if twice { format!("{}:{}", e.technique, e.settings) } else { e.technique.clone() };
        super::label(&name, &e.savings)
    };
    for e in &r.results {
        let inst = cell(&e.instrumented_ms);
        match (&e.refused, e.frame_ms, e.ratio, &e.record_ms) {
            (None, Some(f), Some(ratio), Some(rec)) => s.push_str(&format!(
                "{:<24} {inst:>20} {f:>10.2} {ratio:>8.2} {:>20} {:>20}\n",
                label(e),
                cell(rec),
                e.gpu_ms.as_ref().map_or_else(|| "-".into(), cell)
            )),
            _ => s.push_str(&format!("{:<24} {inst:>20} refused: {}\n", label(e), e.refused.as_deref().unwrap_or("?"))),
        }
    }
    s
}
