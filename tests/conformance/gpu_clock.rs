//! GPU phase times (shadow-wgpu's clock): where the adapter has timestamp queries, every phase has a
//! `gpu_` time, and a technique that runs counter passes after its own work (`WgpuContext::end_of_work`)
//! has them timed apart as `gpu_counters`, so they stay out of its `gpu_query`.

use shadow_core::FrameInputs;
use shadow_core::scenes::{self, SceneParams};
use shadow_core::technique::TechniqueSpec;
use shadowlab::{BackendKind, Renderer, TechniqueRegistry};

#[test]
fn counter_passes_are_timed_apart_from_the_query() {
    let mut renderer = Renderer::new(TechniqueRegistry::builtin());
    let require = std::env::var("SHADOWLAB_REQUIRE_GPU").is_ok_and(|v| v == "1");
    if let Err(e) = renderer.resolve(shadowlab::BackendChoice::Wgpu) {
        assert!(!require, "SHADOWLAB_REQUIRE_GPU=1 but no wgpu adapter: {e}");
        eprintln!("skipped: no wgpu adapter ({e})");
        return;
    }
    let scene = scenes::build("cubes", &SceneParams::default()).expect("scene");
    let frame = FrameInputs::from_scene(&scene, scene.cameras().next().expect("camera").0).expect("frame");
    let mut extras = |spec: &str| {
        let spec = TechniqueSpec::parse(spec).expect("spec");
        renderer.run(BackendKind::Wgpu, &frame, 128, 128, &spec).expect("a frame").stats.timings.extra
    };
    let (zfail, map) = (extras("shadow-volume-zfail"), extras("shadow-map:res=256"));
    if !map.contains_key("gpu_gbuffer") {
        eprintln!("skipped: the adapter has no timestamp queries");
        return;
    }
    for phase in ["gpu_gbuffer", "gpu_build", "gpu_query", "gpu_shade"] {
        assert!(zfail.contains_key(phase) && map.contains_key(phase), "{phase} missing: {zfail:?} {map:?}");
    }
    assert!(zfail.contains_key("gpu_counters"), "z-fail's counter passes are not timed apart: {zfail:?}");
    assert!(!map.contains_key("gpu_counters"), "shadow-map has no counter passes: {map:?}");
}
