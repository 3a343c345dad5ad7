//! `penumbra-wedges` against `area-light-reference` under a light of radius 0.2, on `stacked-boxes` (a
//! box's penumbra tens of pixels wide on a box and the ground) and `primitives` (curved casters, whose
//! terminators the centre's silhouette does not soften), and on the teapot of `../shared/models` (an
//! open mesh, both of whose walls cast): at most half of `pcss`'s RMSE on each backend, far below the
//! count alone (`wedges=off`, the hard shadow of the light's centre), and the backends within 0.002 of
//! each other.

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
