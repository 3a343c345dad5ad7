//! `penumbra-wedges` against `area-light-reference` under a light of radius 0.2, on `stacked-boxes` (a
//! box's penumbra tens of pixels wide on a box and the ground) and `primitives` (curved casters, whose
//! terminators the centre's silhouette does not soften), and on the teapot of `../shared/models` (an
//! open mesh, both of whose walls cast): at most half of `pcss`'s RMSE on each backend, far below the
//! count alone (`wedges=off`, the hard shadow of the light's centre), and the backends within 0.002 of
//! each other. And on `tree`, whose thin branches give thousands of side quads a fraction of a pixel
//! wide: no isolated dark pixel in the light on either backend, and the backends nearly equal.

use shadow_core::technique::TechniqueSpec;
use shadowlab::BackendKind;
use shadowlab::compare::{CompareJob, run_compare};
use shadowlab::results::soft::frame_with_radius;

#[test]
fn wedges_halve_the_rmse_of_pcss_and_agree_across_backends() {
    let Some(mut renderer) = crate::with_wgpu("the penumbra wedges' conformance") else {
        return;
    };
    let specs = ["penumbra-wedges", "pcss", "penumbra-wedges:wedges=off"];
    for scene in ["stacked-boxes", "primitives", "teapot.obj"] {
        let Some(frame) = frame_with_radius(scene, 0.2).expect("the scene builds") else {
            eprintln!("{scene} is not in ../shared/models: left out");
            continue;
        };
        let job = CompareJob {
            scene: scene.into(),
            frame: &frame,
            width: 256,
            height: 256,
            techniques: specs.iter().map(|s| TechniqueSpec::parse(s).expect("spec")).collect(),
            reference: TechniqueSpec::named("area-light-reference"),
            soft_reference: None,
            backends: vec![BackendKind::Cpu, BackendKind::Wgpu],
            out_dir: None,
        };
        let report = run_compare(&mut renderer, &job, |_| {}).expect("compare");
        let rmse = |technique: &str, wedges: bool, backend: &str| {
            let entry = report.results.iter().find(|e| {
                e.technique == technique && e.backend == backend && e.settings.contains("wedges=off") != wedges
            });
            entry.expect("an entry").metrics.rmse
        };
        for name in ["cpu", "wgpu"] {
            let (wedges, pcss) = (rmse("penumbra-wedges", true, name), rmse("pcss", true, name));
            let count = rmse("penumbra-wedges", false, name);
            eprintln!("{scene} on {name}: wedges {wedges:.4}, pcss {pcss:.4}, the count alone {count:.4}");
            assert!(wedges <= 0.5 * pcss, "{scene} on {name}: wedges {wedges:.4} against pcss {pcss:.4}");
            assert!(wedges < 0.25 * count, "{scene} on {name}: wedges {wedges:.4} against the count {count:.4}");
        }
        let cross = report.cross_backend.iter().find(|c| c.settings.contains("wedges=on")).expect("a cross entry");
        assert!(cross.rmse <= 0.002, "{scene}: cross-backend RMSE {:.4}", cross.rmse);
    }
}

/// The pixels of `v` darker by more than one half than each of their eight neighbours (all receivers) and
/// than `reference` there: a lone pixel in shadow that no lone caster in the reference explains (a
/// branch's tip in shadow is a lone dark pixel of the reference too).
fn specks(
    v: &shadow_core::Image<f32>,
    reference: &shadow_core::Image<f32>,
    receiver: &shadow_core::Image<bool>,
) -> usize {
    let (w, h) = (v.width(), v.height());
    let mut found = 0;
    for y in 1..h - 1 {
        for x in 1..w - 1 {
            let here = *v.get(x, y);
            let lone = (y - 1..=y + 1).all(|ny| {
                (x - 1..=x + 1).all(|nx| (nx, ny) == (x, y) || (*receiver.get(nx, ny) && *v.get(nx, ny) > here + 0.5))
            });
            found += usize::from(*receiver.get(x, y) && lone && *reference.get(x, y) > here + 0.5);
        }
    }
    found
}

#[test]
fn wedges_leave_no_lone_dark_pixel_in_the_light_of_thin_branches() {
    let Some(mut renderer) = crate::with_wgpu("the penumbra wedges' lone dark pixels") else { return };
    let frame = crate::frame_taken_by("tree", shadow_core::technique::LightKinds::POSITIONED);
    let (w, h) = (256, 256);
    let receiver = shadow_cpu::gbuffer::render(&frame, w, h).expect("the G-buffer").receiver;
    let reference = TechniqueSpec::named("area-light-reference");
    let reference = renderer.run(BackendKind::Cpu, &frame, w, h, &reference).expect("the reference").visibility;
    let spec = TechniqueSpec::named("penumbra-wedges");
    let mut seen = Vec::new();
    for backend in [BackendKind::Cpu, BackendKind::Wgpu] {
        let v = renderer.run(backend, &frame, w, h, &spec).expect("the wedges").visibility.remove(0);
        assert!(v.data().iter().any(|&v| crate::shadowed(v)), "{backend:?}: nothing in shadow");
        assert_eq!(specks(&v, &reference[0], &receiver), 0, "{backend:?}: lone dark pixels in the light");
        seen.push(v);
    }
    let differ = seen[0].data().iter().zip(seen[1].data()).filter(|&(a, b)| (a - b).abs() > 0.5).count();
    let receivers = receiver.data().iter().filter(|&&r| r).count();
    assert!((differ as f64) < 0.0003 * receivers as f64, "{differ} of {receivers} pixels differ across backends");
}
