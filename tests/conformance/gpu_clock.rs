//! GPU phase times (shadow-wgpu's clock): where the adapter has timestamp queries, every phase has a
//! `gpu_` time, and a technique that runs counter passes after its own work (`WgpuContext::end_of_work`)
//! has them timed apart as `gpu_counters`, so they stay out of its `gpu_query`.

use shadow_core::FrameInputs;
use shadow_core::scenes::{self, SceneParams};
use shadow_core::technique::TechniqueSpec;
use shadowlab::{BackendKind, Renderer};

/// A renderer with a wgpu adapter and the `cubes` frame, or `None` (and a note) without an adapter, which
/// `SHADOWLAB_REQUIRE_GPU=1` turns into a failure.
fn on_wgpu() -> Option<(Renderer, FrameInputs)> {
    let renderer = crate::with_wgpu("the GPU clock test")?;
    let scene = scenes::build("cubes", &SceneParams::default()).expect("scene");
    let frame = FrameInputs::from_scene(&scene, scene.cameras().next().expect("camera").0).expect("frame");
    Some((renderer, frame))
}

#[test]
fn counter_passes_are_timed_apart_from_the_query() {
    let Some((mut renderer, frame)) = on_wgpu() else { return };
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

/// A technique's named steps (`WgpuContext::step`) come back as `gpu_<phase>.<name>`, in GPU time that
/// adds up to no more than the phase's own.
#[test]
fn named_steps_split_a_phase() {
    let Some((mut renderer, frame)) = on_wgpu() else { return };
    let spec = TechniqueSpec::parse("hybrid:res=256").expect("spec");
    let extra = renderer.run(BackendKind::Wgpu, &frame, 128, 128, &spec).expect("a frame").stats.timings.extra;
    if !extra.contains_key("gpu_gbuffer") {
        eprintln!("skipped: the adapter has no timestamp queries");
        return;
    }
    for (phase, steps) in [
        ("gpu_build", &["map", "edges", "pieces"][..]),
        ("gpu_query", &["setup", "mask", "casters", "volumes", "answer"][..]),
    ] {
        let whole = extra[phase];
        let mut sum = 0.0;
        for step in steps {
            let key = format!("{phase}.{step}");
            let t = *extra.get(&key).unwrap_or_else(|| panic!("{key} missing: {extra:?}"));
            assert!(t >= 0.0, "{key} = {t}");
            sum += t;
        }
        assert!(sum > 0.0 && sum <= whole + 1e-6, "{phase}: steps {sum} ms against {whole} ms");
    }
}
