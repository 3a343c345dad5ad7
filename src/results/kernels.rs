//! The kernels under the techniques, timed on their own: the mesh adjacency, silhouette extraction and
//! volume extrusion of a sphere of about a million triangles, and the reference's shadow rays (the rays
//! `ray-traced` casts over the G-buffers of `tree` and `outdoor`) through the CPU backend's BVH, on one
//! thread and on all.

use std::fmt::Write as _;
use std::hint::black_box;

use shadow_core::geometry::LightSource;
use shadow_core::geometry::adjacency::Adjacency;
use shadow_core::geometry::silhouette::{CastMode, silhouette};
use shadow_core::geometry::volume::{Caps, extrude};
use shadow_core::glam::Vec3;
use shadow_core::procedural;
use shadow_core::stats::{self, Summary, timed, wake_every_thread};
use shadow_core::technique::TechniqueSettings;
use shadow_cpu::bvh::SceneBvh;
use shadow_cpu::gbuffer;
use shadow_cpu::passes::rays::{count_blocked, count_blocked_on_every_thread, shadow_rays};
use shadow_hard::RayTraced;

use super::scene_frame;
use crate::Error;

/// Runs of each timing; the median is reported.
const RUNS: usize = 11;
/// The view the rays are cast over.
const RAY_VIEW: (u32, u32) = (1024, 768);

/// The timings.
pub struct KernelsReport {
    triangles: usize,
    /// Adjacency, silhouette and extrusion medians, ms.
    geometry: [f64; 3],
    rays: Vec<RaysRow>,
}

struct RaysRow {
    scene: &'static str,
    triangles: usize,
    rays: usize,
    build_ms: f64,
    one_thread: f64,
    all_threads: f64,
}

/// Times the kernels.
///
/// # Errors
/// A scene that cannot be built, or a G-buffer that cannot be rendered.
pub fn run_kernels(progress: &mut impl FnMut(&str)) -> Result<KernelsReport, Error> {
    progress("kernels: adjacency, silhouettes, extrusion");
    // 1000 segments by 500 rings of two triangles, less the poles' halves.
    let sphere = procedural::sphere(1.0, 1000, 501).map_err(|e| Error::Usage(format!("the kernels' sphere: {e}")))?;
    let light = LightSource::Point(Vec3::new(2.0, 4.0, 1.5));
    let adjacency = median(|| {
        black_box(Adjacency::build(&sphere));
    });
    let adj = Adjacency::build(&sphere);
    let silhouettes = median(|| {
        black_box(silhouette(&adj, light, CastMode::Closed));
    });
    let sil = silhouette(&adj, light, CastMode::Closed);
    let extrusion = median(|| {
        black_box(extrude(&adj, &sil, light, Caps::Both));
    });
    let mut rays = Vec::new();
    for scene in ["tree", "outdoor"] {
        progress(&format!("kernels: shadow rays of {scene}"));
        let frame = scene_frame(scene)?;
        let g = gbuffer::render(&frame, RAY_VIEW.0, RAY_VIEW.1)?;
        let set = shadow_rays(&g, &frame, RayTraced::defaults().epsilon);
        let build_ms = median(|| {
            black_box(SceneBvh::build(&frame));
        });
        let bvh = SceneBvh::build(&frame);
        // One thread and all take turns, run by run, so a drift of the machine's speed weighs on both
        // alike; every thread is woken before each run on all of them.
        let (mut one, mut all) = (Vec::new(), Vec::new());
        for _ in 0..RUNS {
            one.push(timed(|| black_box(count_blocked(&bvh, &set))).1);
            wake_every_thread();
            all.push(timed(|| black_box(count_blocked_on_every_thread(&bvh, &set))).1);
        }
        let (one, all) = (Summary::of(&one).median, Summary::of(&all).median);
        let rate = |ms: f64| set.len() as f64 / ms / 1e3;
        rays.push(RaysRow {
            scene,
            triangles: bvh.triangle_count(),
            rays: set.len(),
            build_ms,
            one_thread: rate(one),
            all_threads: rate(all),
        });
    }
    Ok(KernelsReport { triangles: sphere.triangles().len(), geometry: [adjacency, silhouettes, extrusion], rays })
}

/// The median of [`RUNS`] timings of `f`, in ms.
fn median(mut f: impl FnMut()) -> f64 {
    let ms: Vec<f64> = (0..RUNS).map(|_| timed(&mut f).1).collect();
    Summary::of(&ms).median
}

/// Appends the kernels' section.
pub fn markdown(s: &mut String, r: &KernelsReport) {
    let _ = writeln!(s, "\n## Kernels\n");
    let _ = writeln!(
        s,
        "Medians of {RUNS} runs, in ms. Geometry on a closed sphere of {} triangles with a point light off it; \
         the adjacency (weld, edges, components) is built once per mesh, silhouettes and the volume (sides and \
         both caps) every frame. Timed after the rest of the results, in a process whose allocator reuses the \
         memory it freed; a fresh process also pays for first touching the adjacency's hundred megabytes, as \
         `cargo bench -p shadow-core --bench geometry` shows.\n",
        r.triangles
    );
    let _ = writeln!(s, "| adjacency | silhouette extraction | volume extrusion |\n|---:|---:|---:|");
    let [a, si, e] = r.geometry;
    let _ = writeln!(s, "| {a:.1} | {si:.2} | {e:.2} |");
    let _ = writeln!(
        s,
        "\nShadow rays: the rays `ray-traced` casts over each scene's G-buffer at {}x{}, through the CPU \
         backend's BVH (its build, on all threads, and the rays traced on one thread and on all, the two \
         taking turns run by run, every thread kept busy for {} ms before each run on all of them). \
         `cargo bench -p shadow-hard --bench rays` traces the same rays through Embree beside ours.\n",
        RAY_VIEW.0,
        RAY_VIEW.1,
        stats::WAKE.as_millis()
    );
    let _ = writeln!(
        s,
        "| scene | triangles | rays | BVH build (ms) | Mrays/s, one thread | Mrays/s, all threads |\n\
         |---|---:|---:|---:|---:|---:|"
    );
    for row in &r.rays {
        let _ = writeln!(
            s,
            "| {} | {} | {} | {:.1} | {:.2} | {:.2} |",
            row.scene, row.triangles, row.rays, row.build_ms, row.one_thread, row.all_threads
        );
    }
}
