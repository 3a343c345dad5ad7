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
pub(crate) const NOT_RECORDABLE: [&str; 1] = ["volume-reconstruction"];

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
        for entry in renderer.registry().clone().entries().iter().filter(|e| e.wgpu.is_some()) {
            let frame = crate::frame_taken_by(scene, entry.lights);
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
            assert!(vis.data().iter().any(|&v| crate::shadowed(v)), "{case}: nothing in shadow");
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

/// Recorded frames of `technique` on `scene` with its first light circling the vertical axis and its
/// first drawn node moving, `frames` of them, each submitted: what the context made after the first frame, the last
/// frame, and its visibility.
fn made_after_the_first_frame(
    cx: &mut WgpuContext,
    scene: &mut shadow_core::Scene,
    technique: &mut dyn shadow_core::technique::DynShadowTechnique<shadow_wgpu::WgpuBackend>,
    target: &wgpu::Texture,
    frames: u32,
) -> Result<(shadow_wgpu::Created, FrameInputs, shadow_core::Image<f32>), WgpuError> {
    use shadow_core::LightKind;
    use shadow_core::glam::{Mat4, Vec3};
    let light = scene.lights().next().map(|(k, _)| k).expect("a light");
    let node = scene.drawables().next().map(|(k, ..)| k).expect("a drawn node");
    let start = scene.node(node).expect("node").local_transform();
    let mut recorder = FrameRecorder::new();
    let view = target.create_view(&Default::default());
    let color = ColorTarget { view: &view, format: target.format(), width: target.width(), height: target.height() };
    let (mut first, mut last) = (None, None);
    for i in 0..frames {
        // The light circles the scene's vertical axis, turned with it, so it keeps lighting the scene.
        let turn = Mat4::from_rotation_y(0.02);
        if let Some(l) = scene.light_mut(light) {
            match &mut l.kind {
                LightKind::Spot { position, direction, .. } => {
                    *position = turn.transform_point3(*position);
                    *direction = turn.transform_vector3(*direction);
                }
                LightKind::Point { position } => *position = turn.transform_point3(*position),
                LightKind::Directional { direction } => *direction = turn.transform_vector3(*direction),
            }
        }
        let nudge = Mat4::from_translation(Vec3::new(0.002 * i as f32, 0.0, 0.0));
        scene.set_local_transform(node, nudge * start).expect("node");
        let frame = FrameInputs::from_first_camera(scene).expect("frame");
        let mut encoder = cx.device.create_command_encoder(&Default::default());
        recorder.record(cx, &mut encoder, &frame, &mut *technique, &color)?;
        cx.queue.submit([encoder.finish()]);
        first.get_or_insert(cx.created());
        last = Some(frame);
    }
    let (now, first) = (cx.created(), first.unwrap_or_default());
    let made = now.since(first);
    let visibility = recorder.visibility().expect("a recorded frame");
    let visibility = readback::read_f32(cx, visibility, 0, wgpu::TextureAspect::All)?;
    Ok((made, last.expect("a frame"), visibility))
}

#[test]
fn a_moving_light_and_node_allocate_nothing_after_the_first_frame() {
    const FRAMES: u32 = 100;
    let Some(mut renderer) = crate::with_wgpu("recorded allocations") else { return };
    let mut cx = WgpuContext::new(&shadow_wgpu::AdapterChoice { name: None, allow_software: true }).expect("context");
    let target = color_target(&cx, wgpu::TextureFormat::Rgba8UnormSrgb, 128, 96);
    let mut failures = Vec::new();
    let mut checked = 0;
    for entry in
        renderer.registry().clone().entries().iter().filter(|e| e.wgpu.is_some() && !NOT_RECORDABLE.contains(&e.name))
    {
        let mut scene = crate::scene_taken_by("primitives", entry.lights);
        let mut technique = renderer.registry().wgpu(&TechniqueSpec::named(entry.name)).expect("technique");
        let (made, last, visibility) =
            made_after_the_first_frame(&mut cx, &mut scene, technique.as_mut(), &target, FRAMES)
                .unwrap_or_else(|e| panic!("{}: {e}", entry.name));
        if made != shadow_wgpu::Created::default() {
            failures.push(format!("{}: {made:?}", entry.name));
        }
        // What was reused holds this frame's data, not a stale one's: the last frame as a fresh render.
        let (w, h) = (target.width(), target.height());
        let fresh = renderer.run(BackendKind::Wgpu, &last, w, h, &TechniqueSpec::named(entry.name)).expect("a frame");
        failures.extend(stale_or_unshadowed(entry.name, FRAMES, &visibility, &fresh.visibility[0]));
        checked += 1;
    }
    assert!(failures.is_empty(), "made after the first frame:\n{}", failures.join("\n"));
    assert!(checked >= 10, "only {checked} techniques checked");
}

/// What is wrong, if anything, with the visibility of the last of `frames` recorded frames of technique
/// `name`: no shadow in it, or pixels unlike `fresh`, a fresh render of the same frame (what was reused
/// holds a stale frame's data).
pub(crate) fn stale_or_unshadowed(
    name: &str,
    frames: u32,
    visibility: &shadow_core::Image<f32>,
    fresh: &shadow_core::Image<f32>,
) -> Option<String> {
    let differ = visibility.data().iter().zip(fresh.data()).filter(|(a, b)| a != b).count();
    let shadowed = visibility.data().iter().filter(|&&v| crate::shadowed(v)).count();
    (differ > 0 || shadowed == 0).then(|| {
        format!("{name}: the last of {frames} frames has {shadowed} shadowed pixels, {differ} unlike a fresh render's")
    })
}

/// Casters and receivers cut out by their texture in recorded frames: on `foliage`, the leaves' texture goes
/// to the device with the first frame and nothing is made in the 99 after it, while the light circles and
/// a node moves, and the last frame's visibility is a fresh render's, with the leaves' shadow in it.
#[test]
fn recorded_cutouts_allocate_nothing_after_the_first_frame() {
    let Some(mut renderer) = crate::with_wgpu("recorded cut-out casters") else { return };
    let mut cx = WgpuContext::new(&shadow_wgpu::AdapterChoice { name: None, allow_software: true }).expect("context");
    let target = color_target(&cx, wgpu::TextureFormat::Rgba8UnormSrgb, 128, 96);
    let mut scene = scenes::build("foliage", &SceneParams::default()).expect("foliage");
    let spec = TechniqueSpec::parse("shadow-map:res=1024").expect("spec");
    let mut technique = renderer.registry().wgpu(&spec).expect("technique");
    let (made, last, visibility) =
        made_after_the_first_frame(&mut cx, &mut scene, technique.as_mut(), &target, 100).expect("recorded frames");
    assert_eq!(made, shadow_wgpu::Created::default(), "made after the first frame");
    assert_eq!(cx.cache.textures.len(), 1, "the leaves' texture, once");
    let fresh = renderer.run(BackendKind::Wgpu, &last, 128, 96, &spec).expect("a frame");
    assert!(visibility.data() == fresh.visibility[0].data(), "the last recorded frame is not a fresh render's");
    let shadowed = visibility.data().iter().filter(|&&v| crate::shadowed(v)).count();
    assert!(shadowed > 100, "{shadowed} shadowed pixels");
}
