//! The `shadowlab` command line (DESIGN 11). Exit status: 0 on success, 2 for a usage error, 1 for any
//! other error, with one line naming the cause.

use std::process::ExitCode;

use clap::{Parser, Subcommand};
use serde_json::json;
use shadow_core::inspect::Inspection;
use shadow_core::scenes::{self, SceneParams};

#[derive(Parser)]
#[command(
    name = "shadowlab",
    version,
    about = "Real-time shadow techniques, on the GPU and on a CPU reference, measured against ray-traced ground truth"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// List the built-in scenes with their triangle counts.
    Scenes {
        /// Print JSON.
        #[arg(long)]
        json: bool,
    },
    /// Mesh statistics of a model file or built-in scene: triangles, welded vertices, closedness, edge
    /// counts, bounds, silhouette edges from the default light.
    Inspect {
        /// A built-in scene name or a model file (.obj, .gltf, .glb, .ply, .ply.gz).
        target: String,
        /// Print JSON.
        #[arg(long)]
        json: bool,
    },
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(1)
        }
    }
}

fn run(cli: Cli) -> Result<(), Box<dyn std::error::Error>> {
    match cli.command {
        Command::Scenes { json } => list_scenes(json),
        Command::Inspect { target, json } => inspect(&target, json),
    }
}

fn list_scenes(json: bool) -> Result<(), Box<dyn std::error::Error>> {
    let rows: Vec<(&str, usize, &str, &str)> = scenes::ALL
        .iter()
        .map(|info| {
            let tris = scenes::build(info.name, &SceneParams::default()).map(|s| s.triangle_count()).unwrap_or(0);
            (info.name, tris, info.description, info.after)
        })
        .collect();
    if json {
        let v: Vec<_> =
            rows.iter().map(|(n, t, d, a)| json!({"name": n, "triangles": t, "description": d, "after": a})).collect();
        println!("{}", serde_json::to_string_pretty(&v)?);
    } else {
        println!("{:<14} {:>9}  description", "scene", "triangles");
        for (n, t, d, a) in rows {
            println!("{n:<14} {t:>9}  {d} ({a})");
        }
    }
    Ok(())
}

fn inspect(target: &str, json: bool) -> Result<(), Box<dyn std::error::Error>> {
    let path = std::path::Path::new(target);
    let is_file = shadow_core::assets::is_model_path(path) || path.exists();
    let scene = if !is_file {
        scenes::build(target, &SceneParams::default())?
    } else {
        // The file's own numbers; the silhouette is taken from the default staged light, moved into the
        // file's frame by staging a copy.
        let raw = shadowlab::load_model(path)?;
        let bounds = raw.bounds();
        let staged = shadowlab::load_scene(target, &SceneParams::default(), false)?;
        let mut i = Inspection::of(&raw);
        i.silhouette_edges = Inspection::of(&staged).silhouette_edges;
        i.bounds = bounds;
        return print_inspection(target, &i, json);
    };
    print_inspection(target, &Inspection::of(&scene), json)
}

fn print_inspection(target: &str, i: &Inspection, json: bool) -> Result<(), Box<dyn std::error::Error>> {
    if json {
        let v = json!({
            "triangles": i.triangles,
            "vertices": i.vertices,
            "closed": i.closed,
            "boundary_edges": i.boundary_edges,
            "non_manifold_edges": i.non_manifold_edges,
            "inconsistent_edges": i.inconsistent_edges,
            "bounds": {"min": i.bounds.min.to_array(), "max": i.bounds.max.to_array()},
            "silhouette_edges": i.silhouette_edges,
        });
        println!("{}", serde_json::to_string_pretty(&v)?);
    } else {
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
    }
    Ok(())
}
