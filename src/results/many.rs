//! The scenes of many objects' part of the results ([`scenes::MANY`]): each as built, its meshes drawn by
//! thousands of instances, beside the same scene with a copy of its mesh for every instance
//! ([`shadow_core::Scene::unshare_meshes`]), so the two say what sharing a mesh is worth: the geometry
//! held, the build of the CPU's ray-casting BVH, and the frame time per phase of a few techniques. Then
//! a scene of many one-triangle meshes beside the same triangles as one mesh, so they say what a mesh
//! costs beyond its triangles.

use std::fmt::Write as _;
use std::time::Instant;

use shadow_core::geometry::adjacency::Adjacency;
use shadow_core::glam::{Mat4, Vec3};
use shadow_core::inspect::Inspection;
use shadow_core::scenes::{self, SceneParams};
use shadow_core::technique::TechniqueSpec;
use shadow_core::{FrameInputs, Material, Mesh, Scene};
use shadow_cpu::bvh::SceneBvh;

use crate::Error;
use crate::bench::{BenchJob, BenchReport, Motion, run_bench};
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

/// The one-triangle meshes of the comparison of many small meshes against one.
const SMALL_MESHES: u32 = 100_000;

/// The same triangles as [`SMALL_MESHES`] meshes or as one, as built (`many`: each its own mesh).
struct Triangles {
    many: bool,
    /// Medians over [`BUILDS`], in ms: every mesh's adjacency, and the ray-casting BVH.
    adjacency_ms: f64,
    bvh_ms: f64,
    bench: BenchReport,
}

/// The measurements.
pub struct ManyReport {
    scenes: Vec<(&'static str, [Variant; 2])>,
    triangles: [Triangles; 2],
    size: (u32, u32),
}

/// [`SMALL_MESHES`] upright triangles strewn over a square (the same every time), each its own mesh or
/// all of them one, staged on a ground under the model scenes' camera and light.
fn triangles_scene(many: bool) -> Result<Scene, Error> {
    let mut state = 0x9e37_79b9_7f4a_7c15u64;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 40) as f32 / (1u64 << 24) as f32 * 50.0
    };
    let corners: Vec<[Vec3; 3]> = (0..SMALL_MESHES)
        .map(|_| {
            let p = Vec3::new(next(), 0.5, next());
            [p, p + Vec3::new(0.3, 0.0, 0.0), p + Vec3::new(0.0, 0.3, 0.3)]
        })
        .collect();
    let mut scene = Scene::new();
    let material = scene.add_material(Material::default());
    let bad = |e: &dyn std::fmt::Display| Error::Usage(format!("the triangles scene: {e}"));
    let mut add = |name: &str, corners: &[[Vec3; 3]]| -> Result<(), Error> {
        let positions = corners.iter().flatten().copied().collect();
        let triangles = (0..corners.len() as u32).map(|t| [3 * t, 3 * t + 1, 3 * t + 2]).collect();
        let mesh = scene.add_mesh(Mesh::new(positions, triangles).map_err(|e| bad(&e))?);
        scene.add_instance(name, mesh, material, Mat4::IDENTITY).map_err(|e| bad(&e))?;
        Ok(())
    };
    if many {
        for (k, c) in corners.iter().enumerate() {
            add(&format!("t{k}"), std::slice::from_ref(c))?;
        }
    } else {
        add("triangles", &corners)?;
    }
    scenes::stage_model(&mut scene, true);
    Ok(scene)
}

/// The median of `f`'s time over [`BUILDS`] runs, in ms.
fn median_ms(mut f: impl FnMut()) -> f64 {
    let mut runs: Vec<f64> = (0..BUILDS)
        .map(|_| {
            let t0 = Instant::now();
            f();
            t0.elapsed().as_secs_f64() * 1e3
        })
        .collect();
    runs.sort_by(f64::total_cmp);
    runs[BUILDS / 2]
}

/// Measures the triangles as many meshes and as one: the adjacency and the BVH built from scratch, and a
/// shadow map's frame on the CPU.
fn run_triangles(
    renderer: &mut Renderer,
    size: (u32, u32),
    many: bool,
    progress: &mut impl FnMut(&str),
) -> Result<Triangles, Error> {
    let what = if many { "many meshes" } else { "one mesh" };
    progress(&format!("triangles as {what}: building"));
    let scene = triangles_scene(many)?;
    let frame = FrameInputs::from_first_camera(&scene)?;
    let meshes: Vec<&Mesh> = scene.meshes().map(|(_, m)| m.as_ref()).collect();
    let adjacency_ms = median_ms(|| drop(std::hint::black_box(Adjacency::build_all(&meshes))));
    let bvh_ms = median_ms(|| drop(std::hint::black_box(SceneBvh::build(&frame))));
    let job = BenchJob {
        scene: format!("{SMALL_MESHES} triangles as {what}"),
        frame: &frame,
        width: size.0,
        height: size.1,
        frames: FRAMES,
        warmup: 2,
        techniques: vec![TechniqueSpec::named("shadow-map")],
        backends: vec![BackendKind::Cpu],
        rebuild: false,
        motion: Motion::Lights,
        savings: vec![shadow_core::frame::Savings::ALL],
    };
    let bench = run_bench(renderer, &job, |m| progress(&format!("triangles as {what}: {m}")))?;
    Ok(Triangles { many, adjacency_ms, bvh_ms, bench })
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
            let bvh_ms = median_ms(|| drop(std::hint::black_box(SceneBvh::build(&frame))));
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
                motion: Motion::Lights,
                savings: vec![shadow_core::frame::Savings::ALL],
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
            Ok(Variant { shared, inspection: Inspection::of(&scene), bvh_ms, bench })
        };
        out.push((name, [measure(true)?, measure(false)?]));
    }
    let triangles =
        [run_triangles(renderer, size, true, &mut progress)?, run_triangles(renderer, size, false, &mut progress)?];
    Ok(ManyReport { scenes: out, triangles, size })
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
    let _ = writeln!(
        s,
        "\n{SMALL_MESHES} one-triangle meshes, each drawn by its own instance, against the same triangles as \
         one mesh, on a ground: every mesh's adjacency and the CPU's ray-casting BVH built from scratch \
         (median of {BUILDS}), and `shadow-map`'s G-buffer and build on the CPU at {}x{} ({FRAMES} frames, \
         median ms). Each kernel reads a mesh's few triangles where it would read a large one's many; \
         the ratio is what the meshes cost beyond their triangles.\n",
        r.size.0, r.size.1
    );
    let _ = writeln!(
        s,
        "| triangles as | adjacency | BVH build | G-buffer | shadow-map build |\n|---|---:|---:|---:|---:|"
    );
    let phase = |t: &Triangles, p: &str| {
        t.bench.results.first().and_then(|e| e.timings_ms.get(p)).map_or(f64::NAN, |st| st.median)
    };
    let row = |t: &Triangles| [t.adjacency_ms, t.bvh_ms, phase(t, "gbuffer"), phase(t, "build")];
    for t in &r.triangles {
        let cells = row(t).map(|v| format!("{v:.1}")).join(" | ");
        let _ =
            writeln!(s, "| {} | {cells} |", if t.many { format!("{SMALL_MESHES} meshes") } else { "one mesh".into() });
    }
    let [many, one] = &r.triangles;
    let ratios = row(many).iter().zip(row(one)).map(|(m, o)| format!("{:.2}x", m / o)).collect::<Vec<_>>().join(" | ");
    let _ = writeln!(s, "| ratio | {ratios} |");
}
