//! The maps fitted to the camera's view (cascades, light-space perspective, post-perspective) on the
//! outdoor street, where a uniform map's perspective aliasing shows: each agrees across the backends,
//! beats the uniform map of the same texel budget (one 4096^2 map against four 2048^2 cascades) in the
//! near third of the view, a silhouette map in the same cascades sharpens their edges, and stabilised
//! cascades hold still as the camera walks.

use shadow_core::FrameInputs;
use shadow_core::scenes::{self, SceneParams};
use shadow_core::technique::TechniqueSpec;
use shadowlab::BackendKind;
use shadowlab::compare::{CompareJob, run_compare};
use shadowlab::flicker::{FlickerWalk, walk};

fn outdoor() -> FrameInputs {
    let scene = scenes::build("outdoor", &SceneParams::default()).expect("outdoor scene");
    FrameInputs::from_first_camera(&scene).expect("frame")
}

#[test]
fn view_fitted_maps_beat_the_uniform_map_near_the_viewer() {
    let Some(mut renderer) = crate::with_wgpu("view-fitted maps") else { return };
    let frame = outdoor();
    let names = ["shadow-map:res=4096", "cascaded-shadow-map", "lispsm", "perspective-shadow-map"];
    let silhouettes = "silhouette-map:res=2048,cascades=4";
    let dual = "dual-shadow-map:res=2048,cascades=4";
    let job = CompareJob {
        scene: "outdoor".into(),
        frame: &frame,
        width: 320,
        height: 180,
        techniques: names.iter().chain([&silhouettes, &dual]).map(|n| TechniqueSpec::parse(n).expect("spec")).collect(),
        reference: TechniqueSpec::named("ray-traced"),
        soft_reference: None,
        backends: vec![BackendKind::Cpu, BackendKind::Wgpu],
        out_dir: None,
    };
    let report = run_compare(&mut renderer, &job, |_| {}).expect("compare");
    let near = |name: &str, backend: &str| {
        let e = report.results.iter().find(|e| e.technique == name && e.backend == backend).expect("a result");
        e.vs_reference["near_field_mismatch"]
    };
    for backend in ["cpu", "wgpu"] {
        let uniform = near("shadow-map", backend);
        assert!(
            uniform > 0.01,
            "{backend}: the uniform map's near field is {:.3}%: no aliasing to fix",
            uniform * 100.0
        );
        let fitted: Vec<(&str, f64)> = names[1..].iter().map(|&n| (n, near(n, backend))).collect();
        for &(name, err) in &fitted {
            assert!(
                err <= 0.5 * uniform,
                "{backend}: {name} near field {:.3}% vs uniform {:.3}%",
                err * 100.0,
                uniform * 100.0
            );
        }
        // The silhouette map in the same cascades (and their texels) takes most of the edges' error away.
        let edges = |name: &str| {
            let e = report.results.iter().find(|e| e.technique == name && e.backend == backend).expect("a result");
            e.metrics.edge_band_mismatch
        };
        let (sm, csm) = (edges("silhouette-map"), edges("cascaded-shadow-map"));
        assert!(sm <= 0.6 * csm, "{backend}: silhouette cascades' edge band {:.3}% vs {:.3}%", sm * 100.0, csm * 100.0);
        // Weiskopf and Ertl's dual map in cascades is as near-sighted as the plain cascades.
        let dual = near("dual-shadow-map", backend);
        assert!(dual <= 0.5 * uniform, "{backend}: dual cascades' near field {:.3}%", dual * 100.0);
        let best = fitted.iter().map(|f| f.1).fold(f64::INFINITY, f64::min);
        assert!(
            best <= 0.25 * uniform,
            "{backend}: best near field {:.3}% vs uniform {:.3}%",
            best * 100.0,
            uniform * 100.0
        );
    }
    for c in &report.cross_backend {
        assert!(c.mismatch <= 0.005, "{}: cpu and wgpu disagree on {:.3}%", c.technique, c.mismatch * 100.0);
    }
    // The maps are where the texels went: far more per pixel than the uniform map's.
    let density = |name: &str| report.results.iter().find(|e| e.technique == name).expect("a result").vs_reference["near_texel_density_median"];
    for name in &names[1..] {
        assert!(density(name) > 4.0 * density("shadow-map"), "{name}: {} texels per pixel", density(name));
    }
}

#[test]
fn stabilised_cascades_hold_still_as_the_camera_walks() {
    let mut renderer = shadowlab::Renderer::new(shadowlab::TechniqueRegistry::builtin());
    let frame = outdoor();
    let path = walk(&frame.camera, 8, 0.05, 0.15f32.to_radians());
    let walked = FlickerWalk::new(&mut renderer, &frame, &path, (160, 90)).expect("walk");
    let mut flicker = |spec: &str| {
        walked.flicker(&mut renderer, &TechniqueSpec::parse(spec).expect("spec"), |_| {}).expect("flicker")
    };
    // A uniform map does not follow the camera at all.
    assert_eq!(flicker("shadow-map:res=4096"), 0.0);
    let tight = flicker("cascaded-shadow-map:stabilize=off");
    assert!(tight > 0.001, "unstabilised cascades flicker {:.4}%: the walk moves nothing", tight * 100.0);
    for fit in ["snapped", "sphere"] {
        let stable = flicker(&format!("cascaded-shadow-map:stabilize={fit}"));
        assert!(stable <= tight / 10.0, "{fit}: {:.4}% vs unstabilised {:.4}%", stable * 100.0, tight * 100.0);
    }
}
