//! `compare`: every asked-for technique on every asked-for backend, measured against the ray-traced
//! reference (DESIGN 8), with pictures and reports (DESIGN 11).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::Serialize;
use shadow_core::image::{Rgb8, error_map_over, visibility_to_rgb};
use shadow_core::metrics::{
    VisibilityMetrics, back_false_light, compare_visibility, flip_mean, light_bleeding, measured_pixels, min_median,
    near_field, texel_density,
};
use shadow_core::stats::Phase;
use shadow_core::technique::maps::MapSampling;
use shadow_core::technique::{FrameStats, TechniqueSpec};
use shadow_core::{FrameInputs, Image};

use crate::Error;
use crate::renderer::{BackendKind, Renderer, RunOutput};

mod frame;

use crate::sheet::{SheetItem, contact_sheet, disagreement_inset};
pub use frame::{scene_notes, widest_first};
use shadow_core::technique::maps::RESOLUTION;
use shadow_cpu::CpuFrame;
use shadow_cpu::acne::AcneProbe;
use shadow_cpu::bvh::SceneBvh;

/// What to compare.
#[derive(Clone)]
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
    /// Per light, the side of the shadow-atlas tiles its maps had (`None`: maps of its own, at its
    /// technique's size); empty where the frame had no atlas.
    pub atlas_tiles: Vec<Option<u32>>,
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
    /// What the reader must know of the scene to read the figures: which content every technique and
    /// the reference take in a simpler way alike.
    pub notes: Vec<String>,
}

/// The reference for `techniques`: `area-light-reference` when they are all soft, `ray-traced` otherwise
/// (a soft technique's penumbra measured against a hard edge is an error only in name).
#[must_use]
pub fn reference_for(registry: &crate::TechniqueRegistry, techniques: &[TechniqueSpec]) -> TechniqueSpec {
    let soft = |t: &TechniqueSpec| registry.get(&t.name).is_ok_and(|e| e.soft);
    reference_of(registry, !techniques.is_empty() && techniques.iter().all(soft))
}

/// The registry's reference for soft techniques, or for hard ones.
#[must_use]
pub fn reference_of(registry: &crate::TechniqueRegistry, soft: bool) -> TechniqueSpec {
    let found = registry.entries().iter().find(|e| e.reference && e.soft == soft);
    let builtin = if soft { shadow_soft::AreaLightReference::NAME } else { shadow_hard::RayTraced::NAME };
    TechniqueSpec::named(found.map_or(builtin, |e| e.name))
}

/// A technique's score against its reference: the RMSE for a soft technique (a penumbra has no lit or
/// shadowed state to mismatch), the mismatch for a hard one.
#[must_use]
pub fn score(metrics: &VisibilityMetrics, soft: bool) -> String {
    if soft { format!("RMSE {:.4}", metrics.rmse) } else { format!("mismatch {:.3}%", metrics.mismatch * 100.0) }
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

/// The references of a job at one backend's receivers, traced on the CPU over the G-buffer that backend
/// renders: each backend is measured at the very points its techniques were queried at. On sub-pixel
/// casters (a fence's pickets, thin branches) the two backends' pixel samples land on either side of a
/// shadow edge often enough that one shared reference would count the G-buffers' difference as shadow
/// error. The primary reference's frame (its G-buffer, light view and visibility), the measured and
/// reached pixels, and the soft techniques' own reference when the job mixes kinds.
struct Ground {
    frame: CpuFrame,
    mask: Image<bool>,
    /// The measured pixels in the nearest third of the view's depth range.
    near: Image<bool>,
    reach: Image<bool>,
    /// The soft reference's spec, shaded picture and visibility.
    soft: Option<(TechniqueSpec, Image<Rgb8>, Image<f32>)>,
}

impl Ground {
    /// Traces the references of `job` over `backend`'s G-buffer.
    fn trace(
        renderer: &mut Renderer,
        job: &CompareJob<'_>,
        backend: BackendKind,
        any_soft: bool,
        progress: &mut impl FnMut(&str),
    ) -> Result<Self, Error> {
        let gbuffer = renderer.gbuffer_of(backend, job.frame, job.width, job.height)?;
        let mut over = |renderer: &mut Renderer, spec: &TechniqueSpec| -> Result<CpuFrame, Error> {
            progress(&format!("reference: {spec} on cpu, at {}'s pixels", backend.name()));
            let mut reference = renderer.prepare(BackendKind::Cpu, spec)?;
            renderer.run_cpu_over(&mut reference, job.frame, &gbuffer)
        };
        let frame = over(renderer, &job.reference)?;
        let soft = match &job.soft_reference {
            Some(spec) if any_soft => {
                let f = over(renderer, spec)?;
                let vis = f.visibility.into_iter().next().unwrap_or_else(|| frame.visibility[0].clone());
                Some((spec.clone(), f.color, vis))
            }
            _ => None,
        };
        let view = frame.light_views.first().ok_or_else(|| Error::Usage("the scene has no light".into()))?;
        let g = &frame.gbuffer;
        let mask = measured_pixels(&g.receiver, &g.position, &g.geometric_normal, view);
        let reach = Image::from_fn(job.width, job.height, |x, y| {
            *g.receiver.get(x, y) && view.in_domain(*g.position.get(x, y))
        });
        let near = near_field(&mask, &g.position, &job.frame.camera);
        Ok(Self { frame, mask, near, reach, soft })
    }

    /// The reference a technique of this kind is measured against: spec, shaded picture, visibility, and
    /// whether it is the soft one.
    fn of<'a>(
        &'a self,
        job: &'a CompareJob<'_>,
        soft: bool,
    ) -> (&'a TechniqueSpec, &'a Image<Rgb8>, &'a Image<f32>, bool) {
        match &self.soft {
            Some((spec, color, vis)) if soft => (spec, color, vis, true),
            _ => (&job.reference, &self.frame.color, &self.frame.visibility[0], false),
        }
    }

    /// Writes the references' files, `-BACKEND` added to their names past the CPU's, and puts the CPU's on
    /// the contact sheet (`sheet`), first.
    fn show(&self, job: &CompareJob<'_>, backend: BackendKind, sheet: &mut Vec<SheetItem>) -> Result<(), Error> {
        let tail = match backend {
            BackendKind::Cpu => String::new(),
            other => format!("-{}", other.name()),
        };
        let mut show = |spec: &TechniqueSpec, color: &Image<Rgb8>, vis: &Image<f32>, name: String| {
            let picture = visibility_to_rgb(vis, &self.mask);
            if let Some(dir) = &job.out_dir {
                save(color, dir, &format!("{name}{tail}.png"))?;
                save(&picture, dir, &format!("{name}{tail}.vis.png"))?;
            }
            // A reference's tile shows its visibility where the others show their errors.
            if backend == BackendKind::Cpu {
                let label = format!("{}\nreference", spec.name);
                sheet.push(SheetItem { label, picture: color.clone(), errors: Some(picture) });
            }
            Ok::<(), Error>(())
        };
        show(&job.reference, &self.frame.color, &self.frame.visibility[0], "reference".into())?;
        if let Some((spec, color, vis)) = &self.soft {
            show(spec, color, vis, format!("reference-{}", spec.name))?;
        }
        Ok(())
    }
}

/// The references of a job: one [`Ground`] per backend it measures.
struct References {
    grounds: Vec<(BackendKind, Ground)>,
}

impl References {
    /// Traces the references at the pixels of each of `job`'s backends (the CPU's always: cross-backend
    /// numbers are taken over its measured pixels).
    fn trace(
        renderer: &mut Renderer,
        job: &CompareJob<'_>,
        any_soft: bool,
        sheet: &mut Vec<SheetItem>,
        progress: &mut impl FnMut(&str),
    ) -> Result<Self, Error> {
        let mut backends = vec![BackendKind::Cpu];
        backends.extend(job.backends.iter().copied().filter(|&b| b != BackendKind::Cpu));
        let mut grounds = Vec::new();
        for backend in backends {
            let ground = Ground::trace(renderer, job, backend, any_soft, progress)?;
            ground.show(job, backend, sheet)?;
            grounds.push((backend, ground));
        }
        Ok(Self { grounds })
    }

    /// The CPU's references.
    fn cpu(&self) -> &Ground {
        &self.grounds[0].1
    }

    /// The references at `backend`'s pixels.
    fn at(&self, backend: BackendKind) -> &Ground {
        self.grounds.iter().find(|(b, _)| *b == backend).map_or(self.cpu(), |(_, g)| g)
    }
}

/// The map side of a spec whose technique has a `res` key (given, or its default), for the acne probe.
fn map_resolution(renderer: &Renderer, spec: &TechniqueSpec) -> Option<u32> {
    let key = (renderer.registry().get(&spec.name).ok()?.keys)().iter().find(|k| k.key == RESOLUTION)?;
    let given = spec.values.iter().find(|(k, _)| k == RESOLUTION).map(|(_, v)| v.as_str());
    given.unwrap_or(key.default).parse().ok()
}

/// One technique on one backend: the run and its report entry, its files written.
struct Measured {
    run: RunOutput,
    entry: ResultEntry,
    against_soft: bool,
}

/// Runs `spec` (the `index`-th asked for) on `backend` and measures it against its kind's reference at
/// that backend's pixels (`refs`; `bvh` the frame's casters); the run's contact-sheet tile goes on
/// `sheet`.
fn measure(
    renderer: &mut Renderer,
    job: &CompareJob<'_>,
    (refs, bvh): (&Ground, &SceneBvh),
    (index, spec): (usize, &TechniqueSpec),
    backend: BackendKind,
    sheet: &mut Vec<SheetItem>,
) -> Result<Measured, Error> {
    let soft = renderer.registry().get(&spec.name).is_ok_and(|e| e.soft);
    let (reference, ref_color, ref_vis, against_soft) = refs.of(job, soft);
    let probe = AcneProbe {
        frame: job.frame,
        light: &refs.frame.light_views[0],
        gbuffer: &refs.frame.gbuffer,
        bvh,
        reference: &refs.frame.visibility[0],
        mask: &refs.mask,
    };
    let mask = &refs.mask;
    renderer.keep_debug_views(job.out_dir.is_some());
    let run = renderer.run(backend, job.frame, job.width, job.height, spec)?;
    let metrics = compare_visibility(&run.visibility[0], ref_vis, mask)?;
    let flip = flip_mean(&run.color, ref_color, mask)?;
    let errors = error_map_over(&run.visibility[0], ref_vis, mask, &refs.reach, &run.color);
    // A technique asked for more than once is told apart by its place and the settings it was given.
    let same_name = job.techniques.iter().filter(|s| s.name == spec.name).count() > 1;
    let file = if same_name {
        format!("{}-{}-{}", spec.name, index + 1, backend.name())
    } else {
        format!("{}-{}", spec.name, backend.name())
    };
    if let Some(dir) = &job.out_dir {
        save(&run.color, dir, &format!("{file}.png"))?;
        save(&visibility_to_rgb(&run.visibility[0], mask), dir, &format!("{file}.vis.png"))?;
        save(&errors, dir, &format!("{file}.err.png"))?;
        for v in &run.debug_views {
            save(&v.image, dir, &format!("{file}.{}.png", v.name))?;
        }
    }
    // Map-based techniques (a `res` setting) also get acne told apart from undersampling.
    let acne = map_resolution(renderer, spec).filter(|_| !soft).map(|r| probe.texel_acne(&run.visibility[0], r));
    let back = back_false_light(&run.visibility[0], ref_vis, mask, &refs.reach)?;
    let given = if same_name {
        spec.values.iter().map(|(k, v)| format!("{k}={v} ")).collect::<String>()
    } else {
        String::new()
    };
    let score = score(&metrics, soft);
    sheet.push(SheetItem {
        label: format!("{}\n{given}{} {score}", spec.name, backend.name()),
        picture: run.color.clone(),
        errors: Some(errors),
    });
    let mut vs_reference = metrics_map(&metrics, flip);
    vs_reference.insert("back_false_light".into(), back);
    if soft {
        vs_reference.insert("light_bleeding".into(), light_bleeding(&run.visibility[0], ref_vis, mask)?);
    }
    vs_reference
        .insert("near_field_mismatch".into(), compare_visibility(&run.visibility[0], ref_vis, &refs.near)?.mismatch);
    if let Some(layout) = renderer.registry().get(&spec.name).ok().and_then(|e| e.layout) {
        let sampling = layout(spec, job.frame, &refs.frame.light_views[0], job.width as f32 / job.height as f32)?;
        let density = sampling_report(&sampling, refs, &run.color, job.out_dir.as_deref().map(|d| (d, file.as_str())))?;
        vs_reference.extend(density);
    }
    if let Some(a) = acne {
        vs_reference.insert("texel_acne".into(), a);
    }
    let entry = ResultEntry {
        technique: run.technique.clone(),
        settings: run.settings.clone(),
        backend: backend.name().into(),
        reference: reference.to_string(),
        timings_ms: timings_map(&run.stats),
        counters: run.stats.counters.entries().into_iter().collect(),
        atlas_tiles: run
            .atlas
            .as_ref()
            .map_or_else(Vec::new, |a| a.lights.iter().map(|t| t.as_ref().map(|t| t.side)).collect()),
        vs_reference,
        file,
        metrics,
        flip,
    };
    Ok(Measured { run, entry, against_soft })
}

/// Texel density of a technique's maps over the measured pixels and the near field (min and median
/// texels per pixel), with its pictures when `files` names a folder and a file stem: the density, and
/// for more than one map which map each pixel reads over `color`.
fn sampling_report(
    sampling: &MapSampling,
    refs: &Ground,
    color: &Image<Rgb8>,
    files: Option<(&Path, &str)>,
) -> Result<BTreeMap<String, f64>, Error> {
    let g = &refs.frame.gbuffer;
    let density = texel_density(sampling, &g.position, &g.geometric_normal, &refs.mask);
    let mut out = BTreeMap::new();
    if let Some((lo, median)) = min_median(&density, &refs.mask) {
        out.insert("texel_density_min".into(), lo);
        out.insert("texel_density_median".into(), median);
    }
    if let Some((lo, median)) = min_median(&density, &refs.near) {
        out.insert("near_texel_density_min".into(), lo);
        out.insert("near_texel_density_median".into(), median);
    }
    if let Some((dir, file)) = files {
        // log2 of texels per pixel from 1/64 to 64: the middle of the ramp is one texel per pixel.
        let picture = shadow_core::image::false_colour(&density.map(|d| d.log2()), -6.0, 6.0);
        save(&picture, dir, &format!("{file}.density.png"))?;
        if sampling.view.projections.len() > 1 {
            save(&map_picture(sampling, &g.position, &refs.reach, color), dir, &format!("{file}.maps.png"))?;
        }
    }
    Ok(out)
}

/// `color` tinted by the map each receiver pixel of `reach` reads (a cascade, a cube face), cascades
/// mixed with the next one's tint over their blend band.
fn map_picture(
    sampling: &MapSampling,
    position: &Image<glam::Vec3>,
    reach: &Image<bool>,
    color: &Image<Rgb8>,
) -> Image<Rgb8> {
    const TINTS: [[f32; 3]; 6] =
        [[1.0, 0.3, 0.3], [0.3, 1.0, 0.3], [0.35, 0.5, 1.0], [1.0, 0.9, 0.2], [1.0, 0.3, 1.0], [0.2, 1.0, 1.0]];
    let view = &sampling.view;
    Image::from_fn(color.width(), color.height(), |x, y| {
        let c = *color.get(x, y);
        if !*reach.get(x, y) {
            return c;
        }
        let p = *position.get(x, y);
        let tint = match view.cascade_pick(p) {
            Some(pick) => {
                let a = TINTS[pick.cascade % 6];
                let (next, w) = pick.next.map_or((pick.cascade, 0.0), |(k, w)| (k, w));
                let b = TINTS[next % 6];
                [0, 1, 2].map(|i| a[i] * (1.0 - w) + b[i] * w)
            }
            None => TINTS[view.projection_index(p) % 6],
        };
        [0, 1, 2].map(|i| (f32::from(c[i]) * (0.35 + 0.65 * tint[i])).round().min(255.0) as u8)
    })
}

/// Every pair of runs of one technique and settings on two backends, compared with each other.
fn cross_backend(runs: &[Measured], mask: &Image<bool>) -> Result<Vec<CrossEntry>, Error> {
    let mut out = Vec::new();
    for (i, a) in runs.iter().map(|m| &m.run).enumerate() {
        for b in runs[i + 1..].iter().map(|m| &m.run) {
            if a.technique == b.technique && a.settings == b.settings && a.backend != b.backend {
                let m = compare_visibility(&b.visibility[0], &a.visibility[0], mask)?;
                out.push(CrossEntry {
                    technique: a.technique.clone(),
                    settings: a.settings.clone(),
                    mismatch: m.mismatch,
                    rmse: m.rmse,
                    flip_mean: flip_mean(&b.color, &a.color, mask)?,
                });
            }
        }
    }
    Ok(out)
}

/// Writes the contact sheet (with the inset where the techniques disagree most) and both reports.
fn write_reports(
    dir: &Path,
    job: &CompareJob<'_>,
    refs: &References,
    (sheet, runs): (&[SheetItem], &[Measured]),
    report: &CompareReport,
) -> Result<(), Error> {
    let pairs: Vec<(&Image<f32>, &Image<f32>)> = runs
        .iter()
        .map(|m| {
            let ground = refs.at(m.run.backend);
            let against = match &ground.soft {
                Some((_, _, vis)) if m.against_soft => vis,
                _ => &ground.frame.visibility[0],
            };
            (&m.run.visibility[0], against)
        })
        .collect();
    let cpu = refs.cpu();
    let inset = disagreement_inset(&pairs, &cpu.frame.visibility[0], &cpu.mask, (job.width.min(job.height) / 8).max(8));
    save(&contact_sheet(sheet, 320, Some(inset)), dir, "contact.png")?;
    let json = serde_json::to_string_pretty(report).map_err(|e| Error::Usage(e.to_string()))?;
    let write = |name: &str, text: &str| {
        std::fs::write(dir.join(name), text).map_err(|e| Error::Write { path: dir.join(name), why: e.to_string() })
    };
    write("report.json", &json)?;
    write("report.md", &report_markdown(report))
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
    // The figures are the first light's: where another reaches more of the view, that one goes first.
    let moved = widest_first(job.frame, job.width, job.height);
    let moved_job = moved.as_ref().map(|(frame, _)| CompareJob { frame, ..job.clone() });
    let job = moved_job.as_ref().unwrap_or(job);
    let any_soft = job.techniques.iter().any(|s| renderer.registry().get(&s.name).is_ok_and(|e| e.soft));
    let mut sheet = Vec::new();
    let refs = References::trace(renderer, job, any_soft, &mut sheet, &mut progress)?;
    let bvh = renderer.bvh(job.frame);
    let mut runs = Vec::new();
    for (i, spec) in job.techniques.iter().enumerate() {
        for &backend in &job.backends {
            progress(&format!("{spec} on {}", backend.name()));
            runs.push(measure(renderer, job, (refs.at(backend), &bvh), (i, spec), backend, &mut sheet)?);
        }
    }
    let report = CompareReport {
        scene: job.scene.clone(),
        width: job.width,
        height: job.height,
        results: runs.iter().map(|m| m.entry.clone()).collect(),
        cross_backend: cross_backend(&runs, &refs.cpu().mask)?,
        reference: job.reference.to_string(),
        notes: scene_notes(job.frame)
            .into_iter()
            .chain(moved.as_ref().map(|&(_, k)| frame::measured_note(k)))
            .collect(),
    };
    if let Some(dir) = &job.out_dir {
        write_reports(dir, job, &refs, (&sheet, &runs), &report)?;
    }
    Ok(report)
}

/// `report.md`: one table of errors, counters and times.
#[must_use]
pub fn report_markdown(r: &CompareReport) -> String {
    let mut s = format!(
        "# {} at {}x{}\n\nErrors against each row's reference over receiver pixels that face the light and lie in \
         its reach. Mismatch, edge band, interior, false shadow and false light are percentages of those pixels; \
         near field is the mismatch over those in the nearest third of the view's depth range. RMSE and FLIP are \
         on visibility and colour in [0, 1]. Soft techniques are judged by RMSE. Texels per pixel (light-map \
         texels a pixel's footprint covers; below 1 a texel spans several pixels), smallest and median, for \
         techniques built on depth maps.\n\n",
        r.scene, r.width, r.height
    );
    for note in &r.notes {
        s.push_str(&format!("Note: {note}.\n\n"));
    }
    s.push_str("| technique | backend | reference | mismatch | edge band | interior | near field | false shadow | false light | RMSE | FLIP | texels/px | total ms | picture |\n");
    s.push_str("|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|\n");
    for e in &r.results {
        let m = &e.metrics;
        let v = |k: &str| e.vs_reference.get(k).copied();
        let density = match (v("texel_density_min"), v("texel_density_median")) {
            (Some(lo), Some(median)) => format!("{lo:.1e} / {median:.2}"),
            _ => "-".into(),
        };
        s.push_str(&format!(
            "| `{}` | {} | `{}` | {:.3}% | {:.3}% | {:.3}% | {:.3}% | {:.3}% | {:.3}% | {:.4} | {:.4} | {} | {:.1} | [png]({}.png) [errors]({}.err.png) |\n",
            e.technique,
            e.backend,
            e.reference,
            m.mismatch * 100.0,
            m.edge_band_mismatch * 100.0,
            m.interior_mismatch * 100.0,
            v("near_field_mismatch").unwrap_or(0.0) * 100.0,
            m.false_shadow * 100.0,
            m.false_light * 100.0,
            m.rmse,
            e.flip,
            density,
            e.timings_ms.get("total").copied().unwrap_or(0.0),
            e.file,
            e.file
        ));
    }
    s.push_str("\nSettings:\n\n");
    for e in &r.results {
        s.push_str(&format!("- `{}` ({}): `{}`\n", e.technique, e.backend, e.settings));
    }
    let tiled: Vec<&ResultEntry> = r.results.iter().filter(|e| e.atlas_tiles.iter().any(Option::is_some)).collect();
    if !tiled.is_empty() {
        s.push_str(
            "\nShadow-atlas tiles (the maps' side each light was given; the figures above are the first light's):\n\n",
        );
    }
    for e in tiled {
        let sides: Vec<String> =
            e.atlas_tiles.iter().enumerate().filter_map(|(k, t)| t.map(|t| format!("{k}: {t}"))).collect();
        s.push_str(&format!("- `{}` ({}): {}\n", e.technique, e.backend, sides.join(", ")));
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
