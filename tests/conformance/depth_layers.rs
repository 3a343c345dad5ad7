//! Weiskopf-Ertl's claims on heavily undersampled maps (128^2 and 256^2, their Fig. 5 and 6 scenes):
//! the dual map with back-face culling keeps acne away and its leaks flat over two orders of magnitude of
//! z_offset, where a constant bias over the same offsets trades acne for leaks; and the midpoint map with
//! back-face culling unshadows itself behind silhouettes (Fig. 4).

use std::collections::BTreeMap;

use shadow_core::FrameInputs;
use shadow_core::scenes::{self, SceneParams};
use shadow_core::technique::TechniqueSpec;
use shadowlab::compare::{CompareJob, ResultEntry, run_compare};
use shadowlab::{BackendKind, Renderer, TechniqueRegistry};

const SWEEP: [&str; 5] = ["0.1", "0.3", "1", "3", "10"];

fn run(scene: &str, specs: Vec<String>) -> Vec<ResultEntry> {
    let s = scenes::build(scene, &SceneParams::default()).expect("scene");
    let cam = s.cameras().next().expect("camera").0;
    let frame = FrameInputs::from_scene(&s, cam).expect("frame");
    let mut r = Renderer::new(TechniqueRegistry::builtin());
    let techniques = specs.iter().map(|t| TechniqueSpec::parse(t).expect("spec")).collect();
    let job = CompareJob {
        scene: scene.into(),
        frame: &frame,
        width: 384,
        height: 384,
        techniques,
        reference: TechniqueSpec::named("ray-traced"),
        soft_reference: None,
        backends: vec![BackendKind::Cpu],
        out_dir: None,
    };
    run_compare(&mut r, &job, |_| {}).expect("compare").results
}

fn key(e: &ResultEntry, k: &str) -> f64 {
    e.vs_reference[k]
}

#[test]
fn dual_maps_are_robust_to_the_offset_where_a_constant_bias_is_not() {
    for scene in ["l-shape", "double-torus"] {
        for res in [128, 256] {
            let mut specs = Vec::new();
            for z in SWEEP {
                specs.push(format!("dual-shadow-map:res={res},z_offset={z}"));
                specs.push(format!("shadow-map:res={res},bias=world,bias_world={z}"));
            }
            let results = run(scene, specs);
            let by: BTreeMap<&str, Vec<&ResultEntry>> = results.iter().fold(BTreeMap::new(), |mut m, e| {
                m.entry(e.technique.as_str()).or_default().push(e);
                m
            });
            let dual = &by["dual-shadow-map"];
            let light: Vec<f64> = dual.iter().map(|e| key(e, "false_light")).collect();
            let least = light.iter().copied().fold(f64::INFINITY, f64::min);
            for (e, z) in dual.iter().zip(SWEEP) {
                assert!(
                    key(e, "texel_acne") <= 0.0005,
                    "{scene} {res}: dual acne {:.4}% at z_offset {z}",
                    key(e, "texel_acne") * 100.0
                );
                assert!(
                    key(e, "false_light") <= 2.0 * least + 1e-9,
                    "{scene} {res}: dual leaks {:.3}% at {z}",
                    key(e, "false_light") * 100.0
                );
            }
            // The constant bias over the same offsets: leaks at the large end at least ten times the least.
            let map = &by["shadow-map"];
            let map_light: Vec<f64> = map.iter().map(|e| key(e, "false_light")).collect();
            let (lo, hi) = (
                map_light.iter().copied().fold(f64::INFINITY, f64::min),
                map_light.iter().copied().fold(0.0, f64::max),
            );
            assert!(hi > 10.0 * lo, "{scene} {res}: a constant bias should leak at large offsets: {map_light:?}");
        }
    }
    // And acne at the small end of a constant bias (which the dual map shares: below the sweep its bias is
    // the offset itself).
    let small = run("double-torus", vec!["shadow-map:res=128,bias=world,bias_world=0.01".into()]);
    assert!(key(&small[0], "texel_acne") > 0.005, "a 1 cm constant bias should show acne at 128^2");
}

#[test]
fn midpoint_maps_with_back_face_culling_unshadow_themselves() {
    for scene in ["l-shape", "double-torus"] {
        let r = run(scene, vec!["midpoint-shadow-map:res=128,culling=auto".into(), "dual-shadow-map:res=128".into()]);
        let (mid, dual) = (key(&r[0], "back_false_light"), key(&r[1], "back_false_light"));
        assert!(
            mid > 1.3 * dual,
            "{scene}: midpoint+culling back-face false light {:.3}% vs dual {:.3}%",
            mid * 100.0,
            dual * 100.0
        );
    }
}
