//! The perspective-aliasing part of the results: the outdoor street's three views (the sun beside the
//! view, behind the camera, facing it) with the uniform map against the maps fitted to the view at the
//! same texel budget (one 4096^2 map, or four 2048^2 cascades), their near-field error and texel density,
//! what the warps became in each view, and their flicker on a walk; with the contact sheets and the
//! cascades' picture.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use shadow_core::technique::{TechniqueSettings, TechniqueSpec};
use shadow_core::{Aabb, FrameInputs};

use super::scene_frame;
use crate::Error;
use crate::compare::{CompareJob, CompareReport, ResultEntry, run_compare};
use crate::flicker::{FlickerWalk, walk};
use crate::renderer::{BackendKind, Renderer};

/// The techniques compared, the uniform map first.
pub const TECHNIQUES: [&str; 8] = [
    "shadow-map:res=4096",
    "cascaded-shadow-map",
    "cascaded-shadow-map:stabilize=sphere",
    "cascaded-shadow-map:stabilize=off",
    "lispsm",
    "perspective-shadow-map",
    "silhouette-map:res=2048,cascades=4",
    "dual-shadow-map:res=2048,cascades=4",
];

/// The views: the scene and what it shows.
const VIEWS: [(&str, &str); 3] = [
    ("outdoor", "sun beside the view"),
    ("outdoor-behind", "sun behind the camera"),
    ("outdoor-facing", "sun facing the camera (duelling frusta)"),
];

/// The walk the flicker is measured on: frames, scene units and degrees per frame, view size.
const WALK: (usize, f32, f32, (u32, u32)) = (60, 0.05, 0.15, (640, 360));

/// What to measure.
pub struct OutdoorJob {
    /// View size of the error measurements.
    pub size: (u32, u32),
    /// Backends to measure on.
    pub backends: Vec<BackendKind>,
    /// The folder the pictures go to, beside the results page.
    pub pictures: PathBuf,
}

/// The measurements.
pub struct OutdoorReport {
    views: Vec<(&'static str, &'static str, CompareReport, Vec<String>)>,
    flicker: Vec<(String, f64)>,
    size: (u32, u32),
}

/// Measures the three views and the walk; copies the contact sheets and the cascades' picture into
/// `job.pictures`.
///
/// # Errors
/// A scene that cannot be built, a rendering failure, or a picture that cannot be written.
pub fn run_outdoor(
    renderer: &mut Renderer,
    job: &OutdoorJob,
    mut progress: impl FnMut(&str),
) -> Result<OutdoorReport, Error> {
    let specs: Vec<TechniqueSpec> = TECHNIQUES.iter().map(|t| TechniqueSpec::parse(t)).collect::<Result<_, _>>()?;
    let mut views = Vec::new();
    for (name, what) in VIEWS {
        let frame = scene_frame(name)?;
        let scratch = std::env::temp_dir().join(format!("shadowlab-results-{name}"));
        let compare = CompareJob {
            scene: name.to_string(),
            frame: &frame,
            width: job.size.0,
            height: job.size.1,
            techniques: specs.clone(),
            reference: TechniqueSpec::named(shadow_hard::RayTraced::NAME),
            soft_reference: None,
            backends: job.backends.clone(),
            out_dir: Some(scratch.clone()),
        };
        let report = run_compare(renderer, &compare, |m| progress(&format!("{name}: {m}")))?;
        copy(&scratch.join("contact.png"), &job.pictures.join(format!("{name}-contact.png")))?;
        if name == "outdoor" {
            let cascades = report.results.iter().find(|e| e.settings.contains("stabilize=snapped"));
            if let Some(e) = cascades {
                copy(&scratch.join(format!("{}.maps.png", e.file)), &job.pictures.join("outdoor-cascades.png"))?;
            }
        }
        let _ = std::fs::remove_dir_all(&scratch);
        views.push((name, what, report, fits(&frame, job.size)));
    }
    let frame = scene_frame("outdoor")?;
    let (frames, step, turn, size) = WALK;
    let path = walk(&frame.camera, frames, step, turn.to_radians());
    progress("outdoor: the walk's reference");
    let walked = FlickerWalk::new(renderer, &frame, &path, size)?;
    let mut flicker = Vec::new();
    for spec in &specs {
        progress(&format!("outdoor: flicker of {spec}"));
        flicker.push((spec.to_string(), walked.flicker(renderer, spec, |_| {})?));
    }
    Ok(OutdoorReport { views, flicker, size: job.size })
}

fn copy(from: &Path, to: &Path) -> Result<(), Error> {
    std::fs::copy(from, to).map(|_| ()).map_err(|e| Error::Write { path: to.to_path_buf(), why: e.to_string() })
}

/// What the view-fitted maps made of a view: the cascades' splits, the LiSPSM warp, the PSM's light.
fn fits(frame: &FrameInputs, (w, h): (u32, u32)) -> Vec<String> {
    let Some(light) = frame.lights.first().and_then(|l| frame.light_view(l).ok()) else { return Vec::new() };
    let aspect = w as f32 / h as f32;
    let boxes: Vec<Aabb> = frame.instances.iter().map(|i| i.bounds).collect();
    let mut out = Vec::new();
    let csm = shadow_hard::CascadedShadowMap::defaults();
    let cascades = light.cascaded(&frame.camera, aspect, &frame.bounds, &csm.fit());
    if let Some(c) = &cascades.cascades {
        let splits: Vec<String> = c.far.iter().map(|f| format!("{f:.1}")).collect();
        out.push(format!("cascades end at {} m", splits.join(", ")));
    }
    match light.light_space_perspective(&frame.camera, aspect, &boxes, None).1 {
        Some(w) => out.push(format!(
            "lispsm: a perspective with n = {:.1} m over {:.0} m of the view (sin gamma = {:.2})",
            w.n, w.depth, w.sin_gamma
        )),
        None => out.push("lispsm: the uniform map, focused (no warp)".into()),
    }
    if let Some(p) = light.perspective_shadow_map(&frame.camera, aspect, &boxes).1 {
        out.push(format!(
            "perspective-shadow-map: the light became {} after the transform, the virtual camera moved back \
             {:.1} m{}",
            match p.light {
                shadow_core::light::psm::PostPerspectiveLight::Directional => "a directional light",
                shadow_core::light::psm::PostPerspectiveLight::Point => "a point light",
                shadow_core::light::psm::PostPerspectiveLight::InvertedPoint => "an inverted point light",
            },
            p.shift,
            if p.uniform { "; the map fell back to the uniform one, focused" } else { "" }
        ));
    }
    out
}

/// The result of `technique` whose canonical settings hold every `key=value` of `given` (comma-separated).
fn entry<'a>(r: &'a CompareReport, technique: &str, given: &str, backend: &str) -> Option<&'a ResultEntry> {
    let holds =
        |e: &ResultEntry| given.split(',').filter(|kv| !kv.is_empty()).all(|kv| e.settings.split(',').any(|s| s == kv));
    r.results.iter().find(|e| e.technique == technique && e.backend == backend && holds(e))
}

/// The rows' names: the spec as asked for.
fn label(spec: &str) -> &str {
    spec.strip_suffix(":res=4096").unwrap_or(spec)
}

/// The markdown section.
pub fn markdown(s: &mut String, r: &OutdoorReport) {
    let _ = writeln!(s, "\n## Perspective aliasing: the outdoor street\n");
    let _ = writeln!(
        s,
        "{}x{}, the street of `outdoor` seen from head height in three lights. The same texel budget for \
         every map: one 4096^2 map for `shadow-map`, `lispsm` and `perspective-shadow-map`, four 2048^2 \
         cascades for `cascaded-shadow-map` (its three fits), for `silhouette-map` (with a silhouette-point \
         map beside each) and for `dual-shadow-map`. Edge band: the mismatch within two pixels of the reference's shadow edges. Near \
         field: the mismatch over measured pixels in the nearest third of the view's depth range; the factor \
         is that over the uniform map's. Texels per pixel: the median over the near field. Each backend \
         against the reference traced at its own pixels: on the pickets and branches the two G-buffers' \
         samples fall on either side of shadow edges, which the cpu-vs-wgpu numbers show and neither \
         backend's errors count.\n",
        r.size.0, r.size.1
    );
    let _ = write!(s, "| technique | backend |");
    for (name, _, _, _) in &r.views {
        let _ = write!(s, " {name}: mismatch | edge band | near field | x uniform | texels/px |");
    }
    let _ = write!(s, "\n|---|---|");
    for _ in &r.views {
        let _ = write!(s, "---:|---:|---:|---:|---:|");
    }
    s.push('\n');
    let backends: Vec<String> = r.views[0].2.results.iter().map(|e| e.backend.clone()).fold(Vec::new(), |mut v, b| {
        if !v.contains(&b) {
            v.push(b);
        }
        v
    });
    for spec in TECHNIQUES {
        let (name, settings) = spec.split_once(':').unwrap_or((spec, ""));
        for backend in &backends {
            let _ = write!(s, "| `{}` | {backend} |", label(spec));
            for (_, _, report, _) in &r.views {
                let uniform =
                    entry(report, "shadow-map", "res=4096", backend).map(|e| e.vs_reference["near_field_mismatch"]);
                match entry(report, name, settings, backend) {
                    Some(e) => {
                        let near = e.vs_reference["near_field_mismatch"];
                        let factor = uniform.map_or("-".into(), |u| format!("{:.2}", near / u));
                        let density =
                            e.vs_reference.get("near_texel_density_median").map_or("-".into(), |d| format!("{d:.2}"));
                        let _ = write!(
                            s,
                            " {:.3}% | {:.3}% | {:.3}% | {factor} | {density} |",
                            e.metrics.mismatch * 100.0,
                            e.metrics.edge_band_mismatch * 100.0,
                            near * 100.0
                        );
                    }
                    None => {
                        let _ = write!(s, " - | - | - | - | - |");
                    }
                }
            }
            s.push('\n');
        }
    }
    let _ = writeln!(s, "\nWhat the maps fitted to the view made of each:\n");
    for (name, what, _, fits) in &r.views {
        let _ = writeln!(s, "- `{name}` ({what}):");
        for f in fits {
            let _ = writeln!(s, "  - {f}");
        }
    }
    let (frames, step, turn, (w, h)) = WALK;
    let _ = writeln!(
        s,
        "\nFlicker on a walk down the street (`shadowlab flicker`): {frames} frames, {step} m and {turn} degrees \
         per frame, {w}x{h} on the CPU; the percentage of the receivers seen at the start whose lit state changes \
         between consecutive frames as the maps follow the camera.\n"
    );
    let _ = writeln!(s, "| technique | flicker |\n|---|---:|");
    for (spec, f) in &r.flicker {
        let _ = writeln!(s, "| `{}` | {:.4}% |", label(spec), f * 100.0);
    }
    let _ = writeln!(
        s,
        "\nContact sheets (each technique's picture over its errors, the inset where they disagree most):\n"
    );
    for (name, what, _, _) in &r.views {
        let _ = writeln!(s, "- {what}: ![{name}]({name}-contact.png)");
    }
    let _ = writeln!(
        s,
        "\nThe cascades of `outdoor`, each pixel tinted by the cascade it reads (blended over the seams):\n\n![cascades](outdoor-cascades.png)"
    );
}
