//! The soft-shadow part of the results: every soft technique, and the hard map filtered, against
//! `area-light-reference` over the nine configurations (`cylinder`, `primitives`, `stacked-boxes`; light
//! radius 0.05, 0.1, 0.2) at 512x512 with 1024^2 maps, plus `cubes` (boxes shadowing boxes: where the
//! filterable maps bleed); light bleeding with and without each filterable map's reduction; the 10%-90%
//! penumbra width across the upper box's shadow edge on `stacked-boxes`; and that configuration's
//! contact sheet.

use std::fmt::Write as _;
use std::path::PathBuf;

use shadow_core::FrameInputs;
use shadow_core::glam::Vec3;
use shadow_core::metrics::{EdgeLine, penumbra_width};
use shadow_core::scenes::{self, SceneParams};
use shadow_core::technique::TechniqueSpec;

use crate::Error;
use crate::compare::{CompareJob, CompareReport, run_compare};
use crate::renderer::{BackendKind, Renderer};

/// The nine configurations' scenes and light radii, then two models from files, then the bleeding case.
/// A name ending in `.obj` is a file in `MODELS`, staged on a ground under the default spot light.
const CONFIGURATIONS: [(&str, f32); 12] = [
    ("cylinder", 0.05),
    ("cylinder", 0.1),
    ("cylinder", 0.2),
    ("primitives", 0.05),
    ("primitives", 0.1),
    ("primitives", 0.2),
    ("stacked-boxes", 0.05),
    ("stacked-boxes", 0.1),
    ("stacked-boxes", 0.2),
    ("spot.obj", 0.1),
    ("teapot.obj", 0.1),
    ("cubes", 0.2),
];

/// The folder of the test models, from the repository's root; the rows of a model missing there are
/// left out, and the page says so.
const MODELS: &str = "../shared/models";

/// How many of [`CONFIGURATIONS`] are the soft-shadow table's nine.
const NINE: usize = 9;

/// The configuration whose contact sheet and penumbra widths are shown.
const SHOWN: (&str, f32) = ("stacked-boxes", 0.2);

/// The hard map filtered: the baseline every soft technique should beat.
const BASELINES: [&str; 2] = ["shadow-map:res=1024,filter=bilinear", "shadow-map:res=1024,filter=pcf3x3"];

/// The soft technique the geometric one is held to halving.
const HALVED: &str = "pcss";

/// Each filterable map with its light-bleeding reduction turned round: off where its default has one,
/// at the variance map's default where its own default has none.
const TURNED: [&str; 3] =
    ["variance-shadow-map:bleed=0", "exponential-variance-shadow-map:bleed=0.1", "moment-shadow-map:bleed=0.1"];

/// View side.
const SIZE: u32 = 512;

/// What to measure.
pub struct SoftJob {
    /// Backends to measure on.
    pub backends: Vec<BackendKind>,
    /// The folder the contact sheet goes to, beside the results page.
    pub pictures: PathBuf,
}

/// The measurements.
pub struct SoftReport {
    /// The soft techniques by their defaults, in registration order.
    soft: Vec<String>,
    /// Every spec measured, as given, with its canonical settings: how its entries are told apart.
    canonical: Vec<(String, String)>,
    /// Per configuration: its report.
    reports: Vec<((&'static str, f32), CompareReport)>,
    /// Per technique (the reference first): the penumbra widths on the lower box and on the ground.
    widths: Vec<(String, [Option<f32>; 2])>,
    /// The model files not found.
    missing: Vec<&'static str>,
}

/// Built-in scene `name`, or the model file `name` in `MODELS` staged with a ground, with its lights'
/// radius set to `radius`; `None` for a model file that is not there.
///
/// # Errors
/// A scene that cannot be built or loaded, or has no camera.
pub fn frame_with_radius(name: &str, radius: f32) -> Result<Option<FrameInputs>, Error> {
    let mut scene = if name.ends_with(".obj") {
        let path = std::path::Path::new(MODELS).join(name);
        if !path.exists() {
            return Ok(None);
        }
        let mut model =
            shadow_core::assets::load(&path).map_err(|e| Error::Usage(format!("{}: {e}", path.display())))?;
        scenes::stage_model(&mut model, true);
        model
    } else {
        scenes::build(name, &SceneParams::default()).map_err(|e| Error::Usage(format!("{name}: {e}")))?
    };
    let keys: Vec<_> = scene.lights().map(|(k, _)| k).collect();
    for key in keys {
        if let Some(light) = scene.light_mut(key) {
            light.radius = radius;
        }
    }
    Ok(Some(FrameInputs::from_first_camera(&scene)?))
}

/// The two edges of the upper box's shadow on `stacked-boxes` that the penumbra widths are measured
/// across: from where the light projects the upper box's centre onto the lower box's top (towards -x,
/// staying on the top) and onto the ground (towards +x, clear of the lower box). `None` when the frame's
/// first light has no position.
#[must_use]
pub fn stacked_boxes_edges(frame: &FrameInputs) -> Option<[EdgeLine; 2]> {
    let light = frame.lights.first()?.position()?;
    let upper = Vec3::new(0.55, 1.4, 0.35);
    let onto = |y: f32| light + (upper - light) * ((light.y - y) / (light.y - upper.y));
    Some([
        EdgeLine { from: onto(0.5), to: onto(0.5) + Vec3::new(-0.95, 0.0, 0.0), y: 0.5 },
        EdgeLine { from: onto(0.0), to: onto(0.0) + Vec3::new(0.9, 0.0, 0.0), y: 0.0 },
    ])
}

/// Measures the configurations, the widths, and copies the shown configuration's contact sheet into
/// `job.pictures` as `soft-contact.png`.
///
/// # Errors
/// A scene that cannot be built, a rendering failure, or a picture that cannot be written.
pub fn run_soft(renderer: &mut Renderer, job: &SoftJob, mut progress: impl FnMut(&str)) -> Result<SoftReport, Error> {
    let registry = renderer.registry();
    let soft: Vec<String> =
        registry.entries().iter().filter(|e| e.soft && !e.reference).map(|e| e.name.to_string()).collect();
    let reference = registry
        .entries()
        .iter()
        .find(|e| e.soft && e.reference)
        .map(|e| TechniqueSpec::named(e.name))
        .ok_or_else(|| Error::Usage("no soft reference is registered".into()))?;
    let specs: Vec<TechniqueSpec> = soft
        .iter()
        .map(String::as_str)
        .chain(TURNED)
        .chain(BASELINES)
        .map(TechniqueSpec::parse)
        .collect::<Result<_, _>>()?;
    let canonical = specs
        .iter()
        .map(|spec| Ok((spec.to_string(), renderer.registry().canonical(spec)?)))
        .collect::<Result<Vec<_>, Error>>()?;
    let (mut reports, mut missing) = (Vec::new(), Vec::new());
    for (scene, radius) in CONFIGURATIONS {
        let Some(frame) = frame_with_radius(scene, radius)? else {
            progress(&format!("{scene}: not in {MODELS}, left out"));
            missing.push(scene);
            continue;
        };
        let shown = (scene, radius) == SHOWN;
        let scratch = std::env::temp_dir().join(format!("shadowlab-results-soft-{scene}"));
        let compare = CompareJob {
            scene: scene.to_string(),
            frame: &frame,
            width: SIZE,
            height: SIZE,
            techniques: specs.clone(),
            reference: reference.clone(),
            soft_reference: None,
            backends: job.backends.clone(),
            out_dir: shown.then(|| scratch.clone()),
        };
        let report = run_compare(renderer, &compare, |m| progress(&format!("{scene} radius {radius}: {m}")))?;
        if shown {
            let to = job.pictures.join("soft-contact.png");
            std::fs::copy(scratch.join("contact.png"), &to)
                .map_err(|e| Error::Write { path: to.clone(), why: e.to_string() })?;
            let _ = std::fs::remove_dir_all(&scratch);
        }
        reports.push(((scene, radius), report));
    }
    let frame = frame_with_radius(SHOWN.0, SHOWN.1)?.ok_or_else(|| Error::Usage(format!("no scene {}", SHOWN.0)))?;
    let edges = stacked_boxes_edges(&frame).ok_or_else(|| Error::Usage("stacked-boxes has no spot light".into()))?;
    let mut widths = Vec::new();
    for spec in std::iter::once(&reference).chain(&specs[..soft.len()]) {
        progress(&format!("penumbra widths: {spec}"));
        let (f, _) = renderer.run_cpu_frame(&frame, SIZE, SIZE, spec)?;
        let w = edges.map(|line| penumbra_width(&frame.camera, &f.visibility[0], &f.gbuffer.position, line));
        widths.push((spec.to_string(), w));
    }
    Ok(SoftReport { soft, canonical, reports, widths, missing })
}

impl SoftReport {
    /// The technique name and canonical settings of `spec` (as given).
    fn settings_of<'a>(&'a self, spec: &'a str) -> (&'a str, &'a str) {
        let name = spec.split_once(':').map_or(spec, |(n, _)| n);
        (name, self.canonical.iter().find(|(s, _)| s == spec).map_or("", |(_, c)| c.as_str()))
    }

    /// The value of `key` for `spec` (as given) on `backend` in `report`.
    fn value(&self, report: &CompareReport, spec: &str, backend: &str, key: &str) -> Option<f64> {
        let (name, settings) = self.settings_of(spec);
        let e =
            report.results.iter().find(|e| e.technique == name && e.settings == settings && e.backend == backend)?;
        e.vs_reference.get(key).copied()
    }

    /// The largest cross-backend RMSE of `spec` (as given) over `reports`.
    fn cross(&self, reports: &[((&str, f32), CompareReport)], spec: &str) -> Option<f64> {
        let (name, settings) = self.settings_of(spec);
        reports
            .iter()
            .flat_map(|(_, rep)| &rep.cross_backend)
            .filter(|x| x.technique == name && x.settings == settings)
            .map(|x| x.rmse)
            .reduce(f64::max)
    }
}

/// Appends the soft-shadow section to `s`.
pub fn markdown(s: &mut String, r: &SoftReport) {
    let columns: Vec<&str> = r.soft.iter().map(String::as_str).chain(BASELINES).collect();
    let _ = writeln!(s, "\n## Soft shadows: every technique against the area light\n");
    let _ = writeln!(
        s,
        "{SIZE}x{SIZE}, maps 1024^2, each scene's own camera and spot light with its radius set as listed; \
         RMSE of visibility against `area-light-reference` over the measured pixels, on the CPU. The nine \
         configurations of the soft-shadow table, two models from `{MODELS}` on a ground under the default \
         spot light, then `cubes` (boxes shadowing boxes, where filterable maps bleed). Bold: the best of \
         the row.\n"
    );
    if !r.missing.is_empty() {
        let _ = writeln!(s, "Not found in `{MODELS}`, left out: {}.\n", r.missing.join(", "));
    }
    let _ = writeln!(
        s,
        "| scene | radius | {} |",
        columns.iter().map(|c| format!("`{c}`")).collect::<Vec<_>>().join(" | ")
    );
    let _ = writeln!(s, "|---|---:|{}", "---:|".repeat(columns.len()));
    for ((scene, radius), report) in &r.reports {
        let values: Vec<Option<f64>> = columns.iter().map(|c| r.value(report, c, "cpu", "rmse")).collect();
        let best = values.iter().flatten().copied().fold(f64::INFINITY, f64::min);
        let cells: Vec<String> = values
            .iter()
            .map(|v| match v {
                Some(v) if *v == best => format!("**{v:.4}**"),
                Some(v) => format!("{v:.4}"),
                None => "-".into(),
            })
            .collect();
        let _ = writeln!(s, "| {scene} | {radius} | {} |", cells.join(" | "));
    }
    let _ = writeln!(
        s,
        "\nHow many rows each is below the bilinear map's RMSE in, and at most half of `{HALVED}`'s, of the \
         nine and of all, and its largest cross-backend RMSE over the rows but `cubes`, and on `cubes`:\n"
    );
    for c in &columns {
        let rows = |reports: &[((&str, f32), CompareReport)], than: &str, keep: fn(f64, f64) -> bool| {
            reports
                .iter()
                .filter(|(_, rep)| {
                    let (v, b) = (r.value(rep, c, "cpu", "rmse"), r.value(rep, than, "cpu", "rmse"));
                    matches!((v, b), (Some(v), Some(b)) if keep(v, b))
                })
                .count()
        };
        // The first nine rows are the built-in scenes', never left out.
        let below = |reports| rows(reports, BASELINES[0], |v, b| v < b);
        let halved = |reports| rows(reports, HALVED, |v, b| v <= 0.5 * b);
        let (in_nine, in_all) = (below(&r.reports[..NINE]), below(&r.reports));
        let (half_nine, half_all) = (halved(&r.reports[..NINE]), halved(&r.reports));
        // `cubes`, the last row, apart: along its hundreds of small cubes' edges the two backends'
        // G-buffers disagree on a few pixels, which moves every technique's RMSE, the hard map's too.
        let last = r.reports.len() - 1;
        let cross = |reports| r.cross(reports, c).map_or_else(|| "-".into(), |v| format!("{v:.4}"));
        let (others, cubes) = (cross(&r.reports[..last]), cross(&r.reports[last..]));
        let all = r.reports.len();
        let _ = writeln!(
            s,
            "- `{c}`: below bilinear {in_nine} of {NINE}, {in_all} of {all}; at most half of `{HALVED}` \
             {half_nine} of {NINE}, {half_all} of {all}; cross-backend {others} ({cubes} on `cubes`)"
        );
    }
    bleeding(s, r);
    let _ = writeln!(
        s,
        "\n10%-90% penumbra width across the upper box's shadow edge on `{}` (radius {}), in pixels along a \
         world line on each receiver (CPU; a dash: no full ramp from 0.1 to 0.9):\n",
        SHOWN.0, SHOWN.1
    );
    let _ = writeln!(s, "| technique | lower box | ground |");
    let _ = writeln!(s, "|---|---:|---:|");
    for (spec, w) in &r.widths {
        let cell = |v: &Option<f32>| v.map_or_else(|| "-".into(), |v| format!("{v:.1}"));
        let _ = writeln!(s, "| `{spec}` | {} | {} |", cell(&w[0]), cell(&w[1]));
    }
    let _ = writeln!(s, "\n`{}` with radius {}, every technique:\n\n![soft](soft-contact.png)", SHOWN.0, SHOWN.1);
}

/// The light-bleeding table: the filterable maps by their defaults and with the reduction turned round.
fn bleeding(s: &mut String, r: &SoftReport) {
    let maps: Vec<(&str, &str)> = TURNED.iter().filter_map(|t| t.split_once(':').map(|(n, _)| (n, *t))).collect();
    let _ = writeln!(
        s,
        "\nLight bleeding: the percentage of measured pixels in the reference's umbra (visibility at most \
         0.01) that a technique lights to 0.1 or more; each filterable map by its defaults and with its \
         reduction turned round (`bleed`), with RMSE (CPU):\n"
    );
    let heads: Vec<String> = maps.iter().flat_map(|(n, t)| [format!("`{n}`"), format!("`{t}`")]).collect();
    let _ = writeln!(s, "| scene | radius | {} |", heads.join(" | "));
    let _ = writeln!(s, "|---|---:|{}", "---:|".repeat(heads.len()));
    for ((scene, radius), report) in &r.reports {
        let cells: Vec<String> = maps
            .iter()
            .flat_map(|(n, t)| [*n, *t])
            .map(|spec| match (r.value(report, spec, "cpu", "light_bleeding"), r.value(report, spec, "cpu", "rmse")) {
                (Some(b), Some(e)) => format!("{:.3}% ({e:.4})", 100.0 * b),
                _ => "-".into(),
            })
            .collect();
        let _ = writeln!(s, "| {scene} | {radius} | {} |", cells.join(" | "));
    }
}
