//! `shadowlab bench`: techniques timed over frames with the light moving, per phase, on the offline or
//! the real-time path, or swept over a map resolution or a triangle count into a CSV and a plot.

use std::path::PathBuf;

use shadow_core::frame::Savings;
use shadow_core::technique::TechniqueSpec;
use shadow_core::{FrameInputs, LightShadow};
use shadowlab::{Error, Renderer, TechniqueRegistry};

use crate::args::{SceneArgs, TechniqueArgs, ViewArgs};
use crate::{
    backend_choice, backends, check_availability, print_json, progress_bar, report_progress, say_left_out,
    stdout_error, technique_specs,
};

pub(crate) struct BenchArgs {
    pub(crate) choice: TechniqueArgs,
    pub(crate) frames: u32,
    pub(crate) warmup: u32,
    pub(crate) json: bool,
    pub(crate) realtime: bool,
    pub(crate) rebuild: bool,
    pub(crate) animate: bool,
    pub(crate) sweep: Option<String>,
    pub(crate) out_dir: Option<PathBuf>,
    pub(crate) savings: Vec<Savings>,
    /// `--move camera`: the camera moves, the lights stand still.
    pub(crate) camera: bool,
    pub(crate) no_shadows: bool,
}

/// `--move`: lights or camera (true).
pub(crate) fn parse_motion(s: &str) -> Result<bool, Error> {
    match s {
        "lights" => Ok(false),
        "camera" => Ok(true),
        _ => Err(Error::Usage(format!("bad --move '{s}': expected lights or camera"))),
    }
}

/// `--savings`: all, none or both (every technique twice, side by side).
pub(crate) fn parse_savings(s: &str) -> Result<Vec<Savings>, Error> {
    match s {
        "all" => Ok(vec![Savings::ALL]),
        "none" => Ok(vec![Savings::NONE]),
        "both" => Ok(vec![Savings::ALL, Savings::NONE]),
        _ => Err(Error::Usage(format!("bad --savings '{s}': expected all, none or both"))),
    }
}

/// `--sweep KEY=V,V,...` as (key, values).
fn parse_sweep(sweep: &str) -> Result<(&str, Vec<u32>), Error> {
    let bad = |why: &str| Error::Usage(format!("bad --sweep '{sweep}': {why}"));
    let (key, values) = sweep.split_once('=').ok_or_else(|| bad("expected res=N,N,... or tris=N,N,..."))?;
    if key != "res" && key != "tris" {
        return Err(bad("the parameter must be res or tris"));
    }
    let values: Vec<u32> = values
        .split(',')
        .map(|v| v.trim().parse::<u32>().ok().filter(|&v| v > 0))
        .collect::<Option<_>>()
        .ok_or_else(|| bad("values must be positive whole numbers"))?;
    Ok((key, values))
}

pub(crate) fn bench(args: &SceneArgs, view: &ViewArgs, b: BenchArgs) -> Result<(), Error> {
    use shadowlab::bench::sweep_scene;
    if b.frames == 0 {
        return Err(Error::Usage("--frames must be at least 1".into()));
    }
    let sweep = b.sweep.as_deref().map(parse_sweep).transpose()?;
    if b.realtime && sweep.is_some() {
        return Err(Error::Usage("--realtime does not sweep: leave out --sweep".into()));
    }
    if b.animate && sweep.is_some() {
        return Err(Error::Usage("--animate plays the scene's own clip: leave out --sweep".into()));
    }
    if b.animate && b.camera {
        return Err(Error::Usage("--animate plays the scene's own clip: leave out --move camera".into()));
    }
    if b.realtime && b.rebuild {
        return Err(Error::Usage("--rebuild times the instrumented frames: leave out --realtime".into()));
    }
    if b.realtime && !["auto", "wgpu"].contains(&b.choice.backend.as_str()) {
        return Err(Error::Usage(format!("--realtime runs on the wgpu backend, not '{}'", b.choice.backend)));
    }
    view.check_adapter(&b.choice.backend)?;
    let mut renderer = Renderer::new(TechniqueRegistry::builtin()).with_adapter(view.adapter.clone());
    // The scene and its view are checked before the backend says which it is.
    let mut first = args.frame(view)?;
    if b.no_shadows {
        first.0.shadows = vec![LightShadow::NONE; first.0.lights.len()];
    }
    let (specs, left) = technique_specs(&renderer, &b.choice.technique, b.choice.techniques.as_deref(), &first.0)?;
    check_availability(&renderer, &specs, &b.choice.backend)?;
    // A triangle sweep's scenes are built up front too: a count too large is refused before anything runs.
    let mut sweep_scenes = Vec::new();
    if let Some(("tris", values)) = &sweep {
        for &v in values {
            sweep_scenes.push(sweep_scene(v).map_err(|e| Error::Usage(format!("--sweep tris={v}: {e}")))?);
        }
    }
    let clip = if b.animate {
        let mut scene = args.setup().build()?;
        let start = args.time.unwrap_or(0.0);
        Some(shadowlab::bench::Clip::play(&mut scene, start, 1.0 / 30.0, b.warmup + b.frames)?)
    } else {
        None
    };
    let backend = if b.realtime { "wgpu" } else { &b.choice.backend };
    backend_choice(backend)?;
    say_left_out(&left);
    let kinds = backends(&mut renderer, backend)?;
    match sweep {
        None => bench_once(&mut renderer, (args, first), specs, kinds, &b, clip.as_ref()),
        Some((key, values)) => {
            let sweep = Sweep { key, values, scenes: sweep_scenes };
            bench_sweep(&mut renderer, (args, view), &sweep, specs, kinds, &b)
        }
    }
}

/// One bench run of the scene's own frame (with `--realtime`, the real-time path beside the instrumented
/// frames): the table, or JSON.
fn bench_once(
    renderer: &mut Renderer,
    (args, (frame, w, h)): (&SceneArgs, (FrameInputs, u32, u32)),
    specs: Vec<TechniqueSpec>,
    kinds: Vec<shadowlab::BackendKind>,
    b: &BenchArgs,
    clip: Option<&shadowlab::bench::Clip>,
) -> Result<(), Error> {
    use shadowlab::bench::realtime::{realtime_steps, realtime_table, run_realtime_bench};
    use shadowlab::bench::{BenchJob, Motion, bench_table, run_bench};
    let job = BenchJob {
        scene: args.name(),
        frame: &frame,
        width: w,
        height: h,
        frames: b.frames,
        warmup: b.warmup,
        techniques: specs,
        backends: kinds,
        rebuild: b.rebuild,
        motion: match clip {
            Some(clip) => Motion::Clip(clip),
            None if b.camera => Motion::Camera,
            None => Motion::Lights,
        },
        savings: b.savings.clone(),
    };
    let bar = progress_bar(if b.realtime { realtime_steps(&job) } else { job.steps() });
    let (json, table) = if b.realtime {
        let r = run_realtime_bench(renderer, &job, |m| report_progress(&bar, m))?;
        (serde_json::to_value(&r), realtime_table(&r))
    } else {
        let r = run_bench(renderer, &job, |m| report_progress(&bar, m))?;
        (serde_json::to_value(&r), bench_table(&r))
    };
    if let Some(bar) = bar {
        bar.finish_and_clear();
    }
    if b.json {
        return print_json(&json.map_err(|e| Error::Usage(e.to_string()))?);
    }
    out_raw!("{table}");
    Ok(())
}

/// A `--sweep`: the parameter, its values, and for a triangle sweep the scene of each value.
struct Sweep<'a> {
    key: &'a str,
    values: Vec<u32>,
    scenes: Vec<shadow_core::Scene>,
}

/// A bench run per value of a sweep, written as sweep.csv and plotted as sweep.png.
fn bench_sweep(
    renderer: &mut Renderer,
    (args, view): (&SceneArgs, &ViewArgs),
    sweep: &Sweep<'_>,
    specs: Vec<TechniqueSpec>,
    kinds: Vec<shadowlab::BackendKind>,
    b: &BenchArgs,
) -> Result<(), Error> {
    use shadow_core::technique::maps::RESOLUTION;
    use shadowlab::bench::{BenchJob, run_bench};
    let key = sweep.key;
    let has_res = |s: &TechniqueSpec| {
        renderer.registry().get(&s.name).is_ok_and(|e| (e.keys)().iter().any(|k| k.key == RESOLUTION))
    };
    let specs: Vec<TechniqueSpec> = if key == RESOLUTION { specs.into_iter().filter(has_res).collect() } else { specs };
    if specs.is_empty() {
        return Err(Error::Usage("--sweep res needs a technique with a res setting".into()));
    }
    let out = b.out_dir.clone().unwrap_or_else(|| PathBuf::from(format!("out/bench-{}", args.name())));
    std::fs::create_dir_all(&out).map_err(|e| Error::Write { path: out.clone(), why: e.to_string() })?;
    let mut csv = String::from("parameter,value,technique,backend,gbuffer_ms,build_ms,query_ms,shade_ms,total_ms\n");
    let mut series: std::collections::BTreeMap<String, Vec<(f64, f64)>> = Default::default();
    // Per value, as `BenchJob::steps` counts them: per backend, each technique prepared, then the frames.
    let steps = kinds.len() as u64 * (specs.len() as u64 + u64::from(b.warmup + b.frames));
    let bar = progress_bar(sweep.values.len() as u64 * steps);
    for (i, &v) in sweep.values.iter().enumerate() {
        let (mut frame, w, h) = if key == RESOLUTION {
            args.frame(view)?
        } else {
            let (w, h) = view.size()?;
            (FrameInputs::from_first_camera(&sweep.scenes[i])?, w, h)
        };
        if b.no_shadows {
            frame.shadows = vec![LightShadow::NONE; frame.lights.len()];
        }
        let with_value: Vec<TechniqueSpec> = specs
            .iter()
            .map(|s| {
                let mut s = s.clone();
                if key == RESOLUTION {
                    s.values.retain(|(k, _)| k != RESOLUTION);
                    s.values.push((RESOLUTION.into(), v.to_string()));
                }
                s
            })
            .collect();
        let job = BenchJob {
            scene: args.name(),
            frame: &frame,
            width: w,
            height: h,
            frames: b.frames,
            warmup: b.warmup,
            techniques: with_value,
            backends: kinds.clone(),
            rebuild: b.rebuild,
            motion: if b.camera { shadowlab::bench::Motion::Camera } else { shadowlab::bench::Motion::Lights },
            savings: b.savings.clone(),
        };
        let r = run_bench(renderer, &job, |m| report_progress(&bar, &format!("{key}={v}: {m}")))?;
        for e in &r.results {
            let med = |k: &str| e.timings_ms.get(k).map_or(0.0, |t| t.median);
            let phases = ["gbuffer", "build", "query", "shade", "total"].map(|k| format!("{:.3}", med(k))).join(",");
            csv.push_str(&format!("{key},{v},{},{},{phases}\n", e.technique, e.backend));
            series.entry(format!("{} {}", e.technique, e.backend)).or_default().push((f64::from(v), med("total")));
        }
    }
    if let Some(bar) = bar {
        bar.finish_and_clear();
    }
    std::fs::write(out.join("sweep.csv"), &csv)
        .map_err(|e| Error::Write { path: out.join("sweep.csv"), why: e.to_string() })?;
    let x_label = if key == RESOLUTION { "shadow map side (texels)" } else { "triangles" };
    let series: Vec<(String, Vec<(f64, f64)>)> = series.into_iter().collect();
    shadowlab::plot::line_plot(&format!("{} frame time", args.name()), x_label, "median ms per frame", &series)
        .save_png(out.join("sweep.png"))?;
    out_raw!("{csv}");
    out!("wrote {}/sweep.csv and sweep.png", out.display());
    Ok(())
}
