//! Static lights are not built again: a prepared technique given the same frame twice keeps each
//! light's build (the frame's `cached_builds` counts them) and gives the same visibility; a moved light, a
//! moved caster or an explicit invalidate builds afresh; hybrid, whose build reads the camera, always
//! builds. On both backends.

use shadow_core::glam::{Mat4, Vec3};
use shadow_core::scene::ShadowUpdate;
use shadow_core::scenes::{self, SceneParams};
use shadow_core::technique::TechniqueSpec;
use shadow_core::{FrameInputs, LightKind, LightShadow};
use shadowlab::renderer::RunOutput;
use shadowlab::{BackendKind, Renderer, TechniqueRegistry};

const SIZE: u32 = 128;

fn cached(r: &RunOutput) -> f64 {
    r.stats.counters.extra.get("cached_builds").copied().unwrap_or(0.0)
}

/// A renderer, the backends to run (wgpu where there is an adapter) and a frame of `primitives`.
fn primitives() -> (Renderer, Vec<BackendKind>, FrameInputs) {
    let mut backends = vec![BackendKind::Cpu];
    if super::with_wgpu("the static-light cache").is_some() {
        backends.push(BackendKind::Wgpu);
    }
    let scene = scenes::build("primitives", &SceneParams::default()).expect("scene");
    let frame = FrameInputs::from_first_camera(&scene).expect("frame");
    (Renderer::new(TechniqueRegistry::builtin()), backends, frame)
}

#[test]
fn unchanged_lights_keep_their_builds_until_something_moves() {
    let (mut renderer, backends, frame) = primitives();
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

/// A caster moving outside a light's view leaves the builds that only draw casters into that view (the
/// shadow map, its depth layers, PCSS and moment maps) as they were, giving what a fresh build gives; the volumes, which extrude every
/// caster, build afresh; moved into the view, it is built again everywhere. On both backends.
#[test]
fn a_caster_moving_outside_a_lights_view_keeps_the_maps_it_is_not_in() {
    let (mut renderer, backends, frame) = primitives();
    let LightKind::Spot { position, direction, cone_angle } = frame.lights[0].kind else {
        panic!("primitives' light is a spot")
    };
    // A half-size copy of the smallest caster, moved across the light's axis by `reach` times the cone's
    // radius at its depth (the view's corners reach √2 of it) and its size: its corners' depths along the
    // axis stay within that caster's, so the fitted projection is the same wherever it goes.
    let size = |i: &&shadow_core::Instance| i.bounds.size().length();
    let first = frame.instances.iter().filter(|i| i.casts_shadow).min_by(|a, b| size(a).total_cmp(&size(b)));
    let first = first.expect("a caster").clone();
    let (centre, size) = (first.bounds.center(), first.bounds.size().length());
    let dir = direction.normalize();
    let across = dir.any_orthonormal_vector();
    let radius = (centre - position).dot(dir) * (cone_angle * 0.5).tan() + size;
    let with_copy = |reach: f32| {
        let place = Mat4::from_translation(centre + across * radius * reach)
            * Mat4::from_scale(Vec3::splat(0.5))
            * Mat4::from_translation(-centre);
        let mut f = frame.clone();
        let mut copy = first.clone();
        copy.world_from_local = place * first.world_from_local;
        copy.local_from_world = copy.world_from_local.inverse();
        copy.bounds = first.bounds.transformed(place);
        f.instances.push(copy);
        f
    };
    let (outside, further, inside) = (with_copy(2.0), with_copy(3.0), with_copy(0.0));
    for backend in backends {
        let maps = ["shadow-map", "second-depth-shadow-map", "pcss", "variance-shadow-map"].map(|name| (name, true));
        for (name, keeps) in maps.into_iter().chain([("shadow-volume-zfail", false)]) {
            let what = format!("{name} on {backend:?}");
            let spec = TechniqueSpec::named(name);
            let mut p = renderer.prepare(backend, &spec).expect("technique");
            let mut run = |p: &mut shadowlab::renderer::Prepared, f: &FrameInputs| {
                renderer.run_prepared(p, f, SIZE, SIZE).expect("a frame")
            };
            run(&mut p, &outside);
            let moved = run(&mut p, &further);
            assert_eq!(cached(&moved), if keeps { 1.0 } else { 0.0 }, "{what}: a caster moved outside the view");
            assert!(moved.visibility[0].data().contains(&0.0), "{what}: nothing in shadow");
            let mut fresh = renderer.prepare(backend, &spec).expect("technique");
            let fresh = renderer.run_prepared(&mut fresh, &further, SIZE, SIZE).expect("a frame");
            assert!(moved.visibility[0].data() == fresh.visibility[0].data(), "{what}: the kept build differs");
            let mut run = |p: &mut shadowlab::renderer::Prepared, f: &FrameInputs| {
                renderer.run_prepared(p, f, SIZE, SIZE).expect("a frame")
            };
            assert_eq!(cached(&run(&mut p, &inside)), 0.0, "{what}: a caster moved into the view kept the build");
        }
    }
}

/// A light's update policy: every frame builds on every frame even when nothing moved; every third frame
/// keeps its build over two frames whatever moved, then builds; once keeps its first build while the light
/// moves (its shadow stays where it was); and a technique whose build reads the camera (hybrid on the GPU)
/// builds every frame whatever the light says.
#[test]
fn each_light_is_built_again_as_its_update_policy_says() {
    let (mut renderer, backends, frame) = primitives();
    let with = |f: &FrameInputs, update: ShadowUpdate| FrameInputs {
        shadows: vec![LightShadow { update, ..LightShadow::default() }; f.lights.len()],
        ..f.clone()
    };
    let nudged = |k: u32| {
        let mut f = frame.clone();
        if let LightKind::Spot { position, .. } = &mut f.lights[0].kind {
            *position += Vec3::new(0.1 * k as f32, 0.0, 0.0);
        }
        f
    };
    for backend in backends {
        // hybrid's build on the GPU reads the camera (its mask is the view's); on the CPU it does not.
        for (name, reusable) in [("shadow-map", true), ("hybrid", backend == BackendKind::Cpu)] {
            let what = format!("{name} on {backend:?}");
            let mut cached_over = |update: ShadowUpdate, frames: &[FrameInputs]| -> Vec<f64> {
                let mut p = renderer.prepare(backend, &TechniqueSpec::named(name)).expect("technique");
                frames
                    .iter()
                    .map(|f| cached(&renderer.run_prepared(&mut p, &with(f, update), SIZE, SIZE).expect("frame")))
                    .collect()
            };
            let still = vec![frame.clone(); 4];
            let moving: Vec<FrameInputs> = (0..7).map(nudged).collect();
            let every = cached_over(ShadowUpdate::EveryFrame, &still);
            assert_eq!(every, [0.0; 4], "{what}: every frame");
            let third = cached_over(ShadowUpdate::Every(3), &moving);
            let once = cached_over(ShadowUpdate::Once, &moving);
            if reusable {
                assert_eq!(third, [0.0, 1.0, 1.0, 0.0, 1.0, 1.0, 0.0], "{what}: every third frame");
                assert_eq!(once, [0.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0], "{what}: once");
            } else {
                assert_eq!((third, once), (vec![0.0; 7], vec![0.0; 7]), "{what}: reads the camera");
            }
        }
        // Built once, the shadow stays where the first frame's light cast it.
        let mut p = renderer.prepare(backend, &TechniqueSpec::named("shadow-map")).expect("technique");
        let first = renderer.run_prepared(&mut p, &with(&frame, ShadowUpdate::Once), SIZE, SIZE).expect("frame");
        let kept = renderer.run_prepared(&mut p, &with(&nudged(6), ShadowUpdate::Once), SIZE, SIZE).expect("frame");
        let mut fresh = renderer.prepare(backend, &TechniqueSpec::named("shadow-map")).expect("technique");
        let moved = renderer.run_prepared(&mut fresh, &nudged(6), SIZE, SIZE).expect("frame");
        assert!(
            kept.visibility[0].data() != moved.visibility[0].data(),
            "{backend:?}: the kept build followed the light"
        );
        assert!(first.visibility[0].data().contains(&0.0), "{backend:?}: nothing in shadow");
    }
}

#[test]
fn update_policies_parse_by_name() {
    assert_eq!(ShadowUpdate::parse("every-frame"), Ok(ShadowUpdate::EveryFrame));
    assert_eq!(ShadowUpdate::parse("on-change"), Ok(ShadowUpdate::OnChange));
    assert_eq!(ShadowUpdate::parse("every-4"), Ok(ShadowUpdate::Every(4)));
    assert_eq!(ShadowUpdate::parse("once"), Ok(ShadowUpdate::Once));
    for bad in ["every-0", "every-x", "sometimes"] {
        let e = ShadowUpdate::parse(bad).expect_err(bad);
        assert!(e.to_string().contains(bad), "{e}");
    }
}
