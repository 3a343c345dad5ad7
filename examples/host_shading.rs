//! An engine that draws its own G-buffer and shades with its own WGSL, taking from shadowlab only each
//! light's visibility (`host_shading/engine.rs`): it lends its depth and normals to
//! `FrameRecorder::record_visibility` in its own command encoder, and its shading pass reads each light's
//! layer of `FrameRecorder::visibility` through the WGSL module shadow-wgpu ships. Its picture is held
//! to the one shadowlab shades itself (`FrameRecorder::record`): both are written to `out/` with the FLIP
//! between them, and a FLIP past 0.02 is a failure.
//!
//! `cargo run --release --example host_shading [SCENE] [TECHNIQUE]` (cubes and shadow-map by default;
//! any built-in scene whose materials have no textures, any technique the wgpu backend records).

#[path = "host_shading/engine.rs"]
mod engine;

use std::process::ExitCode;

use shadow_core::FrameInputs;
use shadow_core::scenes::{self, SceneParams};

/// The largest FLIP between the engine's picture and shadowlab's own.
const MAX_FLIP: f64 = 0.02;

fn run() -> Result<(), engine::Failure> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let scene_name = args.first().map_or("cubes", String::as_str);
    let technique = args.get(1).map_or("shadow-map", String::as_str);
    let frame = FrameInputs::from_first_camera(&scenes::build(scene_name, &SceneParams::default())?)?;
    let pictures = engine::Pictures::render(&frame, technique, 640, 480).map_err(|e| format!("{scene_name}: {e}"))?;
    let (flip, shadows) = (pictures.flip()?, pictures.flip_of_the_shadows()?);
    std::fs::create_dir_all("out")?;
    pictures.engine.save_png("out/host_shading.png")?;
    pictures.shadowlab.save_png("out/host_shading-record.png")?;
    println!(
        "{scene_name} with {technique}: the engine's picture in out/host_shading.png, shadowlab's own in \
         out/host_shading-record.png; FLIP between them {flip:.4} (at most {MAX_FLIP}; with every light \
         unshadowed it would be {shadows:.4})"
    );
    if flip > MAX_FLIP {
        return Err(format!("the engine's picture is {flip:.4} FLIP from shadowlab's, past {MAX_FLIP}").into());
    }
    Ok(())
}

fn main() -> ExitCode {
    match run() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
