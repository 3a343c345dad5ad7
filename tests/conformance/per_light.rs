//! Each light with its own shadow settings: in one frame, a light shadowed by the frame's technique, one
//! by a technique of its own (with its own map size), and one that casts no shadow. On both backends and
//! in a frame recorded into a host's encoder, each light's visibility is what its technique gives when it
//! shadows every light, and the light that casts none is lit everywhere; a light naming a technique the
//! registry does not have is refused by that name.

use shadow_core::glam::Vec3;
use shadow_core::scenes::{self, SceneParams};
use shadow_core::technique::TechniqueSpec;
use shadow_core::{FrameInputs, Image, Light, LightShadow, Scene};
use shadowlab::{BackendKind, Renderer, TechniqueRegistry};

const SIZE: u32 = 160;

/// `primitives` with two more spot lights: the scene's own (the frame's technique), one shadowed by
/// `own`, and one casting nothing.
fn three_lights(own: &str) -> Scene {
    let mut s = scenes::build("primitives", &SceneParams::default()).expect("scene");
    let second = s.add_light(Light::spot(Vec3::new(-2.0, 3.0, 1.0), Vec3::ZERO, 70.0));
    s.set_light_shadow(second, LightShadow::with(TechniqueSpec::parse(own).expect("spec"))).expect("light");
    let third = s.add_light(Light::spot(Vec3::new(0.5, 3.5, -2.0), Vec3::ZERO, 70.0));
    s.set_light_shadow(third, LightShadow::NONE).expect("light");
    s
}

/// The same frame with every light casting with the frame's technique.
fn all_casting(frame: &FrameInputs) -> FrameInputs {
    FrameInputs { shadows: vec![LightShadow::default(); frame.lights.len()], ..frame.clone() }
}

fn shadowed(v: &Image<f32>) -> usize {
    v.data().iter().filter(|&&x| x == 0.0).count()
}

#[test]
fn each_light_is_shadowed_as_its_own_settings_say() {
    let own = "shadow-volume-zfail";
    let frame = FrameInputs::from_first_camera(&three_lights(own)).expect("frame");
    let plain = all_casting(&frame);
    let mut renderer = Renderer::new(TechniqueRegistry::builtin());
    let mut backends = vec![BackendKind::Cpu];
    if super::with_wgpu("per-light techniques").is_some() {
        backends.push(BackendKind::Wgpu);
    }
    let frame_technique = TechniqueSpec::parse("shadow-map:res=1024").expect("spec");
    for backend in backends {
        let mixed = renderer.run(backend, &frame, SIZE, SIZE, &frame_technique).expect("the mixed frame");
        let maps = renderer.run(backend, &plain, SIZE, SIZE, &frame_technique).expect("shadow maps everywhere");
        let volumes = renderer.run(backend, &plain, SIZE, SIZE, &TechniqueSpec::named(own)).expect("volumes");
        assert!(shadowed(&maps.visibility[0]) > 0 && shadowed(&volumes.visibility[1]) > 0, "{backend:?}: no shadow");
        assert!(
            mixed.visibility[0].data() == maps.visibility[0].data(),
            "{backend:?}: light 0 is not the frame technique's"
        );
        assert!(
            mixed.visibility[1].data() == volumes.visibility[1].data(),
            "{backend:?}: light 1 is not its own technique's"
        );
        assert!(shadowed(&volumes.visibility[2]) > 0, "{backend:?}: light 2 would cast nothing anyway");
        assert!(mixed.visibility[2].data().iter().all(|&x| x == 1.0), "{backend:?}: light 2 casts a shadow");
    }
}

#[test]
fn recorded_frames_shadow_each_light_with_its_own_technique() {
    let Some(mut renderer) = super::with_wgpu("recorded per-light techniques") else { return };
    let own = "shadow-map:res=512,bias_slope=3";
    let frame = FrameInputs::from_first_camera(&three_lights(own)).expect("frame");
    let expected = renderer.run(BackendKind::Wgpu, &frame, SIZE, SIZE, &TechniqueSpec::named("shadow-volume-zpass"));
    let expected = expected.expect("an instrumented frame");
    let mut cx = shadow_wgpu::WgpuContext::new(&shadow_wgpu::AdapterChoice { name: None, allow_software: true })
        .expect("context");
    let registry = TechniqueRegistry::builtin();
    let mut technique = registry.wgpu(&TechniqueSpec::named("shadow-volume-zpass")).expect("technique");
    let mut named = Vec::new();
    shadowlab::renderer::name_techniques(&frame, &mut named, |s| Ok(registry.wgpu(s)?)).expect("named");
    let target = shadow_wgpu::frame::layered(&cx, "host colour", SIZE, SIZE, 1, wgpu::TextureFormat::Rgba8Unorm);
    let view = target.create_view(&Default::default());
    let color = shadow_wgpu::ColorTarget { view: &view, format: target.format(), width: SIZE, height: SIZE };
    let mut recorder = shadow_wgpu::FrameRecorder::new();
    let mut encoder = cx.device.create_command_encoder(&Default::default());
    let techniques = shadow_core::script::LightTechniques { frame: technique.as_mut(), named: &mut named };
    recorder.record(&mut cx, &mut encoder, &frame, techniques, &color).expect("recorded");
    cx.queue.submit([encoder.finish()]);
    let layers = recorder.visibility().expect("visibility");
    let read = |k| shadow_wgpu::readback::read_f32(&cx, layers, k, wgpu::TextureAspect::All).expect("read back");
    assert!(read(0).data() == expected.visibility[0].data(), "light 0 differs from the instrumented frame");
    assert!(read(1).data() == expected.visibility[1].data(), "light 1 differs from the instrumented frame");
    assert!(shadowed(&read(1)) > 0, "light 1 casts nothing");
    assert!(read(2).data().iter().all(|&x| x == 1.0), "light 2 casts a shadow");
}

#[test]
fn a_light_naming_an_unknown_technique_is_refused_by_name() {
    let frame = FrameInputs::from_first_camera(&three_lights("no-such-technique")).expect("frame");
    let mut renderer = Renderer::new(TechniqueRegistry::builtin());
    let err = renderer.run(BackendKind::Cpu, &frame, 32, 32, &TechniqueSpec::named("shadow-map")).err();
    let err = err.expect("refused").to_string();
    assert!(err.contains("no-such-technique"), "{err}");
}
