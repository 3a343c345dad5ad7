//! Casters cut out by their texture, on the CPU backend: on `cutout`, under its own sun and under a spot
//! light in its place, the references and every technique that takes such casters light half of the
//! checkerboard card's shadow, as half of the board is clear.

use shadow_core::FrameInputs;
use shadow_core::scenes::cutouts::card_shadow_lit_share;
use shadow_core::scenes::{self, LightType, SceneParams};
use shadow_core::technique::TechniqueSpec;
use shadowlab::{Renderer, TechniqueRegistry};

const SIZE: u32 = 384;

/// The techniques whose picture of the card's shadow is not half lit for reasons of their own, the same
/// with the card opaque: each with whether under the spot light, and why.
const EXCEPTIONS: &[(&str, bool, &str)] = &[
    (
        "second-depth-shadow-map",
        true,
        "its map holds the second surface from the light, which under a lone card is the ground: no shadow",
    ),
    ("variance-shadow-map", true, "its light-bleeding reduction darkens the penumbrae: 46.6% lit"),
];

/// The share of the card's shadow `spec` lights on the CPU, and the pixels it is measured over.
fn lit_share(renderer: &mut Renderer, frame: &FrameInputs, spec: &TechniqueSpec) -> (f64, usize) {
    let (f, _) = renderer.run_cpu_frame(frame, SIZE, SIZE, spec).unwrap_or_else(|e| panic!("{spec}: {e}"));
    card_shadow_lit_share(f.receiver_points(0))
}

#[test]
fn every_cpu_technique_lights_half_of_a_checkerboards_shadow() {
    let mut renderer = Renderer::new(TechniqueRegistry::builtin());
    let mut failures = Vec::new();
    let mut measured = 0;
    for light in [None, Some(LightType::Spot)] {
        let scene = scenes::build("cutout", &SceneParams { light, ..SceneParams::default() }).expect("cutout");
        let frame = FrameInputs::from_first_camera(&scene).expect("frame");
        let (taken, _) = renderer.registry().measurable(&frame);
        let references = ["ray-traced", "area-light-reference"].map(TechniqueSpec::named);
        let soft_reference = light.is_some();
        let measured_here = taken
            .iter()
            .filter(|t| !EXCEPTIONS.iter().any(|&(name, spot, _)| t.name == name && spot == soft_reference));
        for spec in references.iter().take(1 + usize::from(soft_reference)).chain(measured_here) {
            let (share, pixels) = lit_share(&mut renderer, &frame, spec);
            assert!(pixels > 5000, "{spec}: {pixels} pixels under the card");
            // The references exactly, up to the pixels on the squares' sides; the others within 3%.
            let tolerance = if references.contains(spec) { 0.005 } else { 0.015 };
            if (share - 0.5).abs() > tolerance {
                failures.push(format!("{spec} under {light:?}: {:.2}% lit", share * 100.0));
            }
            measured += 1;
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    assert!(measured > 20, "{measured} techniques measured");
}
