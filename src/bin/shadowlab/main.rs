//! The `shadowlab` command line (DESIGN 11). Exit status: 0 on success, 2 for a usage error, 1 for any
//! other error, with one line naming the cause. Every input is checked before anything is printed or
//! written, so a refusal is that one line.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clap::Parser;
use serde_json::json;
use shadow_core::FrameInputs;
use shadow_core::scenes::{self, SceneParams};
use shadow_core::technique::TechniqueSpec;
use shadowlab::compare::{CompareJob, run_compare};
use shadowlab::registry::LeftOut;
use shadowlab::setup::{OptionError, parse_size};
use shadowlab::{BackendChoice, Error, Renderer, TechniqueRegistry};

mod args;

use args::{Cli, Command, SceneArgs, TechniqueArgs, ViewArgs};
use bench::{BenchArgs, bench};

/// Writes a line to standard output. A closed pipe (`shadowlab techniques | head -1`) ends the program
/// quietly: whoever read the output has what they wanted.
macro_rules! out {
    () => { out!("") };
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        if let Err(e) = writeln!(std::io::stdout().lock(), $($arg)*) {
            return Err(stdout_error(&e));
        }
    }};
}

/// [`out!`] without the line break.
macro_rules! out_raw {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        if let Err(e) = write!(std::io::stdout().lock(), $($arg)*) {
            return Err(stdout_error(&e));
        }
    }};
}

mod bench;
mod inspect;

fn stdout_error(e: &std::io::Error) -> Error {
    if e.kind() == std::io::ErrorKind::BrokenPipe {
        std::process::exit(0);
    }
    Error::Write { path: "standard output".into(), why: e.to_string() }
}

fn main() -> ExitCode {
    private_runtime_dir();
    // A panic is a bug; it is said in one line, like every other failure, not as a backtrace.
    std::panic::set_hook(Box::new(|info| {
        let place = info.location().map_or_else(String::new, |l| format!(" at {}:{}", l.file(), l.line()));
        let what = info.payload_as_str().unwrap_or("a panic").replace('\n', " ");
        eprintln!("error: internal error{place}: {what} (a bug in shadowlab: please report the command)");
    }));
    let cli = Cli::parse();
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}{}", hint(&e));
            ExitCode::from(if e.is_usage() { 2 } else { 1 })
        }
    }
}

/// What the user can do about an error, where the CLI has a flag for it.
fn hint(e: &Error) -> &'static str {
    use shadow_core::assets::AssetFault;
    use shadowlab::SceneSourceError;
    use shadowlab::setup::SetupError;
    match e {
        Error::Setup(SetupError::Source(SceneSourceError::Asset(a)))
            if matches!(a.fault, AssetFault::OutsideFolder(_)) =>
        {
            " (--allow-outside-files reads it, for a model you trust)"
        }
        _ => "",
    }
}

/// Gives the process a private `XDG_RUNTIME_DIR` when it has none: without one the Vulkan loader prints
/// "error: XDG_RUNTIME_DIR is invalid or not set" twice on a run that then succeeds, and a line that
/// says `error:` must only ever be an error. The folder is the user's own (mode 0700) under the system's
/// temp folder; where it cannot be made, the loader's lines are left as they are.
#[allow(unsafe_code)]
fn private_runtime_dir() {
    if std::env::var_os("XDG_RUNTIME_DIR").is_some_and(|d| Path::new(&d).is_dir()) {
        return;
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::{DirBuilderExt, PermissionsExt};
        let user = std::env::var("USER").unwrap_or_else(|_| "user".into());
        let dir = std::env::temp_dir().join(format!("shadowlab-runtime-{user}"));
        let _ = std::fs::DirBuilder::new().mode(0o700).create(&dir);
        let private = std::fs::symlink_metadata(&dir).is_ok_and(|m| m.is_dir() && m.permissions().mode() & 0o077 == 0);
        if private {
            // SAFETY: called first thing in `main`, before any other thread exists, so nothing can be
            // reading the environment while it changes.
            unsafe { std::env::set_var("XDG_RUNTIME_DIR", &dir) };
        }
    }
}

fn run(cli: Cli) -> Result<(), Error> {
    match cli.command {
        Command::Scenes { json } => list_scenes(json),
        Command::Techniques { json } => list_techniques(json),
        Command::Inspect { target, json, allow_outside_files } => inspect::inspect(&target, json, allow_outside_files),
        Command::Render { scene, view, technique, backend, out } => render(&scene, &view, &technique, &backend, &out),
        Command::Compare { scene, view, choice, reference, out_dir } => {
            compare(&scene, &view, &choice, reference.as_deref(), out_dir)
        }
        Command::Bench {
            scene,
            view,
            choice,
            frames,
            warmup,
            json,
            realtime,
            rebuild,
            animate,
            sweep,
            out_dir,
            savings,
            motion,
            no_shadows,
        } => {
            let savings = bench::parse_savings(&savings)?;
            let camera = bench::parse_motion(&motion)?;
            let b = BenchArgs {
                choice,
                frames,
                warmup,
                json,
                realtime,
                rebuild,
                animate,
                sweep,
                out_dir,
                savings,
                camera,
                no_shadows,
            };
            bench(&scene, &view, b)
        }
        Command::Export { scene, out } => export(&scene, &out),
        Command::Flicker { scene, view, technique, frames, step, turn, time_step } => {
            flicker(&scene, &view, &technique, (frames, step, turn, time_step))
        }
        Command::View { scene, technique, backend, size, script } => view(&scene, technique, &backend, &size, script),
        Command::Results { out, size, backend, bench_scene, bench_size, bench_frames, outdoor_size } => {
            results(&out, (&size, &bench_size, &outdoor_size), &backend, bench_scene, bench_frames)
        }
    }
}

fn results(
    out: &Path,
    (size, bench_size, outdoor_size): (&str, &str, &str),
    backend: &str,
    bench_scene: String,
    bench_frames: u32,
) -> Result<(), Error> {
    use shadowlab::results::{ResultsJob, run_results};
    if bench_frames == 0 {
        return Err(Error::Usage("--bench-frames must be at least 1".into()));
    }
    if scenes::info(&bench_scene).is_none() {
        return Err(Error::Usage(format!("--bench-scene '{bench_scene}': not a built-in scene")));
    }
    let size = parse_size(size).map_err(|e| Error::Usage(e.to_string()))?;
    let bench_size =
        parse_size(bench_size).map_err(|e| Error::Usage(OptionError { flag: "--bench-size", ..e }.to_string()))?;
    let outdoor_size =
        parse_size(outdoor_size).map_err(|e| Error::Usage(OptionError { flag: "--outdoor-size", ..e }.to_string()))?;
    let pictures = out.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new(".")).to_path_buf();
    let mut renderer = Renderer::new(TechniqueRegistry::builtin());
    let kinds = backends(&mut renderer, backend)?;
    let command = std::env::args().skip(1).collect::<Vec<_>>().join(" ");
    let job = ResultsJob {
        command: format!("shadowlab {command}"),
        size,
        backends: kinds,
        bench_scene,
        bench_size,
        bench_frames,
        outdoor_size,
        pictures,
    };
    let text = run_results(&mut renderer, &job, |m| eprintln!("{m}"))?;
    std::fs::write(out, text).map_err(|e| Error::Write { path: out.to_path_buf(), why: e.to_string() })?;
    eprintln!("wrote {}", out.display());
    Ok(())
}

fn print_json(v: &serde_json::Value) -> Result<(), Error> {
    out!("{}", serde_json::to_string_pretty(v).map_err(|e| Error::Usage(e.to_string()))?);
    Ok(())
}

fn list_scenes(json: bool) -> Result<(), Error> {
    let rows: Vec<(&str, usize, &str, &str)> = scenes::every()
        .map(|info| {
            let tris = scenes::build(info.name, &SceneParams::default()).map(|s| s.triangle_count()).unwrap_or(0);
            (info.name, tris, info.description, info.after)
        })
        .collect();
    if json {
        return print_json(&json!(
            rows.iter()
                .map(|(n, t, d, a)| json!({"name": n, "triangles": t, "description": d, "after": a}))
                .collect::<Vec<_>>()
        ));
    }
    out!("{:<14} {:>9}  description", "scene", "triangles");
    for (n, t, d, a) in rows {
        out!("{n:<14} {t:>9}  {d} ({a})");
    }
    Ok(())
}

/// A setting as `techniques --json` lists it: what a viewer needs to make its control.
fn setting_json(k: &shadow_core::technique::SettingKey) -> serde_json::Value {
    use shadow_core::technique::settings::SettingKind;
    let mut v = json!({"key": k.key, "default": k.default, "help": k.help, "also": k.word});
    let (kind, values) = match k.kind {
        SettingKind::Int { lo, hi } => ("int", json!([lo, hi])),
        SettingKind::Float { lo, hi } => ("float", json!([lo, hi])),
        SettingKind::Choice(names) => ("choice", json!(names)),
    };
    v["type"] = json!(kind);
    v[if kind == "choice" { "choices" } else { "range" }] = values;
    v
}

fn list_techniques(json: bool) -> Result<(), Error> {
    let reg = TechniqueRegistry::builtin();
    let backends = |e: &shadowlab::TechniqueEntry| {
        let mut b = Vec::new();
        if e.cpu.is_some() {
            b.push("cpu");
        }
        if e.wgpu.is_some() {
            b.push("wgpu");
        }
        b
    };
    if json {
        let v: Vec<_> = reg
            .entries()
            .iter()
            .map(|e| {
                let keys: Vec<_> = (e.keys)().iter().map(setting_json).collect();
                let casters: serde_json::Map<String, serde_json::Value> =
                    e.casters.kinds().iter().map(|(kind, h)| ((*kind).to_string(), json!(h.name()))).collect();
                json!({"name": e.name, "description": e.description, "paper": e.paper, "reference": e.reference, "lights": e.lights.names(), "casters": casters, "settings": keys, "backends": backends(e)})
            })
            .collect();
        return print_json(&json!(v));
    }
    for e in reg.entries() {
        out!(
            "{}  [{}]\n  {}\n  paper: {}\n  lights: {}\n  casters: {}",
            e.name,
            backends(e).join(", "),
            e.description,
            e.paper,
            e.lights.names().join(", "),
            e.casters.describe()
        );
        for k in (e.keys)() {
            out!("    {:<28} {}", format!("{}={}", k.key, k.default), k.help);
        }
    }
    Ok(())
}

/// Checks that every technique exists on the backends `choice` names, before any backend is opened, so
/// the error names the real cause on a machine without a GPU too.
fn check_availability(renderer: &Renderer, specs: &[TechniqueSpec], choice: &str) -> Result<(), Error> {
    let choice: BackendChoice =
        choice.parse().map_err(|e: String| Error::Usage(format!("bad --backend '{choice}': expected {e}")))?;
    for s in specs {
        let e = renderer.registry().get(&s.name)?;
        let missing = match choice {
            BackendChoice::Cpu if e.cpu.is_none() => Some("cpu"),
            BackendChoice::Wgpu | BackendChoice::Both if e.wgpu.is_none() => Some("wgpu"),
            BackendChoice::Both if e.cpu.is_none() => Some("cpu"),
            _ => None,
        };
        if let Some(backend) = missing {
            return Err(shadowlab::RegistryError::NotOnBackend { name: s.name.clone(), backend }.into());
        }
    }
    Ok(())
}

#[cfg(feature = "viewer")]
fn view(args: &SceneArgs, technique: String, backend: &str, size: &str, script: Option<String>) -> Result<(), Error> {
    use shadowlab::viewer::{ViewerOptions, script::parse};
    let size = parse_size(size).map_err(|e| Error::Usage(e.to_string()))?;
    let script = script.map(|s| parse(&s)).transpose().map_err(Error::Usage)?.unwrap_or_default();
    TechniqueRegistry::builtin().canonical(&TechniqueSpec::parse(&technique)?)?;
    let backend = if backend == "cpu" { shadowlab::BackendKind::Cpu } else { shadowlab::BackendKind::Wgpu };
    shadowlab::viewer::run(ViewerOptions { setup: args.setup(), technique, backend, script, size })
}

/// Without the `viewer` feature there is no window to open: the one line says how to get one.
#[cfg(not(feature = "viewer"))]
fn view(_: &SceneArgs, _: String, _: &str, _: &str, _: Option<String>) -> Result<(), Error> {
    Err(Error::Window("this shadowlab was built without its `viewer` feature (cargo's `--features viewer`)".into()))
}

/// The `--backend` choice, or the usage error naming what it takes.
fn backend_choice(choice: &str) -> Result<BackendChoice, Error> {
    choice.parse().map_err(|e: String| Error::Usage(format!("bad --backend '{choice}': expected {e}")))
}

fn backends(renderer: &mut Renderer, choice: &str) -> Result<Vec<shadowlab::BackendKind>, Error> {
    let choice = backend_choice(choice)?;
    let (kinds, note) = renderer.resolve(choice)?;
    eprintln!("{note}");
    Ok(kinds)
}

fn render(args: &SceneArgs, view: &ViewArgs, technique: &str, backend: &str, out: &Path) -> Result<(), Error> {
    view.check_adapter(backend)?;
    let (frame, w, h) = args.frame(view)?;
    let spec = TechniqueSpec::parse(technique)?;
    let mut renderer = Renderer::new(TechniqueRegistry::builtin()).with_adapter(view.adapter.clone());
    renderer.registry().canonical(&spec)?;
    check_availability(&renderer, std::slice::from_ref(&spec), backend)?;
    for kind in backends(&mut renderer, backend)? {
        let run = renderer.run(kind, &frame, w, h, &spec)?;
        let path =
            if backend == "both" { out.with_extension(format!("{}.png", kind.name())) } else { out.to_path_buf() };
        run.color.save_png(&path)?;
        let mask = shadow_core::Image::new(w, h, true);
        shadow_core::image::visibility_to_rgb(&run.visibility[0], &mask).save_png(path.with_extension("vis.png"))?;
        eprintln!("{}: {} in {:.1} ms ({})", path.display(), run.technique, run.stats.timings.total, kind.name());
    }
    Ok(())
}

fn flicker(
    args: &SceneArgs,
    view: &ViewArgs,
    techniques: &[String],
    (frames, step, turn, time_step): (usize, f32, f32, f32),
) -> Result<(), Error> {
    use shadowlab::flicker::{FlickerWalk, walk};
    view.check_adapter("cpu")?;
    if frames < 2 {
        return Err(Error::Usage(format!("--frames {frames}: flicker needs at least 2")));
    }
    if !(step.is_finite() && turn.is_finite() && time_step.is_finite()) {
        return Err(Error::Usage("--step, --turn and --time-step must be finite numbers".into()));
    }
    let (w, h) = view.size()?;
    let mut scene = args.setup().build()?;
    args::print_warnings(&scene);
    let frame = FrameInputs::from_first_camera(&scene)?;
    let specs: Vec<TechniqueSpec> = techniques.iter().map(|t| TechniqueSpec::parse(t)).collect::<Result<_, _>>()?;
    let mut renderer = Renderer::new(TechniqueRegistry::builtin());
    for spec in &specs {
        renderer.registry().canonical(spec)?;
    }
    check_availability(&renderer, &specs, "cpu")?;
    let path = walk(&frame.camera, frames, step, turn.to_radians());
    let bar = progress_bar((frames * specs.len()) as u64);
    let walk = if time_step == 0.0 {
        FlickerWalk::new(&mut renderer, &frame, &path, (w, h))?
    } else {
        if scene.animations().next().is_none() {
            return Err(Error::Usage(format!("--time-step {time_step}: {} has no animations to step", args.scene)));
        }
        // The scene posed a step later at every frame, from --time (or its start).
        let start = args.time.unwrap_or(0.0);
        let mut posed = Vec::with_capacity(frames);
        for (k, camera) in path.iter().enumerate() {
            scene.pose(start + time_step * k as f32).map_err(|e| Error::Usage(e.to_string()))?;
            posed.push(FrameInputs { camera: *camera, ..FrameInputs::from_first_camera(&scene)? });
        }
        FlickerWalk::through(&mut renderer, posed, (w, h))?
    };
    let mut rows = Vec::new();
    for spec in &specs {
        let f = walk.flicker(&mut renderer, spec, |k| report_progress(&bar, &format!("{spec} frame {k}")))?;
        rows.push((spec.to_string(), f));
    }
    if let Some(b) = bar {
        b.finish_and_clear();
    }
    let time = if time_step == 0.0 { String::new() } else { format!(", {time_step} s of the animation per frame") };
    out!("{frames} frames, {step} per frame, {turn} degrees per frame{time}, {w}x{h}, on the cpu");
    out!("{:<48} {:>10}", "technique", "flicker");
    for (name, f) in rows {
        out!("{name:<48} {:>9.4}%", f * 100.0);
    }
    Ok(())
}

fn compare(
    args: &SceneArgs,
    view: &ViewArgs,
    choice: &TechniqueArgs,
    reference: Option<&str>,
    out_dir: Option<PathBuf>,
) -> Result<(), Error> {
    let backend = choice.backend.as_str();
    view.check_adapter(backend)?;
    let mut renderer = Renderer::new(TechniqueRegistry::builtin()).with_adapter(view.adapter.clone());
    let (frame, w, h) = args.frame(view)?;
    let (specs, left) = technique_specs(&renderer, &choice.technique, choice.techniques.as_deref(), &frame)?;
    let (reference, soft_reference) = match reference {
        Some(text) => {
            let spec = TechniqueSpec::parse(text)?;
            if !renderer.registry().get(&spec.name)?.reference {
                return Err(Error::Usage(format!("--reference {text}: '{}' is not a reference technique", spec.name)));
            }
            renderer.registry().canonical(&spec)?;
            (spec, None)
        }
        None => shadowlab::compare::references_for(renderer.registry(), &specs),
    };
    check_availability(&renderer, &specs, backend)?;
    backend_choice(backend)?;
    say_left_out(&left);
    let kinds = backends(&mut renderer, backend)?;
    let out = out_dir.unwrap_or_else(|| PathBuf::from(format!("out/compare-{}", args.name())));
    let job = CompareJob {
        scene: args.name(),
        frame: &frame,
        width: w,
        height: h,
        reference,
        soft_reference,
        techniques: specs,
        backends: kinds,
        out_dir: Some(out.clone()),
    };
    let bar = progress_bar((job.techniques.len() * job.backends.len() + 1) as u64);
    let report = run_compare(&mut renderer, &job, |msg| report_progress(&bar, msg))?;
    if let Some(b) = bar {
        b.finish_and_clear();
    }
    out!(
        "{:<24} {:<5} {:<21} {:>9} {:>9} {:>9} {:>9} {:>7} {:>7} {:>13} {:>9}",
        "technique",
        "",
        "reference",
        "mismatch",
        "edge",
        "interior",
        "near",
        "RMSE",
        "FLIP",
        "texels/px",
        "total ms"
    );
    for r in &report.results {
        let m = &r.metrics;
        let v = |k: &str| r.vs_reference.get(k).copied();
        let density = match (v("texel_density_min"), v("texel_density_median")) {
            (Some(lo), Some(median)) => format!("{lo:.1e} / {median:.2}"),
            _ => "-".into(),
        };
        out!(
            "{:<24} {:<5} {:<21} {:>8.3}% {:>8.3}% {:>8.3}% {:>8.3}% {:>7.4} {:>7.4} {:>13} {:>9.1}",
            r.technique,
            r.backend,
            r.reference,
            m.mismatch * 100.0,
            m.edge_band_mismatch * 100.0,
            m.interior_mismatch * 100.0,
            v("near_field_mismatch").unwrap_or(0.0) * 100.0,
            m.rmse,
            r.flip,
            density,
            r.timings_ms.get("total").copied().unwrap_or(0.0)
        );
    }
    if !report.cross_backend.is_empty() {
        out!("\n{:<24} {:>20} {:>7} {:>7}", "cpu vs wgpu", "mismatch", "RMSE", "FLIP");
        for c in &report.cross_backend {
            out!("{:<24} {:>19.3}% {:>7.4} {:>7.4}", c.technique, c.mismatch * 100.0, c.rmse, c.flip_mean);
        }
    }
    for note in &report.notes {
        out!("note: {note}");
    }
    out!("wrote {}/contact.png, report.md, report.json", out.display());
    Ok(())
}

/// The technique specs of --technique and --techniques (every non-reference technique when neither; of
/// those, the ones that take every light of `frame`), and the names of those left out.
fn technique_specs(
    renderer: &Renderer,
    technique: &[String],
    techniques: Option<&str>,
    frame: &FrameInputs,
) -> Result<(Vec<TechniqueSpec>, Vec<LeftOut>), Error> {
    let mut specs: Vec<TechniqueSpec> = technique.iter().map(|t| TechniqueSpec::parse(t)).collect::<Result<_, _>>()?;
    let mut left = Vec::new();
    let mut all = || {
        let (taken, refused) = renderer.registry().measurable(frame);
        left = refused;
        taken
    };
    match techniques {
        Some("all") => specs.extend(all()),
        Some(list) => {
            specs.extend(list.split(',').filter(|s| !s.trim().is_empty()).map(|s| TechniqueSpec::named(s.trim())))
        }
        None if specs.is_empty() => specs.extend(all()),
        None => {}
    }
    for s in &specs {
        renderer.registry().canonical(s)?;
    }
    if frame.has_cutout_casters() {
        let takes_none = |e: &shadowlab::TechniqueEntry| !e.casters.takes_cutouts();
        for s in specs.iter().filter(|s| renderer.registry().get(&s.name).is_ok_and(takes_none)) {
            eprintln!(
                "warning: {} takes no masked casters: those this scene's textures cut out shadow as solid in it",
                s.name
            );
        }
    }
    Ok((specs, left))
}

/// Names the techniques a run leaves out and why, a line for each reason, once every input has been
/// checked (a refused run says one line, its error).
fn say_left_out(left: &[LeftOut]) {
    let mut reasons: Vec<&str> = Vec::new();
    for l in left {
        if !reasons.contains(&l.why) {
            reasons.push(l.why);
        }
    }
    for why in reasons {
        let names: Vec<&str> = left.iter().filter(|l| l.why == why).map(|l| l.name).collect();
        eprintln!("left out, {why}: {}", names.join(", "));
    }
}

/// A progress bar when stderr is a terminal; plain lines otherwise.
fn progress_bar(steps: u64) -> Option<indicatif::ProgressBar> {
    std::io::stderr().is_terminal().then(|| {
        let b = indicatif::ProgressBar::new(steps);
        let style = indicatif::ProgressStyle::with_template("{bar:30} {pos}/{len} {msg}");
        b.set_style(style.unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()));
        b
    })
}

fn report_progress(bar: &Option<indicatif::ProgressBar>, msg: &str) {
    match bar {
        Some(b) => {
            b.set_message(msg.to_string());
            b.inc(1);
        }
        None => eprintln!("{msg}"),
    }
}

fn export(args: &SceneArgs, out: &Path) -> Result<(), Error> {
    let extension = out.extension().map(|e| e.to_string_lossy().to_ascii_lowercase());
    if !matches!(extension.as_deref(), Some("glb" | "gltf")) {
        return Err(Error::Usage(format!("--out {}: expected a .glb or .gltf file", out.display())));
    }
    let scene = args.setup().build()?;
    args::print_warnings(&scene);
    shadow_core::assets::export::export(&scene, out)
        .map_err(|e| Error::Write { path: e.path.into(), why: e.source.to_string() })?;
    out!("wrote {} ({} triangles)", out.display(), scene.triangle_count());
    Ok(())
}
