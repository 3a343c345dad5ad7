//! An engine that draws its own G-buffer and shades with its own WGSL (the `host_shading` example's),
//! reading each light's visibility through shadow-wgpu's host module after `record_visibility`: its
//! picture matches the one `FrameRecorder::record` shades within the suite's FLIP bound, and lies far
//! closer to it than the same engine's picture with the lights unshadowed (so the shadows came through).
//! Without a wgpu adapter this prints one line and passes, unless SHADOWLAB_REQUIRE_GPU=1.

#[path = "../../examples/host_shading/engine.rs"]
mod engine;

use shadow_core::FrameInputs;
use shadow_core::scenes::{self, SceneParams};

/// The suite's bound on the FLIP error between two renderers' shaded pictures.
const MAX_FLIP: f64 = 0.02;

#[test]
fn an_engine_shading_with_its_own_wgsl_matches_records_picture() {
    if crate::with_wgpu("an engine's own shading").is_none() {
        return;
    }
    for (scene, technique) in
        [("cubes", "shadow-map"), ("cubes", "shadow-volume-zfail"), ("cubes", "pcss"), ("room", "hybrid")]
    {
        let frame = FrameInputs::from_first_camera(&scenes::build(scene, &SceneParams::default()).expect("scene"))
            .expect("frame");
        let pictures = engine::Pictures::render(&frame, technique, 240, 180).unwrap_or_else(|e| panic!("{e}"));
        let flip = pictures.flip().expect("one size");
        let unshadowed = pictures.flip_of_the_shadows().expect("one size");
        assert!(
            flip <= MAX_FLIP && flip < 0.25 * unshadowed,
            "{scene} / {technique}: the engine's picture is {flip:.4} FLIP from record's ({unshadowed:.4} unshadowed)"
        );
    }
}

#[test]
fn the_engine_names_the_textured_material_it_cannot_draw() {
    if crate::with_wgpu("an engine's refusal").is_none() {
        return;
    }
    let frame = FrameInputs::from_first_camera(&scenes::build("foliage", &SceneParams::default()).expect("scene"))
        .expect("frame");
    let err = engine::Pictures::render(&frame, "shadow-map", 64, 48).err().expect("refused");
    assert!(err.to_string().contains("base-colour texture (material '"), "{err}");
}
