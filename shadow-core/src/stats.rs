//! Counters and per-phase timings (DESIGN 8).
//!
//! A counter a technique does not measure stays `None` and is left out of reports, never written as 0.

use std::collections::BTreeMap;
use std::time::{Duration, Instant};

/// The counters every backend reports under the same names.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Counters {
    /// G-buffer pixels that show a receiver.
    pub covered_pixels: Option<u64>,
    /// Silhouette edges found for the light (after welding).
    pub silhouette_edges: Option<u64>,
    /// Shadow-volume triangles sent to the rasterizer (sides, with their weight, and caps).
    pub volume_triangles: Option<u64>,
    /// Every rasterized shadow-volume fragment, before any test (Sen's overdraw O = this / covered_pixels).
    pub volume_fragments: Option<u64>,
    /// Pixels a technique classified as near a silhouette (Sen's P, Chan's silhouette fraction).
    pub silhouette_pixels: Option<u64>,
    /// Stencil writes that changed nothing but were performed all the same (every stencil op applied).
    pub stencil_updates: Option<u64>,
    /// Technique-specific counters, by name.
    pub extra: BTreeMap<String, f64>,
}

impl Counters {
    /// Adds `n` to a counter, starting it at 0 if it was unmeasured.
    pub fn add(slot: &mut Option<u64>, n: u64) {
        *slot = Some(slot.unwrap_or(0) + n);
    }

    /// Every measured counter as (name, value), fixed ones first, in a stable order.
    #[must_use]
    pub fn entries(&self) -> Vec<(String, f64)> {
        let fixed = [
            ("covered_pixels", self.covered_pixels),
            ("silhouette_edges", self.silhouette_edges),
            ("volume_triangles", self.volume_triangles),
            ("volume_fragments", self.volume_fragments),
            ("silhouette_pixels", self.silhouette_pixels),
            ("stencil_updates", self.stencil_updates),
        ];
        let mut out: Vec<(String, f64)> =
            fixed.iter().filter_map(|(k, v)| v.map(|v| ((*k).to_string(), v as f64))).collect();
        out.extend(self.extra.iter().map(|(k, v)| (k.clone(), *v)));
        out
    }

    /// Folds `other` into `self`: measured counters add; extras add.
    pub fn merge(&mut self, other: &Counters) {
        for (dst, src) in [
            (&mut self.covered_pixels, other.covered_pixels),
            (&mut self.silhouette_edges, other.silhouette_edges),
            (&mut self.volume_triangles, other.volume_triangles),
            (&mut self.volume_fragments, other.volume_fragments),
            (&mut self.silhouette_pixels, other.silhouette_pixels),
            (&mut self.stencil_updates, other.stencil_updates),
        ] {
            if let Some(v) = src {
                Self::add(dst, v);
            }
        }
        for (k, v) in &other.extra {
            *self.extra.entry(k.clone()).or_insert(0.0) += v;
        }
    }
}

/// The phases of one frame (DESIGN 5).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Phase {
    /// Camera G-buffer pass.
    GBuffer,
    /// Technique build: maps, volumes, smoothies.
    Build,
    /// Technique query: visibility at every G-buffer pixel.
    Query,
    /// Shading and composition.
    Shade,
}

impl Phase {
    /// Every phase, in frame order.
    pub const ALL: [Phase; 4] = [Phase::GBuffer, Phase::Build, Phase::Query, Phase::Shade];

    /// The report key.
    #[must_use]
    pub fn key(self) -> &'static str {
        match self {
            Phase::GBuffer => "gbuffer",
            Phase::Build => "build",
            Phase::Query => "query",
            Phase::Shade => "shade",
        }
    }
}

/// Milliseconds per phase, plus named sub-phases (a readback, say) and the total.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Timings {
    /// Milliseconds per [`Phase`].
    pub phases: BTreeMap<Phase, f64>,
    /// Technique-specific sub-phases in milliseconds (already included in a phase).
    pub extra: BTreeMap<String, f64>,
    /// Wall-clock milliseconds of the whole frame.
    pub total: f64,
}

impl Timings {
    /// Adds `ms` to a phase.
    pub fn add(&mut self, phase: Phase, ms: f64) {
        *self.phases.entry(phase).or_insert(0.0) += ms;
    }

    /// Milliseconds of a phase (0 when it did not run).
    #[must_use]
    pub fn get(&self, phase: Phase) -> f64 {
        self.phases.get(&phase).copied().unwrap_or(0.0)
    }
}

/// Milliseconds in a duration.
#[must_use]
pub fn ms(d: Duration) -> f64 {
    d.as_secs_f64() * 1e3
}

/// Runs `f` and returns its result with the milliseconds it took.
pub fn timed<R>(f: impl FnOnce() -> R) -> (R, f64) {
    let t = Instant::now();
    let r = f();
    (r, ms(t.elapsed()))
}

/// How long [`wake_every_thread`] keeps the threads busy.
pub const WAKE: Duration = Duration::from_millis(100);

/// Keeps every thread of rayon's pool busy for [`WAKE`], so a timing on all threads that follows measures
/// the threads and not the waking of a core. Between such timings the other threads idle (while one
/// thread works alone, say), and on a virtual machine a core that has idled for tens of milliseconds can
/// run its first tens of milliseconds of work slow: on the 2-core machine this was measured on, the
/// second thread of a trace that followed one-thread work was busy 40% longer than the rays it traced
/// took on one thread, and not at all longer when both had been busy just before.
pub fn wake_every_thread() {
    let start = Instant::now();
    rayon::broadcast(|_| {
        while start.elapsed() < WAKE {
            std::hint::spin_loop();
        }
    });
}

/// Median, minimum and maximum of a series of samples.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Summary {
    /// Median (mean of the middle two for an even count).
    pub median: f64,
    /// Smallest sample.
    pub min: f64,
    /// Largest sample.
    pub max: f64,
}

impl Summary {
    /// Summary of the samples, or all zeros for none.
    #[must_use]
    pub fn of(samples: &[f64]) -> Self {
        if samples.is_empty() {
            return Self::default();
        }
        let mut s = samples.to_vec();
        s.sort_by(f64::total_cmp);
        let n = s.len();
        let median = if n % 2 == 1 { s[n / 2] } else { 0.5 * (s[n / 2 - 1] + s[n / 2]) };
        Self { median, min: s[0], max: s[n - 1] }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unmeasured_counters_are_left_out() {
        let mut c = Counters { covered_pixels: Some(5), ..Default::default() };
        assert_eq!(c.entries(), vec![("covered_pixels".to_string(), 5.0)]);
        c.merge(&Counters { stencil_updates: Some(3), covered_pixels: Some(1), ..Default::default() });
        assert_eq!(c.covered_pixels, Some(6));
        assert_eq!(c.stencil_updates, Some(3));
        assert_eq!(c.volume_fragments, None);
    }

    #[test]
    fn summary_median() {
        let s = Summary::of(&[3.0, 1.0, 2.0, 10.0]);
        assert_eq!((s.median, s.min, s.max), (2.5, 1.0, 10.0));
    }
}
