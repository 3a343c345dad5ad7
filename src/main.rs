//! The `shadowlab` command line (DESIGN 11). Exit status: 0 on success, 2 for a usage error, 1 for any
//! other error, with one line naming the cause.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clap::{Args, Parser, Subcommand};
use serde_json::json;
use shadow_core::FrameInputs;
use shadow_core::inspect::Inspection;
use shadow_core::scenes::{self, SceneParams};
use shadow_core::technique::TechniqueSpec;
use shadowlab::compare::{CompareJob, run_compare};
use shadowlab::setup::{SceneSetup, parse_size};
use shadowlab::{BackendChoice, Error, Renderer, TechniqueRegistry};

#[derive(Parser)]
#[command(
    name = "shadowlab",
    version,
    about = "Real-time shadow techniques on the GPU and on a CPU reference, measured against ray-traced ground truth"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

/// Where and how to look.
#[derive(Args, Clone)]
struct SceneArgs {
    /// A built-in scene (see `shadowlab scenes`) or a model file (.obj, .gltf, .glb, .ply, .ply.gz).
    #[arg(long, default_value = "cylinder")]
    scene: String,
    /// Ground under a model file: plane or none.
    #[arg(long, default_value = "plane", value_parser = ["plane", "none"])]
    ground: String,
    /// Camera override: eye=X,Y,Z,target=X,Y,Z[,fov=DEG].
    #[arg(long)]
    camera: Option<String>,
    /// Light override: spot|directional|point[,pos=X,Y,Z][,target=X,Y,Z][,fov=DEG][,radius=R].
    #[arg(long)]
    light: Option<String>,
    /// Seed for scenes with random placement.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// View size, WxH.
    #[arg(long, default_value = "512x512")]
    size: String,
    /// wgpu adapter by name substring (also SHADOWLAB_ADAPTER); software adapters such as lavapipe only
    /// when named or with --backend wgpu.
    #[arg(long)]
    adapter: Option<String>,
}

impl SceneArgs {
    fn setup(&self) -> SceneSetup {
        SceneSetup {
            source: self.scene.clone(),
            ground: self.ground == "plane",
            params: SceneParams { light: None, seed: self.seed },
            camera: self.camera.clone(),
            light: self.light.clone(),
        }
    }

    fn frame(&self) -> Result<(FrameInputs, u32, u32), Error> {
        let (w, h) = parse_size(&self.size).map_err(|e| Error::Usage(e.to_string()))?;
        let scene = self.setup().build()?;
        let cam =
            scene.cameras().next().map(|(k, _)| k).ok_or_else(|| Error::Usage("the scene has no camera".into()))?;
        Ok((FrameInputs::from_scene(&scene, cam)?, w, h))
    }

    fn name(&self) -> String {
        Path::new(&self.scene).file_stem().and_then(|s| s.to_str()).unwrap_or(&self.scene).to_string()
    }
}

#[derive(Subcommand)]
enum Command {
    /// List the built-in scenes with their triangle counts.
    Scenes {
        /// Print JSON.
        #[arg(long)]
        json: bool,
    },
    /// List the techniques: description, paper, settings with defaults, backends.
    Techniques {
        /// Print JSON.
        #[arg(long)]
        json: bool,
    },
    /// Mesh statistics of a model file or built-in scene.
    Inspect {
        /// A built-in scene name or a model file.
        target: String,
        /// Print JSON.
        #[arg(long)]
        json: bool,
    },
    /// Render one technique: the shaded image and its visibility.
    Render {
        #[command(flatten)]
        scene: SceneArgs,
        /// NAME[:key=value,...].
        #[arg(long, default_value = "shadow-volume-zfail")]
        technique: String,
        /// Backend: auto, cpu, wgpu or both.
        #[arg(long, default_value = "auto")]
        backend: String,
        /// The shaded PNG; the visibility goes beside it as .vis.png.
        #[arg(long, short, default_value = "render.png")]
        out: PathBuf,
    },
    /// Every asked-for technique against the ray-traced reference: pictures, error maps, a contact sheet,
    /// report.md and report.json.
    Compare {
        #[command(flatten)]
        scene: SceneArgs,
        /// NAME[:key=value,...], repeatable.
        #[arg(long)]
        technique: Vec<String>,
        /// all, or NAME,NAME with default settings.
        #[arg(long)]
        techniques: Option<String>,
        /// Backend: auto, cpu, wgpu or both.
        #[arg(long, default_value = "auto")]
        backend: String,
        /// Output folder (default out/compare-SCENE).
        #[arg(long)]
        out_dir: Option<PathBuf>,
    },
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(if e.is_usage() { 2 } else { 1 })
        }
    }
}

fn run(cli: Cli) -> Result<(), Error> {
    match cli.command {
        Command::Scenes { json } => list_scenes(json),
        Command::Techniques { json } => list_techniques(json),
        Command::Inspect { target, json } => inspect(&target, json),
        Command::Render { scene, technique, backend, out } => render(&scene, &technique, &backend, &out),
        Command::Compare { scene, technique, techniques, backend, out_dir } => {
            compare(&scene, technique, techniques, &backend, out_dir)
        }
    }
}

fn print_json(v: &serde_json::Value) -> Result<(), Error> {
    println!("{}", serde_json::to_string_pretty(v).map_err(|e| Error::Usage(e.to_string()))?);
    Ok(())
}

fn list_scenes(json: bool) -> Result<(), Error> {
    let rows: Vec<(&str, usize, &str, &str)> = scenes::ALL
        .iter()
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
    println!("{:<14} {:>9}  description", "scene", "triangles");
    for (n, t, d, a) in rows {
        println!("{n:<14} {t:>9}  {d} ({a})");
    }
    Ok(())
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
                let keys: Vec<_> = (e.keys)().iter().map(|k| json!({"key": k.key, "default": k.default, "help": k.help})).collect();
                json!({"name": e.name, "description": e.description, "paper": e.paper, "reference": e.reference, "settings": keys, "backends": backends(e)})
            })
            .collect();
        return print_json(&json!(v));
    }
    for e in reg.entries() {
        println!("{}  [{}]\n  {}\n  paper: {}", e.name, backends(e).join(", "), e.description, e.paper);
        for k in (e.keys)() {
            println!("    {}={:<10} {}", k.key, k.default, k.help);
        }
    }
    Ok(())
}

fn inspect(target: &str, json: bool) -> Result<(), Error> {
    let path = Path::new(target);
    let is_file = shadow_core::assets::is_model_path(path) || path.exists();
    let i = if is_file {
        // The file's own numbers; the silhouette from the default staged light.
        let raw =
            shadowlab::load_model(path).map_err(|e| Error::Setup(shadowlab::SceneSourceError::Asset(e).into()))?;
        let staged = SceneSetup { ground: false, ..SceneSetup::new(target) }.build()?;
        Inspection { silhouette_edges: Inspection::of(&staged).silhouette_edges, ..Inspection::of(&raw) }
    } else {
        Inspection::of(&SceneSetup::new(target).build()?)
    };
    if json {
        return print_json(&json!({
            "triangles": i.triangles,
            "vertices": i.vertices,
            "closed": i.closed,
            "boundary_edges": i.boundary_edges,
            "non_manifold_edges": i.non_manifold_edges,
            "inconsistent_edges": i.inconsistent_edges,
            "bounds": {"min": i.bounds.min.to_array(), "max": i.bounds.max.to_array()},
            "silhouette_edges": i.silhouette_edges,
        }));
    }
    println!("{target}");
    println!("  triangles           {}", i.triangles);
    println!("  vertices (welded)   {}", i.vertices);
    println!("  closed              {}", i.closed);
    println!("  boundary edges      {}", i.boundary_edges);
    println!("  non-manifold edges  {}", i.non_manifold_edges);
    println!("  inconsistent edges  {}", i.inconsistent_edges);
    println!("  bounds              {} .. {}", i.bounds.min, i.bounds.max);
    match i.silhouette_edges {
        Some(n) => println!("  silhouette edges    {n} (default light)"),
        None => println!("  silhouette edges    - (no light)"),
    }
    Ok(())
}

fn backends(renderer: &mut Renderer, choice: &str) -> Result<Vec<shadowlab::BackendKind>, Error> {
    let choice: BackendChoice =
        choice.parse().map_err(|e: String| Error::Usage(format!("bad --backend '{choice}': expected {e}")))?;
    let (kinds, note) = renderer.resolve(choice)?;
    eprintln!("{note}");
    Ok(kinds)
}

fn render(args: &SceneArgs, technique: &str, backend: &str, out: &Path) -> Result<(), Error> {
    let (frame, w, h) = args.frame()?;
    let spec = TechniqueSpec::parse(technique)?;
    let mut renderer = Renderer::new(TechniqueRegistry::builtin()).with_adapter(args.adapter.clone());
    renderer.registry().canonical(&spec)?;
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

fn compare(
    args: &SceneArgs,
    technique: Vec<String>,
    techniques: Option<String>,
    backend: &str,
    out_dir: Option<PathBuf>,
) -> Result<(), Error> {
    let mut renderer = Renderer::new(TechniqueRegistry::builtin()).with_adapter(args.adapter.clone());
    let kinds = backends(&mut renderer, backend)?;
    let mut specs: Vec<TechniqueSpec> = technique.iter().map(|t| TechniqueSpec::parse(t)).collect::<Result<_, _>>()?;
    match techniques.as_deref() {
        Some("all") => specs.extend(
            renderer.registry().entries().iter().filter(|e| !e.reference).map(|e| TechniqueSpec::named(e.name)),
        ),
        Some(list) => {
            specs.extend(list.split(',').filter(|s| !s.trim().is_empty()).map(|s| TechniqueSpec::named(s.trim())))
        }
        None if specs.is_empty() => specs.extend(
            renderer.registry().entries().iter().filter(|e| !e.reference).map(|e| TechniqueSpec::named(e.name)),
        ),
        None => {}
    }
    for s in &specs {
        renderer.registry().canonical(s)?;
    }
    let (frame, w, h) = args.frame()?;
    let out = out_dir.unwrap_or_else(|| PathBuf::from(format!("out/compare-{}", args.name())));
    let job = CompareJob {
        scene: args.name(),
        frame: &frame,
        width: w,
        height: h,
        techniques: specs,
        backends: kinds,
        out_dir: Some(out.clone()),
    };
    let steps = (job.techniques.len() * job.backends.len() + 1) as u64;
    let bar = std::io::stderr().is_terminal().then(|| {
        let b = indicatif::ProgressBar::new(steps);
        b.set_style(
            indicatif::ProgressStyle::with_template("{bar:30} {pos}/{len} {msg}")
                .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
        );
        b
    });
    let report = run_compare(&mut renderer, &job, |msg| match &bar {
        Some(b) => {
            b.set_message(msg.to_string());
            b.inc(1);
        }
        None => eprintln!("{msg}"),
    })?;
    if let Some(b) = bar {
        b.finish_and_clear();
    }
    println!(
        "{:<24} {:<5} {:>9} {:>9} {:>9} {:>8} {:>9}",
        "technique", "", "mismatch", "edge", "interior", "FLIP", "total ms"
    );
    for r in &report.results {
        let m = &r.metrics;
        println!(
            "{:<24} {:<5} {:>8.3}% {:>8.3}% {:>8.3}% {:>8.4} {:>9.1}",
            r.technique,
            r.backend,
            m.mismatch * 100.0,
            m.edge_band_mismatch * 100.0,
            m.interior_mismatch * 100.0,
            r.flip,
            r.timings_ms.get("total").copied().unwrap_or(0.0)
        );
    }
    println!("wrote {}/contact.png, report.md, report.json", out.display());
    Ok(())
}
