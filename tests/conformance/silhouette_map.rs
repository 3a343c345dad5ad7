//! Sen et al.'s claim, held here: at the same map size and bias, with no filter, a silhouette
//! map's mismatch near shadow edges is at most a third of the shadow map's, at no more than 0.1 points of
//! interior mismatch, on the paper's kind of scenes at 512x512 with 256^2 and 512^2 maps.
//!
//! The paper's own rules (`corner_depth=fragment,keep=last`) are measured alongside and must at least
//! beat the shadow map near edges; they miss the third on `strike` and `crowd` (see
//! silhouette_map::points for why the defaults differ).

use shadow_core::FrameInputs;
use shadow_core::scenes::{self, SceneParams};
use shadow_core::technique::TechniqueSpec;
use shadowlab::compare::{CompareJob, run_compare};
use shadowlab::{BackendKind, Renderer, TechniqueRegistry};

#[test]
fn silhouette_maps_cut_a_shadow_maps_edge_mismatch_to_a_third() {
    let mut rows = Vec::new();
    let mut failures = Vec::new();
    for scene in ["cylinder", "primitives", "strike", "crowd"] {
        let s = scenes::build(scene, &SceneParams::default()).expect("scene");
        let cam = s.cameras().next().expect("camera").0;
        let frame = FrameInputs::from_scene(&s, cam).expect("frame");
        let mut renderer = Renderer::new(TechniqueRegistry::builtin());
        for res in [256, 512] {
            let specs = [
                format!("shadow-map:res={res}"),
                format!("silhouette-map:res={res}"),
                format!("silhouette-map:res={res},corner_depth=fragment,keep=last"),
            ];
            let job = CompareJob {
                scene: scene.into(),
                frame: &frame,
                width: 512,
                height: 512,
                techniques: specs.iter().map(|t| TechniqueSpec::parse(t).expect("spec")).collect(),
                reference: TechniqueSpec::named("ray-traced"),
                soft_reference: None,
                backends: vec![BackendKind::Cpu],
                out_dir: None,
            };
            let results = run_compare(&mut renderer, &job, |_| {}).expect("compare").results;
            let m = |i: usize, k: &str| results[i].vs_reference[k];
            let (map_edge, map_interior) = (m(0, "edge_band_mismatch"), m(0, "interior_mismatch"));
            let (edge, interior) = (m(1, "edge_band_mismatch"), m(1, "interior_mismatch"));
            let paper_edge = m(2, "edge_band_mismatch");
            rows.push(format!(
                "{scene:<10} {res:>3}: edge band shadow map {:.3}%, silhouette map {:.3}% (paper's rules {:.3}%); \
                 interior {:.3}% vs {:.3}%",
                map_edge * 100.0,
                edge * 100.0,
                paper_edge * 100.0,
                map_interior * 100.0,
                interior * 100.0
            ));
            if edge > map_edge / 3.0 {
                failures.push(format!("{scene} {res}: edge band {edge:.5} > a third of {map_edge:.5}"));
            }
            if interior > map_interior + 0.001 {
                failures.push(format!("{scene} {res}: interior {interior:.5} > {map_interior:.5} + 0.1 points"));
            }
            if paper_edge >= map_edge {
                failures.push(format!("{scene} {res}: the paper's rules {paper_edge:.5} do not beat {map_edge:.5}"));
            }
        }
    }
    eprintln!("{}", rows.join("\n"));
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
