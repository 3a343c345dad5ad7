//! Casters cut out by their texture: on `cutout`, under its own sun and under a spot light in its place,
//! the references and every technique that takes such casters light half of the checkerboard card's
//! shadow, as half of the board is clear, on the CPU backend and on wgpu.

use shadow_core::FrameInputs;
use shadow_core::scenes::{self, LightType, SceneParams};
use shadow_core::technique::TechniqueSpec;
use shadowlab::results::cutouts::card_lit_share;
use shadowlab::{BackendKind, Renderer, TechniqueRegistry};

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

/// The share of the card's shadow `spec` lights on `backend`, and the pixels it is measured over (the
/// backend's own G-buffer's).
fn lit_share(renderer: &mut Renderer, backend: BackendKind, frame: &FrameInputs, spec: &TechniqueSpec) -> (f64, usize) {
    card_lit_share(renderer, backend, frame, spec, (SIZE, SIZE))
        .unwrap_or_else(|e| panic!("{spec} on {backend:?}: {e}"))
}

#[test]
fn every_cpu_technique_lights_half_of_a_checkerboards_shadow() {
    half_lit_on(Renderer::new(TechniqueRegistry::builtin()), BackendKind::Cpu);
}

#[test]
fn every_wgpu_technique_lights_half_of_a_checkerboards_shadow() {
    let Some(renderer) = crate::with_wgpu("the cut-out casters on wgpu") else { return };
    half_lit_on(renderer, BackendKind::Wgpu);
}

fn half_lit_on(mut renderer: Renderer, backend: BackendKind) {
    let mut failures = Vec::new();
    let mut measured = 0;
    for light in [None, Some(LightType::Spot)] {
        let scene = scenes::build("cutout", &SceneParams { light, ..SceneParams::default() }).expect("cutout");
        let frame = FrameInputs::from_first_camera(&scene).expect("frame");
        let (taken, _) = renderer.registry().measurable(&frame);
        let references = ["ray-traced", "area-light-reference"].map(TechniqueSpec::named);
        let soft_reference = light.is_some();
        let on_backend = |t: &&TechniqueSpec| {
            backend == BackendKind::Cpu || renderer.registry().get(&t.name).is_ok_and(|e| e.wgpu.is_some())
        };
        let measured_here: Vec<&TechniqueSpec> = taken
            .iter()
            .filter(on_backend)
            .filter(|t| !EXCEPTIONS.iter().any(|&(name, spot, _)| t.name == name && spot == soft_reference))
            .collect();
        // The references run on the CPU, at either backend's pixels: measured with the CPU's.
        let reference_count = if backend == BackendKind::Cpu { 1 + usize::from(soft_reference) } else { 0 };
        for spec in references.iter().take(reference_count).chain(measured_here) {
            let (share, pixels) = lit_share(&mut renderer, backend, &frame, spec);
            assert!(pixels > 5000, "{spec}: {pixels} pixels under the card");
            // The references exactly, up to the pixels on the squares' sides; the others within 3%.
            let tolerance = if references.contains(spec) { 0.005 } else { 0.015 };
            if (share - 0.5).abs() > tolerance {
                failures.push(format!("{spec} on {backend:?} under {light:?}: {:.2}% lit", share * 100.0));
            }
            measured += usize::from(!references.contains(spec));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    // Every map technique under the sun, and the soft ones too under the spot.
    assert!(measured > 17, "{measured} techniques measured on {backend:?}");
}
