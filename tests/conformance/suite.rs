//! Cross-backend conformance (DESIGN 9): every technique the registry has on both backends, on a set of
//! scenes at 256x256, run on the CPU and through wgpu, compared with each other and with the ray-traced
//! reference. Failures write actual, reference and difference PNGs under target/conformance/.
//!
//! Without a wgpu adapter the suite prints one line and passes, unless SHADOWLAB_REQUIRE_GPU=1 (CI),
//! where it fails.

use std::path::{Path, PathBuf};

use shadow_core::image::{error_map, visibility_to_rgb};
use shadow_core::metrics::{VisibilityMetrics, compare_visibility, flip_mean, measured_pixels};
use shadow_core::scenes::{self, SceneParams};
use shadow_core::stats::Counters;
use shadow_core::technique::{TechniqueError, TechniqueSpec};
use shadow_core::{FrameInputs, Image, Scene};
use shadow_cpu::CpuFrame;
use shadowlab::renderer::RunOutput;
use shadowlab::{BackendKind, Renderer, TechniqueRegistry};

const SIZE: u32 = 256;
/// Cross-backend ceilings (DESIGN 9): lit/shadowed disagreement and FLIP of the shaded images.
const MAX_CROSS_MISMATCH: f64 = 0.005;
const MAX_CROSS_FLIP: f64 = 0.02;
/// Cross-backend RMSE of a soft technique's visibility.
const MAX_CROSS_RMSE_SOFT: f64 = 0.02;
/// How far the wgpu result's error may stray from the CPU's, in points of mismatch.
const MAX_ERROR_GAP: f64 = 0.005;

/// Per-technique ceilings of the mismatch against the reference, one table. `None`: not measured there
/// (z-pass with the eye in shadow is wrong by design; that failure is what z-fail exists for).
fn reference_ceiling(technique: &str, scene: &str) -> Option<f64> {
    match (technique, scene) {
        ("shadow-volume-zpass", "room" | "room-point") => None,
        // Fake shadows: right on the ground plane only, by construction.
        ("planar-shadow", "cylinder") => Some(0.001),
        ("planar-shadow", _) => None,
        ("shadow-volume-zpass" | "shadow-volume-zfail", _) => Some(0.001),
        ("shadow-map" | "dual-shadow-map" | "midpoint-shadow-map" | "second-depth-shadow-map", _) => Some(0.03),
        ("cascaded-shadow-map" | "lispsm" | "perspective-shadow-map", _) => Some(0.03),
        ("silhouette-map", _) => Some(0.01),
        ("volume-reconstruction", _) => Some(0.01),
        // Against the area light (lit/shadowed split at 0.5): the penumbra only outside the hard edge.
        ("smoothies", _) => Some(0.015),
        // The volumes decide at the map's silhouette pixels: their accuracy.
        ("hybrid", _) => Some(0.001),
        // A technique registered later gets a loose ceiling until it is given its own row.
        _ => Some(0.10),
    }
}

/// Settings other than the defaults that take a different path through a backend, run as techniques of
/// their own.
const VARIANTS: [&str; 6] = [
    // The light pass's object-ID channel: an R32Uint target read back on the GPU.
    "volume-reconstruction:ids=dangling",
    // The unmasked volume pass that counts what the computation mask saves.
    "hybrid:unmasked_fill=on",
    // The computation mask kept in a scratch depth buffer, the volumes' depth test turned around.
    "hybrid:gpu_mask=depth",
    // Chan's rule alone.
    "hybrid:edge_texels=off",
    // The GPU's tile marks, read back, and the volumes drawn in scissor rectangles around them.
    "hybrid:scissor_tile=32",
    // The CPU's volumes through the whole mask, as the GPU draws them (no caster masks): same fill.
    "hybrid:caster_masks=off",
];

fn scenes() -> Vec<(String, Scene)> {
    let mut v: Vec<(String, Scene)> = ["cylinder", "primitives", "cubes", "room"]
        .iter()
        .map(|n| (n.to_string(), scenes::build(n, &SceneParams::default()).expect("built-in scene")))
        .collect();
    // The other light types: cube maps for point lights, orthographic maps and parallel extrusion.
    for (n, t) in [
        ("primitives", scenes::LightType::Point),
        ("room", scenes::LightType::Point),
        ("primitives", scenes::LightType::Directional),
    ] {
        let params = SceneParams { light: Some(t), ..SceneParams::default() };
        v.push((format!("{n}-{t}"), scenes::build(n, &params).expect("built-in scene")));
    }
    let spot = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/models/spot.obj");
    if spot.exists() {
        let mut s = shadow_core::assets::load(&spot).expect("spot.obj loads");
        scenes::stage_model(&mut s, true);
        v.push(("spot".into(), s));
    } else {
        eprintln!("conformance: {} not found, spot scene skipped", spot.display());
    }
    v
}

fn out_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("target/conformance")
}

/// Every technique on both backends by its defaults, then the variants.
fn specs(registry: &TechniqueRegistry) -> Vec<TechniqueSpec> {
    let mut specs: Vec<TechniqueSpec> = registry
        .entries()
        .iter()
        .filter(|e| e.cpu.is_some() && e.wgpu.is_some())
        .map(|e| TechniqueSpec::named(e.name))
        .collect();
    assert!(!specs.is_empty(), "no technique on both backends");
    specs.extend(VARIANTS.iter().map(|v| TechniqueSpec::parse(v).expect("a variant's spec")));
    specs
}

/// The area light's reference frame, or `None` for a light it does not take (a directional one: the area
/// light needs a position).
fn area_light_reference(renderer: &mut Renderer, frame: &FrameInputs, scene_name: &str) -> Option<CpuFrame> {
    let spec = TechniqueSpec::named("area-light-reference");
    match renderer.run_cpu_frame(frame, SIZE, SIZE, &spec) {
        Ok((f, _)) => Some(f),
        Err(e) if matches!(e.technique(), Some(TechniqueError::UnsupportedLight { .. })) => None,
        Err(e) => panic!("{scene_name}: area-light reference: {e}"),
    }
}

/// One technique on one scene, measured.
struct Case<'a> {
    scene: &'a str,
    spec: &'a TechniqueSpec,
    soft: bool,
    /// The backends' visibility against each other.
    cross: VisibilityMetrics,
    /// FLIP between the backends' shaded images.
    flip: f64,
    /// Each backend's mismatch against the reference.
    cpu_err: f64,
    gpu_err: f64,
}

impl Case<'_> {
    /// Every ceiling the case goes over, with its numbers; empty when it passes.
    fn failures(&self, cpu: &Counters, gpu: &Counters) -> Vec<String> {
        let (cross, flip, cpu_err, gpu_err) = (&self.cross, self.flip, self.cpu_err, self.gpu_err);
        let mut why = Vec::new();
        if cross.mismatch > MAX_CROSS_MISMATCH {
            why.push(format!(
                "cross-backend mismatch {:.3}% > {:.3}%",
                cross.mismatch * 100.0,
                MAX_CROSS_MISMATCH * 100.0
            ));
        }
        if flip > MAX_CROSS_FLIP {
            why.push(format!("cross-backend FLIP {flip:.4} > {MAX_CROSS_FLIP}"));
        }
        if self.soft && cross.rmse > MAX_CROSS_RMSE_SOFT {
            why.push(format!("cross-backend visibility RMSE {:.4} > {MAX_CROSS_RMSE_SOFT}", cross.rmse));
        }
        counter_disagreements(self.spec, cpu, gpu, &mut why);
        if (gpu_err - cpu_err).abs() > MAX_ERROR_GAP {
            why.push(format!("wgpu error {:.3}% vs cpu {:.3}%", gpu_err * 100.0, cpu_err * 100.0));
        }
        if let Some(ceiling) = reference_ceiling(&self.spec.name, self.scene) {
            for (backend, err) in [("cpu", cpu_err), ("wgpu", gpu_err)] {
                if err > ceiling {
                    why.push(format!(
                        "{backend} mismatch vs reference {:.3}% > ceiling {:.3}%",
                        err * 100.0,
                        ceiling * 100.0
                    ));
                }
            }
        }
        why
    }
}

/// The counters both backends report must agree (occlusion queries and atomics against CPU counts); adds
/// each that does not to `why`.
fn counter_disagreements(spec: &TechniqueSpec, c: &Counters, w: &Counters, why: &mut Vec<String>) {
    let extra = |c: &Counters, k: &str| c.extra.get(k).map(|v| *v as u64);
    // Relative tolerances: rasterized counts agree to rounding; silhouette_pixels counts per-pixel
    // depth comparisons, which flip where a corner sample ties the receiver to an ulp.
    // Hybrid counts its volume fragments under a mask made of silhouette pixels: a pixel that ties
    // one way on one backend brings its whole overdraw along, so twice theirs, and a few such pixels
    // on top (on a small mask, as the point light's cube faces of the room give, a handful of tied
    // pixels is a few percent of the count while the pictures agree exactly).
    let (volume_tolerance, volume_slack) = if spec.name == "hybrid" { (0.02, 16.0) } else { (0.001, 2.0) };
    // Both backends' caster masks (on unless turned off) count each small caster only where its
    // shadow can be, but they choose the pieces counted that way differently (the CPU by triangles
    // times pixels, the GPU by triangles alone: primitives' sphere is listed on one and drawn through
    // the whole mask on the other), so that fill is not compared here (the pictures still are;
    // `hybrid:caster_masks=off` compares the fill through the whole mask, and hybrid.rs holds the
    // GPU's caster masks to their own whole mask's picture).
    let caster_masks = spec.name == "hybrid" && !spec.values.iter().any(|(k, v)| k == "caster_masks" && v == "off");
    let cpu_fragments = if caster_masks { None } else { c.volume_fragments };
    for (name, a, b, tolerance, slack) in [
        ("covered_pixels", c.covered_pixels, w.covered_pixels, 0.001, 2.0),
        ("volume_fragments", cpu_fragments, w.volume_fragments, volume_tolerance, volume_slack),
        ("cap_triangles", extra(c, "cap_triangles"), extra(w, "cap_triangles"), 0.0, 2.0),
        ("silhouette_edges", c.silhouette_edges, w.silhouette_edges, 0.0, 2.0),
        ("silhouette_pixels", c.silhouette_pixels, w.silhouette_pixels, 0.01, 2.0),
        ("silhouette_texels", extra(c, "silhouette_texels"), extra(w, "silhouette_texels"), 0.001, 2.0),
        (
            "unmasked_volume_fragments",
            extra(c, "unmasked_volume_fragments"),
            extra(w, "unmasked_volume_fragments"),
            0.001,
            2.0,
        ),
    ] {
        if let (Some(a), Some(b)) = (a, b) {
            if (a as f64 - b as f64).abs() > tolerance * a.max(b) as f64 + slack {
                why.push(format!("{name}: cpu {a}, wgpu {b}"));
            }
        } else if a.is_some() != b.is_some() && name == "covered_pixels" {
            why.push(format!("{name} reported by one backend only"));
        }
    }
}

/// Writes a failing case's pictures (both backends' shaded images, the reference visibility, and the
/// differences) under [`out_dir`], named from `stem`; returns the folder.
fn save_failure_pictures(
    stem: &str,
    cpu: &RunOutput,
    gpu: &RunOutput,
    ref_vis: &Image<f32>,
    mask: &Image<bool>,
) -> PathBuf {
    let dir = out_dir();
    let _ = std::fs::create_dir_all(&dir);
    let _ = gpu.color.save_png(dir.join(format!("{stem}-wgpu.png")));
    let _ = cpu.color.save_png(dir.join(format!("{stem}-cpu.png")));
    let _ = visibility_to_rgb(ref_vis, mask).save_png(dir.join(format!("{stem}-reference.vis.png")));
    let _ = error_map(&gpu.visibility[0], &cpu.visibility[0], mask, mask)
        .save_png(dir.join(format!("{stem}-wgpu-vs-cpu.diff.png")));
    let _ = error_map(&gpu.visibility[0], ref_vis, mask, mask)
        .save_png(dir.join(format!("{stem}-wgpu-vs-reference.diff.png")));
    dir
}

#[test]
fn every_technique_agrees_across_backends_and_with_the_reference() {
    let mut registry = TechniqueRegistry::builtin();
    crate::planar::register(&mut registry);
    let mut renderer = Renderer::new(registry.clone());
    let require = std::env::var("SHADOWLAB_REQUIRE_GPU").is_ok_and(|v| v == "1");
    if let Err(e) = renderer.resolve(shadowlab::BackendChoice::Wgpu) {
        assert!(!require, "SHADOWLAB_REQUIRE_GPU=1 but no wgpu adapter: {e}");
        eprintln!("conformance skipped: no wgpu adapter ({e}); install mesa-vulkan-drivers for lavapipe");
        return;
    }
    let specs = specs(&registry);
    let mut failures = Vec::new();
    let mut rows = Vec::new();
    for (scene_name, scene) in scenes() {
        let cam = scene.cameras().next().expect("camera").0;
        let frame = FrameInputs::from_scene(&scene, cam).expect("frame");
        let (reference, _) =
            renderer.run_cpu_frame(&frame, SIZE, SIZE, &TechniqueSpec::named("ray-traced")).expect("reference");
        let g = &reference.gbuffer;
        let mask = measured_pixels(&g.receiver, &g.position, &g.geometric_normal, &reference.light_views[0]);
        // Soft techniques are measured against the area light, made when the first of them needs it.
        let mut soft_reference = None;
        for spec in &specs {
            let label = spec.to_string();
            let t = label.as_str();
            let soft = registry.get(&spec.name).is_ok_and(|e| e.soft);
            let (cpu, gpu) = match (
                renderer.run(BackendKind::Cpu, &frame, SIZE, SIZE, spec),
                renderer.run(BackendKind::Wgpu, &frame, SIZE, SIZE, spec),
            ) {
                (Ok(cpu), Ok(gpu)) => (cpu, gpu),
                // A light the technique does not support: both backends must refuse it, by name.
                (Err(a), Err(b)) if matches!(a.technique(), Some(TechniqueError::UnsupportedLight { .. })) => {
                    assert_eq!(a.technique(), b.technique(), "{scene_name} / {t}: the backends refuse differently");
                    rows.push(format!("{scene_name:<11} {t:<35} refused: {a}"));
                    continue;
                }
                (cpu, gpu) => panic!("{scene_name} / {t}: cpu {:?}, wgpu {:?}", cpu.err(), gpu.err()),
            };
            let ref_vis = if soft {
                // The area light needs a position: a soft technique under a directional light is held to
                // the other backend only.
                let area =
                    soft_reference.get_or_insert_with(|| area_light_reference(&mut renderer, &frame, &scene_name));
                area.as_ref().map(|a| &a.visibility[0])
            } else {
                Some(&reference.visibility[0])
            };
            let ref_vis = ref_vis.unwrap_or(&cpu.visibility[0]);
            let cross = compare_visibility(&gpu.visibility[0], &cpu.visibility[0], &mask).expect("sizes");
            let flip = flip_mean(&gpu.color, &cpu.color, &mask).expect("sizes");
            let cpu_err = compare_visibility(&cpu.visibility[0], ref_vis, &mask).expect("sizes").mismatch;
            let gpu_err = compare_visibility(&gpu.visibility[0], ref_vis, &mask).expect("sizes").mismatch;
            rows.push(format!(
                "{scene_name:<11} {t:<35} cross {:.4}% rmse {:.4} flip {flip:.4} | vs reference cpu {:.4}% wgpu {:.4}%",
                cross.mismatch * 100.0,
                cross.rmse,
                cpu_err * 100.0,
                gpu_err * 100.0
            ));
            let case = Case { scene: &scene_name, spec, soft, cross, flip, cpu_err, gpu_err };
            let why = case.failures(&cpu.stats.counters, &gpu.stats.counters);
            if !why.is_empty() {
                let stem = format!("{scene_name}-{}", t.replace([':', ',', '='], "-"));
                let dir = save_failure_pictures(&stem, &cpu, &gpu, ref_vis, &mask);
                failures.push(format!("{scene_name} / {t}: {} (pictures in {})", why.join("; "), dir.display()));
            }
        }
    }
    eprintln!("conformance on {}:\n{}", renderer.adapter().map_or("?".into(), |a| a.name.clone()), rows.join("\n"));
    assert!(failures.is_empty(), "conformance failures:\n{}", failures.join("\n"));
}

/// A frame of several lights shades alike on both backends (each light's term, times its own visibility,
/// summed), differently from its first light alone; a frame of more lights than the wgpu backend can
/// shade is refused with the count. Without a wgpu adapter this prints one line and passes, unless
/// SHADOWLAB_REQUIRE_GPU=1.
#[test]
fn several_lights_shade_alike_on_both_backends() {
    use shadow_core::Light;
    use shadow_core::glam::Vec3;

    let Some(mut renderer) = crate::with_wgpu("several lights") else { return };
    let scene = scenes::build("primitives", &SceneParams::default()).expect("scene");
    let camera = *scene.camera(scene.cameras().next().expect("camera").0).expect("camera");
    let spot = scene.lights().next().expect("a light").1;
    let two = vec![spot, Light::point(Vec3::new(-1.5, 2.5, 1.0))];
    let spec = TechniqueSpec::named("shadow-map");
    let (reference, _) = renderer
        .run_cpu_frame(&FrameInputs::new(&scene, camera, two.clone()).expect("frame"), SIZE, SIZE, &spec)
        .expect("cpu frame");
    let g = &reference.gbuffer;
    let mask = measured_pixels(&g.receiver, &g.position, &g.geometric_normal, &reference.light_views[0]);
    let mut run = |lights: Vec<Light>, backend| {
        let frame = FrameInputs::new(&scene, camera, lights).expect("frame");
        renderer.run(backend, &frame, SIZE, SIZE, &spec)
    };
    let cpu = run(two.clone(), BackendKind::Cpu).expect("cpu");
    let gpu = run(two, BackendKind::Wgpu).expect("wgpu");
    let two_lights = gpu.color.clone();
    let one = run(vec![spot], BackendKind::Wgpu).expect("wgpu, one light");
    assert_eq!((cpu.visibility.len(), gpu.visibility.len()), (2, 2), "a visibility per light");
    let across = flip_mean(&gpu.color, &cpu.color, &mask).expect("sizes");
    let second = flip_mean(&gpu.color, &one.color, &mask).expect("sizes");
    assert!(across <= MAX_CROSS_FLIP, "two lights: cross-backend FLIP {across:.4} > {MAX_CROSS_FLIP}");
    assert!(second > 10.0 * MAX_CROSS_FLIP, "the second light changes the picture by only {second:.4}");
    // A point light with a range, on both backends: alike, and unlike the same light without it.
    let ranged = Light { range: Some(2.5), ..Light::point(Vec3::new(-1.5, 2.5, 1.0)) };
    let cpu = run(vec![spot, ranged], BackendKind::Cpu).expect("cpu, ranged");
    let gpu = run(vec![spot, ranged], BackendKind::Wgpu).expect("wgpu, ranged");
    let across = flip_mean(&gpu.color, &cpu.color, &mask).expect("sizes");
    let unranged = flip_mean(&gpu.color, &two_lights, &mask).expect("sizes");
    assert!(across <= MAX_CROSS_FLIP, "a ranged light: cross-backend FLIP {across:.4} > {MAX_CROSS_FLIP}");
    assert!(unranged > 10.0 * MAX_CROSS_FLIP, "the range changes the picture by only {unranged:.4}");
    let many = vec![spot; 1000];
    let err = run(many, BackendKind::Wgpu).err().expect("a thousand lights refused");
    assert!(err.to_string().contains("1000 lights"), "{err}");
}
