//! `compare`: every asked-for technique on every asked-for backend, measured against the ray-traced
//! reference (DESIGN 8), with pictures and reports (DESIGN 11).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::Serialize;
use shadow_core::image::{Rgb8, error_map_over, visibility_to_rgb};
use shadow_core::metrics::{VisibilityMetrics, back_false_light, compare_visibility, flip_mean, measured_pixels};
use shadow_core::stats::Phase;
use shadow_core::technique::{FrameStats, TechniqueSpec};
use shadow_core::{FrameInputs, Image};

use crate::Error;
use crate::renderer::{BackendKind, Renderer, RunOutput};
use crate::sheet::{SheetItem, contact_sheet, disagreement_inset};

/// What to compare.
pub struct CompareJob<'a> {
    /// Scene name for the report.
    pub scene: String,
    /// The frame.
    pub frame: &'a FrameInputs,
    /// View size.
    pub width: u32,
    /// View size.
    pub height: u32,
    /// Techniques to measure (the reference is always run first).
    pub techniques: Vec<TechniqueSpec>,
    /// What they are measured against, on the CPU: `ray-traced` for hard shadows, `area-light-reference`
    /// for soft ones (see [`reference_for`]).
    pub reference: TechniqueSpec,
    /// When set, soft techniques are measured against this reference instead (a run that mixes hard and
    /// soft techniques scores each against its own kind's reference; see [`references_for`]).
    pub soft_reference: Option<TechniqueSpec>,
    /// Backends to run them on.
    pub backends: Vec<BackendKind>,
    /// Where the files go (`None`: compute only).
    pub out_dir: Option<PathBuf>,
}

/// `report.json`'s per-run entry.
#[derive(Clone, Debug, Serialize)]
pub struct ResultEntry {
    /// Technique name.
    pub technique: String,
    /// Canonical settings.
    pub settings: String,
    /// Backend name.
    pub backend: String,
    /// Milliseconds per phase and in total.
    pub timings_ms: BTreeMap<String, f64>,
    /// Measured counters only.
    pub counters: BTreeMap<String, f64>,
    /// The reference this entry is measured against, as its spec reads.
    pub reference: String,
    /// Errors against the reference (fractions in [0, 1], RMSE and FLIP as they are).
    pub vs_reference: BTreeMap<String, f64>,
    /// File stem of its pictures.
    #[serde(skip)]
    pub file: String,
    /// The metrics, typed.
    #[serde(skip)]
    pub metrics: VisibilityMetrics,
    /// FLIP of the shaded image against the reference's.
    #[serde(skip)]
    pub flip: f64,
}

/// `report.json`'s cross-backend entry.
#[derive(Clone, Debug, Serialize)]
pub struct CrossEntry {
    /// Technique name.
    pub technique: String,
    /// Canonical settings.
    pub settings: String,
    /// Fraction of masked pixels where the two backends disagree on lit/shadowed.
    pub mismatch: f64,
    /// RMS visibility difference.
    pub rmse: f64,
    /// FLIP between the two shaded images.
    pub flip_mean: f64,
}

/// The whole `report.json`.
#[derive(Clone, Debug, Serialize)]
pub struct CompareReport {
    /// Scene name.
    pub scene: String,
    /// View width.
    pub width: u32,
    /// View height.
    pub height: u32,
    /// One entry per technique and backend.
    pub results: Vec<ResultEntry>,
    /// One entry per technique run on both backends.
    pub cross_backend: Vec<CrossEntry>,
    /// The reference, as its spec reads.
    pub reference: String,
}

/// The reference for `techniques`: `area-light-reference` when they are all soft, `ray-traced` otherwise
/// (a soft technique's penumbra measured against a hard edge is an error only in name).
#[must_use]
pub fn reference_for(registry: &crate::TechniqueRegistry, techniques: &[TechniqueSpec]) -> TechniqueSpec {
    let soft = |t: &TechniqueSpec| registry.get(&t.name).is_ok_and(|e| e.soft);
    reference_of(registry, !techniques.is_empty() && techniques.iter().all(soft))
}

/// The registry's reference for soft techniques, or for hard ones.
fn reference_of(registry: &crate::TechniqueRegistry, soft: bool) -> TechniqueSpec {
    let found = registry.entries().iter().find(|e| e.reference && e.soft == soft);
    let builtin = if soft { shadow_soft::AreaLightReference::NAME } else { shadow_hard::RayTraced::NAME };
    TechniqueSpec::named(found.map_or(builtin, |e| e.name))
}

/// The references of a run: [`reference_for`], and for a mix of hard and soft techniques
/// `area-light-reference` as the soft techniques' own.
#[must_use]
pub fn references_for(
    registry: &crate::TechniqueRegistry,
    techniques: &[TechniqueSpec],
) -> (TechniqueSpec, Option<TechniqueSpec>) {
    let soft = |t: &TechniqueSpec| registry.get(&t.name).is_ok_and(|e| e.soft);
    let primary = reference_for(registry, techniques);
    let mixed = techniques.iter().any(soft) && !techniques.iter().all(soft);
    (primary, mixed.then(|| reference_of(registry, true)))
}

/// Report keys of a frame's timings.
#[must_use]
pub fn timings_map(stats: &FrameStats) -> BTreeMap<String, f64> {
    let mut m: BTreeMap<String, f64> =
        Phase::ALL.iter().map(|p| (p.key().to_string(), stats.timings.get(*p))).collect();
    m.insert("total".into(), stats.timings.total);
    for (k, v) in &stats.timings.extra {
        m.insert(k.clone(), *v);
    }
    m
}

fn metrics_map(m: &VisibilityMetrics, flip: f64) -> BTreeMap<String, f64> {
    BTreeMap::from([
        ("mismatch".into(), m.mismatch),
        ("edge_band_mismatch".into(), m.edge_band_mismatch),
        ("interior_mismatch".into(), m.interior_mismatch),
        ("false_shadow".into(), m.false_shadow),
        ("false_light".into(), m.false_light),
        ("interior_false_shadow".into(), m.interior_false_shadow),
        ("rmse".into(), m.rmse),
        ("mean_abs".into(), m.mean_abs),
        ("flip_mean".into(), flip),
    ])
}

fn save(img: &Image<Rgb8>, dir: &Path, name: &str) -> Result<(), Error> {
    img.save_png(dir.join(name)).map_err(Error::from)
}

/// Runs the job, writes its files, and returns the report.
///
/// # Errors
/// Rendering failures or files that cannot be written.
pub fn run_compare(
    renderer: &mut Renderer,
    job: &CompareJob<'_>,
    mut progress: impl FnMut(&str),
) -> Result<CompareReport, Error> {
    if let Some(dir) = &job.out_dir {
        std::fs::create_dir_all(dir).map_err(|e| Error::Write { path: dir.clone(), why: e.to_string() })?;
    }
    let reference = &job.reference;
    progress(&format!("reference: {reference} on cpu"));
    let (ref_frame, _) = renderer.run_cpu_frame(job.frame, job.width, job.height, reference)?;
    let view = ref_frame.light_views.first().ok_or_else(|| Error::Usage("the scene has no light".into()))?;
    let g = &ref_frame.gbuffer;
    let mask = measured_pixels(&g.receiver, &g.position, &g.geometric_normal, view);
    let reach =
        Image::from_fn(job.width, job.height, |x, y| *g.receiver.get(x, y) && view.in_domain(*g.position.get(x, y)));
    let ref_vis = &ref_frame.visibility[0];
    let bvh = renderer.bvh(job.frame);
    let probe = shadow_cpu::acne::AcneProbe {
        frame: job.frame,
        light: view,
        gbuffer: g,
        bvh: &bvh,
        reference: ref_vis,
        mask: &mask,
    };
    // A reference's tile shows its visibility where the others show their errors.
    let mut sheet = vec![SheetItem {
        label: format!("{}\nreference", reference.name),
        picture: ref_frame.color.clone(),
        errors: Some(visibility_to_rgb(ref_vis, &mask)),
    }];
    if let Some(dir) = &job.out_dir {
        save(&ref_frame.color, dir, "reference.png")?;
        save(&visibility_to_rgb(ref_vis, &mask), dir, "reference.vis.png")?;
    }
    // The soft techniques' own reference, when the run mixes kinds: same view, same G-buffer and mask.
    let soft: Vec<bool> =
        job.techniques.iter().map(|s| renderer.registry().get(&s.name).is_ok_and(|e| e.soft)).collect();
    let soft_reference = match &job.soft_reference {
        Some(spec) if soft.contains(&true) => {
            progress(&format!("reference: {spec} on cpu"));
            let (frame, _) = renderer.run_cpu_frame(job.frame, job.width, job.height, spec)?;
            sheet.push(SheetItem {
                label: format!("{}\nreference", spec.name),
                picture: frame.color.clone(),
                errors: Some(visibility_to_rgb(&frame.visibility[0], &mask)),
            });
            if let Some(dir) = &job.out_dir {
                save(&frame.color, dir, &format!("reference-{}.png", spec.name))?;
                save(
                    &visibility_to_rgb(&frame.visibility[0], &mask),
                    dir,
                    &format!("reference-{}.vis.png", spec.name),
                )?;
            }
            Some((spec, frame.color, frame.visibility.into_iter().next()))
        }
        _ => None,
    };

    let mut results = Vec::new();
    let mut runs: Vec<RunOutput> = Vec::new();
    // Which reference each run was measured against: false for the first, true for the soft one.
    let mut against_soft: Vec<bool> = Vec::new();
    for (i, spec) in job.techniques.iter().enumerate() {
        let same_name = job.techniques.iter().filter(|s| s.name == spec.name).count() > 1;
        // Each technique against its own kind's reference.
        let soft = soft[i];
        let (reference, ref_color, ref_vis) = match &soft_reference {
            Some((spec_ref, color, Some(vis))) if soft => (*spec_ref, color, vis),
            _ => (reference, &ref_frame.color, ref_vis),
        };
        for &backend in &job.backends {
            progress(&format!("{spec} on {}", backend.name()));
            let run = renderer.run(backend, job.frame, job.width, job.height, spec)?;
            let metrics = compare_visibility(&run.visibility[0], ref_vis, &mask)?;
            let flip = flip_mean(&run.color, ref_color, &mask)?;
            let errors = error_map_over(&run.visibility[0], ref_vis, &mask, &reach, &run.color);
            let file = if same_name {
                format!("{}-{}-{}", spec.name, i + 1, backend.name())
            } else {
                format!("{}-{}", spec.name, backend.name())
            };
            if let Some(dir) = &job.out_dir {
                save(&run.color, dir, &format!("{file}.png"))?;
                save(&visibility_to_rgb(&run.visibility[0], &mask), dir, &format!("{file}.vis.png"))?;
                save(&errors, dir, &format!("{file}.err.png"))?;
                for v in &run.debug_views {
                    save(&v.image, dir, &format!("{file}.{}.png", v.name))?;
                }
            }
            // Map-based techniques (a `res` setting) also get acne told apart from undersampling.
            let res =
                run.settings.split(',').find_map(|kv| kv.strip_prefix("res=")).and_then(|v| v.parse::<u32>().ok());
            let acne = res.filter(|_| !soft).map(|r| probe.texel_acne(&run.visibility[0], r));
            let back = back_false_light(&run.visibility[0], ref_vis, &mask, &reach)?;
            // A technique asked for more than once is told apart by the settings it was given.
            let given = if same_name {
                spec.values.iter().map(|(k, v)| format!("{k}={v} ")).collect::<String>()
            } else {
                String::new()
            };
            // Soft techniques are scored by RMSE: a penumbra has no lit/shadowed state to mismatch.
            let score = if soft {
                format!("RMSE {:.4}", metrics.rmse)
            } else {
                format!("mismatch {:.3}%", metrics.mismatch * 100.0)
            };
            let label = format!("{}\n{given}{} {score}", spec.name, backend.name());
            sheet.push(SheetItem { label, picture: run.color.clone(), errors: Some(errors) });
            results.push(ResultEntry {
                technique: run.technique.clone(),
                settings: run.settings.clone(),
                backend: backend.name().into(),
                reference: reference.to_string(),
                timings_ms: timings_map(&run.stats),
                counters: run.stats.counters.entries().into_iter().collect(),
                vs_reference: {
                    let mut m = metrics_map(&metrics, flip);
                    m.insert("back_false_light".into(), back);
                    if let Some(a) = acne {
                        m.insert("texel_acne".into(), a);
                    }
                    m
                },
                file,
                metrics,
                flip,
            });
            runs.push(run);
            against_soft.push(soft && soft_reference.is_some());
        }
    }

    let mut cross_backend = Vec::new();
    for (i, a) in runs.iter().enumerate() {
        for b in &runs[i + 1..] {
            if a.technique == b.technique && a.settings == b.settings && a.backend != b.backend {
                let m = compare_visibility(&b.visibility[0], &a.visibility[0], &mask)?;
                let flip = flip_mean(&b.color, &a.color, &mask)?;
                cross_backend.push(CrossEntry {
                    technique: a.technique.clone(),
                    settings: a.settings.clone(),
                    mismatch: m.mismatch,
                    rmse: m.rmse,
                    flip_mean: flip,
                });
            }
        }
    }

    let report = CompareReport {
        scene: job.scene.clone(),
        width: job.width,
        height: job.height,
        results,
        cross_backend,
        reference: job.reference.to_string(),
    };
    if let Some(dir) = &job.out_dir {
        let soft_vis = soft_reference.as_ref().and_then(|(_, _, v)| v.as_ref());
        let pairs: Vec<(&Image<f32>, &Image<f32>)> = runs
            .iter()
            .zip(&against_soft)
            .map(|(run, &soft)| (&run.visibility[0], if soft { soft_vis.unwrap_or(ref_vis) } else { ref_vis }))
            .collect();
        let inset = disagreement_inset(&pairs, ref_vis, &mask, (job.width.min(job.height) / 8).max(8));
        save(&contact_sheet(&sheet, 320, Some(inset)), dir, "contact.png")?;
        let json = serde_json::to_string_pretty(&report).map_err(|e| Error::Usage(e.to_string()))?;
        let write = |name: &str, text: &str| {
            std::fs::write(dir.join(name), text).map_err(|e| Error::Write { path: dir.join(name), why: e.to_string() })
        };
        write("report.json", &json)?;
        write("report.md", &report_markdown(&report))?;
    }
    Ok(report)
}

/// `report.md`: one table of errors, counters and times.
#[must_use]
pub fn report_markdown(r: &CompareReport) -> String {
    let mut s = format!(
        "# {} at {}x{}\n\nErrors against each row's reference over receiver pixels that face the light and lie in \
         its reach. Mismatch, edge band, interior, false shadow and false light are percentages of those pixels; \
         RMSE and FLIP are on visibility and colour in [0, 1]. Soft techniques are judged by RMSE.\n\n",
        r.scene, r.width, r.height
    );
    s.push_str("| technique | backend | reference | mismatch | edge band | interior | false shadow | false light | RMSE | FLIP | total ms | picture |\n");
    s.push_str("|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---|\n");
    for e in &r.results {
        let m = &e.metrics;
        s.push_str(&format!(
            "| `{}` | {} | `{}` | {:.3}% | {:.3}% | {:.3}% | {:.3}% | {:.3}% | {:.4} | {:.4} | {:.1} | [png]({}.png) [errors]({}.err.png) |\n",
            e.technique,
            e.backend,
            e.reference,
            m.mismatch * 100.0,
            m.edge_band_mismatch * 100.0,
            m.interior_mismatch * 100.0,
            m.false_shadow * 100.0,
            m.false_light * 100.0,
            m.rmse,
            e.flip,
            e.timings_ms.get("total").copied().unwrap_or(0.0),
            e.file,
            e.file
        ));
    }
    s.push_str("\nSettings:\n\n");
    for e in &r.results {
        s.push_str(&format!("- `{}` ({}): `{}`\n", e.technique, e.backend, e.settings));
    }
    if !r.cross_backend.is_empty() {
        s.push_str("\n| technique | cpu vs wgpu mismatch | RMSE | FLIP |\n|---|---:|---:|---:|\n");
        for c in &r.cross_backend {
            s.push_str(&format!(
                "| `{}` | {:.3}% | {:.4} | {:.4} |\n",
                c.technique,
                c.mismatch * 100.0,
                c.rmse,
                c.flip_mean
            ));
        }
    }
    s.push_str("\nCounters:\n\n");
    for e in &r.results {
        let c: Vec<String> = e.counters.iter().map(|(k, v)| format!("{k} {v}")).collect();
        s.push_str(&format!("- `{}` ({}): {}\n", e.technique, e.backend, c.join(", ")));
    }
    s
}
