//! A technique written outside the workspace crates, through their public APIs alone, on both backends:
//! Blinn's projected planar shadows (see `planar/mod.rs`). Registered at runtime, it gets everything a
//! built-in technique gets: here, `compare` against the ray-traced reference with its pictures and
//! reports; and the conformance suite includes the same module, so it is held to the CPU on the GPU too.
//!
//! `cargo run --release --example custom_technique [SCENE] [OUT_DIR]`

#[path = "planar/mod.rs"]
mod planar;

use shadow_core::FrameInputs;
use shadow_core::technique::TechniqueSpec;
use shadowlab::compare::{CompareJob, run_compare};
use shadowlab::setup::SceneSetup;
use shadowlab::{BackendChoice, Renderer, TechniqueRegistry};

const USAGE: &str = "usage: custom_technique [SCENE] [OUT_DIR]
  SCENE    a built-in scene or a model file (default: cylinder)
  OUT_DIR  where compare's pictures and reports go (default: out/custom-technique)";

fn main() -> Result<(), Box<dyn std::error::Error>> {
    if let Some(flag) = std::env::args().skip(1).find(|a| a.starts_with('-')) {
        println!("{USAGE}");
        return if flag == "-h" || flag == "--help" { Ok(()) } else { Err(format!("unknown flag {flag}").into()) };
    }
    let mut args = std::env::args().skip(1);
    let scene_name = args.next().unwrap_or_else(|| "cylinder".into());
    let out = args.next().unwrap_or_else(|| "out/custom-technique".into());

    let mut registry = TechniqueRegistry::builtin();
    planar::register(&mut registry);
    let mut renderer = Renderer::new(registry);
    // Both backends when a wgpu adapter exists (lavapipe counts), else the CPU alone.
    let backends = match renderer.resolve(BackendChoice::Both) {
        Ok((b, note)) => {
            eprintln!("{note}");
            b
        }
        Err(e) => {
            eprintln!("cpu only ({e})");
            vec![shadowlab::BackendKind::Cpu]
        }
    };
    let scene = SceneSetup::new(&scene_name).build()?;
    let frame = FrameInputs::from_first_camera(&scene)?;
    let job = CompareJob {
        scene: scene_name,
        frame: &frame,
        width: 512,
        height: 512,
        techniques: vec![TechniqueSpec::named("planar-shadow"), TechniqueSpec::named("shadow-map")],
        reference: TechniqueSpec::named("ray-traced"),
        soft_reference: None,
        backends,
        out_dir: Some(out.clone().into()),
    };
    let report = run_compare(&mut renderer, &job, |m| eprintln!("{m}"))?;
    for r in &report.results {
        println!(
            "{:<14} {:<5} mismatch {:.3}%  FLIP {:.4}",
            r.technique,
            r.backend,
            r.metrics.mismatch * 100.0,
            r.flip
        );
    }
    for c in &report.cross_backend {
        println!("{:<14} cpu vs wgpu mismatch {:.4}%", c.technique, c.mismatch * 100.0);
    }
    println!("wrote {out}/contact.png and reports");
    Ok(())
}
