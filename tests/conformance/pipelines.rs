//! Pipelines are compiled once per description: a second light, or a technique made again with the same
//! settings, compiles nothing; a settings change compiles exactly the pipelines that depend on it (a
//! setting read as a uniform none, a depth bias the light pass, a filter the query), and going back to
//! settings seen before compiles nothing. Without a wgpu adapter this prints one line and passes, unless
//! SHADOWLAB_REQUIRE_GPU=1.

use shadow_core::FrameInputs;
use shadow_core::glam::{Mat4, Vec3};
use shadow_core::scenes::{self, SceneParams};
use shadow_core::technique::TechniqueSpec;
use shadow_wgpu::{ColorTarget, Created, FrameRecorder, WgpuContext};
use shadowlab::TechniqueRegistry;

/// The techniques whose frames cannot be recorded (they read the GPU's results back within the frame).
const NOT_RECORDABLE: [&str; 1] = ["volume-reconstruction"];

/// What the context made while recording one frame of `technique` (submitted, as a host would).
fn made_by_a_frame(
    cx: &mut WgpuContext,
    technique: &mut dyn shadow_core::technique::DynShadowTechnique<shadow_wgpu::WgpuBackend>,
    frame: &FrameInputs,
    target: &wgpu::Texture,
) -> Created {
    let before = cx.created();
    let view = target.create_view(&Default::default());
    let color = ColorTarget { view: &view, format: target.format(), width: target.width(), height: target.height() };
    let mut encoder = cx.device.create_command_encoder(&Default::default());
    FrameRecorder::new().record(cx, &mut encoder, frame, technique, &color).expect("a recorded frame");
    cx.queue.submit([encoder.finish()]);
    cx.created().since(before)
}

/// The compiled part of `made`: (pipelines, shader modules).
fn compiled(made: Created) -> (u64, u64) {
    (made.pipelines, made.shader_modules)
}

fn setup() -> Option<(WgpuContext, FrameInputs, wgpu::Texture)> {
    crate::with_wgpu("the pipeline cache")?;
    let cx = WgpuContext::new(&shadow_wgpu::AdapterChoice { name: None, allow_software: true }).expect("context");
    let scene = scenes::build("primitives", &SceneParams::default()).expect("scene");
    let frame = FrameInputs::from_first_camera(&scene).expect("frame");
    let target = shadow_wgpu::frame::layered(&cx, "colour", 96, 72, 1, wgpu::TextureFormat::Rgba8UnormSrgb);
    Some((cx, frame, target))
}

#[test]
fn a_second_light_and_a_remade_technique_compile_nothing() {
    let Some((mut cx, _, target)) = setup() else { return };
    let registry = TechniqueRegistry::builtin();
    let mut failures = Vec::new();
    let recordable = registry.entries().iter().filter(|e| e.wgpu.is_some() && !NOT_RECORDABLE.contains(&e.name));
    for entry in recordable {
        let frame = crate::frame_taken_by("primitives", entry.lights);
        let mut two = frame.clone();
        two.lights.push(frame.lights[0].transformed(Mat4::from_translation(Vec3::new(0.5, 0.0, 0.25))));
        let spec = TechniqueSpec::named(entry.name);
        let mut technique = registry.wgpu(&spec).expect("technique");
        let first = made_by_a_frame(&mut cx, technique.as_mut(), &frame, &target);
        let lights = made_by_a_frame(&mut cx, technique.as_mut(), &two, &target);
        let mut again = registry.wgpu(&spec).expect("technique");
        let remade = made_by_a_frame(&mut cx, again.as_mut(), &two, &target);
        if compiled(lights) != (0, 0) || compiled(remade) != (0, 0) {
            failures.push(format!("{}: second light {lights:?}, remade {remade:?}", entry.name));
        }
        // The first technique's first frame compiles its pipelines, so the counts see what is compiled.
        assert!(first.pipelines > 0 || entry.name != "shadow-map", "{}: {first:?}", entry.name);
    }
    assert!(failures.is_empty(), "compiled again:\n{}", failures.join("\n"));
}

#[test]
fn a_settings_change_compiles_only_the_pipelines_that_depend_on_it() {
    let Some((mut cx, frame, target)) = setup() else { return };
    let registry = TechniqueRegistry::builtin();
    let mut run = |spec: &str| {
        let mut technique = registry.wgpu(&TechniqueSpec::parse(spec).expect("spec")).expect("technique");
        compiled(made_by_a_frame(&mut cx, technique.as_mut(), &frame, &target))
    };
    let (pipelines, _) = run("shadow-map");
    assert!(pipelines >= 2, "the first shadow-map frame compiled {pipelines} pipelines");
    // Read by the query as uniforms, or the map's size: nothing to compile.
    assert_eq!(run("shadow-map:filter_radius=2.5"), (0, 0), "a uniform");
    assert_eq!(run("shadow-map:res=512"), (0, 0), "the map's size");
    // The depth bias is the light pass's fixed-function state; the filter is the query's constant.
    assert_eq!(run("shadow-map:bias_constant=8"), (1, 0), "a depth bias");
    assert_eq!(run("shadow-map:filter=pcf3x3"), (1, 0), "a filter");
    assert_eq!(run("shadow-map:bias_constant=8,filter=pcf3x3"), (0, 0), "both, each seen before");
    assert_eq!(run("shadow-map"), (0, 0), "back to the defaults");
}

/// The volumes and the hybrid render a map of the casters their texture cuts out only for a frame with
/// such casters: on a scene without them, the map's settings compile nothing (no pass of theirs runs); on
/// `cutout`, the first frame compiles its light pass and lookup.
#[test]
fn silhouette_techniques_make_their_cutout_map_only_for_cutout_casters() {
    let Some((mut cx, frame, target)) = setup() else { return };
    let registry = TechniqueRegistry::builtin();
    let cutout = FrameInputs::from_first_camera(&scenes::build("cutout", &SceneParams::default()).expect("scene"))
        .expect("frame");
    let mut run = |spec: &str, frame: &FrameInputs| {
        let mut technique = registry.wgpu(&TechniqueSpec::parse(spec).expect("spec")).expect("technique");
        compiled(made_by_a_frame(&mut cx, technique.as_mut(), frame, &target))
    };
    // Each with a filter of its own, so that the second's lookup is not the first's.
    let techniques = [("shadow-volume-zfail", "pcf3x3"), ("shadow-volume-zpass", "poisson16"), ("hybrid", "bilinear")];
    for (name, filter) in techniques {
        run(name, &frame);
        let other_map = format!("{name}:cutout_res=512,cutout_filter={filter}");
        assert_eq!(run(&other_map, &frame), (0, 0), "{name}: no cut-out casters, no map");
        let (pipelines, _) = run(&other_map, &cutout);
        assert!(pipelines >= 1, "{name}: the cut-out casters' map compiled {pipelines} pipelines");
    }
}
