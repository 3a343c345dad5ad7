//! Static lights are not built again: a prepared technique given the same frame twice keeps each
//! light's build (the frame's `cached_builds` counts them) and gives the same visibility; a moved light, a
//! moved caster or an explicit invalidate builds afresh; hybrid, whose build reads the camera, always
//! builds. On both backends.

use shadow_core::glam::{Mat4, Vec3};
use shadow_core::scenes::{self, SceneParams};
use shadow_core::technique::TechniqueSpec;
use shadow_core::{FrameInputs, LightKind};
use shadowlab::renderer::RunOutput;
use shadowlab::{BackendKind, Renderer, TechniqueRegistry};

const SIZE: u32 = 128;

fn cached(r: &RunOutput) -> f64 {
    r.stats.counters.extra.get("cached_builds").copied().unwrap_or(0.0)
}

#[test]
fn unchanged_lights_keep_their_builds_until_something_moves() {
    let mut renderer = Renderer::new(TechniqueRegistry::builtin());
    let mut backends = vec![BackendKind::Cpu];
    if super::with_wgpu("the static-light cache").is_some() {
        backends.push(BackendKind::Wgpu);
    }
    let scene = scenes::build("primitives", &SceneParams::default()).expect("scene");
    let frame = FrameInputs::from_first_camera(&scene).expect("frame");
    let mut moved_light = frame.clone();
    if let LightKind::Spot { position, .. } = &mut moved_light.lights[0].kind {
        *position += Vec3::new(0.3, 0.0, 0.0);
    }
    let mut moved_caster = frame.clone();
    let nudge = Mat4::from_translation(Vec3::new(0.05, 0.0, 0.0));
    moved_caster.instances[0].world_from_local = nudge * moved_caster.instances[0].world_from_local;
    for backend in backends {
        for name in ["shadow-map", "shadow-volume-zfail", "pcss"] {
            let what = format!("{name} on {backend:?}");
            let mut p = renderer.prepare(backend, &TechniqueSpec::named(name)).expect("technique");
            let run = |renderer: &mut Renderer, p: &mut shadowlab::renderer::Prepared, f: &FrameInputs| {
                renderer.run_prepared(p, f, SIZE, SIZE).expect("a frame")
            };
            let first = run(&mut renderer, &mut p, &frame);
            let again = run(&mut renderer, &mut p, &frame);
            assert_eq!((cached(&first), cached(&again)), (0.0, 1.0), "{what}");
            assert!(again.visibility[0].data() == first.visibility[0].data(), "{what}: the kept build differs");
            assert!(first.visibility[0].data().contains(&0.0), "{what}: nothing in shadow");
            let light = run(&mut renderer, &mut p, &moved_light);
            assert_eq!(cached(&light), 0.0, "{what}: a moved light kept its build");
            assert!(light.visibility[0].data() != first.visibility[0].data(), "{what}: the moved light's shadow");
            run(&mut renderer, &mut p, &moved_caster);
            assert_eq!(cached(&run(&mut renderer, &mut p, &moved_caster)), 1.0, "{what}");
            assert_eq!(cached(&run(&mut renderer, &mut p, &frame)), 0.0, "{what}: a moved caster kept the build");
            p.invalidate();
            assert_eq!(cached(&run(&mut renderer, &mut p, &frame)), 0.0, "{what}: kept after an invalidate");
        }
    }
    let Some(mut renderer) = super::with_wgpu("hybrid's builds") else { return };
    let mut p = renderer.prepare(BackendKind::Wgpu, &TechniqueSpec::named("hybrid")).expect("hybrid");
    renderer.run_prepared(&mut p, &frame, SIZE, SIZE).expect("a frame");
    let again = renderer.run_prepared(&mut p, &frame, SIZE, SIZE).expect("a frame");
    assert_eq!(cached(&again), 0.0, "hybrid kept a build");
}
