//! Loads a model file (glTF, GLB, OBJ or PLY), puts it on a ground plane with the default light and
//! camera, and renders it with a technique on a backend chosen at runtime.
//!
//! `cargo run --release --example render_model -- [MODEL] [BACKEND] [TECHNIQUE]`
//! Without a model it exports the built-in `strike` scene to a .glb and renders that, so the glTF path is
//! exercised on any machine.

use shadow_core::FrameInputs;
use shadow_core::technique::TechniqueSpec;
use shadowlab::setup::SceneSetup;
use shadowlab::{BackendChoice, Renderer, TechniqueRegistry};

const USAGE: &str = "usage: render_model [MODEL] [BACKEND] [TECHNIQUE]
  MODEL      a .gltf, .glb, .obj, .ply or .ply.gz file (default: the built-in strike scene, exported to .glb)
  BACKEND    auto, cpu, wgpu or both (default: auto)
  TECHNIQUE  NAME[:key=value,...] (default: shadow-volume-zfail)
writes out/render_model-BACKEND.png";

fn main() -> Result<(), Box<dyn std::error::Error>> {
    if let Some(flag) = std::env::args().skip(1).find(|a| a.starts_with('-')) {
        println!("{USAGE}");
        return if flag == "-h" || flag == "--help" { Ok(()) } else { Err(format!("unknown flag {flag}").into()) };
    }
    let mut args = std::env::args().skip(1);
    let model = match args.next() {
        Some(m) => m,
        None => {
            let path = std::env::temp_dir().join("shadowlab-strike.glb");
            let strike = shadow_core::scenes::build("strike", &Default::default())?;
            shadow_core::assets::export::export_glb(&strike, &path)?;
            path.display().to_string()
        }
    };
    let choice: BackendChoice = args.next().unwrap_or_else(|| "auto".into()).parse()?;
    let spec = TechniqueSpec::parse(&args.next().unwrap_or_else(|| "shadow-volume-zfail".into()))?;

    let scene = SceneSetup::new(&model).build()?;
    let frame = FrameInputs::from_first_camera(&scene)?;
    let mut renderer = Renderer::new(TechniqueRegistry::builtin());
    let (backends, note) = renderer.resolve(choice)?;
    eprintln!("{note}");
    std::fs::create_dir_all("out")?;
    for backend in backends {
        let run = renderer.run(backend, &frame, 640, 480, &spec)?;
        let path = format!("out/render_model-{}.png", backend.name());
        run.color.save_png(&path)?;
        println!(
            "{model}: {} triangles, {} on {} in {:.1} ms -> {path}",
            frame.triangle_count(),
            spec.name,
            backend.name(),
            run.stats.timings.total
        );
    }
    Ok(())
}
