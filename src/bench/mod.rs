//! `bench`: frames with the light moving every frame (nothing light-dependent can be cached), a warm-up,
//! then per phase the median, minimum and maximum over the measured frames, with the counters of the
//! last frame (DESIGN 11). `--sweep` repeats it over a parameter; `--animate` plays the scene's clip
//! through the frames instead of moving the light ([`Clip`]).
//!
//! On each backend in turn, the techniques take turns frame by frame (frame 1 of every technique, then
//! frame 2, ...), so a machine that slows down or speeds up during a run moves them all alike and their
//! ratios hold: on the development machine, timings drift 20-40% over minutes, more than most differences
//! measured. The backends do not take turns: between CPU frames, which share the machine's cores with it,
//! lavapipe ran `smoothies` 1.52 times its shadow map's frame on cylinder, against 1.28 to 1.32 on its own.

pub mod realtime;

use std::collections::BTreeMap;
use std::sync::Arc;

use glam::{Mat3, Vec3};
use rayon::prelude::*;
use serde::Serialize;
use shadow_core::frame::{FrameError, Savings};
use shadow_core::geometry::adjacency::Adjacency;
use shadow_core::scene::{Light, LightKind};
use shadow_core::stats::{Phase, Summary};
use shadow_core::technique::{FrameStats, TechniqueSpec};
use shadow_core::{FrameInputs, Scene};

use crate::Error;
use crate::renderer::{BackendKind, Prepared, Renderer};

/// What to measure.
pub struct BenchJob<'a> {
    /// Scene name for the report.
    pub scene: String,
    /// The frame (its lights are moved frame by frame).
    pub frame: &'a FrameInputs,
    /// View size.
    pub width: u32,
    /// View size.
    pub height: u32,
    /// Measured frames.
    pub frames: u32,
    /// Frames run first and not measured (pipeline compilation, first allocations).
    pub warmup: u32,
    /// Techniques.
    pub techniques: Vec<TechniqueSpec>,
    /// Backends.
    pub backends: Vec<BackendKind>,
    /// Rebuild every frame what a still scene keeps from frame to frame (the meshes' adjacency, the CPU's
    /// ray-casting BVH), so its cost is measured: the adjacency as its own `adjacency` time, the BVH in
    /// the build phase of the techniques that cast rays.
    pub rebuild: bool,
    /// What changes from frame to frame.
    pub motion: Motion<'a>,
    /// What the frames save ([`Savings`]): each technique is measured under each, side by side.
    pub savings: Vec<Savings>,
}

/// What changes from frame to frame in a bench.
#[derive(Clone, Copy, Debug, Default)]
pub enum Motion<'a> {
    /// The lights turn about the scene's centre, a quarter turn over the run: no light's build can be kept.
    #[default]
    Lights,
    /// The lights stand still and the camera turns about the point it looks at, an eighth of a turn over
    /// the run: the builds of still lights may be kept (`--move camera`).
    Camera,
    /// The scene's clip plays through the frames (`--animate`): its poses, under its own lights.
    Clip(&'a Clip),
}

impl Motion<'_> {
    /// Its name in reports: "lights", "camera" or "clip".
    #[must_use]
    pub fn name(&self) -> &'static str {
        match self {
            Self::Lights => "lights",
            Self::Camera => "camera",
            Self::Clip(_) => "clip",
        }
    }
}

/// The name of `savings` in reports: "all" or "none".
#[must_use]
pub fn savings_name(savings: Savings) -> &'static str {
    if savings == Savings::NONE { "none" } else { "all" }
}

/// A technique's label in a table: with ", no savings" where it ran with none.
fn label(technique: &str, savings: &str) -> String {
    if savings == "none" { format!("{technique}, no savings") } else { technique.to_string() }
}

/// A scene's animations played through a bench's frames (`bench --animate`): frame `k` is the scene
/// posed `k` steps after the start, seen from its first camera under its own lights (which follow their
/// nodes). Every frame is posed before the bench runs, and the host's time to pose each (the scene's
/// nodes, skins and morph weights, then the frame's inputs gathered, the CPU's posed meshes and their
/// adjacency included) is kept apart from the frames' own times.
#[derive(Clone, Debug)]
pub struct Clip {
    frames: Vec<FrameInputs>,
    pose_ms: Vec<f64>,
}

impl Clip {
    /// `count` frames of `scene`'s animations, from `start` seconds, `step` seconds apart.
    ///
    /// # Errors
    /// A scene without animations, or a pose or frame that fails (naming its time).
    pub fn play(scene: &mut Scene, start: f32, step: f32, count: u32) -> Result<Self, Error> {
        if scene.animations().next().is_none() {
            return Err(Error::Usage("--animate: the scene has no animations to play".into()));
        }
        let mut clip = Self { frames: Vec::with_capacity(count as usize), pose_ms: Vec::new() };
        for k in 0..count {
            let t = start + step * k as f32;
            let at = std::time::Instant::now();
            let posed = scene.pose(t).map_err(FrameError::from).and_then(|()| FrameInputs::from_first_camera(scene));
            let frame = posed.map_err(|e| Error::Usage(format!("--animate: the pose at {t} s: {e}")))?;
            clip.pose_ms.push(shadow_core::stats::ms(at.elapsed()));
            clip.frames.push(frame);
        }
        Ok(clip)
    }

    /// The host's time to pose each frame, in ms.
    #[must_use]
    pub fn pose_ms(&self) -> &[f64] {
        &self.pose_ms
    }
}

/// Median, minimum and maximum, in milliseconds.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct Stat {
    /// Median.
    pub median: f64,
    /// Minimum.
    pub min: f64,
    /// Maximum.
    pub max: f64,
}

/// One technique on one backend.
#[derive(Clone, Debug, Serialize)]
pub struct BenchEntry {
    /// Technique name.
    pub technique: String,
    /// Canonical settings.
    pub settings: String,
    /// Backend name.
    pub backend: String,
    /// What the frames saved ([`savings_name`]).
    pub savings: String,
    /// Per phase (and total), over the measured frames.
    pub timings_ms: BTreeMap<String, Stat>,
    /// Counters of the last frame.
    pub counters: BTreeMap<String, f64>,
}

/// The whole `bench --json` output.
#[derive(Clone, Debug, Serialize)]
pub struct BenchReport {
    /// Scene name.
    pub scene: String,
    /// View width.
    pub width: u32,
    /// View height.
    pub height: u32,
    /// Measured frames.
    pub frames: u32,
    /// One entry per technique and backend.
    pub results: Vec<BenchEntry>,
}

/// The light of frame `k`: turned about the vertical axis through `center`, a quarter turn over a run of
/// `n` frames (position and direction for spot and point lights, direction for directional ones).
#[must_use]
pub fn moved_light(light: &Light, center: Vec3, k: u32, n: u32) -> Light {
    let angle = std::f32::consts::FRAC_PI_2 * k as f32 / n.max(1) as f32;
    let r = Mat3::from_rotation_y(angle);
    let kind = match light.kind {
        LightKind::Spot { position, direction, cone_angle } => {
            LightKind::Spot { position: center + r * (position - center), direction: r * direction, cone_angle }
        }
        LightKind::Point { position } => LightKind::Point { position: center + r * (position - center) },
        LightKind::Directional { direction } => LightKind::Directional { direction: r * direction },
    };
    Light { kind, ..*light }
}

impl BenchJob<'_> {
    /// The frame of run frame `k` of `total` with `savings`, as the job's [`Motion`] moves it.
    #[must_use]
    pub fn frame_at(&self, k: u32, total: u32, savings: Savings) -> FrameInputs {
        let mut frame = match self.motion {
            Motion::Clip(c) => c.frames.get(k as usize).or(c.frames.last()).unwrap_or(self.frame).clone(),
            Motion::Lights => {
                let center = self.frame.bounds.center();
                let lights = self.frame.lights.iter().map(|l| moved_light(l, center, k, total)).collect();
                FrameInputs { lights, ..self.frame.clone() }
            }
            Motion::Camera => {
                let mut frame = self.frame.clone();
                let turn = Mat3::from_rotation_y(std::f32::consts::FRAC_PI_4 * k as f32 / total.max(1) as f32);
                let c = &mut frame.camera;
                c.eye = c.target + turn * (c.eye - c.target);
                frame
            }
        };
        frame.savings = savings;
        frame
    }

    /// Each technique under each of the job's savings, in the order they are measured and reported: its
    /// place among the techniques, its spec and the savings.
    #[must_use]
    pub fn variants(&self) -> Vec<(usize, &TechniqueSpec, Savings)> {
        let savings = if self.savings.is_empty() { vec![Savings::ALL] } else { self.savings.clone() };
        self.techniques.iter().enumerate().flat_map(|(k, spec)| savings.iter().map(move |&s| (k, spec, s))).collect()
    }

    /// How many times [`run_bench`] reports progress: per backend, once per technique as it is prepared,
    /// then once per frame round (warm-up included).
    #[must_use]
    pub fn steps(&self) -> u64 {
        self.backends.len() as u64 * (self.variants().len() as u64 + u64::from(self.warmup + self.frames))
    }
}

/// One technique on one backend while a bench runs: what it has measured so far.
struct Lane {
    /// Its place in the job's techniques.
    technique: usize,
    prepared: Prepared,
    backend: BackendKind,
    savings: Savings,
    samples: BTreeMap<String, Vec<f64>>,
    counters: BTreeMap<String, f64>,
}

/// Runs the job: backend by backend, the techniques taking turns frame by frame.
///
/// # Errors
/// Rendering failures.
pub fn run_bench(
    renderer: &mut Renderer,
    job: &BenchJob<'_>,
    mut progress: impl FnMut(&str),
) -> Result<BenchReport, Error> {
    let total = job.warmup + job.frames;
    let mut lanes = Vec::new();
    for &backend in &job.backends {
        let first = lanes.len();
        for (technique, spec, savings) in job.variants() {
            progress(&format!("{spec} on {}", backend.name()));
            let prepared = renderer.prepare(backend, spec)?;
            let (samples, counters) = (BTreeMap::new(), BTreeMap::new());
            lanes.push(Lane { technique, prepared, backend, savings, samples, counters });
        }
        for k in 0..total {
            let warm = if k < job.warmup { " (warm-up)" } else { "" };
            progress(&format!("{}: frame {} of {total}{warm}", backend.name(), k + 1));
            let mut frame = job.frame_at(k, total, Savings::ALL);
            let adjacency = job.rebuild.then(|| rebuild_adjacency(&mut frame));
            for lane in &mut lanes[first..] {
                if job.rebuild {
                    renderer.forget_caches();
                }
                frame.savings = lane.savings;
                let run = renderer.run_prepared(&mut lane.prepared, &frame, job.width, job.height)?;
                if k >= job.warmup {
                    lane.record(&run.stats);
                    if let Some(ms) = adjacency {
                        lane.samples.entry("adjacency".into()).or_default().push(ms);
                    }
                }
            }
        }
    }
    // Technique by technique, each one's backends in order, as the table lists them (a stable sort).
    lanes.sort_by_key(|lane| lane.technique);
    let results = lanes.into_iter().map(Lane::into_entry).collect();
    Ok(BenchReport { scene: job.scene.clone(), width: job.width, height: job.height, frames: job.frames, results })
}

/// Builds the adjacency of every mesh of `frame` afresh (each mesh once, however many instances draw
/// it, small meshes in batches on every thread, as [`Scene::build_adjacencies`] builds them) and hands
/// each instance its mesh's, dropping the old ones, as a scene does when its meshes change; returns the
/// milliseconds that took. Finding the frame's distinct meshes is not timed: a scene holds them in a
/// table of its own.
fn rebuild_adjacency(frame: &mut FrameInputs) -> f64 {
    let mut by_mesh: Vec<(usize, usize)> =
        frame.instances.iter().enumerate().map(|(i, inst)| (Arc::as_ptr(&inst.mesh) as usize, i)).collect();
    by_mesh.par_sort_unstable();
    let users: Vec<&[(usize, usize)]> = by_mesh.chunk_by(|a, b| a.0 == b.0).collect();
    let meshes: Vec<&shadow_core::Mesh> = users.iter().map(|u| frame.instances[u[0].1].mesh.as_ref()).collect();
    let mut mesh_of = vec![0; frame.instances.len()];
    for (k, users) in users.iter().enumerate() {
        for &(_, i) in *users {
            mesh_of[i] = k;
        }
    }
    let start = std::time::Instant::now();
    let built: Vec<Arc<Adjacency>> = Adjacency::build_all(&meshes).into_par_iter().map(Arc::new).collect();
    frame.instances.par_iter_mut().zip(&mesh_of).for_each(|(inst, &k)| inst.adjacency = Arc::clone(&built[k]));
    start.elapsed().as_secs_f64() * 1e3
}

impl Lane {
    /// One measured frame's timings and counters.
    fn record(&mut self, stats: &FrameStats) {
        let mut sample = |key: &str, v: f64| self.samples.entry(key.into()).or_default().push(v);
        for phase in Phase::ALL {
            sample(phase.key(), stats.timings.get(phase));
        }
        sample("total", stats.timings.total);
        for (key, v) in &stats.timings.extra {
            sample(key, *v);
        }
        self.counters = stats.counters.entries().into_iter().collect();
    }

    fn into_entry(self) -> BenchEntry {
        let timings_ms = self
            .samples
            .into_iter()
            .map(|(k, v)| {
                let s = Summary::of(&v);
                (k, Stat { median: s.median, min: s.min, max: s.max })
            })
            .collect();
        BenchEntry {
            technique: self.prepared.name().into(),
            settings: self.prepared.settings().into(),
            backend: self.backend.name().into(),
            savings: savings_name(self.savings).into(),
            timings_ms,
            counters: self.counters,
        }
    }
}

/// The bench table as text.
#[must_use]
pub fn bench_table(r: &BenchReport) -> String {
    let mut s =
        format!("{} at {}x{}, {} frames (median ms, min..max in brackets)\n", r.scene, r.width, r.height, r.frames);
    s.push_str(&format!(
        "{:<22} {:<5} {:>16} {:>16} {:>16} {:>16} {:>18}\n",
        "technique", "", "gbuffer", "build", "query", "shade", "total"
    ));
    let mut counters_apart = false;
    for e in &r.results {
        let cell = |k: &str| {
            e.timings_ms.get(k).map_or("-".to_string(), |t| format!("{:.1} [{:.1}..{:.1}]", t.median, t.min, t.max))
        };
        let row = |technique: &str, backend: &str, prefix: &str, total: String| {
            format!(
                "{technique:<22} {backend:<5} {:>16} {:>16} {:>16} {:>16} {total:>18}\n",
                cell(&format!("{prefix}gbuffer")),
                cell(&format!("{prefix}build")),
                cell(&format!("{prefix}query")),
                cell(&format!("{prefix}shade")),
            )
        };
        s.push_str(&row(&label(&e.technique, &e.savings), &e.backend, "", cell("total")));
        // Where the adapter has timestamp queries: the GPU's own time per phase, counters taken out.
        if e.timings_ms.contains_key("gpu_query") {
            let gpu: f64 = ["gbuffer", "build", "query", "shade"]
                .iter()
                .filter_map(|p| e.timings_ms.get(&format!("gpu_{p}")))
                .map(|t| t.median)
                .sum();
            s.push_str(&row("", "gpu", "gpu_", format!("{gpu:.1}")));
            counters_apart |= e.timings_ms.contains_key("gpu_counters");
        }
    }
    if let Some(t) = r.results.iter().find_map(|e| e.timings_ms.get("adjacency")) {
        s.push_str(&format!(
            "adjacency rebuilt every frame (not in the rows): {:.1} [{:.1}..{:.1}]\n",
            t.median, t.min, t.max
        ));
    }
    if counters_apart {
        s.push_str(
            "gpu rows: timestamp queries, medians per phase; the counter passes are not in them (gpu_counters)\n",
        );
    }
    s
}

/// The scene of a triangle-count sweep: a sphere of about `tris` triangles on the ground, staged like a
/// model file (DESIGN 11).
///
/// # Errors
/// [`ShapeError::TooManyVertices`](shadow_core::procedural::ShapeError) for a sphere past
/// [`MAX_SHAPE_VERTICES`](shadow_core::procedural::MAX_SHAPE_VERTICES).
pub fn sweep_scene(tris: u32) -> Result<shadow_core::Scene, shadow_core::procedural::ShapeError> {
    let segments = (tris as f32).sqrt().round().max(3.0) as u32;
    let rings = (tris / segments).div_ceil(2).max(2) + 1;
    let mut s = shadow_core::Scene::new();
    let m = s.add_mesh(shadow_core::procedural::sphere(0.5, segments, rings)?);
    let mat = s.add_material(shadow_core::Material::colored("sphere", Vec3::new(0.85, 0.45, 0.25)));
    let _ = s.add_instance("sphere", m, mat, glam::Mat4::IDENTITY);
    shadow_core::scenes::stage_model(&mut s, true);
    Ok(s)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::TechniqueRegistry;
    use shadow_core::scenes::{self, SceneParams};

    /// Rebuilding gives every instance the adjacency of its own mesh, built once for the instances that
    /// share it: new, and the same as the scene's.
    #[test]
    fn a_rebuilt_adjacency_is_built_once_a_mesh() {
        let scene = scenes::build("props", &SceneParams::default()).expect("a built-in scene");
        let mut frame = FrameInputs::from_first_camera(&scene).expect("a frame");
        let before: Vec<Arc<Adjacency>> = frame.instances.iter().map(|i| Arc::clone(&i.adjacency)).collect();
        rebuild_adjacency(&mut frame);
        let mut distinct: Vec<*const Adjacency> = frame.instances.iter().map(|i| Arc::as_ptr(&i.adjacency)).collect();
        distinct.sort_unstable();
        distinct.dedup();
        assert_eq!(distinct.len(), 4, "one adjacency for each of the ground, rock, crate and post");
        for (inst, old) in frame.instances.iter().zip(&before) {
            assert!(!Arc::ptr_eq(&inst.adjacency, old), "{:?}: not rebuilt", inst.mesh_key);
            assert_eq!(inst.adjacency.triangles(), old.triangles());
            assert_eq!(inst.adjacency.planes(), old.planes());
        }
    }

    #[test]
    fn every_lane_runs_every_frame_and_results_list_technique_by_technique() {
        let scene = scenes::build("stacked-boxes", &SceneParams::default()).expect("a built-in scene");
        let camera = scene.cameras().next().expect("the scene's camera").0;
        let frame = FrameInputs::from_scene(&scene, camera).expect("a frame");
        let specs = ["shadow-map:res=64", "shadow-volume-zfail"].map(|s| TechniqueSpec::parse(s).expect("spec"));
        // The CPU twice stands in for two backends: the lanes run backend by backend but are listed
        // technique by technique.
        let job = BenchJob {
            scene: "stacked-boxes".into(),
            frame: &frame,
            width: 24,
            height: 16,
            frames: 3,
            warmup: 1,
            techniques: specs.to_vec(),
            backends: vec![BackendKind::Cpu, BackendKind::Cpu],
            rebuild: false,
            motion: Motion::Lights,
            savings: vec![Savings::ALL],
        };
        let mut renderer = Renderer::new(TechniqueRegistry::builtin());
        let mut steps = Vec::new();
        let report = run_bench(&mut renderer, &job, |m| steps.push(m.to_string())).expect("bench");
        assert_eq!(steps.len() as u64, job.steps(), "{steps:?}");
        assert_eq!(steps.iter().filter(|m| m.contains("(warm-up)")).count(), 2, "{steps:?}");
        let names: Vec<&str> = report.results.iter().map(|e| e.technique.as_str()).collect();
        assert_eq!(names, ["shadow-map", "shadow-map", "shadow-volume-zfail", "shadow-volume-zfail"]);
        for e in &report.results {
            let total = e.timings_ms["total"];
            assert!(total.min > 0.0 && total.min <= total.median && total.median <= total.max, "{e:?}");
            assert!(e.counters.contains_key("covered_pixels"), "{e:?}");
        }
    }

    /// A clip's frames are the scene posed step after step (the walker's posed mesh changes from frame
    /// to frame, its light stays), each with its host time, and a bench runs them.
    #[test]
    fn a_clip_plays_through_the_frames() {
        let mut scene = scenes::build("walker", &SceneParams::default()).expect("a built-in scene");
        let clip = Clip::play(&mut scene, 0.2, 0.1, 3).expect("a clip");
        let frame = FrameInputs::from_first_camera(&scene).expect("a frame");
        let job = BenchJob {
            scene: "walker".into(),
            frame: &frame,
            width: 24,
            height: 16,
            frames: 2,
            warmup: 1,
            techniques: vec![TechniqueSpec::named("shadow-map")],
            backends: vec![BackendKind::Cpu],
            rebuild: false,
            motion: Motion::Clip(&clip),
            savings: vec![Savings::ALL],
        };
        let frames: Vec<FrameInputs> = (0..4).map(|k| job.frame_at(k, 3, Savings::ALL)).collect();
        let versions: Vec<Vec<u64>> =
            frames.iter().map(|f| f.instances.iter().map(|i| i.mesh_version).collect()).collect();
        assert!(versions[0] != versions[1] && versions[1] != versions[2], "{versions:?}");
        assert_eq!(versions[3], versions[2], "past its end the clip holds its last frame");
        assert_eq!(frames[0].lights[0].kind, frames[2].lights[0].kind, "the light stays");
        assert!(clip.pose_ms().len() == 3 && clip.pose_ms().iter().all(|&t| t > 0.0), "{:?}", clip.pose_ms());
        let report = run_bench(&mut Renderer::new(TechniqueRegistry::builtin()), &job, |_| {}).expect("bench");
        assert!(report.results[0].timings_ms["total"].min > 0.0);
        let mut still = scenes::build("cubes", &SceneParams::default()).expect("a built-in scene");
        let e = Clip::play(&mut still, 0.0, 0.1, 2).expect_err("no animations");
        assert!(e.to_string().contains("no animations"), "{e}");
    }

    /// With the camera moving, the lights stand still and the eye turns about the point it looks at.
    #[test]
    fn a_moving_camera_leaves_the_lights_still() {
        let scene = scenes::build("cubes", &SceneParams::default()).expect("a built-in scene");
        let frame = FrameInputs::from_first_camera(&scene).expect("a frame");
        let job = BenchJob {
            scene: "cubes".into(),
            frame: &frame,
            width: 24,
            height: 16,
            frames: 4,
            warmup: 0,
            techniques: vec![TechniqueSpec::named("shadow-map")],
            backends: vec![BackendKind::Cpu],
            rebuild: false,
            motion: Motion::Camera,
            savings: vec![Savings::ALL],
        };
        let (first, last) = (job.frame_at(0, 4, Savings::ALL), job.frame_at(4, 4, Savings::ALL));
        assert_eq!(first.lights[0].kind, last.lights[0].kind, "the light stays");
        let (a, b) = (first.camera, last.camera);
        assert_eq!(a.target, b.target);
        assert!((a.eye - b.eye).length() > 0.1, "the camera moved");
        assert!(((a.eye - a.target).length() - (b.eye - b.target).length()).abs() < 1e-4, "about its target");
        let lights = BenchJob { motion: Motion::Lights, ..job };
        assert_ne!(lights.frame_at(4, 4, Savings::ALL).lights[0].kind, first.lights[0].kind, "the light turns");
    }

    #[test]
    fn rebuilding_times_the_adjacency_and_rays_are_counted_as_cast() {
        let scene = scenes::build("stacked-boxes", &SceneParams::default()).expect("a built-in scene");
        let frame = FrameInputs::from_first_camera(&scene).expect("a frame");
        let mut renderer = Renderer::new(TechniqueRegistry::builtin());
        for rebuild in [false, true] {
            let job = BenchJob {
                scene: "stacked-boxes".into(),
                frame: &frame,
                width: 48,
                height: 32,
                frames: 2,
                warmup: 1,
                techniques: vec![TechniqueSpec::named("ray-traced")],
                backends: vec![BackendKind::Cpu],
                rebuild,
                motion: Motion::Lights,
                savings: vec![Savings::ALL],
            };
            let report = run_bench(&mut renderer, &job, |_| {}).expect("bench");
            let e = &report.results[0];
            assert_eq!(e.timings_ms.contains_key("adjacency"), rebuild, "{e:?}");
            assert_eq!(bench_table(&report).contains("adjacency rebuilt"), rebuild);
            // Receivers that face away from the light cast no ray: fewer rays than receivers, but some.
            let (rays, receivers) = (e.counters["rays_cast"], e.counters["covered_pixels"]);
            assert!(rays > 0.0 && rays < receivers, "{rays} rays cast from {receivers} receivers");
        }
    }
}
