//! Chan's claims for `hybrid` (thesis chapter 3), as issue 9 states them, at 512x512 against the ray-traced
//! reference (CPU backend):
//!
//! - shadow-volume accuracy from a 512^2 classifying map: mismatch at or under 0.1% on every built-in
//!   scene with the default `edge_texels=paired`; with Chan's rule alone (`edge_texels=off`) on every one
//!   but `tree`, whose thin branches the map undersamples (the thesis's Fig. 3-8), and `tree` with a
//!   1024^2 map;
//! - the computation mask confines the volumes to the silhouette pixels, and the caster masks (on by
//!   default) each connected component's volume to those its shadow can hold: the fragments processed are
//!   at most a tenth of `shadow-volume-zfail`'s on cubes, cage and tree, and the unmasked fill it reports
//!   is exactly z-fail's;
//! - with `edge_texels=all` (receivers under a silhouette edge's texels masked too) every built-in scene
//!   is at or under 0.1% with a 512^2 map too, and `paired` masks fewer pixels than `all` does.

use shadow_core::FrameInputs;
use shadow_core::scenes::{self, SceneParams};
use shadow_core::technique::TechniqueSpec;
use shadowlab::compare::{CompareJob, ResultEntry, run_compare};
use shadowlab::{BackendKind, Renderer, TechniqueRegistry};

fn run(scene: &str, specs: &[&str]) -> Vec<ResultEntry> {
    let s = scenes::build(scene, &SceneParams::default()).expect("scene");
    let cam = s.cameras().next().expect("camera").0;
    let frame = FrameInputs::from_scene(&s, cam).expect("frame");
    let mut renderer = Renderer::new(TechniqueRegistry::builtin());
    let job = CompareJob {
        scene: scene.into(),
        frame: &frame,
        width: 512,
        height: 512,
        techniques: specs.iter().map(|t| TechniqueSpec::parse(t).expect("spec")).collect(),
        reference: TechniqueSpec::named("ray-traced"),
        backends: vec![BackendKind::Cpu],
        out_dir: None,
    };
    run_compare(&mut renderer, &job, |_| {}).expect("compare").results
}

fn counter(r: &ResultEntry, name: &str) -> f64 {
    r.counters.get(name).copied().unwrap_or_else(|| panic!("{} has no counter {name}", r.technique))
}

#[test]
fn silhouette_pixels_get_shadow_volume_accuracy() {
    let (mut rows, mut failures) = (Vec::new(), Vec::new());
    for scene in scenes::names() {
        let chan = if scene == "tree" { "hybrid:res=1024,edge_texels=off" } else { "hybrid:res=512,edge_texels=off" };
        let specs = ["hybrid:res=512", chan];
        let r = run(scene, &specs);
        for (spec, result) in specs.iter().zip(&r) {
            let m = result.vs_reference["mismatch"];
            rows.push(format!("{scene:<14} {spec} {:.3}%", m * 100.0));
            if m > 0.001 {
                failures.push(format!("{scene}: {spec} {:.3}% > 0.1%", m * 100.0));
            }
        }
    }
    eprintln!("{}", rows.join("\n"));
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn the_computation_mask_saves_nine_tenths_of_the_fill() {
    let (mut rows, mut failures) = (Vec::new(), Vec::new());
    for scene in ["cubes", "cage", "tree"] {
        let r =
            run(scene, &["hybrid:res=512,unmasked_fill=on", "hybrid:res=512,caster_masks=off", "shadow-volume-zfail"]);
        let (processed, unmasked) = (counter(&r[0], "volume_fragments"), counter(&r[0], "unmasked_volume_fragments"));
        let (mask_only, zfail) = (counter(&r[1], "volume_fragments"), counter(&r[2], "volume_fragments"));
        let ratio = processed / zfail;
        rows.push(format!(
            "{scene:<6} processed {processed} of z-fail's {zfail} ({:.1}%; without caster masks {:.1}%)",
            ratio * 100.0,
            mask_only / zfail * 100.0
        ));
        if unmasked != zfail {
            failures.push(format!("{scene}: unmasked fill {unmasked} is not z-fail's {zfail}"));
        }
        if ratio > 0.1 {
            failures.push(format!("{scene}: {:.1}% of z-fail's fill > 10%", ratio * 100.0));
        }
    }
    eprintln!("{}", rows.join("\n"));
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn every_edge_texel_brings_every_scene_under_a_tenth_of_a_percent_and_pairs_fewer_pixels() {
    let (mut rows, mut failures) = (Vec::new(), Vec::new());
    for scene in scenes::names() {
        let r = run(scene, &["hybrid:res=512,edge_texels=all", "hybrid:res=512"]);
        let m = r[0].vs_reference["mismatch"];
        let (all, paired) = (counter(&r[0], "silhouette_pixels"), counter(&r[1], "silhouette_pixels"));
        rows.push(format!("{scene:<14} {:.3}% ({all} silhouette pixels; paired {paired})", m * 100.0));
        if m > 0.001 {
            failures.push(format!("{scene}: {:.3}% > 0.1%", m * 100.0));
        }
        if paired > all {
            failures.push(format!("{scene}: paired masks {paired} pixels, all {all}"));
        }
    }
    eprintln!("{}", rows.join("\n"));
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn the_pencil_order_changes_no_fragment() {
    // The CPU's pencil order (volume sides tested at the silhouette pixels in their angle around the
    // light's image) against the row walk, every volume drawn through the whole mask: the same fragments,
    // stencil updates and picture on every built-in scene, the pencil taking most sides where the scene
    // has any to take.
    let mut failures = Vec::new();
    for scene in scenes::names() {
        let r =
            run(scene, &["hybrid:res=512,caster_masks=off,pencil=on", "hybrid:res=512,caster_masks=off,pencil=off"]);
        for key in ["volume_fragments", "stencil_updates", "silhouette_pixels"] {
            if counter(&r[0], key) != counter(&r[1], key) {
                failures.push(format!(
                    "{scene}: {key} {} with the pencil, {} without",
                    counter(&r[0], key),
                    counter(&r[1], key)
                ));
            }
        }
        if r[0].vs_reference["mismatch"] != r[1].vs_reference["mismatch"] {
            failures.push(format!("{scene}: mismatch differs"));
        }
        let (taken, sides) = (counter(&r[0], "pencil_triangles"), counter(&r[0], "silhouette_edges"));
        eprintln!("{scene:<14} {taken} volume triangles in pencil order ({sides} silhouette edges)");
        if counter(&r[1], "pencil_triangles") != 0.0 || (sides > 100.0 && taken < sides) {
            failures.push(format!("{scene}: {taken} triangles in pencil order for {sides} silhouette edges"));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
