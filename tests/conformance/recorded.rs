//! The frame recorded into a host's encoder against the instrumented frame: every technique that can be
//! recorded gives the same visibility, byte for byte, and the same shaded image in an Rgba8Unorm target
//! (and within one level of it in a Bgra8UnormSrgb one, whose stores encode); a technique that needs the
//! GPU's results within the frame (or a variant that reads tiles back) is refused by name. Without a wgpu
//! adapter this prints one line and passes, unless SHADOWLAB_REQUIRE_GPU=1.

use shadow_core::FrameInputs;
use shadow_core::scenes::{self, SceneParams};
use shadow_core::technique::TechniqueSpec;
use shadow_wgpu::{ColorTarget, FrameRecorder, WgpuContext, WgpuError, readback};
use shadowlab::{BackendKind, TechniqueRegistry};

/// The techniques that read the GPU's results back within a frame: volume reconstruction rebuilds its
/// volume on the CPU from the depth map it reads back.
const NOT_RECORDABLE: [&str; 1] = ["volume-reconstruction"];

/// A colour target of `format`, `w x h`, that can be read back.
fn color_target(cx: &WgpuContext, format: wgpu::TextureFormat, w: u32, h: u32) -> wgpu::Texture {
    shadow_wgpu::frame::layered(cx, "host colour", w, h, 1, format)
}

/// Records one frame into a fresh encoder, as a host would, and submits it.
fn record(
    cx: &mut WgpuContext,
    recorder: &mut FrameRecorder,
    frame: &FrameInputs,
    spec: &TechniqueSpec,
    target: &wgpu::Texture,
) -> Result<(), WgpuError> {
    let mut technique = TechniqueRegistry::builtin().wgpu(spec).expect("technique");
    let mut encoder = cx.device.create_command_encoder(&Default::default());
    let view = target.create_view(&Default::default());
    let color = ColorTarget { view: &view, format: target.format(), width: target.width(), height: target.height() };
    recorder.record(cx, &mut encoder, frame, technique.as_mut(), &color)?;
    cx.queue.submit([encoder.finish()]);
    Ok(())
}

#[test]
fn recorded_frames_match_the_instrumented_ones() {
    let Some(mut renderer) = crate::with_wgpu("recorded frames") else { return };
    let mut cx = WgpuContext::new(&shadow_wgpu::AdapterChoice { name: None, allow_software: true }).expect("context");
    let (w, h) = (160, 120);
    let unorm = color_target(&cx, wgpu::TextureFormat::Rgba8Unorm, w, h);
    let srgb = color_target(&cx, wgpu::TextureFormat::Bgra8UnormSrgb, w, h);
    let mut recorder = FrameRecorder::new();
    let mut recorded = 0;
    for scene in ["cubes", "room"] {
        let s = scenes::build(scene, &SceneParams::default()).expect("scene");
        let frame = FrameInputs::from_first_camera(&s).expect("frame");
        for entry in renderer.registry().clone().entries().iter().filter(|e| e.wgpu.is_some()) {
            let (spec, case) = (TechniqueSpec::named(entry.name), format!("{scene} / {}", entry.name));
            let outcome = record(&mut cx, &mut recorder, &frame, &spec, &unorm);
            if NOT_RECORDABLE.contains(&entry.name) {
                let err = outcome.err().unwrap_or_else(|| panic!("{case}: recorded"));
                assert!(matches!(err, WgpuError::NotRecordable { .. }), "{case}: {err}");
                continue;
            }
            outcome.unwrap_or_else(|e| panic!("{case}: {e}"));
            let vis = recorder.visibility().expect("a recorded frame's visibility");
            let vis = readback::read_f32(&cx, vis, 0, wgpu::TextureAspect::All).expect("read back");
            let color = readback::read_rgb8(&cx, &unorm).expect("read back");
            record(&mut cx, &mut recorder, &frame, &spec, &srgb).unwrap_or_else(|e| panic!("{case}, sRGB: {e}"));
            let bgra = readback::read_rgb8(&cx, &srgb).expect("read back");
            let own = renderer.run(BackendKind::Wgpu, &frame, w, h, &spec).expect("instrumented frame");
            assert!(vis.data().contains(&0.0), "{case}: nothing in shadow");
            assert!(vis.data() == own.visibility[0].data(), "{case}: the recorded visibility differs");
            assert_eq!(color.data(), own.color.data(), "{case}: the recorded colour differs");
            for (b, c) in bgra.data().iter().zip(color.data()) {
                let rgb = [b[2], b[1], b[0]];
                assert!(rgb.iter().zip(c).all(|(x, y)| x.abs_diff(*y) <= 1), "{case}: sRGB target {rgb:?} vs {c:?}");
            }
            recorded += 1;
        }
    }
    assert!(recorded >= 18, "only {recorded} techniques recorded");
    // The scissor rectangles come from tile marks read back within the frame.
    let s = scenes::build("cubes", &SceneParams::default()).expect("scene");
    let frame = FrameInputs::from_first_camera(&s).expect("frame");
    let spec = TechniqueSpec::parse("hybrid:scissor_tile=32").expect("spec");
    let err = record(&mut cx, &mut recorder, &frame, &spec, &unorm).expect_err("refused");
    assert!(matches!(err, WgpuError::NotRecordable { .. }), "{err}");
}
