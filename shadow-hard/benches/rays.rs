//! Shadow rays against Embree, side by side in one run: the rays `ray-traced` casts over the G-buffer of
//! `tree` and of `outdoor` (788k triangles) at 1024x768, traced by our BVH on one thread and on all, and,
//! where Python has the embreex binding (`pip install numpy embreex`), the same rays through Embree's
//! occluded query on one thread (`embree_rays.py` beside this file); with both BVH builds (Embree's is
//! its scene commit, on all threads; the binding's copy of the triangles is left out) and the rays whose
//! answers differ. Ours and Embree take turns run by run, so the ratios hold through the machine's
//! drifts in speed. A development measurement: Embree is never a dependency of the library.
//! `cargo bench -p shadow-hard --bench rays`.

use std::hint::black_box;
use std::path::Path;
use std::process::Command;

use shadow_core::FrameInputs;
use shadow_core::scenes::{self, SceneParams};
use shadow_core::stats::{Summary, timed, wake_every_thread};
use shadow_core::technique::TechniqueSettings;
use shadow_cpu::bvh::SceneBvh;
use shadow_cpu::gbuffer;
use shadow_cpu::passes::rays::{self, ShadowRay};
use shadow_hard::RayTraced;

/// Each timing is the median of this many runs.
const RUNS: usize = 5;
/// BVH builds in a row per run, on each side (`BUILDS` in `embree_rays.py`); the median counts.
const BUILDS: usize = 3;

fn main() {
    let folder = std::env::temp_dir().join("shadowlab-rays");
    if let Err(e) = std::fs::create_dir_all(&folder) {
        eprintln!("cannot make {}: {e}", folder.display());
        std::process::exit(1);
    }
    let embree =
        Command::new("python3").args(["-c", "import numpy, embreex"]).output().is_ok_and(|o| o.status.success());
    if !embree {
        println!("Embree not found (python3 with numpy and embreex: pip install numpy embreex): ours only");
    }
    println!(
        "{:<8} {:>9} {:>9} | {:>10} {:>10} {:>10} {:>6} | {:>9} {:>9} {:>6} | {:>8}",
        "scene", "triangles", "rays", "ours 1T", "ours all", "Embree 1T", "ratio", "build", "Embree", "ratio", "differ"
    );
    println!(
        "{:<8} {:>9} {:>9} | {:>39} | {:>26} |",
        "", "", "", "Mrays/s (median), ratio ours / Embree", "ms (median), ours / Embree"
    );
    for name in ["tree", "outdoor"] {
        measure(name, &folder, embree);
    }
}

fn measure(name: &str, folder: &Path, embree: bool) {
    let scene = scenes::build(name, &SceneParams::default()).expect("built-in scene");
    let frame = FrameInputs::from_first_camera(&scene).expect("frame");
    let rays = shadow_rays(&frame, 1024, 768);
    let bvh = SceneBvh::build(&frame);
    let ours: Vec<bool> = rays.iter().map(|&(o, d, t)| bvh.occluded(o, d, t)).collect();
    let embree = embree && dump(name, folder, &frame, &rays);
    // Ours and Embree's turn about, run by run, so a drift of the machine's speed weighs on both alike.
    let (mut build, mut one, mut all, mut theirs) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for _ in 0..RUNS {
        // Each side builds its BVH a few times in a row (the first after the other's run, from cold
        // caches) and keeps the median.
        build.push(median((0..BUILDS).map(|_| timed(|| black_box(SceneBvh::build(&frame))).1).collect()));
        one.push(timed(|| black_box(rays::count_blocked(&bvh, &rays))).1);
        wake_every_thread();
        all.push(timed(|| black_box(rays::count_blocked_on_every_thread(&bvh, &rays))).1);
        if embree {
            theirs.extend(embree_once(name, folder));
        }
    }
    let (build, one, all) = (median(build), median(one), median(all));
    let theirs =
        (embree && theirs.len() == RUNS).then(|| embree_answers(name, folder, rays.len())).flatten().map(|answers| {
            (median(theirs.iter().map(|t| t.0).collect()), median(theirs.iter().map(|t| t.1).collect()), answers)
        });
    let rate = |ms: f64| rays.len() as f64 / ms / 1e3;
    let (e_rate, e_build, differ) = match &theirs {
        Some((trace, build, answers)) => (
            format!("{:.2}", rate(*trace)),
            format!("{build:.1}"),
            ours.iter().zip(answers).filter(|(a, b)| a != b).count().to_string(),
        ),
        None => ("-".into(), "-".into(), "-".into()),
    };
    let ratio = |a: f64, b: Option<f64>| b.map_or("-".into(), |b| format!("{:.2}", a / b));
    println!(
        "{name:<8} {:>9} {:>9} | {:>10.2} {:>10.2} {e_rate:>10} {:>6} | {build:>9.1} {e_build:>9} {:>6} | {differ:>8}",
        bvh.triangle_count(),
        rays.len(),
        rate(one),
        rate(all),
        ratio(rate(one), theirs.as_ref().map(|t| rate(t.0))),
        ratio(build, theirs.as_ref().map(|t| t.1)),
    );
}

/// The rays `ray-traced` casts over the frame's G-buffer at `w` x `h`.
fn shadow_rays(frame: &FrameInputs, w: u32, h: u32) -> Vec<ShadowRay> {
    let g = gbuffer::render(frame, w, h).expect("G-buffer");
    rays::shadow_rays(&g, frame, RayTraced::defaults().epsilon)
}

/// Writes the casting triangles and the rays for `embree_rays.py`; false (with a line saying why) when
/// it cannot.
fn dump(name: &str, folder: &Path, frame: &FrameInputs, rays: &[ShadowRay]) -> bool {
    let mut tris = Vec::new();
    for inst in frame.instances.iter().filter(|i| i.casts_shadow) {
        let p = inst.mesh.positions();
        for t in inst.mesh.triangles() {
            for &k in t {
                tris.extend(inst.world_from_local.transform_point3(p[k as usize]).to_array());
            }
        }
    }
    let flat: Vec<f32> = rays.iter().flat_map(|(o, d, t)| [o.x, o.y, o.z, d.x, d.y, d.z, *t]).collect();
    let write = |ext: &str, v: &[f32]| {
        let bytes: Vec<u8> = v.iter().flat_map(|f| f.to_le_bytes()).collect();
        std::fs::write(folder.join(format!("{name}.{ext}")), bytes)
    };
    if let Err(e) = write("tris", &tris).and_then(|()| write("rays", &flat)) {
        eprintln!("{name}: cannot write the ray set to {}: {e}", folder.display());
        return false;
    }
    true
}

/// One Embree run over the dumped set: trace and build milliseconds. `None` (with a line saying why)
/// when it fails.
fn embree_once(name: &str, folder: &Path) -> Option<(f64, f64)> {
    let script = concat!(env!("CARGO_MANIFEST_DIR"), "/benches/embree_rays.py");
    let out = Command::new("python3").arg(script).arg(folder).arg(name).output().ok()?;
    let text = String::from_utf8_lossy(&out.stdout);
    let field =
        |key: &str| text.split_whitespace().find_map(|kv| kv.strip_prefix(key).and_then(|v| v.parse::<f64>().ok()));
    let times = field("trace_ms=").zip(field("build_ms="));
    if times.is_none() {
        eprintln!("{name}: Embree run failed: {}", String::from_utf8_lossy(&out.stderr).trim());
    }
    times
}

/// Embree's answers to the dumped set: whether each ray is occluded.
fn embree_answers(name: &str, folder: &Path, rays: usize) -> Option<Vec<bool>> {
    let answers = std::fs::read(folder.join(format!("{name}.embree"))).ok()?;
    (answers.len() == rays).then(|| answers.iter().map(|&a| a == 1).collect())
}

fn median(v: Vec<f64>) -> f64 {
    Summary::of(&v).median
}
