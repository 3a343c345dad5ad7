//! The filterable maps (`variance-shadow-map`, `exponential-variance-shadow-map`, `moment-shadow-map`)
//! against `area-light-reference` on `stacked-boxes` under a light of radius 0.2, where the upper box
//! throws a penumbra tens of pixels wide onto the lower box and the ground: each beats the bilinear
//! shadow map's RMSE and agrees across the backends within 0.002. On `cubes`, the variance map's
//! light bleeding, and what the reduction and the exponential warp leave of it.

use shadow_core::FrameInputs;
use shadow_core::scenes::{self, SceneParams};
use shadow_core::technique::TechniqueSpec;
use shadowlab::BackendKind;
use shadowlab::compare::{CompareJob, CompareReport, run_compare};

const MAPS: [&str; 3] = ["variance-shadow-map", "exponential-variance-shadow-map", "moment-shadow-map"];

/// Built-in scene `name` with a light of radius 0.2 (the scenes' is 0.05).
fn wide_penumbra_frame(name: &str) -> FrameInputs {
    let mut scene = scenes::build(name, &SceneParams::default()).expect("scene");
    let key = scene.lights().next().expect("a light").0;
    scene.light_mut(key).expect("the light").radius = 0.2;
    FrameInputs::from_first_camera(&scene).expect("frame")
}

/// `specs` on `backends` against `area-light-reference` on `scene` under [`wide_penumbra_frame`], 256x256.
fn compare(
    scene: &str,
    specs: &[&str],
    backends: Vec<BackendKind>,
    renderer: &mut shadowlab::Renderer,
) -> CompareReport {
    let frame = wide_penumbra_frame(scene);
    let job = CompareJob {
        scene: scene.into(),
        frame: &frame,
        width: 256,
        height: 256,
        techniques: specs.iter().map(|s| TechniqueSpec::parse(s).expect("spec")).collect(),
        reference: TechniqueSpec::named("area-light-reference"),
        soft_reference: None,
        backends,
        out_dir: None,
    };
    run_compare(renderer, &job, |_| {}).expect("compare")
}

#[test]
fn filterable_maps_beat_the_bilinear_map_and_agree_across_backends() {
    let Some(mut renderer) = crate::with_wgpu("the filterable maps' conformance") else {
        return;
    };
    let specs = [MAPS.as_slice(), &["shadow-map:res=1024,filter=bilinear"]].concat();
    let report = compare("stacked-boxes", &specs, vec![BackendKind::Cpu, BackendKind::Wgpu], &mut renderer);
    let rmse = |name: &str, backend: &str| {
        let e = report.results.iter().find(|e| e.technique == name && e.backend == backend).expect("an entry");
        e.metrics.rmse
    };
    for backend in ["cpu", "wgpu"] {
        let bilinear = rmse("shadow-map", backend);
        for map in MAPS {
            let r = rmse(map, backend);
            eprintln!("{map} on {backend}: RMSE {r:.4} (bilinear shadow map {bilinear:.4})");
            assert!(r < bilinear, "{map} on {backend}: RMSE {r:.4}, bilinear shadow map {bilinear:.4}");
        }
    }
    for map in MAPS {
        let cross = report.cross_backend.iter().find(|c| c.technique == map).expect("a cross entry");
        assert!(cross.rmse <= 0.002, "{map}: cross-backend RMSE {:.4}", cross.rmse);
    }
}

#[test]
fn the_exponential_warp_and_the_reduction_cut_the_bleeding() {
    // On `cubes` boxes shadow boxes: a receiver in one box's umbra often has another blocker behind the
    // first in its filter region, the case where Chebyshev's bound lets light through.
    let specs = ["variance-shadow-map:bleed=0", "variance-shadow-map", "exponential-variance-shadow-map"];
    let mut renderer = shadowlab::Renderer::new(shadowlab::TechniqueRegistry::builtin());
    let report = compare("cubes", &specs, vec![BackendKind::Cpu], &mut renderer);
    let [plain, reduced, exponential] = [0, 1, 2].map(|i| report.results[i].vs_reference["light_bleeding"]);
    eprintln!(
        "light bleeding on cubes: variance {:.2}%, with its reduction {:.2}%, exponential {:.2}%",
        plain * 100.0,
        reduced * 100.0,
        exponential * 100.0
    );
    assert!(plain > 0.005, "the variance map does not bleed here: {plain}");
    assert!(reduced < 0.75 * plain, "the reduction leaves {reduced} of {plain}");
    assert!(exponential < 0.75 * plain, "the exponential map bleeds {exponential} against {plain}");
}
