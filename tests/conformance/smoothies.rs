//! Chan's claims for `smoothies` (thesis chapter 4) against the Monte Carlo
//! `area-light-reference` (CPU backend):
//!
//! - the alpha remap (Eq. 4.1, Fig. 4-10): on `stacked-boxes` the upper box's shadow has a sharper edge on
//!   the lower box than on the ground, measured as the 10%-90% width in pixels along a line across each
//!   edge; without the remap the ramp is as wide in the map on both.

use shadow_core::FrameInputs;
use shadow_core::metrics::penumbra_width;
use shadow_core::scenes::{self, SceneParams};
use shadow_core::technique::TechniqueSpec;
use shadowlab::{Renderer, TechniqueRegistry};

#[test]
fn the_remap_sharpens_the_shadow_on_the_nearer_receiver() {
    // A light of radius 0.2 (the scene's is 0.05), so the penumbrae span pixels enough to measure.
    let mut scene = scenes::build("stacked-boxes", &SceneParams::default()).expect("scene");
    let key = scene.lights().next().expect("a light").0;
    scene.light_mut(key).expect("the light").radius = 0.2;
    let cam = scene.cameras().next().expect("camera").0;
    let frame = FrameInputs::from_scene(&scene, cam).expect("frame");
    let [top, ground] = shadowlab::results::soft::stacked_boxes_edges(&frame).expect("a spot light");
    let mut renderer = Renderer::new(TechniqueRegistry::builtin());
    let mut rows = Vec::new();
    let mut widths = Vec::new();
    // The thesis's comparisons are measured alongside, for the record (no claim is tested for them).
    for spec in [
        "smoothies",
        "smoothies:remap=off",
        "area-light-reference",
        "pcss",
        "penumbra-map",
        "variance-shadow-map",
        "exponential-variance-shadow-map",
        "moment-shadow-map",
    ] {
        let (f, _) =
            renderer.run_cpu_frame(&frame, 512, 512, &TechniqueSpec::parse(spec).expect("spec")).expect("frame");
        let g = &f.gbuffer;
        let [on_top, on_ground] = [top, ground].map(|line| {
            penumbra_width(&frame.camera, &f.visibility[0], &g.position, line).expect("a full ramp from 0.1 to 0.9")
        });
        rows.push(format!("{spec:<22} lower box {on_top:5.1} px, ground {on_ground:5.1} px"));
        widths.push((on_top, on_ground));
    }
    eprintln!("10%-90% penumbra width across the upper box's shadow edge, 512x512:\n{}", rows.join("\n"));
    let (remapped, fixed) = (widths[0], widths[1]);
    assert!(
        remapped.0 * 1.2 < remapped.1,
        "remapped: lower box {} px is not sharper than ground {} px",
        remapped.0,
        remapped.1
    );
    // Without the remap the ramp is as wide in the map on both receivers (Fig. 4-10, left): much wider on
    // the lower box, and no sharper there than on the ground.
    assert!(fixed.0 > remapped.0 * 2.0, "without the remap the lower box's edge should widen: {fixed:?}");
    assert!(fixed.0 * 1.2 > fixed.1, "without the remap the edges should be alike: {fixed:?}");
}
