//! The scenes of many objects' part of the results ([`scenes::MANY`]): each as built, its meshes drawn by
//! thousands of instances, beside the same scene with a copy of its mesh for every instance
//! ([`shadow_core::Scene::unshare_meshes`]), so the two say what sharing a mesh is worth: the geometry
//! held, the build of the CPU's ray-casting BVH, and the frame time per phase of a few techniques.

use std::fmt::Write as _;
use std::time::Instant;

use shadow_core::FrameInputs;
use shadow_core::inspect::Inspection;
use shadow_core::scenes::{self, SceneParams};
use shadow_core::technique::TechniqueSpec;
use shadow_cpu::bvh::SceneBvh;

use crate::Error;
use crate::bench::{BenchJob, BenchReport, run_bench};
use crate::renderer::{BackendKind, Renderer};

/// The techniques timed beside the reference (whose BVH keeps each shared mesh once, on the CPU): a map
/// and a volume.
const TECHNIQUES: &[&str] = &["shadow-map", "shadow-volume-zfail"];
/// The reference timed, on the CPU alone.
const REFERENCE: &str = "ray-traced";
/// Frames timed (after two unmeasured ones), and BVH builds timed.
const FRAMES: u32 = 5;
const BUILDS: usize = 3;

/// One scene, shared or unshared.
struct Variant {
    shared: bool,
    inspection: Inspection,
    /// The ray-casting BVH's build, median over [`BUILDS`], in ms.
    bvh_ms: f64,
    bench: BenchReport,
}

/// The measurements.
pub struct ManyReport {
    scenes: Vec<(&'static str, [Variant; 2])>,
    size: (u32, u32),
}

/// Measures every scene of many objects, as built and unshared, on `backends`.
///
/// # Errors
/// A scene that cannot be built, or a rendering failure.
pub fn run_many(
    renderer: &mut Renderer,
    size: (u32, u32),
    backends: &[BackendKind],
    mut progress: impl FnMut(&str),
) -> Result<ManyReport, Error> {
    let mut out = Vec::new();
    for info in scenes::MANY {
        let name = info.name;
        let mut measure = |shared: bool| -> Result<Variant, Error> {
            let mut scene =
                scenes::build(name, &SceneParams::default()).map_err(|e| Error::Usage(format!("{name}: {e}")))?;
            if !shared {
                scene.unshare_meshes();
            }
            let frame = FrameInputs::from_first_camera(&scene)?;
            let mut builds: Vec<f64> = (0..BUILDS)
                .map(|_| {
                    let t0 = Instant::now();
                    std::hint::black_box(SceneBvh::build(&frame));
                    t0.elapsed().as_secs_f64() * 1e3
                })
                .collect();
            builds.sort_by(f64::total_cmp);
            let (measurable, _) = renderer.registry().measurable(&frame);
            let techniques = measurable
                .into_iter()
                .filter(|t| TECHNIQUES.contains(&t.name.as_str()))
                .collect::<Vec<TechniqueSpec>>();
            let job = BenchJob {
                scene: name.to_string(),
                frame: &frame,
                width: size.0,
                height: size.1,
                frames: FRAMES,
                warmup: 2,
                techniques,
                backends: backends.to_vec(),
                rebuild: false,
                clip: None,
            };
            let what = if shared { "shared" } else { "unshared" };
            let mut bench = run_bench(renderer, &job, |m| progress(&format!("{name} {what}: {m}")))?;
            if backends.contains(&BackendKind::Cpu) {
                let job = BenchJob {
                    techniques: vec![TechniqueSpec::named(REFERENCE)],
                    backends: vec![BackendKind::Cpu],
                    ..job
                };
                let reference = run_bench(renderer, &job, |m| progress(&format!("{name} {what}: {m}")))?;
                bench.results.splice(0..0, reference.results);
            }
            Ok(Variant { shared, inspection: Inspection::of(&scene), bvh_ms: builds[BUILDS / 2], bench })
        };
        out.push((name, [measure(true)?, measure(false)?]));
    }
    Ok(ManyReport { scenes: out, size })
}

/// Appends the section.
pub fn markdown(s: &mut String, r: &ManyReport) {
    let _ = writeln!(s, "\n## Many objects\n");
    let _ = writeln!(
        s,
        "Each scene as built (its meshes each held once, drawn by many instances: *shared*) and with a copy of \
         its mesh for every instance (*unshared*, `--unshare`): the meshes and their geometry held, the CPU's \
         ray-casting BVH built from scratch (median of {BUILDS}; shared meshes are kept once under a tree of \
         their instances, the rest in world space), and the frame time per phase at {}x{} (`bench`, {FRAMES} \
         frames, median ms). The pictures of the two are the same.\n",
        r.size.0, r.size.1
    );
    let _ = writeln!(s, "| scene | meshes | instances | geometry (MiB) | BVH build (ms) |\n|---|---:|---:|---:|---:|");
    for (name, variants) in &r.scenes {
        for v in variants {
            let i = &v.inspection;
            let _ = writeln!(
                s,
                "| {name} {} | {} | {} | {:.2} | {:.1} |",
                if v.shared { "shared" } else { "unshared" },
                i.meshes,
                i.instances,
                i.mesh_bytes as f64 / f64::from(1 << 20),
                v.bvh_ms
            );
        }
    }
    let _ = writeln!(
        s,
        "\n| scene | technique | backend | shared: gbuffer / build / query / shade / total | unshared: the same \
         |\n|---|---|---|---|---|"
    );
    for (name, [shared, unshared]) in &r.scenes {
        for e in &shared.bench.results {
            let other = unshared.bench.results.iter().find(|o| o.technique == e.technique && o.backend == e.backend);
            let phases = |t: &std::collections::BTreeMap<String, crate::bench::Stat>| {
                ["gbuffer", "build", "query", "shade", "total"]
                    .map(|p| t.get(p).map_or("-".into(), |st| format!("{:.1}", st.median)))
                    .join(" / ")
            };
            let _ = writeln!(
                s,
                "| {name} | {} | {} | {} | {} |",
                e.technique,
                e.backend,
                phases(&e.timings_ms),
                other.map_or("-".into(), |o| phases(&o.timings_ms))
            );
        }
    }
}
