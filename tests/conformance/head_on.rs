//! Surfaces squarely facing the light: a card over a wall, both perpendicular to the light's travel along
//! each world axis, under a directional, a spot and a point light. Such a card has no depth slope in the
//! light's map, so only the constant bias settles the tie between its stored and looked-up depths, and
//! it must do so whatever the card's depth in the fitted range. Each light comes exactly along the axis
//! and tilted by the f32 rounding of a glTF node rotated a quarter turn (the noon sun of a file), which
//! is where a near-zero depth once showed as bands of false shadow across the card.

use shadow_core::FrameInputs;
use shadow_core::glam::{Mat4, Quat, Vec3};
use shadow_core::procedural;
use shadow_core::scene::{Camera, Light, Material, Scene};
use shadow_core::technique::TechniqueSpec;
use shadowlab::BackendKind;
use shadowlab::compare::{CompareJob, run_compare};

/// The tilt of a quarter-turn node rotation's forward axis in f32: `sin(pi / 4)` squared rounds to just
/// under a half, leaving about 6e-8 of the forward axis across it.
const ROUNDING_TILT: f32 = 5.960_465e-8;

/// The card (1 x 1) at the origin and a 3 x 3 wall 0.6 behind it, both facing against `travel`, lit by
/// `light`, seen from the light's side at an angle.
fn card_over_wall(travel: Vec3, light: Light) -> Scene {
    let mut s = Scene::new();
    let facing = Quat::from_rotation_arc(Vec3::Y, -travel);
    let card = s.add_mesh(procedural::plane(1.0, 1.0).expect("card"));
    let wall = s.add_mesh(procedural::plane(3.0, 3.0).expect("wall"));
    let grey = s.add_material(Material::colored("grey", Vec3::splat(0.7)));
    s.add_instance("card", card, grey, Mat4::from_quat(facing)).expect("card node");
    let behind = Mat4::from_translation(travel * 0.6) * Mat4::from_quat(facing);
    s.add_instance("wall", wall, grey, behind).expect("wall node");
    let across = travel.any_orthonormal_vector();
    s.add_camera(Camera::look_at(-travel * 2.2 + across * 1.1, travel * 0.2, 45.0));
    s.add_light(light);
    s
}

#[test]
fn surfaces_facing_the_light_are_lit_along_every_axis() {
    let Some(mut renderer) = crate::with_wgpu("head-on lights") else { return };
    let axes = [Vec3::X, Vec3::NEG_X, Vec3::Y, Vec3::NEG_Y, Vec3::Z, Vec3::NEG_Z];
    let mut failures = Vec::new();
    for travel in axes {
        for tilt in [0.0, ROUNDING_TILT] {
            let along = (travel + travel.any_orthonormal_vector() * tilt).normalize();
            let lights = [
                ("directional", Light::directional(along), &["shadow-map", "cascaded-shadow-map"][..]),
                ("spot", Light::spot(-travel * 3.0, -travel * 3.0 + along, 60.0), &["shadow-map"][..]),
                ("point", Light::point(-travel * 3.0), &["shadow-map"][..]),
            ];
            for (kind, light, techniques) in lights {
                let scene = card_over_wall(travel, light);
                let frame = FrameInputs::from_first_camera(&scene).expect("frame");
                let job = CompareJob {
                    scene: format!("head-on-{kind}"),
                    frame: &frame,
                    width: 128,
                    height: 128,
                    techniques: techniques.iter().map(|n| TechniqueSpec::parse(n).expect("spec")).collect(),
                    reference: TechniqueSpec::named("ray-traced"),
                    soft_reference: None,
                    backends: vec![BackendKind::Cpu, BackendKind::Wgpu],
                    out_dir: None,
                };
                let report = run_compare(&mut renderer, &job, |_| {}).expect("compare");
                for e in &report.results {
                    // The card's shadow on the wall has edges, which may differ by a pixel; a surface
                    // facing the light has no business being shadowed anywhere inside it.
                    if e.metrics.interior_mismatch > 0.0 {
                        failures.push(format!(
                            "{kind} light along {travel} (tilt {tilt:e}), {} on {}: interior mismatch {:.3}% (false shadow {:.3}%)",
                            e.technique,
                            e.backend,
                            e.metrics.interior_mismatch * 100.0,
                            e.metrics.false_shadow * 100.0
                        ));
                    }
                }
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
